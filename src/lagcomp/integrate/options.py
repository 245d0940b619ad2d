"""The options `simulate` and `sweep` share, checked in one place: `run_options` turns the user's
arguments into a `RunOptions`, which both translate into their driver's or sweep loop's arguments.

Each check returns the checked value or raises `OptionError` naming the option, what it got and what
it needs; a mistake gets the same message from `simulate` and from `sweep`.
"""

from __future__ import annotations

import difflib
import functools
import inspect
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from lagcomp.errors import OptionError
from lagcomp.integrate.contacts import contacts_of, frictions_of, integrates_modes
from lagcomp.integrate.dae import DAE_RTOL_MIN
from lagcomp.integrate.drivers.events import (
    ACTION_IGNORE,
    ACTION_IMPACT,
    ACTION_RECORD,
    ACTION_RESET,
    ACTION_TERMINAL,
)
from lagcomp.integrate.memory import checked_limit
from lagcomp.integrate.methods import (
    DEFAULT_IMPLICIT_SOLVER,
    METHODS,
    RTOL_MIN,
    Method,
    get_method,
    implicit_solver_for,
    method_names,
)
from lagcomp.integrate.tolerances import absolute_tolerance, positive


def time_span(t_span) -> tuple[float, float]:
    try:
        t0, t1 = (float(v) for v in t_span)
    except (TypeError, ValueError) as err:
        raise OptionError(f"`t_span` must be a pair (t0, t1) of numbers, got {t_span!r}.") from err
    if not (math.isfinite(t0) and math.isfinite(t1)):
        raise OptionError(f"`t_span` must be finite, got ({t0}, {t1}).")
    if not t1 > t0:
        raise OptionError(f"`t_span` = ({t0}, {t1}) is empty: the end time must be after the start time.")
    return t0, t1


def count(value, name: str) -> int:
    if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or value < 1:
        raise OptionError(f"`{name}` must be a positive integer, got {value!r}.")
    return int(value)


def t_eval_points(t_eval, t0: float, t1: float) -> np.ndarray | None:
    if t_eval is None:
        return None
    try:
        t_eval = np.asarray(t_eval, dtype=float).ravel()
    except (TypeError, ValueError):
        t_eval = np.empty(0)   # not numbers: the message below
    if t_eval.size == 0 or not np.all(np.isfinite(t_eval)):
        raise OptionError("`t_eval` must be a non-empty array of finite times.")
    if np.any(np.diff(t_eval) <= 0) or t_eval[0] < t0 or t_eval[-1] > t1:
        raise OptionError(f"`t_eval` must be strictly increasing and within t_span = ({t0}, {t1}).")
    return t_eval


def tolerances(rtol, atol, m=None, state_names=None) -> tuple[float, float | np.ndarray]:
    """`rtol` and `atol` checked: positive, finite, and rtol in [100 eps, 1) (float64 cannot do better).

    With a method `m`, None stands for its defaults (`Method.default_rtol`, `default_atol`) and
    rtol may go down to its `rtol_min` (machine epsilon for the Taylor method, which has no error
    estimate to keep above rounding).  With the model's `state_names`, `atol` may also be one per state
    component, or a mapping by coordinate (`lagcomp.integrate.tolerances.absolute_tolerance`: then an array).
    """
    if m is not None:
        rtol = m.default_rtol if rtol is None else rtol
        atol = (rtol if m.default_atol is None else m.default_atol) if atol is None else atol
    rtol = positive(rtol, "rtol")
    atol = positive(atol, "atol") if state_names is None else absolute_tolerance(atol, state_names)
    rtol_min = RTOL_MIN if m is None else m.rtol_min
    if not rtol_min <= rtol < 1:
        reason = "100 machine epsilons; float64 cannot do better" if rtol_min >= RTOL_MIN else "machine epsilon"
        raise OptionError(f"`rtol` = {rtol:g} is out of range: it must be at least {rtol_min:.2g} ({reason}) "
                          "and below 1.")
    return rtol, atol


