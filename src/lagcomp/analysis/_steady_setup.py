"""The point of a steady-motion linearization: the form, parameters, checked state, and the choice of
independent coordinates and speeds (for `lagcomp.analysis.steady`)."""

from __future__ import annotations

import math
import numbers
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
from scipy import linalg

from lagcomp.analysis._common import relative_residual
from lagcomp.analysis._form_jacobians import evaluator
from lagcomp.errors import InitialConditionError, LinearizationError, ModelError, OptionError, ParameterError
from lagcomp.mechanics.first_order import FirstOrderForm, from_eom, inputs_as_parameters
from lagcomp.names import by_name

#: Largest constraint residual accepted at the point, relative to the size of the terms each constraint sums there
#: (`lagcomp.analysis._form_jacobians.magnitude`: in Φ_k's own units, so the same in any units).
CONSISTENT = 1e-8
#: Forms derived from Systems, by fingerprint (the derivation is the slow part).
_FORMS: OrderedDict = OrderedDict()


@dataclass(frozen=True)
class FormPoint:
    """A checked point (q, u, p, t) of a form, with everything evaluated there."""

    form: FirstOrderForm
    q: np.ndarray
    u: np.ndarray
    p: np.ndarray
    t: float
    params: dict
    values: dict
    acceleration: np.ndarray
    multipliers: np.ndarray
    kkt: np.ndarray

    @property
    def full_states(self) -> tuple:
        return tuple(self.form.coordinate_names) + tuple(self.form.speed_names)


@dataclass(frozen=True)
class Choice:
    """Which coordinates and speeds are independent (indices into q and u) and which are dropped."""

    q_independent: list
    q_dependent: list
    u_independent: list
    u_dependent: list
    states: tuple
    dependent: tuple
    dropped: tuple
    rows: list


def first_order_form(system) -> tuple[FirstOrderForm, dict]:
    """(form, default parameter values) of a Model, a System or a FirstOrderForm.

    A model that carries its form as ``first_order_form`` (one compiled from a
    KanesMethod) gives that form; other models and Systems are derived
    (Lagrange's equations, u = q̇), once per System.
    """
    from lagcomp.mechanics.lagrange import derive
    from lagcomp.model.system import System

    if isinstance(system, FirstOrderForm):
        return system, {}
    carried = getattr(system, "first_order_form", None)  # a model compiled from Kane's equations keeps its form
    if isinstance(carried, FirstOrderForm):
        return carried, dict(getattr(system, "defaults", None) or {})
    source = getattr(system, "system", system)
    if source is None:
        raise ModelError(f"linearize_steady reads the equations of {system.name!r}, which a model from "
                         "lagcomp.load() does not carry: pass its System (or lagcomp.compile(system)).")
    if getattr(source, "on_demand_refusal", None) is not None:   # a lagcomp.Tree: no symbolic equations to reduce
        raise ModelError(source.on_demand_refusal("linearize_steady (and stability_sweep), which reduce a System's "
                                                  "symbolic equations,"))
    if not isinstance(source, System):
        raise ModelError(f"linearize_steady takes a Model, a System or a FirstOrderForm, got {type(system).__name__}.")
    key = source.fingerprint()
    if key not in _FORMS:
        _FORMS[key] = inputs_as_parameters(from_eom(derive(source)), source.inputs)
        while len(_FORMS) > 16:
            _FORMS.popitem(last=False)
    return _FORMS[key], dict(source.defaults)


def parameter_vector(form: FirstOrderForm, params, defaults: dict, inputs=None) -> tuple[np.ndarray, dict]:
    """The form's parameter values in its order, from `params` by name over `defaults`, checked; then the values
    its inputs are held at (`inputs`, by name: numbers)."""
    held = list(form.input_names)
    names = [str(s) for s in form.parameters][:len(form.parameters) - len(held)]
    values = {**defaults, **by_name(params or {}, "params", names)}
    if held:
        values.update(_input_values(held, inputs))
        names += held
    elif inputs:
        raise OptionError(f"`inputs` given, but the system has no inputs (lagcomp.Input without a law): {inputs!r}.")
    unknown = sorted(set(values) - set(names))
    if unknown:
        raise ParameterError(f"Unknown parameter(s) {unknown}; the parameters are {names}.")
    missing = [n for n in names if n not in values]
    if missing:
        raise ParameterError(f"Missing value(s) for parameter(s) {missing}; pass them in `params`.")
    p = np.array([float(values[n]) for n in names])
    bad = [n for n, x in zip(names, p) if not math.isfinite(x)]
    if bad:
        raise ParameterError(f"Parameter(s) {bad} are not finite.")
    return p, dict(zip(names, p.tolist()))


