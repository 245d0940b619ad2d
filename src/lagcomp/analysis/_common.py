"""Shared plumbing of the analysis modules: argument checks and direct kernel calls."""

from __future__ import annotations

import numpy as np
import sympy as sp

from lagcomp.errors import InitialConditionError, ModelError


def unconstrained(model, what: str) -> None:
    """Refuse a constrained model for `what` (its equations need the multipliers as unknowns)."""
    if model.k:
        raise ModelError(
            f"{what} needs an unconstrained system: {model.name!r} has constraints {list(model.constraints)}. "
            "Eliminate them with independent coordinates (the reference chapter's way) and compile that system."
        )


def symbolic_system(model, what: str):
    """The System `model` was compiled from; a loaded model (`lagcomp.load`) has none to give.

    A Kane model (compiled from a KanesMethod) has no System at all: its
    equations are Kane's, not Lagrange's, so the message says what applies to it.
    """
    if getattr(model, "speeds", None) is not None:  # a KaneModel: state (q, u), no L to read
        raise ModelError(
            f"{what} reads the Lagrangian (T, V, generalized forces) of a System; {model.name!r} is a Kane model, "
            "compiled from a KanesMethod's equations (state (q, u)), which has none. For a Kane model lagcomp "
            "offers simulate and sweep (the Runge-Kutta methods and radau), rhs, energy (T + V where the loads have a "
            "potential; watch Solution.energy for conservation), constraint_residuals, reactions, and "
            "linearize_steady / stability_sweep about steady motions. For this analysis, build the model as a "
            "lagcomp.System or sympy LagrangesMethod (possible when its velocities are the time derivatives of "
            "its positions) and compile that."
        )
    if getattr(model.system, "on_demand_refusal", None) is not None:   # a lagcomp.Tree: no T and V to read
        raise ModelError(model.system.on_demand_refusal(what))
    if model.system is None:
        raise ModelError(f"{what} reads the equations of {model.name!r}, which a model from lagcomp.load() does not "
                         "carry: build its System and use lagcomp.compile(system) (a cache hit, no recompilation).")
    return model.system


def tree_of(model):
    """The `lagcomp.Tree` `model` was compiled from (``lc.compile(tree)``), None for any other model: the analyses
    that read a System's T and V read what the tree knows instead where that is enough (its joints' torques and
    dampers are its only non-conservative forces, and its torques the only part of it that may read t)."""
    from lagcomp.multibody.tree import Tree

    system = getattr(model, "system", None)
    return system if isinstance(system, Tree) else None


def explicit_time(*exprs, system) -> bool:
    """Whether any of `exprs` depends on t other than through the coordinates q(t) and velocities q̇(t)."""
    from lagcomp.model.system import t

    plain = {}
    for i, q in enumerate(system.coordinates):
        plain[q.diff(t)] = sp.Dummy(f"v{i}")
    for i, q in enumerate(system.coordinates):
        plain[q] = sp.Dummy(f"q{i}")
    return any(sp.sympify(e).xreplace(plain).has(t) for e in exprs)


def coordinates_vector(model, q, what: str = "q") -> np.ndarray:
    """`q` as a float vector of shape (n,), checked."""
    q = np.atleast_1d(np.asarray(q, dtype=float)).ravel()
    if q.shape != (model.n,):
        raise InitialConditionError(
            f"`{what}` has {q.size} value(s); {model.name!r} has {model.n} coordinates {list(model.coordinates)}."
        )
    if not np.all(np.isfinite(q)):
        raise InitialConditionError(f"`{what}` = {q.tolist()} is not finite.")
    return q