def event_arguments(model, m, events) -> tuple[np.ndarray, np.ndarray]:
    """``directions`` and ``actions`` (0 off, 1 record, 2 record and stop, 3 record and reset the state, 4 the
    same for a contact's impact: `lagcomp.integrate.drivers.events`) of the model's events.

    An event with a reset changes the motion: a method that cannot apply it (`Method.kernels` without
    ``event_reset``) is refused unless the run leaves the event out by name (``events=False`` or a list).
    A contact's event cannot be left out (`lagcomp.model.contacts`): its impacts are part of the motion.
    A method that switches charts (`Method.switches_charts`: the Gauss methods) applies a tree's chart switches (its
    ball joints' shadow switches, `lagcomp.multibody.Tree.chart_events`) in a run that does not choose its events
    (``events`` None), and resets no other event.
    """
    declared = model.events
    if not declared and (events is None or events is True or events is False):  # (nor contacts: they are events)
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    if events is None or events is True:
        chosen = [e.name for e in declared] if (m.adaptive or events is True) else []
    elif events is False:
        chosen = []
    else:
        try:
            chosen = [events] if isinstance(events, str) else list(events)
        except TypeError:
            chosen = [events]
        unknown = [name for name in chosen if not isinstance(name, str) or name not in model.event_names]
        if unknown:
            raise OptionError(f"Unknown event(s) {unknown}; {model.name!r} declares {list(model.event_names)}.")
    # contacts' impacts and friction's stick–slip are part of the motion: never left out, only capable methods
    inherent = [name for name, *_ in contacts_of(model) + frictions_of(model)]
    if inherent and "event_reset" not in m.kernels:
        capable = method_names(lambda m: "event_reset" in m.kernels
                               and (integrates_modes(model, m) or not frictions_of(model))
                               and not (m.unconstrained_only and model.k))
        raise OptionError(f"The contacts and friction elements {inherent} of {model.name!r} switch and jump within "
                          f"its motion, which `{m.name}` cannot do; use {capable}.")
    left_out = [name for name in inherent if name not in chosen]
    if left_out:
        raise OptionError(f"The contacts and friction elements {left_out} of {model.name!r} are part of its motion, "
                          "which a run cannot leave out: keep them among `events`.")
    if chosen and not m.adaptive:
        raise OptionError(f"Events are located on dense output, which {m.name} lacks; use "
                          f"{method_names(lambda m: m.adaptive)}.")
    tree = getattr(model, "system", None)
    charts = getattr(tree, "chart_events", ()) if m.switches_charts and events is None else ()
    resetting = [e.name for e in declared if e.resets and (e.name in chosen or events is None) and e.name not in charts]
    if resetting and "event_reset" not in m.kernels:
        raise OptionError(f"Event(s) {resetting} of {model.name!r} reset the state, which `{m.name}` cannot do; use "
                          f"{method_names(lambda m: 'event_reset' in m.kernels)}, or leave them out "
                          "(`events=False`, or the names of the others) to integrate without the resets.")
    directions = np.array([e.direction for e in declared], dtype=np.int64)
    impacts = {name for name, _, _ in contacts_of(model)}
    actions = np.array([(ACTION_IMPACT if e.name in impacts else ACTION_RESET if e.resets else ACTION_TERMINAL
                         if e.terminal else ACTION_RECORD) if e.name in chosen else ACTION_RESET if e.name in charts
                        else ACTION_IGNORE for e in declared], dtype=np.int64)
    return directions, actions


