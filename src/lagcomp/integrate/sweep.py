"""Swept runs: many trajectories over a grid of initial values and parameters, on every core.

`sweep` builds the N initial states and parameter vectors of a grid, checks
the memory its outputs need, and hands them to the compiled sweep loop of
the method (`Method.sweep`, a library loop taking the model's kernels, which
releases the GIL; `lagcomp.integrate.drivers`) chunk by chunk, each chunk split
across `workers` threads: Python runs once per chunk, so a long sweep shows progress and stops cleanly on Ctrl-C,
keeping the chunks already done.  Trajectories are independent and each
writes only its own output rows, so the result is identical — bitwise —
whatever the number of threads.

Grid names are coordinate names (initial coordinates), ``<coordinate>_dot``
(initial velocities) and parameter names; everything not swept comes from
`q0`, `qd0`, `params` or the System's defaults.  A Kane model (state (q, u),
`lagcomp.kane_model`) sweeps its speeds by their names (`Model.state_names`)
and takes the speeds not swept as `qd0` (its ``sweep`` passes `u0` there).
"""

from __future__ import annotations

import contextlib
import functools
import math
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from lagcomp.errors import InitialConditionError, ModelError, OptionError
from lagcomp.integrate.balance_kernels import balance_row_kernel, slots
from lagcomp.integrate.constraints import consistent_initial_state
from lagcomp.integrate.contacts import (
    check_contacts,
    contacts_of,
    frictions_of,
    set_initial_modes,
    sweep_impulses,
)
from lagcomp.integrate.dae import dae_states, differential_size, refuse_stabilisation
from lagcomp.integrate.drivers.events import ACTION_RESET
from lagcomp.integrate.energy_balance import sweep_balances
from lagcomp.integrate.files import output_path
from lagcomp.integrate.function_inputs import driven
from lagcomp.integrate.memory import MEMORY_LIMIT, sweep_bytes
from lagcomp.integrate.memory import check as check_memory
from lagcomp.integrate.methods import library_function, method_names
from lagcomp.integrate.options import count, run_options
from lagcomp.integrate.run_control import LazyProgress, deferred_interrupt
from lagcomp.integrate.stiffness import warn_if_sweep_stiff
from lagcomp.integrate.tolerances import driver_atol, uniform
from lagcomp.names import by_name

#: Outputs a sweep can keep besides the final state and status.
OUTPUTS = ("dense", "energy", "events")
#: The arrays of an event's record in a sweep (`Sweep.events`), the longest suffix first (as `load_npz` reads them).
EVENT_PARTS = ("y_after", "impulses", "count", "t", "y")
#: Target wall time of one chunk (progress and Ctrl-C granularity), and the first chunk's size per thread
#: (batched drivers: enough trajectories to fill a block of lanes, 64 to 128 (`drivers.lanes`), or the 32
#: lanes of a batched Taylor sweep several times over, so that few lanes idle while the last ones finish).
CHUNK_SECONDS, FIRST_CHUNK_PER_THREAD, FIRST_BATCHED_CHUNK_PER_THREAD = 0.5, 8, 128
#: Solution-style status of trajectories a Ctrl-C left unstarted.
NOT_RUN = 2


