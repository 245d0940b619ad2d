"""Run a compiled model: validate at the boundary, call the numba driver chunk by chunk.

The drivers keep their whole state in small in/out arrays, so a run whose
output outgrows one buffer simply continues in the next; Python is involved
once per call, never per step.  Calls are also cut by a step budget
(``pause_at``) sized to take about `CALL_SECONDS`, so that a long run shows
progress and stops cleanly on Ctrl-C, returning what it computed.  Memory is
bounded by what is kept: every saved row (`save_every`, `t_eval`) or, with
``record="summary"``, only running reductions (`lagcomp.integrate.recording`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import math
import time
import weakref

import numpy as np

from lagcomp.animation_bodies import BodyGeometry
from lagcomp.errors import IntegrationError, OptionError, SingularMassMatrixError
from lagcomp.integrate import sensitivities as sens
from lagcomp.integrate import specialize as tiers
from lagcomp.integrate.constraints import consistent_initial_state, reactions_along
from lagcomp.integrate.contacts import (
    check_contacts,
    contact_forces_along,
    contact_reactions_along,
    contact_switches,
    contacts_of,
    frictions_of,
    impulses,
    set_initial_modes,
)
from lagcomp.integrate.dae import dae_state, differential_size, refuse_stabilisation
from lagcomp.integrate.drivers.events import ACTION_RESET
from lagcomp.integrate.drivers.run_state import STEP, RunState
from lagcomp.integrate.energy_balance import PowerSource
from lagcomp.integrate.function_inputs import driven
from lagcomp.integrate.memory import MEMORY_LIMIT, run_bytes
from lagcomp.integrate.memory import check as check_memory
from lagcomp.integrate.methods import library_function
from lagcomp.integrate.options import RunOptions, run_options
from lagcomp.integrate.recording import RECORD_MODES, Recorder
from lagcomp.integrate.reset_checks import warn_of_resets_gone_through
from lagcomp.integrate.run_control import deferred_interrupt, progress_bar
from lagcomp.integrate.solution import (
    ContactSwitch,
    EventRecord,
    FrictionSwitch,
    Solution,
)
from lagcomp.integrate.status import Status
from lagcomp.integrate.stiffness import (
    ADVISED_FAILURES,
    stiffness_advice,
    warn_if_stiff,
)
from lagcomp.integrate.tolerances import driver_atol, positive

#: Rows per output chunk, the first and the largest (each full buffer doubles the next).  A full buffer ends a
#: driver call, and a call costs (numba unboxing each kernel of a library driver, ~35 µs, and an f evaluation):
#: with 1024 rows, saving every step of DOP853 on the double pendulum ([0, 100], tol 1e-10, 3900 steps) took
#: three calls more than saving every tenth step, 1.34 times the driver's time alone against 1.19 with one call
#: (`bench/bench_tiers.py`).  An unwritten buffer costs address space only (numpy's large arrays are mapped
#: lazily), so the first holds 16384 rows.
FIRST_CHUNK, MAX_CHUNK = 1 << 14, 1 << 18
#: Target wall time of one driver call, and the step budget of the first one.
CALL_SECONDS, FIRST_BUDGET = 0.25, 2048
#: Target wall time of a run's first driver call once the model's step rate is known (`_STEP_RATES`):
#: that call binds the kernels by address (`_bound_drivers`), cheap to make and ~1% slower per step, so
#: it is kept short; a run that ends within it takes one call.
FIRST_CALL_SECONDS = 0.0125
#: Steps per second of each model's last call that spent its whole step budget, per method, {model:
#: {method name: steps/s}}: a model's next run sizes its calls from it rather than from `FIRST_BUDGET`
#: (each call costs up to ~0.15 ms of numba unboxing its kernels: a tenth of a 5000-step DOP853 run).
_STEP_RATES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
#: `pause_at` of a call without a step budget.
NO_PAUSE_AT = int(np.iinfo(np.int64).max)
#: The library function a "module:function" reference names, looked up once per reference (a method's
#: `Method.carry`; `library_function` checks the module's numba cache at each look-up, ~1.5 µs).
_library_function = functools.cache(library_function)
#: {model: {requested sensitivities (a tuple of names): `sens.Columns`}}: resolving the names takes 6 µs of a
#: short sensitivity run's ~0.19 ms (`_columns`).
_COLUMNS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _columns(model, requested):
    """`sens.columns(model, requested)`, resolved once per model and names (a name or a tuple or list of them)."""
    names = (requested,) if isinstance(requested, str) else requested
    if not isinstance(names, tuple | list) or not all(isinstance(name, str) for name in names):
        return sens.columns(model, requested)     # (it says what is wrong)
    resolved = _COLUMNS.setdefault(model, {})
    if tuple(names) not in resolved:
        resolved[tuple(names)] = sens.columns(model, tuple(names))
    return resolved[tuple(names)]


def _adaptive_driver(kernels, state: RunState, p, run_args, options: RunOptions, differential: int,
                     tier=(None,)):
    """The chunk call of an adaptive method, and the rows its output will need (None: not known).

    `differential`: the state's first components that are differential, the rest algebraic (a DAE's; Radau).
    `tier`: a one-item list holding the model's specialised driver (`lagcomp.integrate.specialize`) to call instead
    of the library's, or None; read at each call, so that a run can move to it between calls (`_upgrade`).
    """
    m = options.method
    if options.first_step is not None:
        state.clock[STEP] = options.first_step
    events = options.t_eval_after_start()
    dae = differential < state.y.size
    library = _bound_drivers(m, kernels, dae) if tier[0] is None else None
    tableau_arrays = options.driver_arguments()
    if m.tableau is None:  # the Taylor method: the carry of its compensated summation, kept across calls
        tableau_arrays = (np.zeros(state.y.size),)
    elif m.carry is not None:  # Radau: the count of differential components (all: an ODE), then what it keeps
        tableau_arrays = (*tableau_arrays, differential, *_library_function(m.carry)(state.y.size))
    t1, rtol, max_step = options.t1, options.rtol, options.max_step
    atol = driver_atol(options.atol, state.y.size)    # (N,): one per component of the driver's state
    # the drivers that reset also write the states after the events, and keep which events are at their zero
    resets = "event_reset" in m.kernels
    buffers = 4 if resets else 3
    at_zero = (np.zeros(options.directions.size, dtype=np.int64),) if resets else ()

    def advance(ts, ys, pause_at, event_buffers, first_call):
        driver = library[first_call] if tier[0] is None else tier[0]
        return driver(state.y, state.clock, state.counters, p, *run_args, t1, rtol, atol, max_step,
                      options.max_steps, pause_at, options.save_every, events, ts, ys,
                      options.directions, options.actions, *event_buffers[:buffers], *at_zero, *tableau_arrays)
    return advance, (len(events) + 1 if options.t_eval is not None else None)


def _fixed_step_driver(kernels, state: RunState, p, run_args, options: RunOptions, tier=(None,)):
    """The chunk call of a fixed-step method, and the rows its output will need (`tier`: as `_adaptive_driver`'s)."""
    library = _bound_drivers(options.method, kernels) if tier[0] is None else None
    coefficients = options.driver_arguments()
    charts = options.method.switches_charts
    if charts:    # the events' actions: which are chart switches (`Method.switches_charts`)
        coefficients = (*coefficients, options.actions)
    carry = ()
    if options.method.carry is not None:  # the Gauss methods: what their steps carry from call to call
        stages = options.method.tableau.B.size
        carry = _library_function(options.method.carry)(state.y.size, stages)
    t0, t1, dt, n_steps = options.t0, options.t1, options.dt, options.n_steps

    def advance(ts, ys, pause_at, event_buffers, first_call):
        driver = library[first_call] if tier[0] is None else tier[0]
        # a method that switches charts records them in the event buffers (times, states before, events, after)
        return driver(state.y, state.clock, state.counters, p, *run_args, t0, dt, n_steps, pause_at, t1,
                      options.save_every, ts, ys, *coefficients, *(event_buffers if charts else ()), *carry)
    return advance, n_steps // options.save_every + 1


def _bound_drivers(m, kernels, dae: bool = False) -> tuple:
    """The driver of method `m` bound to `kernels`, for later calls of a run and for its first (indexed by
    `first_call`): the first binds them as `AddressedKernel`s, which numba unboxes in ~10 µs instead of
    ~35 µs per kernel (a tenth of a short run), at ~1% per step of a small model (kernel calls through their
    C wrappers); the later, long calls (`CALL_SECONDS`) bind the dispatchers, called at their native entry.
    """
    return m.bound_driver(kernels, dae=dae), m.bound_driver(kernels, addressed=True, dae=dae)


def simulate(model, t_span, q0=None, qd0=None, params=None, *, method="dop853", dt=None, rtol=None,
             atol=None, t_eval=None, save_every=1, first_step=None, max_step=math.inf, implicit_solver=None,
             max_steps=100_000_000, projection=None, baumgarte=(0.0, 0.0), project_initial=False,
             events=None, record="trajectory", progress=None, throw=False, max_residual=None,
             memory_limit=MEMORY_LIMIT, inputs=None, sensitivities=None, sensitivity_control="both",
             specialize=None) -> Solution:
    """Integrate `model` over `t_span`; see `lagcomp.Model.simulate` for the arguments."""
    columns = None if sensitivities is None else _columns(model, sensitivities)
    k_columns = 0 if columns is None else columns.k
    scale = sens.scale_for(sensitivity_control)
    options = run_options(model, t_span, method=method, dt=dt, rtol=rtol, atol=atol, t_eval=t_eval,
                          save_every=save_every, first_step=first_step, max_step=max_step, max_steps=max_steps,
                          implicit_solver=implicit_solver, events=events, projection=projection,
                          memory_limit=memory_limit,
                          check_rows=_memory_check(model, memory_limit, k_columns) if record == "trajectory" else None)
    if record not in RECORD_MODES:
        raise OptionError(f"`record` must be one of {RECORD_MODES}, got {record!r}.")
    m, t0, t1, t_eval = options.method, options.t0, options.t1, options.t_eval
    p = model.parameter_vector(params, baumgarte, inputs, (t0, t1))
    given = model
    model = driven(model, inputs, p, m)  # function inputs: kernels that write their values into p first
    if columns is not None:
        _refuse_resets_with_sensitivities(model, options)
        sens.check(model, m, options, columns, given)
    tier = [_specialised(model, given, m, specialize, columns, progress)]
    upgrade = _upgrade(model, given, m, columns, tier) if specialize is None and tier[0] is None else None
    y0, projected = consistent_initial_state(model, t0, model.initial_state(q0, qd0), p, project_initial)
    resting = check_contacts(model, t0, y0[None, :], p[None, :])
    set_initial_modes(model, m, t0, y0[None, :], p[None, :], resting)  # (p is this run's own: parameter_vector's)
    if max_residual is not None and not m.checks_residual:
        raise OptionError(f"`max_residual` stops a run whose constraint residual drifts past it; `{m.name}` does not "
                          "evaluate the residual during the run (it solves the constraints with the motion). "
                          "Leave it unset and read `Solution.constraint_residual` after the run.")
    bound = math.inf if max_residual is None else positive(max_residual, "max_residual")
    residual_max = np.array([0.0, bound])  # running maximum, and the bound the drivers stop at
    width = y0.size  # the columns of the state that are (q, q̇): all but a DAE's algebraic ones
    if m.solves_dae(model):
        refuse_stabilisation(m.name, model, baumgarte)
        start, singular = dae_state(model, t0, y0, p)
        if singular:
            _refuse_singular_start(model, t0, y0, p)
        state, differential = RunState(start, t0), differential_size(model)
    else:
        state, differential = RunState(y0, t0), y0.size
    run_args = (options.projecting, residual_max)
    kernels, p_run = model.kernels, p.copy()    # (the drivers' resets write the contacts' modes into p_run)
    if columns is not None:  # the variational equations ride along: an augmented state, rhs and p
        kernels = sens.run_kernels(model, m, columns, scale)
        state = RunState(sens.initial_state(y0, columns, scale), t0)
        p_run = sens.run_parameters(p, model, columns, scale)
        differential = width = state.y.size
        rtol, atol = sens.driver_tolerances(options.rtol, options.atol, columns, scale, m)
        if rtol != options.rtol:    # (both shrink, or neither; the Taylor method's are the run's: 4 µs saved)
            options = dataclasses.replace(options, rtol=rtol, atol=atol)
    if options.adaptive:
        advance, rows = _adaptive_driver(kernels, state, p_run, run_args, options, differential, tier)
    else:
        advance, rows = _fixed_step_driver(model.kernels, state, p, run_args, options, tier)

    recorder = Recorder(model, p, record, progress)
    if columns is not None:
        recorder = sens.SensitivityRecorder(recorder, y0.size, columns.k, scale)
    if t_eval is None or t_eval[0] == t0:
        recorder.add(np.array([t0]), state.y[None, :width] if columns is not None else y0[None, :])
    n_events = len(model.events)
    event_parts: list[tuple] = []
    max_rows = (options.memory_limit // _row_bytes(model, k_columns) if record == "trajectory" else math.inf)
    # (a run of unknown length checks its rows against the memory limit after each buffer: no larger than the limit)
    chunk = int(min(FIRST_CHUNK, max(max_rows, 16))) if rows is None else int(min(max(rows, 16), MAX_CHUNK))
    first = None if tier[0] is not None else _numba_stage(model, m, progress)
    rate_key = m.name if columns is None else (m.name, columns.k)  # (a sensitivity run's steps cost more)
    if tier[0] is not None:
        rate_key = (m.name, "specialised")
    # (a specialised driver's kernels are compiled into it: none of them compiles in its first call)
    watched = _kernels_of(model, m) if tier[0] is None else ()
    status = _run(advance, state, t1, (chunk, max_rows, width), recorder, n_events, event_parts, progress, first,
                  (_STEP_RATES.setdefault(model, {}), rate_key), watched, upgrade)
    if status == Status.RHS_FAILED and state.nsteps == 0:
        _refuse_singular_start(model, t0, y0, p)
    if (status < 0 or status == Status.INTERRUPTED) and (recorder.last is None or recorder.last[0][0] != state.t):
        recorder.add(np.array([state.t]), state.y[None, :width])  # keep the last good state
    run = dict(method=m.name, status=status, state=state, projected=projected,
               residual_max=float(residual_max[0]), max_residual=bound, events=_event_records(model, p, event_parts),
               switches=_switches(model, p, event_parts, status))
    if columns is not None:
        run.update(sensitivities=recorder.sensitivities(), sensitivity_columns=columns, sensitivity_names=columns.names,
                   event_sensitivities=sens.event_sensitivities(model, p, columns, scale,
                                                                [part[:3] for part in event_parts]))
        recorder = recorder.recorder
    solution = _solution(model, p, recorder, run, throw)
    if model.events:
        warn_of_resets_gone_through(model, p, options.actions, solution.events, solution.t,
                                    np.hstack([solution.q, solution.qd]))
    return solution


def _specialised(model, given, m, specialize, columns, progress):
    """The driver a run starts with: None for the library driver; the model's specialised driver
    (`lagcomp.integrate.specialize`) for ``specialize=True`` (loaded, or compiled under a progress stage, after
    refusing a run it does not cover) and for ``None`` (the automatic tier) when it is loaded in this process
    already, which costs nothing (each call of it even less than a library driver's: no kernel to unbox)."""
    if specialize is not None and not isinstance(specialize, bool | np.bool_):
        raise OptionError(f"`specialize` must be True, False or None (automatic), got {specialize!r}.")
    if specialize is None:
        covered = tiers.covers(m, model, given, columns)
        return tiers.driver(model, m) if covered and tiers.loaded(model, m) else None
    if not specialize:
        return None
    if columns is not None:
        raise OptionError("`specialize=True` with `sensitivities=`: a sensitivity run's kernels are made per run, "
                          "so no driver is specialised for them. Leave `specialize` unset.")
    tiers.check(m, model, given)
    if tiers.loaded(model, m):
        return tiers.driver(model, m)
    from lagcomp.stages import Stages

    what = f"numba: compiling the {m.name} driver specialised for {model.name} (once; cached for later runs)"
    with Stages(f"preparing {model.name}", (what,), progress) as stages:
        stages.start(what)
        return tiers.driver(model, m)


def _upgrade(model, given, m, columns, tier):
    """The automatic tier's move of a long run to the model's specialised driver, or None for a run it does not cover.

    `_run` calls it between driver calls with the run's estimated remaining seconds.  Once they reach
    `specialize.AUTO_REMAINING_SECONDS`, it looks once whether the specialised driver is ready without a compile
    (in numba's cache beside its module, `specialize.cached`): if so it loads it (~0.1 s, a tenth of the rest of the
    run at most) into `tier`, where the run's next call takes it; either way it returns True and is not called again.
    It never compiles: a compile (12 s of CPU for DOP853's) is no part of a run that did not ask for it.  The two
    drivers being bitwise the same, the run is the one either driver alone gives.
    """
    if not tiers.covers(m, model, given, columns):
        return None

    def upgrade(remaining: float) -> bool:
        if not remaining >= tiers.AUTO_REMAINING_SECONDS:
            return False
        if tiers.cached(model, m):
            tier[0] = tiers.driver(model, m)
        return True
    return upgrade


def _row_bytes(model, k_columns: int) -> int:
    """Peak bytes of one kept row (`memory.run_bytes`), with `k_columns` sensitivity columns of the state
    (kept while the chunks are joined, then reshaped into `Solution.sensitivities`: twice)."""
    return run_bytes(1, model.n, model.k) + 16 * model.state_size * k_columns


def _memory_check(model, memory_limit, k_columns: int = 0):
    """`run_options`' `check_rows` for a run keeping every saved row: refuse, before it starts, a run whose
    rows would exceed `memory_limit` (see `memory.run_bytes`; `_row_bytes` with `k_columns` sensitivities).

    The rows are known up front for `t_eval` (its size: an array of 10⁹ times is refused before it is
    copied) and for fixed-step methods (steps / save_every); an adaptive run without `t_eval` saves
    every `save_every`-th accepted step, a number no one knows in advance.
    """
    def check_rows(rows: int | None, where: str) -> None:
        if rows is not None:
            check_memory(rows * _row_bytes(model, k_columns), memory_limit, "The run's saved rows", where,
                         "save fewer rows (`save_every=K` keeps every K-th step; pass fewer `t_eval` points), "
                         "keep only the first and last rows and running reductions (`record=\"summary\"`)")
    return check_rows


def _kernels_of(model, m) -> tuple:
    """The numba dispatchers among the kernels the run's driver takes (numba compiles those it has not yet in
    the driver's first call: the library driver itself was compiled, or loaded, on import)."""
    names = m.dae_kernels if m.solves_dae(model) else m.driver_kernels
    return tuple(kernel for kernel in (getattr(model.kernels, name, None) for name in names)
                 if hasattr(kernel, "signatures"))


def _numba_stage(model, m, progress):
    """What the first driver call of a run shows while numba compiles its kernels and driver."""
    from lagcomp.stages import numba_stage

    # the first kernel stands for the model's
    kernels = m.dae_kernels if m.solves_dae(model) else m.kernels
    return numba_stage(getattr(model.kernels, kernels[0], None), f"the kernels and the {m.name} driver",
                       f"preparing {model.name}", progress)


def _run(advance, state: RunState, t1, chunk, recorder, n_events, event_parts, progress, first=None,
         learned=None, watched=(), upgrade=None) -> int:
    """Call the driver until the run ends; returns the run's `Status`.

    `first`, if not None, is a context around the first call (numba compiles there: `_numba_stage`).
    `watched`: the run's kernels (`_kernels_of`).  Ctrl-C during a first call in which numba compiled one of
    them meant to stop the script, not to keep a run that had barely begun: the compilation finishes (its
    machine code kept, in the process and numba's disk cache), then KeyboardInterrupt.  Ctrl-C at any other
    time stops the run with status INTERRUPTED, its rows kept.
    `chunk` is (rows of the first output buffer, rows the run may keep before it stops with MEMORY_FULL, the
    leading columns of the state that are recorded: (q, q̇), not a DAE's algebraic components).
    `learned`, if not None, is (rates, key): ``rates[key]``, if there, is the steps per second that sizes
    the first call (`FIRST_CALL_SECONDS`) and the second (`CALL_SECONDS`); the rate of each call that
    spends its whole budget outside numba's compilation is stored there for the next run.
    `upgrade`, if not None, is `_upgrade`'s, called after each call that did not end the run with the seconds the
    rest of the run is estimated to take (from the CPU time of this thread in the calls so far after the first, which
    a loaded machine does not inflate) until it returns True.
    """
    chunk, max_rows, width = chunk
    n = state.y.size
    rates, key = learned if learned is not None else ({}, None)
    known = rates.get(key)
    budget = FIRST_BUDGET if known is None else max(16, int(known * FIRST_CALL_SECONDS))
    t0, first_call = state.t, True
    signatures = [len(kernel.signatures) for kernel in watched]
    timed = [0.0, 0.0]      # CPU seconds and span of t of the calls after the first (`upgrade`'s estimate)
    with deferred_interrupt() as interrupted, progress_bar(t0, t1, progress) as bar:
        ts, ys = np.empty(chunk), np.empty((chunk, n))
        rows_e = max(n_events, 16)      # (each call's event rows are copied out: the buffers serve every call)
        event_buffers = (np.empty(rows_e), np.empty((rows_e, n)), np.empty(rows_e, dtype=np.int64),
                         np.full((rows_e, n), np.nan))  # times, states before, events, states after
        while True:
            state.new_event_buffer()
            started, cpu_started = time.perf_counter(), time.thread_time()
            steps_before, t_before = state.nsteps, state.t
            with first or contextlib.nullcontext() as stages:
                if stages is not None:
                    stages.start(stages.names[0])
                status, n_saved = advance(ts, ys, min(steps_before + budget, NO_PAUSE_AT), event_buffers,
                                          first_call)
            compiled = first is not None
            if compiled:  # numba was compiling: the run's bar times the run from here
                first, bar.started = None, time.perf_counter()
            if first_call and interrupted[0] and signatures != [len(kernel.signatures) for kernel in watched]:
                raise KeyboardInterrupt
            elapsed = time.perf_counter() - started
            if not first_call:  # (the first may compile kernels, and binds them: not a rate of the run's steps)
                timed[0], timed[1] = timed[0] + time.thread_time() - cpu_started, timed[1] + (state.t - t_before)
            outcome = Status(status)
            # (the buffers are filled again by the next call, if any: the rows of the last are not copied here)
            recorder.add(ts[:n_saved], ys[:n_saved, :width], outcome.call_again)
            if recorder.rows > max_rows and outcome.call_again:
                return Status.MEMORY_FULL  # what was computed is kept; a fixed-step or t_eval run was refused up front
            if state.event_rows:
                event_parts.append(tuple(a[:state.event_rows].copy() for a in event_buffers))
                event_buffers[3][:state.event_rows] = np.nan    # (a driver that does not write them leaves NaN)
            bar.update(state.t - t0 - bar.n)
            if status == Status.BUFFER_FULL and n_saved == chunk and chunk < MAX_CHUNK:
                chunk = min(2 * chunk, MAX_CHUNK)
                ts, ys = np.empty(chunk), np.empty((chunk, n))
            if status == Status.PAUSED and state.nsteps - steps_before == budget:
                if not compiled:
                    rates[key] = budget / max(elapsed, 1e-6)
                if first_call and known is not None:
                    budget = max(16, int(known * CALL_SECONDS))
                else:
                    budget = max(16, int(budget * min(8.0, max(0.5, CALL_SECONDS / max(elapsed, 1e-6)))))
            first_call = False
            if not outcome.call_again:
                if status == Status.DONE and interrupted[0]:
                    return Status.INTERRUPTED  # Ctrl-C in the last call (often numba compiling): reported
                return outcome
            if interrupted[0]:
                return Status.INTERRUPTED
            if upgrade is not None and timed[1] > 0 and upgrade(timed[0] / timed[1] * (t1 - state.t)):
                upgrade = None


def _refuse_singular_start(model, t0: float, y0: np.ndarray, p: np.ndarray) -> None:
    """Raise SingularMassMatrixError if the equations are singular at the initial state itself.

    That is bad input (parameter values or q0), not a failure of the run: the
    message names the parameters that are zero and, with constraints, those
    whose rows of Λ are linearly dependent there (redundant constraints).
    """
    n = model.n
    if not model.kernels.rhs(t0, y0, p, np.empty(y0.size)):
        return  # singular at a stage of the first step, not at the start: a run failure
    where = ", ".join(f"{c}={v:.6g}" for c, v in zip(model.coordinates, y0[:n]))
    zero = [name for name, value in zip(model.parameters, p) if value == 0]
    hint = (f" Parameter(s) {zero} are zero: a zero mass, length or moment of inertia takes the inertia out "
            "of a coordinate." if zero else "")
    redundant = _redundant_constraints(model, t0, y0, p) if model.k else []
    if redundant:
        raise SingularMassMatrixError(
            f"Constraint(s) {redundant} of {model.name!r} are redundant at the initial state t={t0:g}, {where}: "
            f"there their rows of Λ depend linearly on the rows of the constraints before them (in the order "
            f"{list(model.constraints)}). "
            "Remove them, or start from a state where the constraints are independent."
        )
    matrix = "augmented matrix [M Λᵀ; Λ 0]" if model.k else "mass matrix"
    raise SingularMassMatrixError(
        f"The {matrix} of {model.name!r} is singular at the initial state t={t0:g}, {where}, with parameters "
        f"{dict(zip(model.parameters, p.tolist()))}: the kinetic energy is not positive definite there.{hint} "
        "Change q0 or the parameter values."
    )


def _redundant_constraints(model, t0: float, y0: np.ndarray, p: np.ndarray) -> list[str]:
    """Names of the constraints whose row Λ_k(q0) depends on the rows before it.

    Λ comes from the ``constraint_residuals`` kernel: its velocity-level
    entries Λ q̇ + b are linear in q̇, so unit velocities give Λ's columns exactly.
    """
    n, k = model.n, model.k
    out = np.empty(len(model.residual_labels))
    velocity = np.empty((n + 1, k))
    for j in range(n + 1):
        y = y0.copy()
        y[n:] = 0.0
        if j < n:
            y[n + j] = 1.0
        model.kernels.constraint_residuals(t0, y, p, out)
        velocity[j] = out[-k:]
    rows = (velocity[:n] - velocity[n]).T  # Λ, shape (k, n)
    tolerance = 1e-10 * max(1.0, float(np.abs(rows).max()))
    redundant, rank = [], 0
    for i in range(k):
        new_rank = np.linalg.matrix_rank(rows[: i + 1], tol=tolerance)
        if new_rank == rank:
            redundant.append(model.constraints[i])
        rank = new_rank
    return redundant


def _refuse_resets_with_sensitivities(model, options: RunOptions) -> None:
    """Refuse `sensitivities=` on a run whose events reset the state: the jump of the sensitivities at a reset
    (the saltation matrix) is not computed."""
    resetting = [e.name for e, action in zip(model.events, options.actions.tolist(), strict=True)
                 if action >= ACTION_RESET]
    if resetting:
        raise OptionError(f"`sensitivities=` on a run whose event(s) {resetting} reset the state: the jump of the "
                          "sensitivities at a reset (its saltation matrix) is not computed yet. Run without "
                          "`sensitivities`, or leave the events out (`events=False`).")


def _event_records(model, p, event_parts) -> dict:
    """Occurrences of each declared event: {name: EventRecord(t, q, qd, q_after, qd_after)}, in time order (qd: u of a
    Kane model); the states after are those before for an event without a reset, NaN from a driver that does not
    write them (radau, whose events cannot reset); a contact's impacts with their impulses."""
    if not model.events:
        return {}
    n, size = model.n, model.state_size
    if event_parts:
        t_all, y_all, i_all, after_all = (np.concatenate(column) for column in zip(*event_parts, strict=True))
    else:
        t_all, y_all, i_all = np.empty(0), np.empty((0, size)), np.empty(0, dtype=np.int64)
        after_all = y_all
    records = {}
    contacts = {name for name, _, _ in contacts_of(model)}
    for index, event in enumerate(model.events):
        hit = i_all == index
        after = after_all[hit, :size] if event.resets else y_all[hit, :size]
        records[event.name] = EventRecord(
            t=t_all[hit], q=y_all[hit, :n], qd=y_all[hit, n:size], q_after=after[:, :n], qd_after=after[:, n:],
            impulses=(impulses(model, p, index, t_all[hit], y_all[hit, :size], after) if event.name in contacts
                      else None))
    return records


def _switches(model, p, event_parts, status) -> tuple:
    """The contacts' and friction elements' mode switches (`lagcomp.integrate.contacts.contact_switches`) from the
    run's event rows."""
    if not event_parts:
        return ()
    t_all, y_all, i_all = (np.concatenate(column) for column in list(zip(*event_parts, strict=True))[:3])
    stopped = status in (Status.TERMINATED, Status.EVENTS_ACCUMULATED, Status.RESET_FAILED)  # (no reset at its end)
    return contact_switches(model, p, t_all, y_all, i_all, stopped)


def _modes_along(model, p, ts, ys, switches) -> dict:
    """The `Solution` fields of the modes: the contacts' and friction elements' switches and forces."""
    forces = contact_forces_along(model, p, ts, ys, switches)
    count, frictions = len(contacts_of(model)), {name for name, *_ in frictions_of(model)}
    return dict(
        contact_switches=tuple(ContactSwitch(t, name, bool(mode)) for t, name, mode in switches
                               if name not in frictions),
        contact_forces=None if forces is None or (frictions and not count) else forces[:, :count],
        friction_switches=tuple(FrictionSwitch(t, name, int(mode)) for t, name, mode in switches if name in frictions),
        friction_forces=forces[:, count:] if frictions else None)


def _solution(model, p, recorder, run, throw) -> Solution:
    ts, ys, observed = recorder.result()
    status, run_state = run["status"], run["state"]
    t_failure = None
    message = Status(status).message
    stiff_at = run_state.stiff_at
    if stiff_at is not None and status in ADVISED_FAILURES:
        message = f"{message} The steps were limited by stability from t = {stiff_at[1]:.6g}: the problem is " \
                  f"stiff. {stiffness_advice(model)}"
    if status < 0 or status == Status.INTERRUPTED:
        state = ", ".join(f"{name}={v:.6g}" for name, v in zip(model.state_names, run_state.y))  # (q, q̇), or (q, u)
        last = "state" if status == Status.RESIDUAL_EXCEEDED else "last good state"
        message = f"{message} Stopped at t = {run_state.t:.10g}, {last} {state}."
        if status == Status.RESIDUAL_EXCEEDED:
            message += f" Residual {run['residual_max']:.3g} > max_residual = {run['max_residual']:g}."
        t_failure = run_state.t if status < 0 else None
    if status == Status.TERMINATED:
        fired = [name for name, record in run["events"].items() if record.t.size and record.t[-1] == run_state.t]
        message = f"{message} Event {fired[0] if fired else '?'!r} at t = {run_state.t:.10g}."
    reactions, residual = reactions_along(model, ts, ys, p)
    reactions = contact_reactions_along(model, p, ts, ys, run.get("switches", ()), reactions)
    reaction_sensitivities = (None if run.get("sensitivities") is None else
                              sens.reaction_sensitivities(model, ts, ys, p, run["sensitivities"],
                                                          run["sensitivity_columns"]))
    n = model.n
    solution = Solution.of_run(
        t=ts, q=ys[:, :n].copy(), qd=ys[:, n:].copy(), observed=observed, cyclic=model.cyclic,
        status=status, message=message, t_failure=t_failure,
        nfev=run_state.nfev, nsteps=run_state.nsteps, nrejected=run_state.nrejected,
        njev=run_state.njev, nlu=run_state.nlu, method=run["method"], coordinates=model.coordinates,
        params=dict(zip(model.parameters, p.tolist())),
        reactions=reactions, constraint_residual=max(run["residual_max"], residual),
        projected_initial_state=ys[0].copy() if run["projected"] else None,
        events=run["events"], model_name=model.name, geometry=BodyGeometry.of(model, p),
        power_source=PowerSource.of(model, p),
        **_modes_along(model, p, ts, ys, run.get("switches", ())),
        sensitivities=run.get("sensitivities"), sensitivity_names=run.get("sensitivity_names", ()),
        event_sensitivities=run.get("event_sensitivities", {}), reaction_sensitivities=reaction_sensitivities,
    )
    # simulate -> Model.simulate -> the user's call
    warn_if_stiff(run["method"], stiff_at, run_state.nsteps, run_state.nfev, stacklevel=4, model=model)
    if throw and status < 0:
        raise IntegrationError(message, solution)
    return solution