def check_method(model, m) -> None:
    """Refuse a method that does not apply to `model` (separable-only, holonomic-separable-only (RATTLE) or
    unconstrained-only methods, and the Taylor method where the module has no Taylor kernel: ``TAYLOR_REFUSED``
    says why)."""
    kane = getattr(model, "speeds", None)
    if kane is not None and not m.any_state:
        raise OptionError(f"`{m.name}` needs the state (q, q̇) of Lagrange's equations; {model.name!r} is a Kane "
                          f"model with state (q, u). Use {method_names(lambda m: m.any_state)}.")
    refused = getattr(model.kernels, "TAYLOR_REFUSED", None) if m.name == "taylor" and not model.k else None
    if refused is not None:
        raise OptionError(f"`taylor` cannot integrate {model.name!r}: its equations hold {refused}. "
                          "Use dop853 (adaptive, dense output, events) instead.")
    if m.separable_only and not model.separable:
        symplectic = ("rattle (symplectic, holds its holonomic constraints)" if model.holonomic_separable else
                      "gauss2 (symplectic for any Lagrangian)")
        raise OptionError(
            f"`{m.name}` needs a separable system (no constraints, a constant mass matrix and forces that do not "
            f"depend on velocities); {model.name!r} is not one. Use {symplectic}, "
            f"{method_names(lambda m: m.any_state)}."
        )
    if m.holonomic_separable_only and not model.holonomic_separable:
        raise OptionError(_not_holonomic_separable(model, m))
    if m.unconstrained_only and model.k:
        raise OptionError(f"`{m.name}` does not handle constraints yet; {model.name!r} has {list(model.constraints)}. "
                          f"Use {method_names(lambda m: m.any_state)}.")


def _not_holonomic_separable(model, m) -> str:
    """Why `m` (RATTLE) refuses `model`, and what to use instead."""
    if not model.k:
        better = "verlet (RATTLE without constraints is Störmer-Verlet)" if model.separable else \
            f"gauss2 (symplectic for any Lagrangian) or {method_names(lambda m: m.any_state)}"
        return f"`{m.name}` integrates constrained systems; {model.name!r} has no constraints: use {better}."
    nonholonomic = [name for name, holonomic in zip(model.constraints, model.holonomic, strict=True)
                    if not holonomic]
    why = (f"its constraint(s) {nonholonomic} are nonholonomic" if nonholonomic else
           "its mass matrix depends on the coordinates or time, its forces on the velocities, or a constraint "
           "on time")
    return (f"`{m.name}` needs a system that is separable apart from its constraints (a constant mass matrix, "
            f"forces that depend on the coordinates and time only) and whose constraints are all holonomic and "
            f"scleronomic (Φ(q) = 0, free of time); {model.name!r} is not one: {why}. Use "
            f"{method_names(lambda m: m.any_state)} (projection=True or baumgarte=(alpha, beta) hold the "
            "constraints).")


def known_options(function, options: dict, what: str) -> None:
    """Refuse keyword `options` that `function` (simulate, sweep) does not take, naming the nearest."""
    accepted = _keyword_only(function)
    unknown = [name for name in options if name not in accepted]
    if unknown:
        near = difflib.get_close_matches(unknown[0], accepted, n=1)
        hint = f" (did you mean `{near[0]}`?)" if near else ""
        raise OptionError(f"Unknown option(s) {unknown} for {what}{hint}; its options are {sorted(accepted)}.")


@functools.cache
def _keyword_only(function) -> tuple[str, ...]:
    """The keyword-only parameters of `function`, read once: `inspect.signature` costs ~50 µs per call of
    `Model.simulate`, a tenth of a short run."""
    return tuple(name for name, parameter in inspect.signature(function).parameters.items()
                 if parameter.kind is inspect.Parameter.KEYWORD_ONLY)