def _input_values(held: list, inputs) -> dict:
    """{input: value} of the inputs `held` constant, from `inputs`, or an OptionError naming what is missing."""
    from lagcomp.integrate.inputs import inputs_by_name

    given = inputs_by_name(inputs or {})
    unknown, missing = sorted(set(given) - set(held)), [name for name in held if name not in given]
    if unknown or missing:
        raise OptionError(f"The linearization holds the input(s) {held} at constant values: pass `inputs="
                          f"{{{held[0]!r}: value, ...}}` with a number for each (unknown {unknown}, missing "
                          f"{missing}).")
    bad = [name for name in held if isinstance(given[name], bool) or not isinstance(given[name], numbers.Real)]
    if bad:
        raise OptionError(f"Input(s) {bad}: a linearization holds each input at a constant, a number; got "
                          f"{[given[name] for name in bad]!r}.")
    return {name: float(given[name]) for name in held}


def state_vector(values, names, what: str) -> np.ndarray:
    """`values` (a sequence or a dict by name) as a finite float vector in the order of `names`."""
    if isinstance(values, dict):
        unknown = sorted(set(values) - set(names))
        missing = [n for n in names if n not in values]
        if unknown or missing:
            raise InitialConditionError(f"`{what}` must give exactly {list(names)}; "
                                        f"unknown {unknown}, missing {missing}.")
        values = [values[n] for n in names]
    x = np.atleast_1d(np.asarray(values, dtype=float)).ravel()
    if x.shape != (len(names),):
        raise InitialConditionError(f"`{what}` has {x.size} value(s); expected {len(names)}: {list(names)}.")
    if not np.all(np.isfinite(x)):
        raise InitialConditionError(f"`{what}` = {x.tolist()} is not finite.")
    return x


def _evaluated(system, q, u, params, t: float, inputs=None):
    """(form, q, u, p, named parameters, values at the point), the inputs checked."""
    form, defaults = first_order_form(system)
    p, named = parameter_vector(form, params, defaults, inputs)
    q = state_vector(q, form.coordinate_names, "q")
    u = np.zeros(form.n_u) if u is None else state_vector(u, form.speed_names, "u")
    return form, q, u, p, named, evaluator(form).point(q, u, p, float(t))


def form_point(system, q, u, params, t: float, inputs=None) -> FormPoint:
    """Evaluate the form at (q, u): constraints checked, accelerations and multipliers from the KKT system."""
    form, q, u, p, named, values = _evaluated(system, q, u, params, t, inputs)
    _check_consistent(form, values)
    k = form.C.rows
    kkt = np.block([[values["M"], -values["C"].T], [values["C"], np.zeros((k, k))]])
    try:
        solution = linalg.solve(kkt, np.concatenate([values["F"][:, 0], values["gamma"][:, 0]]))
    except linalg.LinAlgError as err:
        raise LinearizationError("The mass matrix (with the constraint rows) is singular at this point: "
                                 f"q = {q.tolist()}; choose a point where the equations are regular.") from err
    return FormPoint(form, q, u, p, float(t), named, values, solution[: form.n_u], solution[form.n_u:], kkt)


def _check_consistent(form, values) -> None:
    for what, residual, scale in (("configuration", values["Phi"], values["Phi_size"]),
                                  ("velocity", values["Psi"], values["Psi_size"])):
        if residual.size == 0:
            continue
        ratio, worst = relative_residual(residual[:, 0], scale[:, 0])
        if not ratio <= CONSISTENT:
            raise InitialConditionError(
                f"The point is off the constraint manifold: {what} constraint {worst} "
                f"{_row_name(form, what, worst)}has residual {residual[worst, 0]:.3g}, {ratio:.3g} times the size of the terms "
                f"it sums there (above {CONSISTENT:g}). Choose q on Φ(q) = 0, "
                "and complete the speeds with lagcomp.analysis.consistent_speeds.")