@dataclass(frozen=True)
class Sweep:
    """The outcome of `Model.sweep`: outputs shaped like the grid.

    Attributes
    ----------
    names : tuple of str
        The swept quantities, in grid order.
    combine : str
        "product" (a Cartesian grid), "zip" or "explicit" (one trajectory per row).
    axes : dict of str to ndarray
        For ``combine="product"`` the 1-D values along each grid axis; for
        ``"zip"`` and explicit arrays the value of each name per trajectory.
    shape : tuple of int
        Grid shape: one axis per name for a product, (N,) otherwise.
    final : ndarray, shape (*shape, n_y)
        State where each trajectory ended: (q, q̇), n_y = 2n; for a Kane
        model (q, u), n_y = n_q + n_u, the speeds named in `speeds`.
    t_final : ndarray, shape
        Time it ended (t_end, or earlier on failure or a terminal event).
    status : ndarray of int, shape
        As `Solution.status`: 0 reached the end, 1 terminal event, 2 not run
        (interrupted sweep), negative failures (`MESSAGES`).
    nfev, nsteps, nrejected : ndarray of int, shape
        Counters per trajectory.
    t_dense, dense : ndarray, shapes (m,) and (*shape, m, n_y), or None
        States at common times (``output`` includes "dense").
    energy_error : ndarray, shape, or None
        Largest relative deviation of T + V from its initial value over the
        saved rows (every step unless `save_every`/`t_eval` say otherwise);
        for a system that is not conservative (`energy_balance` True), the
        energy balance's residual instead: the largest |h − h(0) − ∫P dt|
        over the saved rows, each relative to the largest of |h(0)|,
        |h − h(0)| and each power term's |work| up to that row
        (`lagcomp.integrate.energy_balance`; what `Solution.energy_balance`
        computes along the same rows).  A batched Taylor sweep keeps the
        drift of T + V (its lanes module holds no ``power`` kernel).
    energy_balance : bool
        Whether `energy_error` is the energy balance's residual (forces,
        inputs, dissipation, imposed motions or moving constraints) rather
        than the drift of T + V.
    events : dict of str to dict, or None
        Per event: ``count`` (shape), ``t`` (*shape, cap) and ``y``
        (*shape, cap, n_y) of the first `event_cap` occurrences (NaN beyond);
        for an event that resets the state ``y_after`` (*shape, cap, n_y),
        the state its reset gave, and for a contact ``impulses`` (*shape,
        cap, C), the normal impulses of the model's contacts: what a single
        run's `EventRecord` keeps (``q_after``, ``qd_after``, ``impulses``).
    done : ndarray of bool, shape
        Which trajectories ran (all, unless Ctrl-C interrupted the sweep).
    coordinates : tuple of str
    method : str
    speeds : tuple of str
        A Kane model's speed names (the last n_u columns of a state); empty for Lagrange models.
    """

    names: tuple
    combine: str
    axes: dict
    shape: tuple
    final: np.ndarray
    t_final: np.ndarray
    status: np.ndarray
    nfev: np.ndarray
    nsteps: np.ndarray
    nrejected: np.ndarray
    done: np.ndarray
    coordinates: tuple
    method: str
    t_dense: np.ndarray | None = None
    dense: np.ndarray | None = None
    energy_error: np.ndarray | None = None
    events: dict | None = field(default=None)
    speeds: tuple = ()
    energy_balance: bool = False

    @property
    def interrupted(self) -> bool:
        return not bool(self.done.all())

    def to_numpy(self) -> dict[str, np.ndarray]:
        """Every array by name (what `save_npz` writes and `load_npz` reads)."""
        arrays = {
            "names": np.asarray(self.names), "combine": np.asarray(self.combine),
            "shape": np.asarray(self.shape, dtype=np.int64),
            "coordinates": np.asarray(self.coordinates), "method": np.asarray(self.method),
            "final": self.final, "t_final": self.t_final, "status": self.status, "nfev": self.nfev,
            "nsteps": self.nsteps, "nrejected": self.nrejected, "done": self.done,
        }
        if self.speeds:
            arrays["speeds"] = np.asarray(self.speeds)
        if self.energy_balance:
            arrays["energy_balance"] = np.asarray(True)
        arrays.update({f"axis_{name}": values for name, values in self.axes.items()})
        for key in ("t_dense", "dense", "energy_error"):
            if getattr(self, key) is not None:
                arrays[key] = getattr(self, key)
        for name, record in (self.events or {}).items():
            arrays.update({f"event_{name}_{part}": values for part, values in record.items()})
        return arrays

    def save_npz(self, path) -> None:
        """Write `to_numpy()` to a compressed .npz file; a directory that does not exist is an OptionError."""
        np.savez_compressed(output_path(path, "Sweep.save_npz"), **self.to_numpy())

    @classmethod
    def load_npz(cls, path) -> Sweep:
        """The Sweep `save_npz` wrote to `path`; a file without a sweep's arrays is an OptionError."""
        with np.load(path) as data:
            arrays = {key: data[key] for key in data.files}
        missing = sorted({"names", "shape", "combine", "method", "coordinates"} - set(arrays))
        if missing:
            written = ("a Solution's arrays (Solution.save_npz): read them with numpy.load"
                       if {"t", "q", "qd", "status"} <= set(arrays) else f"the arrays {sorted(arrays)[:8]}")
            raise OptionError(f"Sweep.load_npz: {path} is not a Sweep's file (Sweep.save_npz): it lacks {missing} "
                              f"and holds {written}.")
        names = tuple(arrays.pop("names").tolist())
        events: dict = {}
        for key in [k for k in arrays if k.startswith("event_")]:
            part = next(part for part in EVENT_PARTS if key.endswith(f"_{part}"))
            events.setdefault(key[len("event_"):-len(part) - 1], {})[part] = arrays.pop(key)
        return cls(
            names=names, axes={name: arrays.pop(f"axis_{name}") for name in names},
            shape=tuple(arrays.pop("shape").tolist()), coordinates=tuple(arrays.pop("coordinates").tolist()),
            speeds=tuple(arrays.pop("speeds").tolist()) if "speeds" in arrays else (),
            energy_balance=bool(arrays.pop("energy_balance", False)),
            method=str(arrays.pop("method")), combine=str(arrays.pop("combine")), events=events or None, **arrays,
        )

    def to_xarray(self):
        """An ``xarray.Dataset`` with one dimension per swept name (product grids) or ``trajectory``."""
        try:
            import xarray as xr
        except ImportError as err:
            raise ImportError("Sweep.to_xarray needs xarray: pip install 'lagcomp[xarray]'.") from err
        product = self.combine == "product"
        dims = self.names if product else ("trajectory",)
        coords = {name: (name if product else "trajectory", self.axes[name]) for name in self.names}
        state = list(self.coordinates) + (list(self.speeds) or [f"{c}_dot" for c in self.coordinates])
        data = {
            "final": ((*dims, "state"), self.final), "t_final": (dims, self.t_final), "status": (dims, self.status),
            "nsteps": (dims, self.nsteps), "nfev": (dims, self.nfev),
        }
        if self.energy_error is not None:
            data["energy_error"] = (dims, self.energy_error)
        if self.dense is not None:
            data["dense"] = ((*dims, "time", "state"), self.dense)
            coords["time"] = self.t_dense
        return xr.Dataset(data, coords={**coords, "state": state},
                          attrs={"energy_balance": int(self.energy_balance)} if self.energy_error is not None else {})


def _floats(values, what: str) -> np.ndarray:
    """`values` as floats; booleans refused (float(True) is 1.0: a flag where a coordinate or parameter was meant)."""
    if _holds_boolean(values):
        raise OptionError(f"{what} hold a boolean ({_shown(values)}), which would be taken as 1 or 0; give numbers.")
    try:
        return np.asarray(values, dtype=float)
    except (TypeError, ValueError) as err:
        raise OptionError(f"{what} must hold numbers, got {values!r}.") from err