@dataclass(frozen=True, eq=False)
class RunOptions:
    """The checked, normalised options of one run or sweep (built by `run_options` only).

    Times in the model's time unit.  Adaptive methods have `rtol`, `atol`, `first_step` (None: the
    driver picks one), `max_step` and `t_eval`; fixed-step ones `dt` and `n_steps` (`rtol`, `atol`,
    `t_eval`, `dt` and `n_steps` are None where they do not apply).
    """

    method: Method
    t0: float
    t1: float
    save_every: int
    max_steps: int
    #: (E,) int64 per declared event: its direction, and 0 off, 1 record, 2 record and stop, 3 record and reset.
    directions: np.ndarray
    actions: np.ndarray
    #: Constrained systems: project onto the constraints after every step (0 or 1).
    projecting: int
    #: Bytes the run's or sweep's outputs may take.
    memory_limit: float
    implicit_solver: str = DEFAULT_IMPLICIT_SOLVER
    rtol: float | None = None
    #: A number, or (2n,) per state component (`lagcomp.integrate.tolerances`); the drivers take `driver_atol`'s.
    atol: float | np.ndarray | None = None
    first_step: float | None = None
    max_step: float = math.inf
    #: (m,) strictly increasing times in [t0, t1], or None.
    t_eval: np.ndarray | None = None
    dt: float | None = None
    n_steps: int | None = None

    @property
    def adaptive(self) -> bool:
        return self.method.adaptive

    def t_eval_after_start(self) -> np.ndarray:
        """The `t_eval` times after t0, which the adaptive drivers fill by dense output (empty: none)."""
        return self.t_eval[self.t_eval > self.t0] if self.t_eval is not None else np.empty(0)

    def fixed_step_times(self) -> np.ndarray:
        """Times of the rows a fixed-step run keeps: t0, every `save_every`-th step, and t1."""
        steps = np.minimum(np.arange(0, self.n_steps + self.save_every, self.save_every), self.n_steps)
        times = np.unique(np.minimum(self.t0 + steps * self.dt, self.t1))
        times[-1] = self.t1
        return times

    def driver_arguments(self) -> tuple:
        """The coefficient arrays (and settings) the method's driver or sweep loop takes last: fresh copies of
        the arrays `Method.driver_arguments` makes, made once per method and solver (`_DRIVER_ARGUMENTS`;
        making them costs ~6 µs for DOP853, copying them ~2 µs)."""
        key = (self.method.name, self.implicit_solver)
        if key not in _DRIVER_ARGUMENTS:
            _DRIVER_ARGUMENTS[key] = self.method.driver_arguments(self.implicit_solver)
        return tuple(a.copy() if isinstance(a, np.ndarray) else a for a in _DRIVER_ARGUMENTS[key])


#: {(method name, implicit solver): `Method.driver_arguments`}, copied for each run (`RunOptions.driver_arguments`).
_DRIVER_ARGUMENTS: dict[tuple[str, str], tuple] = {}


def fixed_step_count(t0: float, t1: float, dt: float) -> int:
    """Steps of size `dt` from t0 to t1; the last one ends at t1 (a rounding of (t1 - t0) / dt just above an
    integer adds no step)."""
    return max(1, math.ceil((t1 - t0) / dt * (1 - 1e-12)))


