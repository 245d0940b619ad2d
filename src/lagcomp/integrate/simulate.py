"""Run a compiled model: validate at the boundary, call the numba driver chunk by chunk.

The drivers keep their whole state in small in/out arrays, so a run whose
output outgrows one buffer simply continues in the next; Python is involved
once per chunk, never per step, and memory is bounded by what is saved
(`save_every`, `t_eval`).
"""

from __future__ import annotations

import math

import numpy as np

from lagcomp.errors import IntegrationError, OptionError
from lagcomp.integrate.constraints import consistent_initial_state, reactions_along
from lagcomp.integrate.methods import get_method, implicit_solver_for
from lagcomp.integrate.solution import MESSAGES, Solution

#: Rows per output chunk: small runs allocate little, long ones grow to this.
FIRST_CHUNK, MAX_CHUNK = 1024, 1 << 18
BUFFER_FULL = 1


def _time_span(t_span) -> tuple[float, float]:
    try:
        t0, t1 = (float(v) for v in t_span)
    except (TypeError, ValueError) as err:
        raise OptionError(f"`t_span` must be a pair (t0, t1) of numbers, got {t_span!r}.") from err
    if not (math.isfinite(t0) and math.isfinite(t1)):
        raise OptionError(f"`t_span` must be finite, got ({t0}, {t1}).")
    if not t1 > t0:
        raise OptionError(f"`t_span` = ({t0}, {t1}) is empty: the end time must be after the start time.")
    return t0, t1


def _positive(value, name: str) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError) as err:
        raise OptionError(f"`{name}` must be a number, got {value!r}.") from err
    if not (value > 0 and math.isfinite(value)):
        raise OptionError(f"`{name}` must be positive and finite, got {value}.")
    return value


def _t_eval(t_eval, t0: float, t1: float) -> np.ndarray | None:
    if t_eval is None:
        return None
    t_eval = np.asarray(t_eval, dtype=float).ravel()
    if t_eval.size == 0 or not np.all(np.isfinite(t_eval)):
        raise OptionError("`t_eval` must be a non-empty array of finite times.")
    if np.any(np.diff(t_eval) <= 0) or t_eval[0] < t0 or t_eval[-1] > t1:
        raise OptionError(f"`t_eval` must be strictly increasing and within t_span = ({t0}, {t1}).")
    return t_eval


def _adaptive_driver(m, kernels, y, clock, counters, p, run_args, t_eval, options):
    """The chunk call of an adaptive method, and the rows its output will need."""
    t0, t1 = clock[0], options["t1"]
    if options["dt"] is not None:
        raise OptionError(f"`dt` sets the step of fixed-step methods; {m.name} chooses its own (use `first_step`).")
    rtol, atol = _positive(options["rtol"], "rtol"), _positive(options["atol"], "atol")
    if options["first_step"] is not None:
        clock[1] = _positive(options["first_step"], "first_step")
    max_step = options["max_step"]
    max_step = _positive(max_step, "max_step") if max_step != math.inf else math.inf
    events = t_eval[t_eval > t0] if t_eval is not None else np.empty(0)
    driver, tableau_arrays = getattr(kernels, m.driver), m.driver_arguments()

    def advance(ts, ys):
        return driver(y, clock, counters, p, *run_args, t1, rtol, atol, max_step, options["max_steps"],
                      options["save_every"], events, ts, ys, *tableau_arrays)
    return advance, (len(events) + 1 if t_eval is not None else None)


def _fixed_step_driver(m, kernels, y, clock, counters, p, run_args, t_eval, options):
    """The chunk call of a fixed-step method, and the rows its output will need."""
    t0, t1 = clock[0], options["t1"]
    if options["dt"] is None:
        raise OptionError(f"`{m.name}` is a fixed-step method: give the step `dt`.")
    if t_eval is not None:
        raise OptionError(f"`t_eval` needs dense output, which {m.name} lacks; use `save_every` or dopri5/dop853.")
    dt = _positive(options["dt"], "dt")
    n_steps = max(1, math.ceil((t1 - t0) / dt * (1 - 1e-12)))
    if n_steps > options["max_steps"]:
        raise OptionError(f"{n_steps} steps of dt = {dt} exceed `max_steps` = {options['max_steps']}.")
    driver, coefficients = getattr(kernels, m.driver), m.driver_arguments(options["implicit_solver"])

    def advance(ts, ys):
        return driver(y, clock, counters, p, *run_args, t0, dt, n_steps, t1, options["save_every"], ts, ys,
                      *coefficients)
    return advance, n_steps // options["save_every"] + 1


def _count(value, name: str) -> int:
    if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or value < 1:
        raise OptionError(f"`{name}` must be a positive integer, got {value!r}.")
    return int(value)