class RestForces:
    """F(q, 0, t) and its partials at rest for one parameter vector, straight from the kernels.

    Holds the parameter vector and work arrays, so that root finders can call
    it thousands of times without re-validating the parameters each time.
    """

    def __init__(self, model, params: dict | None, t: float, inputs=None):
        self.model, self.t = model, float(t)
        self.p = model.parameter_vector(params, inputs=inputs)
        self.params_given = params
        self.params = dict(zip(model.parameters, self.p.tolist()))
        self._y = np.zeros(2 * model.n)
        self._blocks = np.empty((2, model.n, model.n))

    def _state(self, q) -> np.ndarray:
        self._y[: self.model.n] = q
        return self._y

    def force(self, q, t: float | None = None) -> np.ndarray:
        """F(q, 0, t), shape (n,)."""
        out = np.empty(self.model.n)
        self.model.kernels.forcing(self.t if t is None else float(t), self._state(q), self.p, out)
        return out

    def partials(self, q, t: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(∂F/∂q, ∂F/∂q̇) at (q, 0, t), each (n, n)."""
        self.model.kernels.rest_partials(self.t if t is None else float(t), self._state(q), self.p, self._blocks)
        return self._blocks[0].copy(), self._blocks[1].copy()

    def mass_matrix(self, q) -> np.ndarray:
        out = np.empty((self.model.n, self.model.n))
        self.model.kernels.mass_matrix(self.t, self._state(q), self.p, out)
        return out

    def force_scale(self, q, force=None, tolerance: float = 0.0) -> np.ndarray:
        """A size for each F_i near q, shape (n,): `force_scale` (the terms that grow with q), and where `force`
        is not within `tolerance` of 0 against that, also Σ_m |∂F_i/∂p_m| |p_m|, the terms the parameters carry
        (a weight m g balanced by a spring's pre-load k δ at q = 0, where the first is 0).

        Residuals are judged against it, so that "F = 0" means the same for a
        bead of 0.1 kg and a jack lifting 4000 N, in any units.  The second part
        needs the parameter Jacobian kernel (built on first use), hence only when
        the first does not settle it.
        """
        stiffness, _ = self.partials(q)
        scale = force_scale(stiffness, q)
        if force is not None and not relative_residual(force, scale)[0] <= tolerance:
            scale = scale + self.parameter_scale(q)
        return scale

    def parameter_scale(self, q) -> np.ndarray:
        """Σ_m |∂F_i/∂p_m| |p_m| at (q, 0, t), shape (n,) (0 where the kernel fails): ∂F/∂p = M ∂q̈/∂p from the
        ``rhs_parameter_jacobian`` kernel, exact where q̈ = 0 (an equilibrium) and a size elsewhere."""
        n, count = self.model.n, len(self.model.parameters)
        out = np.empty((2 * n, count))
        y = np.concatenate([np.asarray(q, dtype=float), np.zeros(n)])
        if self.model.kernels.rhs_parameter_jacobian(self.t, y, self.p, out) != 0:
            return np.zeros(n)
        return np.abs(self.mass_matrix(q) @ out[n:]) @ np.abs(self.p[:count])


def force_scale(stiffness: np.ndarray, q) -> np.ndarray:
    """The size of each generalized force near q, Σ_j |∂F_i/∂q_j| |q_j|, shape (n,), in F_i's own units.

    The forces that balance at an equilibrium grow with q away from q = 0 (a spring's k q, a weight's moment
    m g l sin q), so this is the size of the terms whose difference F_i is, up to rounding.  Each row in its own
    unit (force per unit of coordinate i), none compared with another's, and no unit of length or force assumed:
    scaling lengths, masses or times scales F_i and its scale alike.  Where every q_j that F_i depends on is 0
    the scale is 0 and only an exact zero passes (a force odd in q, such as sin q's, is exactly 0 there).
    """
    return np.abs(np.asarray(stiffness, dtype=float)) @ np.abs(np.asarray(q, dtype=float))


def relative_residual(residual, scale) -> tuple[float, int]:
    """(max_i |r_i| / scale_i, that row i): how far r is from 0, each entry against its own size, as
    as `force_scale` gives it (0/0 = 0, r_i/0 = inf).  NaN when r is."""
    residual, scale = np.abs(np.asarray(residual, dtype=float)).ravel(), np.asarray(scale, dtype=float).ravel()
    if residual.size == 0:
        return 0.0, 0
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = np.where(residual == 0.0, 0.0, residual / scale)
    worst = int(np.argmax(ratios))
    return float(ratios[worst]), worst