def _holds_boolean(values) -> bool:
    """Whether `values` is or holds a bool or numpy.bool_ (a float array cannot: no walk over it)."""
    if isinstance(values, np.ndarray) and values.dtype != object:
        return values.dtype == np.bool_
    if isinstance(values, (bool, np.bool_)):
        return True
    if isinstance(values, (list, tuple, np.ndarray)):
        return any(_holds_boolean(v) for v in values)
    return False


def _shown(values) -> str:
    """`values` for a message, cut at 80 characters."""
    text = repr(values)
    return text if len(text) <= 80 else text[:77] + "..."


def _grid_name(key) -> str:
    """A grid key as a name: a sympy Symbol (a parameter) stands for its name."""
    name = key.name if getattr(key, "is_Symbol", False) else key
    if not isinstance(name, str):
        raise OptionError(f"Grid names must be strings (coordinates, '<coordinate>_dot' velocities or parameters), "
                          f"got {key!r}.")
    return name


def _swept_coordinates(model, q0, names, values):
    """`q0`, or where neither it nor the model gives the coordinates and the grid sweeps every one of them,
    the first point's (each trajectory then writes its own)."""
    if q0 is not None or model.q0 is not None or not set(model.coordinates) <= set(names):
        return q0
    return [values[0, names.index(name)] for name in model.coordinates]


def _with_swept(model, params, names, values):
    """`params` with each swept parameter's first grid value where `params` does not give it.

    Every trajectory overwrites its swept parameters with its own grid values, so a parameter swept by the
    grid needs no value (nor a default) in `params`; the first point's stands in while p is assembled and
    checked.  `params` that is not a mapping is returned as it is, for `parameter_vector` to refuse.
    """
    swept = {name: values[0, column] for column, name in enumerate(names) if name in model.parameters}
    if not swept or (params is not None and not isinstance(params, Mapping)):
        return params
    return {**swept, **by_name(params or {}, "params", model.parameters)}


def _grid(model, grid, combine: str, names, memory_limit) -> tuple[tuple, dict, tuple, np.ndarray]:
    """(names, axes, shape, values (N, k)) from the user's grid description.

    The number of points is checked against `memory_limit` before the grid is built: a product of
    a few long axes is larger than the memory it names.
    """
    if isinstance(grid, dict):
        names = tuple(_grid_name(key) for key in grid)
        columns = [_floats(v, f"Grid values of `{name}`").ravel() for name, v in zip(names, grid.values())]
        if any(c.size == 0 for c in columns):
            raise OptionError("Every swept quantity needs at least one value.")
        if combine not in ("product", "zip"):
            raise OptionError(f"`combine` must be 'product' or 'zip', got {combine!r}.")
        points = math.prod(c.size for c in columns) if combine == "product" else columns[0].size
        check_memory(sweep_bytes(points, 2 * model.n, len(columns), 0, 0), memory_limit, "The sweep's grid",
                     f"{points:,} trajectories", "sweep fewer points, or split the grid")
        if combine == "product":
            shape = tuple(c.size for c in columns)
            mesh = np.meshgrid(*columns, indexing="ij")
            values = np.column_stack([m.ravel() for m in mesh])
            axes = dict(zip(names, columns))
        else:
            if len({c.size for c in columns}) != 1:
                raise OptionError(f"`combine='zip'` needs arrays of one length; got {[c.size for c in columns]}.")
            values = np.column_stack(columns)
            shape, axes = (values.shape[0],), dict(zip(names, columns))
    else:
        values = _floats(grid, "An explicit grid")
        if isinstance(names, str) or values.ndim != 2 or names is None or len(names) != values.shape[1]:
            raise OptionError("An explicit grid is an (N, k) array with `names` giving its k columns.")
        names = tuple(_grid_name(name) for name in names)
        shape, axes = (values.shape[0],), {name: values[:, i].copy() for i, name in enumerate(names)}
    known = list(model.state_names) + list(model.parameters)
    unknown = [name for name in names if name not in known]
    if unknown or len(set(names)) != len(names):
        velocities = "speeds" if getattr(model, "speeds", None) is not None else "'<coordinate>_dot' velocities"
        raise OptionError(f"Cannot sweep {unknown or names}: grid names must be distinct coordinates, "
                          f"{velocities} or parameters: {known}.")
    ambiguous = [name for name in names if known.count(name) > 1]
    if ambiguous:
        raise OptionError(f"Cannot sweep {ambiguous}: in {model.name!r} the name stands for two quantities (a "
                          "coordinate or parameter, and the velocity '<coordinate>_dot'); rename one of them.")
    if not np.all(np.isfinite(values)):
        raise OptionError("The grid holds non-finite values.")
    return names, axes, shape, values


def _row_every(save_every: int, output: tuple, n_steps: int) -> int:
    """Steps between the rows the drivers hand back: `save_every` when rows are used (dense output,
    energy errors), else only the last one — then each trajectory is one driver call, not one per
    buffer of rows (which would also re-evaluate the adaptive methods' first stage each time)."""
    return save_every if ("dense" in output or "energy" in output) else n_steps + 1


