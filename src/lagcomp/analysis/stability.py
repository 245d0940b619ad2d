r"""Eigenvalues of a steady motion followed along a parameter, and where stability changes.

`stability_sweep` linearizes (`linearize_steady`) at each value of a
parameter — a model parameter, or a speed of the steady motion such as a
bicycle's wheel rate or a top's spin (the dependent speeds are completed from
the velocity constraints) — follows each eigenvalue from one value to the
next (the assignment of least total distance, so curves do not swap where
they cross), and locates every change of the verdict "unstable" (some
Re λ > 0) between neighbouring samples:

- where the largest Re λ changes sign (a real eigenvalue or a complex pair
  crossing the imaginary axis, as at a bicycle's weave and capsize speeds),
  by `scipy.optimize.brentq` on the largest Re λ;
- where it goes from > 0 to 0 (conservative and gyroscopic systems: a real
  pair ±σ meets at 0 and turns into an imaginary pair ±iω, as at a sleeping
  top's or a rolling disc's critical spin), the largest Re λ grows like
  √|value − critical| and has no sign change: there the verdict itself is
  bisected to `xtol`, which finds the critical value to rounding because
  √ is so steep.

A change between two samples is found only when the verdicts there differ:
sample finely enough that no stable window fits between two samples.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

from lagcomp.analysis._steady_setup import consistent_speeds, first_order_form, state_vector
from lagcomp.analysis.steady import ZERO, linearize_steady
from lagcomp.errors import LinearizationError, OptionError

#: Absolute tolerance of a located change, relative to the sweep's span.
XTOL = 1e-13


@dataclass(frozen=True)
class StabilityChange:
    """One change of stability: at `value` the motion `becomes` "stable" or "unstable" (increasing value).

    `crossing` is "transversal" (the largest Re λ changes sign; brentq) or
    "marginal" (it reaches 0 from above without changing sign; bisection).
    """

    value: float
    becomes: str
    crossing: str


@dataclass(frozen=True)
class StabilitySweep:
    """Eigenvalues along a parameter (module docstring).

    Attributes
    ----------
    parameter : str
    values : ndarray, shape (n,)
    eigenvalues : ndarray of complex, shape (n, m)
        Column j follows one eigenvalue continuously along `values`.
    growth : ndarray, shape (n,)
        Largest Re λ at each value.
    unstable : ndarray of bool, shape (n,)
    changes : tuple of StabilityChange
    states : tuple of str
        The reduced state the eigenvalues belong to.
    """

    parameter: str
    values: np.ndarray
    eigenvalues: np.ndarray
    growth: np.ndarray
    unstable: np.ndarray
    changes: tuple
    states: tuple

    def __repr__(self) -> str:
        found = ", ".join(f"{c.becomes} at {self.parameter} = {c.value:.10g}" for c in self.changes) or "none"
        return (f"StabilitySweep({self.parameter} in [{self.values[0]:g}, {self.values[-1]:g}], "
                f"{len(self.values)} values, changes: {found})")


def stability_sweep(system, parameter, values, q, u=None, params: dict | None = None, *, t: float = 0.0,
                    drop=(), independent=None, label: str | None = None, inputs=None) -> StabilitySweep:
    """Follow the eigenvalues of the steady motion (q, u) as `parameter` runs through `values`.

    Parameters
    ----------
    system : Model, System or FirstOrderForm
    parameter : str or callable
        A model parameter's name, a speed's name (that speed is set, and the
        dependent speeds are solved from the velocity constraints with it
        independent), or a function ``value -> dict`` giving any of ``q``,
        ``u``, ``params`` (merged over the base point) for each value.
    values : sequence of float, increasing, at least 2
    q, u, params, t, drop, independent, inputs
        The base point and the options of `linearize_steady` (`inputs`: the values the system's inputs are
        held at).
    label : str, optional
        The parameter's name in results and plots (default: `parameter`'s
        name, or the function's).
    """
    values = np.asarray(values, dtype=float).ravel()
    if values.size < 2 or not np.all(np.isfinite(values)) or np.any(np.diff(values) <= 0):
        raise OptionError(f"`values` must be at least 2 finite, increasing numbers; got {values[:5].tolist()}...")
    at = _point_function(system, parameter, q, u, params, t, independent, inputs)

    def linearize(value):
        point = at(value)
        return linearize_steady(system, point["q"], point["u"], point["params"], t=t, drop=drop,
                                independent=independent, inputs=inputs)

    results = [linearize(v) for v in values]
    eigenvalues = _follow([r.eigenvalues for r in results])
    unstable = np.array([r.stability == "unstable" for r in results])
    changes = tuple(_locate(linearize, a, b, ra, rb, XTOL * (values[-1] - values[0]))
                    for a, b, ra, rb in zip(values[:-1], values[1:], results[:-1], results[1:])
                    if (ra.stability == "unstable") != (rb.stability == "unstable"))
    name = label or (parameter if isinstance(parameter, str) else getattr(parameter, "__name__", "parameter"))
    return StabilitySweep(parameter=name, values=values, eigenvalues=eigenvalues,
                          growth=np.array([r.growth_rate for r in results]), unstable=unstable,
                          changes=changes, states=results[0].states)


def _point_function(system, parameter, q, u, params, t, independent, inputs=None):
    """value -> dict(q, u, params) of the point at that value of `parameter`."""
    base = {"q": q, "u": u, "params": dict(params or {})}
    if callable(parameter):
        def given(value):
            point = parameter(value)
            return {**base, **point, "params": {**base["params"], **point.get("params", {})}}
        return given
    form, _ = first_order_form(system)
    if parameter in [str(s) for s in form.parameters[:len(form.parameters) - len(form.input_names)]]:
        return lambda value: {**base, "params": {**base["params"], parameter: value}}
    if parameter in form.speed_names:
        k = list(form.speed_names).index(parameter)
        start = np.zeros(form.n_u) if u is None else state_vector(u, form.speed_names, "u")
        keep = list(dict.fromkeys([parameter, *(n for n in independent or () if n in form.speed_names)]))

        def speeds(value):
            new = start.copy()
            new[k] = value
            return {**base, "u": consistent_speeds(system, q, new, base["params"], t=t, independent=keep,
                                                    inputs=inputs)}
        return speeds
    names = [str(s) for s in form.parameters[:len(form.parameters) - len(form.input_names)]]
    raise LinearizationError(f"Unknown sweep parameter {parameter!r}: name a parameter {names} or a speed "
                             f"{list(form.speed_names)}, or pass a function value -> dict(q=..., u=..., params=...).")


def _follow(spectra: list) -> np.ndarray:
    """Order each spectrum to continue the previous one (least total |Δλ|, Hungarian assignment)."""
    from scipy.optimize import linear_sum_assignment

    ordered = [np.asarray(spectra[0])]
    for current in spectra[1:]:
        previous = ordered[-1]
        _, columns = linear_sum_assignment(np.abs(previous[:, None] - current[None, :]))
        ordered.append(np.asarray(current)[columns])
    return np.array(ordered)


def _locate(linearize, a, b, ra, rb, xtol) -> StabilityChange:
    """The value in (a, b) where the verdict changes (module docstring)."""
    becomes = "unstable" if rb.stability == "unstable" else "stable"
    tol_a, tol_b = ZERO * ra.rate_scale, ZERO * rb.rate_scale
    if (ra.growth_rate < -tol_a and rb.growth_rate > tol_b) or (ra.growth_rate > tol_a and rb.growth_rate < -tol_b):
        value = optimize.brentq(lambda x: linearize(x).growth_rate, a, b, xtol=xtol, rtol=4 * np.finfo(float).eps)
        return StabilityChange(float(value), becomes, "transversal")
    unstable_at_a = ra.stability == "unstable"
    lo, hi = a, b
    while hi - lo > xtol:
        mid = 0.5 * (lo + hi)
        if (linearize(mid).stability == "unstable") == unstable_at_a:
            lo = mid
        else:
            hi = mid
    return StabilityChange(float(0.5 * (lo + hi)), becomes, "marginal")