def simulate(model, t_span, q0=None, qd0=None, params=None, *, method="dop853", dt=None, rtol=1e-8,
             atol=1e-10, t_eval=None, save_every=1, first_step=None, max_step=math.inf, implicit_solver=None,
             max_steps=100_000_000, projection=None, baumgarte=(0.0, 0.0), project_initial=False,
             throw=False) -> Solution:
    """Integrate `model` over `t_span`; see `lagcomp.Model.simulate` for the arguments."""
    t0, t1 = _time_span(t_span)
    m = get_method(method)
    if m.separable_only and not model.separable:
        raise OptionError(
            f"`{m.name}` needs a separable system (no constraints, a constant mass matrix and forces that do not "
            f"depend on velocities); {model.name!r} is not one. Use gauss2 (symplectic for any Lagrangian), "
            "dop853, dopri5 or rk4."
        )
    if m.unconstrained_only and model.k:
        raise OptionError(f"`{m.name}` does not handle constraints yet; {model.name!r} has {list(model.constraints)}. "
                          "Use dop853, dopri5 or rk4.")
    p = model.parameter_vector(params, baumgarte)
    options = dict(t1=t1, dt=dt, rtol=rtol, atol=atol, first_step=first_step, max_step=max_step,
                   save_every=_count(save_every, "save_every"), max_steps=_count(max_steps, "max_steps"))
    options["implicit_solver"] = implicit_solver_for(m, implicit_solver)
    t_eval = _t_eval(t_eval, t0, t1)
    y0, projected = consistent_initial_state(model, t0, model.initial_state(q0, qd0), p, project_initial)
    projecting = int(bool(model.k) and (not m.adaptive if projection is None else bool(projection)))
    residual_max = np.zeros(1)
    y, clock, counters = y0.copy(), np.array([t0, 0.0]), np.zeros(5, dtype=np.int64)
    make = _adaptive_driver if m.adaptive else _fixed_step_driver
    advance, rows = make(m, model.kernels, y, clock, counters, p, (projecting, residual_max), t_eval, options)

    save_initial = t_eval is None or t_eval[0] == t0
    ts_parts = [np.array([t0])] if save_initial else []
    ys_parts = [y0[None, :].copy()] if save_initial else []
    chunk = FIRST_CHUNK if rows is None else int(min(max(rows, 16), MAX_CHUNK))
    while True:
        ts, ys = np.empty(chunk), np.empty((chunk, y.size))
        status, n_saved = advance(ts, ys)
        ts_parts.append(ts[:n_saved])
        ys_parts.append(ys[:n_saved])
        if status != BUFFER_FULL:
            break
        chunk = min(2 * chunk, MAX_CHUNK)
    run = dict(method=m.name, status=int(status), clock=clock, counters=counters, projected=projected,
               residual_max=float(residual_max[0]))
    return _solution(model, p, ts_parts, ys_parts, y, run, throw)


def _solution(model, p, ts_parts, ys_parts, y, run, throw) -> Solution:
    ts, ys = np.concatenate(ts_parts), np.concatenate(ys_parts)
    status, clock, counters = run["status"], run["clock"], run["counters"]
    t_failure = None
    message = MESSAGES[status]
    if status < 0:
        t_failure = float(clock[0])
        if ts.size == 0 or ts[-1] != t_failure:  # keep the last good state
            ts, ys = np.append(ts, t_failure), np.vstack([ys, y])
        n = model.n
        state = ", ".join(f"{c}={v:.6g}" for c, v in zip(model.coordinates, y[:n]))
        rates = ", ".join(f"{c}_dot={v:.6g}" for c, v in zip(model.coordinates, y[n:]))
        message = f"{message} Stopped at t = {t_failure:.10g}, last good state {state}, {rates}."
    energy, energy_function, momenta = np.empty(ts.size), np.empty(ts.size), np.empty((ts.size, model.n))
    model.kernels.observables(ts, ys, p, energy, energy_function, momenta)
    reactions, residuals = reactions_along(model, ts, ys, p)
    n = model.n
    solution = Solution(
        t=ts, q=ys[:, :n].copy(), qd=ys[:, n:].copy(), energy=energy, energy_function=energy_function,
        momenta=momenta, cyclic=model.cyclic,
        status=status, message=message, t_failure=t_failure,
        nfev=int(counters[0]), nsteps=int(counters[1]), nrejected=int(counters[2]),
        method=run["method"], coordinates=model.coordinates,
        params=dict(zip(model.parameters, p.tolist())),
        reactions=reactions, constraint_residual=max(run["residual_max"], float(np.max(residuals, initial=0.0))),
        projected_initial_state=ys[0].copy() if run["projected"] else None,
    )
    if throw and status < 0:
        raise IntegrationError(message, solution)
    return solution