def sweep(model, t_span, grid, *, combine="product", names=None, q0=None, qd0=None, params=None,
          method="dop853", dt=None, rtol=None, atol=None, t_eval=None, save_every=1, max_step=math.inf,
          max_steps=100_000_000, implicit_solver=None, events=None, event_cap=16, output=(), workers=None,
          client=None, batched=False, progress=None, memory_limit=MEMORY_LIMIT, projection=None,
          baumgarte=(0.0, 0.0), project_initial=False, inputs=None, sensitivities=None) -> Sweep:
    """Integrate every point of `grid`; see `lagcomp.Model.sweep` for the arguments."""
    if sensitivities is not None:
        raise OptionError("`sensitivities` are integrated by `simulate`, one trajectory at a time; a sweep does not "
                          "integrate them yet: call model.simulate(..., sensitivities=...) per point.")
    try:
        output = (output,) if isinstance(output, str) else tuple(output)
    except TypeError:
        raise OptionError(f"`output` must be one of {OUTPUTS} or a sequence of them, got {output!r}.") from None
    unknown = [o for o in output if o not in OUTPUTS]
    if unknown:
        raise OptionError(f"Unknown sweep output(s) {unknown}; choose from {OUTPUTS} (the final state is always kept).")
    names, axes, shape, values = _grid(model, grid, combine, names, memory_limit)
    n_traj, n2 = values.shape[0], model.state_size
    want_events = "events" in output
    cap = count(event_cap, "event_cap") if want_events else 0
    n_events = len(model.events) if want_events else 0
    after_width = n2 if want_events and any(event.resets for event in model.events) else 0  # states after resets

    def check_rows(times: int | None, where: str) -> None:
        """The memory of the sweep's outputs: `times` dense rows per trajectory if they are kept."""
        rows = (times or 0) if "dense" in output else 0
        check_memory(sweep_bytes(n_traj, n2, rows, n_events, cap) + 8 * n_traj * n_events * cap * after_width,
                     memory_limit, "The sweep's outputs",
                     f"{n_traj} trajectories", "save fewer rows (t_eval, save_every), fewer events (event_cap), "
                     "split the grid")

    options = run_options(model, t_span, method=method, dt=dt, rtol=rtol, atol=atol, t_eval=t_eval,
                          save_every=save_every, max_step=max_step, max_steps=max_steps,
                          implicit_solver=implicit_solver, events=events, projection=projection,
                          memory_limit=memory_limit, check_rows=check_rows)
    m, t0, t1, actions = options.method, options.t0, options.t1, options.actions
    if want_events and not actions.any():
        raise OptionError(f"`output` asks for events but none are active ({model.name!r} declares "
                          f"{list(model.event_names)}; events need {method_names(lambda m: m.adaptive)}).")
    if options.adaptive:
        if "dense" in output and options.t_eval is None:
            raise OptionError("`output='dense'` with an adaptive method needs the common times `t_eval`.")
        t_dense = options.t_eval if "dense" in output else None
        save_initial = options.t_eval is not None and options.t_eval[0] == t0
        fixed = (t0, t1, options.rtol, options.atol, options.max_step, options.max_steps,
                 _row_every(options.save_every, output, options.max_steps), options.t_eval_after_start(),
                 save_initial, options.directions, actions)
    else:
        t_dense = options.fixed_step_times() if "dense" in output else None
        fixed = (t0, options.dt, options.n_steps, t1, _row_every(options.save_every, output, options.n_steps))
    rows = 0 if t_dense is None else t_dense.size

    y_base = model.initial_state(_swept_coordinates(model, q0, names, values), qd0)
    p_base = model.parameter_vector(_with_swept(model, params, names, values), baumgarte, inputs, (t0, t1))
    given = model
    model = driven(model, inputs, p_base, m, client)  # function inputs: each trajectory writes their values in its row
    Y0 = np.repeat(y_base[None, :], n_traj, axis=0)
    P = np.repeat(p_base[None, :], n_traj, axis=0)
    state_names = list(model.state_names)
    for column, name in enumerate(names):
        if name in state_names:
            Y0[:, state_names.index(name)] = values[:, column]
        else:
            P[:, list(model.parameters).index(name)] = values[:, column]
    # the energy balance's running state, in slots after each row's parameters (`balance_kernels.balance_row`)
    balance = ("energy" in output and not (batched and m.name == "taylor") and sweep_balances(model)
               and (model.n * 2, model.k, P.shape[1]))
    if balance:
        P = np.hstack([P, np.zeros((n_traj, slots(model.n * 2)))])
    if model.residual_labels:  # (a Kane model's Φ and Ψ have no multipliers: model.k is 0)
        _consistent_initial_states(model, t0, Y0, P, project_initial, names, values)
    where = lambda i: f" in trajectory {i} of the sweep ({_where(names, values[i])})"  # noqa: E731
    resting = check_contacts(model, t0, Y0, P, where)
    set_initial_modes(model, m, t0, Y0, P, resting, where)  # each row its own modes (the drivers copy their row)
    projecting = options.projecting
    dae = m.solves_dae(model)       # then the loop runs z = (q, v, w, λ, μ); the outputs keep (q, v)
    if dae:
        refuse_stabilisation(m.name, model, baumgarte)
        Y0 = dae_states(model, t0, Y0, P, lambda i: f"Trajectory {i} of the sweep ({_where(names, values[i])})")

    if options.adaptive:    # atol (N,) over the loop's state (a DAE's wider: `driver_atol`)
        fixed = (*fixed[:3], driver_atol(options.atol, Y0.shape[1]), *fixed[4:])
    resetting = want_events and bool((actions >= ACTION_RESET).any())  # then event rows keep the state after too
    layout = (Y0.shape[1], rows, len(options.directions), cap, (2 if resetting else 1) * Y0.shape[1])
    out = _allocate(n_traj, layout)
    spec = None        # the model's own module; a batched Taylor sweep has a module of its own
    if batched:
        resetting = [e.name for e, action in zip(model.events, actions.tolist(), strict=True) if action >= ACTION_RESET]
        if resetting:
            raise OptionError(_batched_resets_refusal(model, resetting))
        driver = _batched_driver(model, m)
        if m.adaptive and (rows or want_events):
            raise OptionError("A batched adaptive sweep keeps final states and energy errors only (no dense rows or "
                              "events yet); drop `batched` for those outputs.")
        fixed = fixed[:7] if m.adaptive else fixed      # (the lane loops take their tableaux from `tableaux`)
        if m.name == "taylor":      # the library loop around the lane kernels of this order (a module of their own)
            spec = _taylor_lanes_spec(model, options.rtol, options.atol)
            fixed = (*fixed[:3], uniform(options.atol), *fixed[4:])    # (its lanes' norms: one atol, checked there)
            task = _Task(driver, True, fixed, layout, (), projecting, *TAYLOR_LANES_LOOP)
        else:
            task = _Task(driver, m.adaptive, fixed, layout, (), projecting, driver, ("rhs_lanes",), balance or None)
    else:
        coefficients = options.driver_arguments()
        if m.dae_kernels:           # Radau: the count of differential components (all: an ODE)
            coefficients = (*coefficients, differential_size(model) if dae else n2)
        if m.switches_charts:       # the events' actions: which are chart switches (`Method.switches_charts`)
            coefficients = (*coefficients, actions)
        task = _Task(m.driver, m.adaptive, fixed, layout, coefficients, projecting, m.sweep,
                     m.dae_kernels if dae else m.driver_kernels, balance or None, m.adaptive or m.switches_charts)
    if client is None:
        kernels = model.kernels if spec is None else _worker_kernels(spec)
        if spec is None and not batched:
            _specialised_loop(model, given, m, n_traj)
        done = _run_locally(kernels, task, Y0, P, out, workers, progress)
    else:
        done = _run_on_dask(client, spec or _worker_spec(model, task.kernels + (("power",) if balance else ())), task,
                            Y0, P, out, progress)
    statuses = out["status"]
    counts = out["counts"]
    warn_if_sweep_stiff(m.name, counts[:, 3], stacklevel=3, model=model)     # (column 3: embedded pairs only)
    e0, deviation = out["energy"][:, 0], out["energy"][:, 1]
    relative = np.where(e0 != 0, deviation / np.where(e0 != 0, np.abs(e0), 1.0), deviation)
    shaped = lambda a: a.reshape(*shape, *a.shape[1:])  # noqa: E731
    events_out = _event_outputs(model, out, actions, P, Y0.shape[1], shaped) if want_events else None
    return Sweep(
        names=names, combine=combine if isinstance(grid, dict) else "explicit", axes=axes, shape=shape,
        final=shaped(out["final"][:, :n2]), t_final=shaped(out["t_final"]),
        status=shaped(statuses), nfev=shaped(counts[:, 0]), nsteps=shaped(counts[:, 1]),
        nrejected=shaped(counts[:, 2]), done=shaped(done), coordinates=model.coordinates, method=m.name,
        speeds=tuple(getattr(model, "speeds", None) or ()),
        t_dense=t_dense, dense=shaped(out["dense"][:, :, :n2]) if t_dense is not None else None,
        energy_error=shaped(relative) if "energy" in output else None, events=events_out,
        energy_balance=bool(balance),
    )