def _row_name(form, what: str, row: int) -> str:
    names = form.multiplier_names
    if what == "velocity" and len(names) == form.Psi.rows:
        return f"({names[row]}) "
    return ""


def choose_states(point: FormPoint, independent, drop) -> Choice:
    """Independent coordinates and speeds: those named in `independent`, else by pivoted QR (module docstring)."""
    form, v = point.form, point.values
    q_names, u_names = list(form.coordinate_names), list(form.speed_names)
    named, drop = list(independent or ()), tuple(drop)
    unknown = sorted(set(named + list(drop)) - set(q_names) - set(u_names))
    if unknown:
        raise LinearizationError(f"Unknown state name(s) {unknown}: coordinates are {q_names}, speeds {u_names}.")
    q_dep = _dependent(v["Phi_q"], q_names, [n for n in named if n in q_names], drop, "coordinates")
    u_dep = _dependent(v["Psi_u"], u_names, [n for n in named if n in u_names], drop, "speeds")
    q_ind = [j for j in range(form.n_q) if j not in q_dep]
    u_ind = [j for j in range(form.n_u) if j not in u_dep]
    return Choice(q_ind, q_dep, u_ind, u_dep,
                  states=tuple(q_names[j] for j in q_ind) + tuple(u_names[j] for j in u_ind),
                  dependent=tuple(q_names[j] for j in q_dep) + tuple(u_names[j] for j in u_dep),
                  dropped=drop, rows=q_ind + [form.n_q + j for j in u_ind])


def _dependent(jacobian: np.ndarray, names: list, independent: list, drop: tuple, what: str) -> list:
    """Indices of the dependent columns of `jacobian` (rows = constraints), checked regular.

    All of `independent` (and `drop`) stay independent; when `independent`
    does not name the whole independent set, pivoted QR picks the dependent
    columns among the others (best conditioned first).
    """
    rows = jacobian.shape[0]
    if len(independent) > len(names) - rows:
        raise LinearizationError(f"{len(independent)} independent {what} {independent} named; there are only "
                                 f"{len(names) - rows} ({len(names)} {what}, {rows} constraints).")
    if not rows:
        return []
    candidates = [j for j, n in enumerate(names) if n not in independent and n not in drop]
    if len(candidates) < rows:
        raise LinearizationError(f"Too few {what} left to be dependent: {rows} constraints, candidates "
                                 f"{[names[j] for j in candidates]}; drop or name fewer {what}.")
    _, _, pivots = linalg.qr(jacobian[:, candidates], mode="economic", pivoting=True)
    dependent = sorted(candidates[j] for j in pivots[:rows])
    block = jacobian[:, dependent]
    if np.linalg.cond(block) > 1 / (1e3 * np.finfo(float).eps):
        raise LinearizationError(
            f"The constraints do not determine the dependent {what} {[names[j] for j in dependent]} at this "
            f"point (their Jacobian block is singular): the constraints are redundant there, or name other "
            f"independent {what} in `independent`.")
    return dependent


def consistent_speeds(system, q, u, params: dict | None = None, *, t: float = 0.0, independent=None,
                      inputs=None) -> np.ndarray:
    """`u` with its dependent speeds solved from the velocity constraints Ψ(q, u, t) = 0 (linear in u).

    The speeds named in `independent` keep their values, and so do the
    other independent ones (chosen by pivoted QR of Ψ_u).  The speeds of a steady motion, e.g. a
    disc's spin with its contact point's velocity completed.
    """
    form, q, u, p, _, values = _evaluated(system, q, u, params, t, inputs)
    names = list(form.speed_names)
    dependent = _dependent(values["Psi_u"], names, [n for n in (independent or ()) if n in names], (), "speeds")
    u = u.copy()
    if dependent:
        # Ψ is linear in u: Ψ(u) = Ψ(u with u_d = 0) + Ψ_ud u_d
        u[dependent] = 0.0
        zeroed = evaluator(form).point(q, u, p, float(t))["Psi"][:, 0]
        u[dependent] = linalg.solve(values["Psi_u"][:, dependent], -zeroed)
    return u
