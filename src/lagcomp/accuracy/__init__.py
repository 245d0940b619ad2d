r"""How accurate the emitted kernels are: errors in ulps against a 40-digit evaluation.

`kernel_accuracy(model, states)` evaluates the compiled ``rhs``, ``reactions``
and ``energy`` kernels at the given states and compares them with the same
equations evaluated in many-digit arithmetic (`reference_equations`: the
System's own T, V, forces and constraints differentiated by plain sympy and
evaluated by mpmath, independent of lagcomp's derivation and CSE).  A model
compiled from a kinematic tree (`lagcomp.Tree`), whose kernels come from
recursions over the tree, is measured against the equations of motion that
`tree_reference` forms from the tree's description alone (d'Alembert's
principle over its forward kinematics, derivatives by central differences, in
4 × `digits` digits; none of the recursions' code): the same q̈, λ and T + V.

The error of component i is reported in ulps,

    e_i = |computed_i − exact_i| / ulp(max(|exact_i|, s_i)),

ulp(x) = `numpy.spacing(x)` (2⁻⁵² x up to a factor 2), in two ways that differ
in the component scale s_i, i.e. in how near-zero components are treated:

- componentwise (``KernelError.ulps``): s_i = FLOOR × max_j |exact_j| over the
  same output at the same state (FLOOR = 2⁻²⁶ ≈ 1.5e-8): each component in ulps
  of its own value, unless it is below that fraction of the largest one.  A
  component that is a near-cancelling sum of large terms (two pulls that almost
  balance) shows many ulps here in any float64 implementation, hand-written too.
- normwise (``KernelError.normwise``): s_i = max_j |exact_j|: the error in ulps of
  the largest component, the usual ‖δ‖∞/‖x‖∞ of numerical analysis.

The outputs: ``rhs``, the accelerations q̈ (its q̇ half is a copy of the input);
``reactions``, the multipliers λ; ``energy``, T + V, measured in ulps of
|T| + |V| (exact) both ways: the rounding of the two terms it adds is the floor
of any form of it.  A careful hand-written kernel reaches a few ulps normwise;
a kernel that cancels (squared distances multiplied out at a close approach)
shows thousands to 10¹³.  `Reference.ulps` measures any other implementation
(a hand-written rhs) the same way.
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath
import numpy as np

from lagcomp.accuracy.reference import ReferenceEquations, reference_equations
from lagcomp.accuracy.states import close_approach_states, random_states
from lagcomp.accuracy.tree_reference import tree_reference
from lagcomp.errors import ModelError
from lagcomp.multibody.tree import Tree

__all__ = ["kernel_accuracy", "reference_values", "Reference", "KernelError", "Accuracy",
           "reference_equations", "tree_reference", "random_states", "close_approach_states", "FLOOR", "DIGITS"]

#: Digits of the reference evaluation.
DIGITS = 40
#: Near-zero components are measured in ulps of FLOOR × the largest component (2⁻²⁶ ≈ 1.5e-8).
FLOOR = 2.0**-26


@dataclass(frozen=True)
class Reference:
    """Exact values at m states (mpmath numbers rounded to `digits`), and the scales they are measured in.

    qdd : list of m lists of n numbers;  reactions : m lists of k;  energy, energy_scale : m numbers.
    """

    qdd: list
    reactions: list
    energy: list
    energy_scale: list
    floor: float = FLOOR

    def ulps(self, kernel: str, computed, floor: float | None = None) -> np.ndarray:
        """Errors in ulps of `computed` (shape (m, n) q̈, (m, k) λ, or (m,) energy) against this reference.

        `floor` (default this reference's): near-zero components are measured in ulps of
        floor × the largest exact component of the same state; 1.0 gives the normwise error.
        """
        floor = self.floor if floor is None else floor
        if kernel == "energy":
            return np.array([_ulps(c, e, s) for c, e, s in zip(np.asarray(computed, float), self.energy,
                                                                self.energy_scale)])
        exact = {"rhs": self.qdd, "reactions": self.reactions}[kernel]
        computed = np.asarray(computed, dtype=float)
        rows = []
        for row, values in zip(computed, exact):
            biggest = max((abs(v) for v in values), default=0)
            rows.append([_ulps(c, e, floor * biggest) for c, e in zip(row, values)])
        return np.array(rows, dtype=float).reshape(computed.shape)


def _ulps(computed: float, exact, scale) -> float:
    if not np.isfinite(computed):
        return np.inf
    size = float(max(abs(exact), abs(scale)))
    if size == 0:
        return 0.0 if computed == 0 else np.inf
    return float(abs(mpmath.mpf(computed) - exact)) / float(np.spacing(size))


@dataclass(frozen=True)
class KernelError:
    """Errors of one kernel in ulps, shape (m, components) ((m,) for energy): componentwise
    (`ulps`) and normwise (`normwise`), as the module docstring defines them."""

    kernel: str
    ulps: np.ndarray
    normwise: np.ndarray

    @property
    def max(self) -> float:
        """Largest componentwise error."""
        return float(np.max(self.ulps)) if self.ulps.size else 0.0

    @property
    def median(self) -> float:
        return float(np.median(self.ulps)) if self.ulps.size else 0.0

    @property
    def max_normwise(self) -> float:
        return float(np.max(self.normwise)) if self.normwise.size else 0.0

    @property
    def worst_state(self) -> int:
        """Index (into the states measured) of the state with the largest componentwise error."""
        per_state = self.ulps.reshape(len(self.ulps), -1).max(axis=1)
        return int(np.argmax(per_state))


@dataclass(frozen=True)
class Accuracy:
    """`kernel_accuracy`'s result: a KernelError per kernel, the states used and those skipped.

    states : (m, 2n) the states measured;  skipped : states where M (or the augmented
    matrix) was singular in float64 (the kernel reported it), left out.
    """

    model_name: str
    errors: dict
    states: np.ndarray
    skipped: int

    def __getitem__(self, kernel: str) -> KernelError:
        return self.errors[kernel]

    def summary(self) -> str:
        parts = [f"{k}: max {e.max:.3g} ulps (normwise {e.max_normwise:.3g}), median {e.median:.3g}"
                 for k, e in self.errors.items()]
        return f"{self.model_name} ({len(self.states)} states): " + "; ".join(parts)


def _checked_states(model, states, t) -> tuple[np.ndarray, np.ndarray]:
    try:
        y = np.atleast_2d(np.asarray(states, dtype=float))
    except (TypeError, ValueError) as err:
        raise ModelError(f"`states` must be an (m, {2 * model.n}) array of numbers for {model.name!r}: {err}.") from err
    if y.ndim != 2 or y.shape[1] != 2 * model.n:
        raise ModelError(f"`states` must have shape (m, {2 * model.n}) for {model.name!r} (q then q̇), "
                         f"got shape {np.shape(states)}.")
    times = np.broadcast_to(np.asarray(t, dtype=float), (len(y),))
    if not (np.all(np.isfinite(y)) and np.all(np.isfinite(times))):
        raise ModelError("`states` and `t` must be finite.")
    return y, np.array(times)


def _equations(model) -> ReferenceEquations:
    if getattr(model, "kanes_method", None) is not None:
        raise ModelError(f"The accuracy check measures kernels against Lagrange's equations of a System; "
                         f"{model.name!r} was compiled from a KanesMethod, whose equations it does not re-derive. "
                         "Compare its `rhs` with sympy's own `km.rhs()` evaluated in mpmath instead.")
    if model.system is None:
        raise ModelError(f"The accuracy check of {model.name!r} needs its System: this model came from "
                         "`lagcomp.load`; use `lagcomp.compile(system)` instead.")
    if isinstance(model.system, Tree):   # d'Alembert's principle over its forward kinematics, numerically
        return tree_reference(model.system)
    return reference_equations(model.system)


def _full_parameters(model, params, baumgarte) -> np.ndarray:
    """p as the kernels take it, with the Baumgarte gains appended for the reference (zeros if unconstrained)."""
    p = model.parameter_vector(params, baumgarte=baumgarte)
    return p if model.k else np.concatenate([p, [0.0, 0.0]])


def reference_values(model, states, *, t=0.0, params=None, baumgarte=(0.0, 0.0), digits: int = DIGITS,
                     floor: float = FLOOR) -> Reference:
    """q̈, λ and T + V of `model`'s System at `states` (shape (m, 2n)) in `digits`-digit arithmetic."""
    equations = _equations(model)
    y, times = _checked_states(model, states, t)
    p = _full_parameters(model, params, baumgarte)
    qdd, reactions, energy, scale = [], [], [], []
    for ti, yi in zip(times, y):
        a, lam, (T, V) = equations.evaluate(ti, yi, p, digits)
        qdd.append(a)
        reactions.append(lam)
        energy.append(T + V)
        scale.append(abs(T) + abs(V))
    return Reference(qdd, reactions, energy, scale, floor)


def kernel_accuracy(model, states=None, *, t=0.0, params=None, baumgarte=(0.0, 0.0), digits: int = DIGITS,
                    floor: float = FLOOR, n: int = 50, seed: int = 0) -> Accuracy:
    """Errors in ulps of the kernels ``rhs`` (q̈), ``reactions`` (λ) and ``energy`` of a compiled `model`.

    Parameters
    ----------
    model : Model
        From `lagcomp.compile` of a System or a `lagcomp.Tree` (needed for the reference).
    states : array, shape (m, 2n), optional
        States y = (q, q̇) to measure at; default `random_states(model, n, seed=seed)`.
        Pass `close_approach_states(...)` or your own near-singular configurations too.
    t : float or array of shape (m,)
        Times of the states.
    params : dict, optional
        Parameter values (the model's defaults fill in the rest).
    baumgarte : (alpha, beta)
        Gains of the constraint stabilization (constrained systems), as in `simulate`.
    digits, floor
        Digits of the reference, and the near-zero scale (module docstring).

    Returns
    -------
    Accuracy
        ``acc["rhs"].max`` etc.; states where the float64 matrix was singular are skipped.
    """
    if states is None:
        states = random_states(model, n, seed=seed)
    y, times = _checked_states(model, states, t)
    p = model.parameter_vector(params, baumgarte=baumgarte)
    rhs, lam, energy, kept = [], [], [], []
    for i, (ti, yi) in enumerate(zip(times, y)):
        out = np.empty(2 * model.n)
        if model.kernels.rhs(ti, yi, p, out):
            continue
        rhs.append(out[model.n:])
        if model.k:
            reactions = np.empty(model.k)
            model.kernels.reactions(ti, yi, p, reactions)
            lam.append(reactions)
        energy.append(model.kernels.energy(ti, yi, p))
        kept.append(i)
    skipped = len(y) - len(kept)
    y, times = y[kept], times[kept]
    reference = reference_values(model, y, t=times, params=params, baumgarte=baumgarte, digits=digits, floor=floor)
    computed = {"rhs": np.reshape(rhs, (len(kept), model.n)), "energy": np.array(energy)}
    if model.k:
        computed["reactions"] = np.reshape(lam, (len(kept), model.k))
    errors = {kernel: KernelError(kernel, reference.ulps(kernel, values), reference.ulps(kernel, values, floor=1.0))
              for kernel, values in computed.items()}
    return Accuracy(model.name, errors, y, skipped)