def _event_outputs(model, out: dict, actions: np.ndarray, P: np.ndarray, width: int, shaped) -> dict:
    """Each active event's record in a sweep: ``count`` (*shape), and of its first `cap` occurrences ``t``
    (*shape, cap) and ``y`` (*shape, cap, n_y), the state just before; for an event that resets the state
    ``y_after`` (*shape, cap, n_y) too, and for a contact ``impulses`` (*shape, cap, C), the normal impulses of
    the model's contacts (`Model.contacts`) computed from each jump as `simulate` does (`contacts.sweep_impulses`):
    what a single run's `EventRecord` holds, per trajectory.  NaN beyond each trajectory's count.

    `width` is the width of the loop's state (the DAE state of radau: larger than n_y); ``out["event_y"]``
    holds the states after in its columns `width` to 2 `width` when some event resets.
    """
    n_y = model.state_size
    contacts = {name for name, _, _ in contacts_of(model)}
    records = {}
    for i, event in enumerate(model.events):
        if not actions[i]:
            continue
        count, times, before = out["event_count"][:, i], out["event_t"][:, i], out["event_y"][:, i, :, :n_y]
        record = {"count": shaped(count), "t": shaped(times), "y": shaped(before)}
        if actions[i] >= ACTION_RESET:
            after = out["event_y"][:, i, :, width:width + n_y]
            record["y_after"] = shaped(after)
            if event.name in contacts:
                record["impulses"] = shaped(sweep_impulses(model, i, P, count, times, before, after))
        records[event.name] = record
    return records


def _consistent_initial_states(model, t0: float, Y0: np.ndarray, P: np.ndarray, project: bool, names, values) -> None:
    """Check every initial state against the constraints, or project it (in place), as `simulate` does."""
    for k in range(Y0.shape[0]):
        try:
            Y0[k], _ = consistent_initial_state(model, t0, Y0[k], P[k], project)
        except InitialConditionError as err:
            raise InitialConditionError(f"Trajectory {k} of the sweep ({_where(names, values[k])}): {err}") from err