def run_options(model, t_span, *, method="dop853", dt=None, rtol=None, atol=None, t_eval=None, save_every=1,
                first_step=None, max_step=math.inf, max_steps=100_000_000, implicit_solver=None, events=None,
                projection=None, memory_limit,
                check_rows: Callable[[int | None, str], None] | None = None) -> RunOptions:
    """The options of a run or a sweep of `model` checked, in one order, each with one message.

    `check_rows(times, where)`, if given, is called once the number of output times is known and
    before `t_eval` is copied: `times` is the size of `t_eval`, or for a fixed-step method the number
    of saved rows (`RunOptions.fixed_step_times`), or None (an adaptive run without `t_eval`: its rows
    are not known in advance); `where` says what they are.  It raises `OptionError` when the caller's
    outputs would not fit in `memory_limit` (simulate and sweep count their bytes differently).
    """
    memory_limit = checked_limit(memory_limit)  # first: a sweep has used it to check its grid already
    t0, t1 = time_span(t_span)
    m = METHODS[method] if type(method) is str and method in METHODS else get_method(method)  # (fast path: a name)
    check_method(model, m)
    if m.solves_dae(model) and projection:
        raise OptionError(f"`{m.name}` solves {model.name!r} as a DAE: its constraints hold at every step without "
                          "projection. Leave `projection` unset.")
    if m.holonomic_separable_only and projection:
        raise OptionError(f"`{m.name}` holds the constraints to round-off at every step without projection; projecting "
                          "would break its symplectic structure. Leave `projection` unset.")
    if projection and model.residual_labels and "project" not in m.kernels:     # radau on a Kane model
        raise OptionError(f"`{m.name}` does not project onto the constraints; {model.name!r} keeps them as well as "
                          "its integration is accurate (`Solution.constraint_residual` reports the drift). Leave "
                          f"`projection` unset, or project with {method_names(lambda m: 'project' in m.kernels)}.")
    common = dict(
        method=m, t0=t0, t1=t1, memory_limit=memory_limit,
        save_every=count(save_every, "save_every"), max_steps=count(max_steps, "max_steps"),
        implicit_solver=DEFAULT_IMPLICIT_SOLVER if implicit_solver is None else implicit_solver_for(m, implicit_solver),
        projecting=int(bool(model.residual_labels) and not m.holonomic_separable_only
                       and (not m.adaptive if projection is None else bool(projection))),
    )
    common["directions"], common["actions"] = event_arguments(model, m, events)
    check_rows = check_rows or (lambda times, where: None)
    if m.adaptive:
        if dt is not None:
            raise OptionError(f"`dt` sets the step of fixed-step methods; {m.name} chooses its own "
                              "(bound it with `max_step`).")
        rtol, atol = tolerances(rtol, atol, m, model.state_names)
        if m.solves_dae(model) and rtol < DAE_RTOL_MIN:
            raise OptionError(f"`{m.name}` solves the constraints of {model.name!r} with the motion (a DAE) to rtol "
                              f"≥ {DAE_RTOL_MIN:g}; tighter, the constraints' rounding noise stalls its Newton "
                              f"iteration (rtol = {rtol:g} asked; at rtol = {DAE_RTOL_MIN:g} the constraints hold to "
                              "~1e-12). Use that, or dop853 with projection=True for tighter tolerances.")
        first_step = None if first_step is None else positive(first_step, "first_step")
        max_step = math.inf if _is_inf(max_step) else positive(max_step, "max_step")
        times = None if t_eval is None else int(np.size(t_eval))
        check_rows(times, f"{times:,} `t_eval` times" if times is not None else "rows not known in advance")
        return RunOptions(**common, rtol=rtol, atol=atol, first_step=first_step, max_step=max_step,
                          t_eval=t_eval_points(t_eval, t0, t1))
    if dt is None:
        raise OptionError(f"`{m.name}` is a fixed-step method: give the step `dt`.")
    if t_eval is not None:
        raise OptionError(f"`t_eval` needs dense output, which {m.name} lacks; use `save_every` or "
                          f"{method_names(lambda m: m.adaptive)}.")
    dt = positive(dt, "dt")
    n_steps = fixed_step_count(t0, t1, dt)
    if n_steps > common["max_steps"]:
        raise OptionError(f"{n_steps} steps of dt = {dt} exceed `max_steps` = {common['max_steps']}.")
    save_every = common["save_every"]
    rows = -(-n_steps // save_every) + 1
    check_rows(rows, f"{rows:,} rows ({n_steps:,} steps of dt = {dt:g}, every {save_every}-th saved)")
    return RunOptions(**common, dt=dt, n_steps=n_steps)


def _is_inf(value) -> bool:
    """Whether `value` is +inf (`max_step`'s default: no bound), without converting what is not a number."""
    return isinstance(value, (int, float, np.floating)) and value == math.inf
