"""Checks of the options `simulate` and `sweep` share: each returns the checked value or raises
`OptionError` naming the option, what it got and what it needs."""

from __future__ import annotations

import difflib
import inspect
import math

import numpy as np

from lagcomp.errors import OptionError
from lagcomp.integrate.methods import METHODS, RTOL_MIN


def method_names(test) -> str:
    """The registry's methods that pass `test`, as "a, b or c" (messages name what would work)."""
    names = [name for name, m in METHODS.items() if test(m)]
    return ", ".join(names[:-1]) + " or " + names[-1] if len(names) > 1 else names[0]


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


def positive(value, name: str) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError) as err:
        raise OptionError(f"`{name}` must be a number, got {value!r}.") from err
    if not (value > 0 and math.isfinite(value)):
        raise OptionError(f"`{name}` must be positive and finite, got {value}.")
    return value


def count(value, name: str) -> int:
    if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or value < 1:
        raise OptionError(f"`{name}` must be a positive integer, got {value!r}.")
    return int(value)


def t_eval_points(t_eval, t0: float, t1: float) -> np.ndarray | None:
    if t_eval is None:
        return None
    t_eval = np.asarray(t_eval, dtype=float).ravel()
    if t_eval.size == 0 or not np.all(np.isfinite(t_eval)):
        raise OptionError("`t_eval` must be a non-empty array of finite times.")
    if np.any(np.diff(t_eval) <= 0) or t_eval[0] < t0 or t_eval[-1] > t1:
        raise OptionError(f"`t_eval` must be strictly increasing and within t_span = ({t0}, {t1}).")
    return t_eval


def tolerances(rtol, atol, m=None) -> tuple[float, float]:
    """`rtol` and `atol` checked: positive, finite, and rtol in [100 eps, 1) (float64 cannot do better).

    With a method `m`, None stands for its defaults (`Method.default_rtol`, `default_atol`) and
    rtol may go down to its `rtol_min` (machine epsilon for the Taylor method, which has no error
    estimate to keep above rounding).
    """
    if m is not None:
        rtol = m.default_rtol if rtol is None else rtol
        atol = (rtol if m.default_atol is None else m.default_atol) if atol is None else atol
    rtol, atol = positive(rtol, "rtol"), positive(atol, "atol")
    rtol_min = RTOL_MIN if m is None else m.rtol_min
    if not rtol_min <= rtol < 1:
        reason = "100 machine epsilons; float64 cannot do better" if rtol_min >= RTOL_MIN else "machine epsilon"
        raise OptionError(f"`rtol` = {rtol:g} is out of range: it must be at least {rtol_min:.2g} ({reason}) "
                          "and below 1.")
    return rtol, atol


def event_arguments(model, m, events) -> tuple[np.ndarray, np.ndarray]:
    """``directions`` and ``actions`` (0 off, 1 record, 2 record and stop) of the model's events."""
    declared = model.events
    if events is None or events is True:
        chosen = [e.name for e in declared] if (m.adaptive or events is True) else []
    elif events is False:
        chosen = []
    else:
        chosen = [events] if isinstance(events, str) else list(events)
        unknown = [name for name in chosen if name not in model.event_names]
        if unknown:
            raise OptionError(f"Unknown event(s) {unknown}; {model.name!r} declares {list(model.event_names)}.")
    if chosen and not m.adaptive:
        raise OptionError(f"Events are located on dense output, which {m.name} lacks; use "
                          f"{method_names(lambda m: m.adaptive)}.")
    directions = np.array([e.direction for e in declared], dtype=np.int64)
    actions = np.array([(2 if e.terminal else 1) if e.name in chosen else 0 for e in declared], dtype=np.int64)
    return directions, actions


def check_method(model, m) -> None:
    """Refuse a method that does not apply to `model` (separable-only or unconstrained-only methods,
    and the Taylor method where the module has no Taylor kernel: ``TAYLOR_REFUSED`` says why)."""
    kane = getattr(model, "speeds", None)
    if kane is not None and not m.any_state:
        raise OptionError(f"`{m.name}` needs the state (q, q̇) of Lagrange's equations; {model.name!r} is a Kane "
                          f"model with state (q, u). Use {method_names(lambda m: m.any_state)}.")
    refused = getattr(model.kernels, "TAYLOR_REFUSED", None) if m.name == "taylor" and not model.k else None
    if refused is not None:
        raise OptionError(f"`taylor` cannot integrate {model.name!r}: its equations hold {refused}. "
                          "Use dop853 (adaptive, dense output, events) instead.")
    if m.separable_only and not model.separable:
        raise OptionError(
            f"`{m.name}` needs a separable system (no constraints, a constant mass matrix and forces that do not "
            f"depend on velocities); {model.name!r} is not one. Use gauss2 (symplectic for any Lagrangian), "
            f"{method_names(lambda m: m.any_state)}."
        )
    if m.unconstrained_only and model.k:
        raise OptionError(f"`{m.name}` does not handle constraints yet; {model.name!r} has {list(model.constraints)}. "
                          f"Use {method_names(lambda m: m.any_state)}.")


def known_options(function, options: dict, what: str) -> None:
    """Refuse keyword `options` that `function` (simulate, sweep) does not take, naming the nearest."""
    accepted = [name for name, parameter in inspect.signature(function).parameters.items()
                if parameter.kind is inspect.Parameter.KEYWORD_ONLY]
    unknown = [name for name in options if name not in accepted]
    if unknown:
        near = difflib.get_close_matches(unknown[0], accepted, n=1)
        hint = f" (did you mean `{near[0]}`?)" if near else ""
        raise OptionError(f"Unknown option(s) {unknown} for {what}{hint}; its options are {sorted(accepted)}.")