def _where(names, values) -> str:
    """A grid point as ``name=value, ...``."""
    return ", ".join(f"{name}={value:g}" for name, value in zip(names, values, strict=True))


#: Batched (SIMD) sweep loops by method: library loops around the model's lane kernel ``rhs_lanes``
#: (`lagcomp.integrate.drivers.lanes`); taylor: lane kernels in a module of their own per order
#: (`lagcomp.codegen.taylor_lanes`) and the library loop `TAYLOR_LANES_LOOP`.
BATCHED = {"rk4": "lagcomp.integrate.drivers.lanes:sweep_rk4_lanes",
           "dop853": "lagcomp.integrate.drivers.lanes:sweep_dop853_lanes",
           "taylor": "taylor_lanes"}
#: The batched Taylor sweep's library loop and what it takes from the lanes module, by name (then ``energy``).
TAYLOR_LANES_LOOP = ("lagcomp.integrate.drivers.taylor_lanes:sweep_taylor_lanes",
                     ("taylor_lanes", "taylor_lanes_advance", "TAYLOR_ORDER", "TAYLOR_LANES"))


def _batched_resets_refusal(model, resetting: list[str]) -> str:
    """Why a batched sweep refuses the events `resetting` (their names) of `model`, and what to do: drop `batched`;
    or leave them out, unless some are contacts or friction elements, which are part of the motion
    (`lagcomp.integrate.options` refuses a run without them)."""
    inherent = [name for name, _, _ in contacts_of(model)] + [name for name, *_ in frictions_of(model)]
    charts = set(getattr(getattr(model, "system", None), "chart_events", ())) & set(resetting)
    message = (f"Event(s) {resetting} reset the state, which a batched sweep's lanes cannot do yet: drop `batched` "
               "(each trajectory then runs with its own resets)")
    if set(resetting) & set(inherent):
        return message + f"; the contacts and friction elements {sorted(set(resetting) & set(inherent))} are part " \
                         "of the motion and cannot be left out."
    return message + (", or leave the events out (`events=False`" + (
        f": the ball joints' shadow switches {sorted(charts)} then stay off, which is right until a joint's "
        "rotation nears a full turn" if charts else "") + ").")


def _batched_driver(model, m) -> str:
    if getattr(model, "speeds", None) is not None:
        raise OptionError(f"`batched=True` needs the SIMD kernels of Lagrange's equations; {model.name!r} is a Kane "
                          "model (state (q, u)) without them: drop `batched` (its sweep runs one trajectory per "
                          "thread with any method it takes).")
    if m.name not in BATCHED:
        raise OptionError(f"`batched=True` is available for {sorted(BATCHED)}; not yet for {m.name}.")
    if m.name == "taylor":
        return BATCHED["taylor"]       # check_method has checked that the model has a Taylor program
    if not hasattr(model.kernels, "rhs_lanes"):
        beyond = getattr(getattr(model, "system", None), "lanes_refusal", lambda: None)()
        if beyond is not None:      # a kinematic tree whose motion is more than its articulated-body rhs
            raise ModelError(f"`rhs_lanes` (batched sweeps) is not available for the kinematic tree {model.name!r} "
                             f"yet: its motion has {beyond}, which the lanes (the articulated-body rhs per lane) do "
                             "not evaluate (issue 39). Drop `batched`: each trajectory then runs on its own, with "
                             "any method the tree takes.")
        raise OptionError(f"{model.name!r} has no batched kernel (constrained, with inputs, or more coordinates "
                          "than lagcomp.codegen.lower.UNROLL_MAX, whose LDLᵀ solve is a loop).")
    return BATCHED[m.name]


@dataclass(frozen=True)
class _Task:
    """What every chunk of one sweep runs: the driver, its fixed arguments and the output layout."""

    driver: str
    adaptive: bool
    fixed: tuple
    layout: tuple          # (2n, dense rows, events, event cap, width of an event row: 2n, or 4n with states after)
    coefficients: tuple
    projecting: int        # constrained systems: project onto the constraints after every step (0 or 1)
    sweep: str             # the library sweep loop, ``"module:function"`` (`Method.sweep`)
    kernels: tuple         # what it takes first from the generated module, by name (`Method.kernels`), then ``energy``
    balance: tuple | None = None   # (2n, k, offset of the slots in p): the energy balance's kernel for ``energy``
    events: bool = False   # whether the loop takes the event outputs (adaptive methods; those that switch charts)

    def loop(self, kernels):
        """The compiled sweep loop of this task for the model's `kernels` (its generated module): the loop specialised
        for them if it is loaded in this process (`_specialised_loop`) and the sweep reports the plain energy drift
        (a specialised loop binds the model's own ``energy``, not the energy balance's fold), else the library loop
        with them bound."""
        from lagcomp.integrate.specialize import loaded_for

        special = loaded_for(kernels, self.sweep) if self.balance is None else None
        if special is not None:
            return special
        energy = kernels.energy if self.balance is None else balance_row_kernel(kernels, *self.balance)
        bound = [getattr(kernels, name) for name in self.kernels]
        return functools.partial(library_function(self.sweep), *bound, energy)


#: The automatic tier of a sweep: one of at least this many trajectories loads the model's specialised sweep loop
#: (`lagcomp.integrate.specialize`, bitwise the library loop's results) when numba's cache holds it.  Loading takes
#: ~0.1 s; the loop saved 2.4% of the CPU time of a DOP853 double-pendulum trajectory (0.976 times the library
#: loop's, 0.32 ms a trajectory over [0, 10] at tol 1e-10; RK4 at dt 1e-3: 0.99 times), ~8 µs, which repays the load
#: from about this many trajectories on (200 trajectories timed alternately in one process, loaded machine).
AUTO_TRAJECTORIES = 10_000


def _specialised_loop(model, given, m, n_traj: int) -> None:
    """Load the model's specialised sweep loop for method `m` into this process where the automatic tier takes it: a
    sweep of `AUTO_TRAJECTORIES` or more whose loop is cached (never compiled here: `lagcomp precompile MODEL
    --specialize METHOD` compiles it), or at once when it is loaded already; `_Task.loop` then runs it."""
    from lagcomp.integrate import specialize

    if not specialize.covers(m, model, given, None) or specialize.loaded(model, m, sweep=True):
        return
    if n_traj >= AUTO_TRAJECTORIES and specialize.cached(model, m, sweep=True):
        specialize.driver(model, m, sweep=True)


def _allocate(n_traj: int, layout: tuple) -> dict[str, np.ndarray]:
    """Output arrays of `n_traj` trajectories, NaN (or status "not run") until they run."""
    n2, rows, n_events, cap, event_width = layout
    return dict(
        final=np.full((n_traj, n2), np.nan), t_final=np.full(n_traj, np.nan),
        status=np.full(n_traj, NOT_RUN, dtype=np.int64), counts=np.zeros((n_traj, 4), dtype=np.int64),
        dense=np.full((n_traj, rows, n2), np.nan), energy=np.full((n_traj, 2), np.nan),
        event_count=np.zeros((n_traj, n_events), dtype=np.int64), event_t=np.full((n_traj, n_events, cap), np.nan),
        event_y=np.full((n_traj, n_events, cap, event_width), np.nan),
    )


def _run_chunk(kernels, task: _Task, Y0: np.ndarray, P: np.ndarray) -> dict[str, np.ndarray]:
    """Integrate the trajectories Y0, P (a chunk) with the task's compiled sweep loop; their outputs."""
    out = _allocate(Y0.shape[0], task.layout)
    loop = task.loop(kernels)
    common = (out["final"], out["t_final"], out["status"], out["counts"], out["dense"], out["energy"])
    if task.driver in BATCHED.values():
        loop(Y0, P, *task.fixed, *common, *task.coefficients)
    elif task.events:
        loop(Y0, P, task.projecting, *task.fixed, *common, out["event_count"], out["event_t"], out["event_y"],
             *task.coefficients)
    else:
        loop(Y0, P, task.projecting, *task.fixed, *common, *task.coefficients)
    return out


def _store(out: dict, a: int, chunk: dict) -> None:
    for key, values in chunk.items():
        out[key][a:a + values.shape[0]] = values


def _run_locally(kernels, task: _Task, Y0, P, out, workers, progress) -> np.ndarray:
    """Run consecutive chunks, each split across `workers` threads; returns which trajectories ran.

    The compiled sweep loops release the GIL, so the threads run them in
    parallel; a chunk is sized to take about `CHUNK_SECONDS`, which is how
    often the progress bar moves and Ctrl-C is looked at.
    """
    from concurrent.futures import ThreadPoolExecutor

    from lagcomp.stages import numba_stage

    n_traj = Y0.shape[0]
    threads = (os.cpu_count() or 1) if workers is None else count(workers, "workers")
    watched = getattr(kernels, task.kernels[0], None)   # the library loop was compiled (or loaded) on import
    first = numba_stage(watched, f"the {task.driver.rpartition(':')[2]} sweep loop",
                        "preparing the sweep", progress)
    done = np.zeros(n_traj, dtype=bool)
    chunk = (FIRST_BATCHED_CHUNK_PER_THREAD if task.driver in BATCHED.values() else FIRST_CHUNK_PER_THREAD) * threads
    with ThreadPoolExecutor(threads) as pool, deferred_interrupt() as interrupted, \
            LazyProgress(n_traj, progress, unit="traj") as bar:
        a = 0
        while a < n_traj and not interrupted[0]:
            b = min(a + chunk, n_traj)
            if n_traj - b < chunk // 2:
                b = n_traj          # a short tail joins this chunk: one wait for the slowest thread fewer
            bounds = np.linspace(a, b, min(threads, b - a) + 1).astype(int)
            started = time.perf_counter()
            parts = [(lo, pool.submit(_run_chunk, kernels, task, Y0[lo:hi], P[lo:hi]))
                     for lo, hi in zip(bounds[:-1], bounds[1:])]
            with first or contextlib.nullcontext() as stages:  # numba compiles in the first chunk
                if stages is not None:
                    stages.start(stages.names[0])
                for lo, future in parts:
                    _store(out, lo, future.result())
            if first is not None:
                first, bar.started = None, time.perf_counter()
            elapsed = time.perf_counter() - started
            done[a:b] = True
            bar.update(b - a)
            if b - a == chunk:
                chunk = max(threads, int(chunk * min(8.0, max(0.5, CHUNK_SECONDS / max(elapsed, 1e-6)))))
            a = b
    return done


# -- beyond one machine: Dask -------------------------------------------------------

#: Modules loaded by this (worker) process, by source key: each is compiled (or loaded) once per process.
_WORKER_MODULES: dict = {}


def _worker_spec(model, names: tuple[str, ...]) -> tuple[tuple[tuple[str, str], ...], str]:
    """What a worker needs to load the model's kernels `names`: the emitted sources with their system names, in
    the order to load them, and a cache root.

    The eager module's source, then the companion modules' of the on-demand kinds among `names`
    (`lagcomp.codegen.kinds`), which import the eager kernels they call from the eager module by its name (the
    worker loads it first, under that name: `lagcomp.cache.import_name`).
    """
    from lagcomp.codegen.kinds import KIND_OF

    kinds = sorted({KIND_OF[name].name for name in names if name in KIND_OF})
    entries = [(kind, model.on_demand_entry(kind)) for kind in kinds] if hasattr(model, "on_demand_entry") else []
    sources = [(model.source_path.read_text(encoding="utf-8"), model.name)]
    sources += [(entry.path.read_text(encoding="utf-8"), f"{model.name}_on_demand_{kind}")
                for kind, entry in entries if entry is not None]   # (a Kane model: one module, every kernel)
    return tuple(sources), str(model.source_path.parent.parent)


def _taylor_lanes_spec(model, rtol: float, atol) -> tuple[tuple[tuple[str, str], ...], str]:
    """The spec of the module with the batched Taylor kernel of the order these tolerances need.

    Written from the model's module and its Taylor program (no sympy), then
    cached like any module: numba compiles it once, at the first sweep of this
    model at this order (`lagcomp.codegen.taylor_lanes`).
    """
    from lagcomp.codegen import taylor_lanes

    if uniform(atol) is None:
        raise OptionError(f"A batched Taylor sweep takes one `atol` for every component (its lane kernels' norms are "
                          f"unweighted); {model.name!r} was given one per component: drop `batched` (each trajectory "
                          "then runs the Taylor driver, which weighs its norms by them) or pass one number.")
    atol = uniform(atol)
    program, order = model._taylor_program, taylor_lanes.taylor_order(rtol, atol)
    if program is None:     # (check_method refuses systems without a Taylor kernel before this)
        raise OptionError(f"{model.name!r} has no Taylor program for a batched sweep; drop `batched`.")
    terms = taylor_lanes.unrolled_terms(program, order)
    if terms > taylor_lanes.TERMS_MAX:
        raise OptionError(
            f"A batched Taylor sweep of {model.name!r} at order {order} (rtol={rtol:g}, atol={atol:g}) would unroll "
            f"about {terms:,} terms, above lagcomp.codegen.taylor_lanes.TERMS_MAX = {taylor_lanes.TERMS_MAX:,} "
            "(numba's compile time grows with them): loosen the tolerances, or drop `batched`.")
    source = taylor_lanes.taylor_lanes_module(model.source_path.read_text(encoding="utf-8"), program, order)
    return ((source, model.name),), str(model.source_path.parent.parent)


def _worker_kernels(spec: tuple[tuple[tuple[str, str], ...], str]):
    """The kernels of `spec` in this process (its modules, loaded in order), from the worker's cache, written
    there if missing: the module, or for several (an eager module and its companions) one namespace of them.

    The modules are rebuilt from their source text, never unpickled, so numba
    compiles them (or loads its own on-disk cache) once per worker process.
    The client's cache root is used when the worker can write to it (same
    machine or a shared file system), else the worker's default root.
    """
    from lagcomp.cache import Cache, load_module, source_key

    sources, root = spec
    modules = []
    for source, system_name in sources:
        key = source_key(source)
        if key not in _WORKER_MODULES:
            cache = Cache(root) if os.access(root, os.W_OK) else Cache(None)
            entry = cache.store(f"worker-{key}", source, system_name, {})
            _WORKER_MODULES[key] = load_module(entry)
        modules.append(_WORKER_MODULES[key])
    return modules[0] if len(modules) == 1 else _Modules(tuple(modules))


class _Modules:
    """Several modules' names as one namespace: a name is read from the first module that defines it."""

    def __init__(self, modules: tuple):
        self.modules = modules

    def __getattr__(self, name: str):
        if name == "modules":   # (before __init__ set it)
            raise AttributeError(name)
        for module in self.modules:
            if hasattr(module, name):
                return getattr(module, name)
        raise AttributeError(name)


def _remote_chunk(spec, task: _Task, Y0: np.ndarray, P: np.ndarray) -> dict[str, np.ndarray]:
    return _run_chunk(_worker_kernels(spec), task, Y0, P)


def _run_on_dask(client, spec, task: _Task, Y0, P, out, progress) -> np.ndarray:
    """One Dask task per chunk (about four per worker thread); returns which trajectories ran.

    Ctrl-C cancels the tasks not yet finished and keeps the others.
    """
    from distributed import as_completed

    n_traj = Y0.shape[0]
    slots = max(1, sum(client.nthreads().values()))
    bounds = np.linspace(0, n_traj, min(n_traj, 4 * slots) + 1).astype(int)
    # hash=False: a fresh key per sweep.  With content hashing, a second sweep of the same model
    # reuses the first one's key, and the release of the first sweep's future can reach the
    # scheduler after the new scatter and delete the data under the new tasks ("lost
    # dependencies": the LocalCluster test failed so now and then).
    [spec_future] = client.scatter([spec], broadcast=True, hash=False)
    futures = {client.submit(_remote_chunk, spec_future, task, Y0[a:b], P[a:b], pure=False): (a, b)
               for a, b in zip(bounds[:-1], bounds[1:])}
    done = np.zeros(n_traj, dtype=bool)
    with deferred_interrupt() as interrupted, LazyProgress(n_traj, progress, unit="traj") as bar:
        for future in as_completed(futures):
            a, b = futures[future]
            _store(out, a, future.result())
            done[a:b] = True
            bar.update(b - a)
            if interrupted[0]:
                client.cancel([f for f in futures if not f.done()])
                break
    return done
