r"""Linearization about a steady motion (or an equilibrium) of a constrained system.

Works on the first-order form of `lagcomp.mechanics.first_order`,

    q̇ = N(q, u, t),   M u̇ = F + Cᵀλ,   C u̇ = γ,   Φ(q, t) = 0,   Ψ(q, u, t) = 0,

so Lagrange systems (u = q̇, multipliers λ) and Kane systems (M not
symmetric, no multipliers, n_q ≠ n_u) go the same way.

Derivation
----------
State x = (q, u).  The accelerations a = u̇ and multipliers λ solve
G(x, a, λ) = [R; S] = 0 with R = M a − F − Cᵀλ and S = C a − γ; the
Jacobian of G in (a, λ) is J = [[M, −Cᵀ], [C, 0]], regular where the motion is
well posed.  By the implicit-function theorem, at the point (x*, a*, λ*),

    ∂(a, λ)/∂x = −J⁻¹ ∂G/∂x,

exactly (∂G/∂x differentiated symbolically, `_form_jacobians`), and the
variation δx of a neighbouring motion obeys δẋ = A_full δx with

    A_full = [[N_q, N_u], [a_q, a_u]].

Both motions lie on the constraint manifold {Φ = 0, Ψ = 0} at every t, so
δx lies in its tangent space T = {Φ_q δq = 0, Ψ_q δq + Ψ_u δu = 0}.  Split
q = (q_i, q_d) with the n_h × n_h block Φ_qd regular and u = (u_i, u_d) with
the n_v × n_v block Ψ_ud regular (pivoted QR of Φ_q and Ψ_u picks the best
conditioned blocks, or the user names the independent ones).  On T,

    δq_d = −Φ_qd⁻¹ Φ_qi δq_i,
    δu_d = −Ψ_ud⁻¹ (Ψ_q δq + Ψ_ui δu_i),

i.e. δx = P y with y = (δq_i, δu_i) and P the (n_q + n_u) × (n_q − n_h +
n_u − n_v) basis of T these two lines define.  The independent rows E of
δẋ = A_full δx then give the reduced state equation

    ẏ = A y,    A = E A_full P.

At an equilibrium, and on a steady motion where the change of basis
between two choices of independent states stays constant, another choice
gives a similar A (the same eigenvalues): both are the restriction of A_full
to T in two bases.  (ẏ = E A_full P y holds exactly for any choice, since
E P = I makes E Ṗ = 0; but if P changes along the motion, A does too.)

Steady motions and ignorable coordinates: about a steady motion (a bicycle
running straight, a sleeping top, a disc rolling upright) some coordinates
drift — yaw, wheel angles, the contact point, the top's spin angle — while the
others and all speeds stay constant, so A does not depend on time.  Such a
coordinate is ignorable when no kept rate depends on it (its column of A
vanishes off its own row); `drop=` removes it (and ignorable speeds, such as
a wheel's spin rate) from y.  With those columns zero, A is block triangular,
so the kept block's eigenvalues are eigenvalues of A and the dropped block's
(`dropped_eigenvalues`, zero for cyclic coordinates) are the rest; the check
that the columns vanish is made, and a state that is not ignorable is refused.
The eigenvalues are the motion's stability exponents when the reduced system
is autonomous along it: the kept states constant (`residual` ≈ 0) and A
unchanged as the dropped coordinates drift.  The column check verifies the
latter to first order at the point, and catches a basis that follows a
drifting coordinate (on a disc's steady turn, φ̇ dependent makes the kept
rates depend on the heading ψ; the pivoted QR takes ẋ, ẏ dependent instead).  `residual` is the largest rate of the kept
coordinates and of the kept independent speeds: zero (to rounding) exactly
when the point is a steady motion of the reduced system; `drift` gives the
rates of the dropped coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import linalg

from lagcomp.analysis._form_jacobians import evaluator
from lagcomp.analysis._steady_setup import Choice, FormPoint, choose_states, consistent_speeds, form_point
from lagcomp.errors import LinearizationError

__all__ = ["SteadyLinearization", "consistent_speeds", "linearize_steady"]

#: Relative size below which a rate, column or Re λ counts as zero.
ZERO = 1e-10


@dataclass(frozen=True)
class SteadyLinearization:
    """ẏ = A y about a steady motion (module docstring), with its eigen-decomposition.

    Attributes
    ----------
    A : ndarray, shape (m, m)
        State matrix of the reduced state y (rows and columns labelled `states`).
    states : tuple of str
        Labels of y: the kept independent coordinates, then the kept
        independent speeds (``<coordinate>_dot`` for Lagrange systems).
    eigenvalues : ndarray of complex, shape (m,)
        Eigenvalues of A, by decreasing real part, then decreasing imaginary part.
    vectors : ndarray of complex, shape (m, m)
        Eigenvectors (columns, unit 2-norm) in the reduced state y.
    basis : ndarray, shape (n_q + n_u, m)
        δ(q, u) = basis @ y: the full variation, dependent coordinates and speeds included.
    full_states : tuple of str
        Labels of δ(q, u): coordinate names, then speed names.
    q, u : ndarray
        The point (coordinates n_q, speeds n_u).
    t : float
    params : dict
    dependent : tuple of str
        Coordinates and speeds eliminated through the constraints.
    dropped : tuple of str
        Ignorable coordinates and speeds removed from y.
    residual : float
        Largest |rate| of the kept states at the point: ~0 on a steady motion.
    drift : dict
        Rates of the dropped coordinates and speeds (the cyclic drift).
    dropped_eigenvalues : ndarray of complex
        Eigenvalues of the dropped block of the reduced A (0 for truly
        cyclic coordinates; the rest of the spectrum, not in `stability`).
    B : ndarray, shape (m, U)
        Input matrix ∂ẏ/∂w of the inputs held constant (`inputs`; U = 0 without), rows as A's.
    inputs : tuple of str
        The inputs, the columns of B.
    input_derivatives : tuple of str
        Inputs whose derivatives the equations read: B (with respect to w alone) describes no response to
        them, and `state_space` refuses.
    reactions : dict
        {constraint: (∂λ/∂y (m,), ∂λ/∂w (U,), λ at the point)}, the multipliers' linearization, for
        `state_space` outputs.
    """

    A: np.ndarray
    states: tuple
    eigenvalues: np.ndarray
    vectors: np.ndarray
    basis: np.ndarray
    full_states: tuple
    q: np.ndarray
    u: np.ndarray
    t: float
    params: dict
    dependent: tuple
    dropped: tuple
    residual: float
    drift: dict = field(default_factory=dict)
    dropped_eigenvalues: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=complex))
    B: np.ndarray | None = None
    inputs: tuple = ()
    input_derivatives: tuple = ()
    reactions: dict = field(default_factory=dict, repr=False)

    def state_space(self, outputs=None):
        """ẏ = A y + B w, z = C y + D w (`lagcomp.analysis.StateSpace`): y the reduced state `states`, w the
        deviations of the inputs from the values held, z what `outputs` names (all the states by default): states,
        and constraints' reactions (their multipliers' deviations δλ = ∂λ/∂y y + ∂λ/∂w w).

        Raises LinearizationError where an input's derivatives enter the equations (`input_derivatives`:
        the motion responds to u̇ too, which no B describes).
        """
        from lagcomp.analysis.state_space import StateSpace

        rows = {name: (C, D) for name, (C, D, _) in self.reactions.items()}
        return StateSpace.of_states(self.A, self.B, self.states, self.inputs, outputs, self.input_derivatives, rows)

    @property
    def growth_rate(self) -> float:
        """Largest Re λ (0.0 for an empty state)."""
        return float(np.max(self.eigenvalues.real)) if self.eigenvalues.size else 0.0

    @property
    def rate_scale(self) -> float:
        """A rate (1/time) against which Re λ is judged: the largest |λ| or |B_ij| of the balanced B = T⁻¹ A T
        (`balanced`; at least 1e-300).

        |B| and not |λ| alone: the rounding error of computed eigenvalues
        scales with it, and near a collision of eigenvalues at 0 (where
        stability changes in conservative and gyroscopic systems) every |λ|
        is small while their rounding errors are not.  B and not A: A's
        entries are in the units of its states (positions and angles, their
        rates), B's are rates whatever those units.
        """
        largest = float(np.max(np.abs(self.eigenvalues))) if self.eigenvalues.size else 0.0
        return max(largest, float(np.max(np.abs(balanced(self.A)), initial=0.0)), 1e-300)

    @property
    def stability(self) -> str:
        """ "asymptotically stable" (every Re λ < 0), "marginal" (the largest Re λ is 0 to
        rounding: linear theory cannot decide) or "unstable" (some Re λ > 0)."""
        growth, tol = self.growth_rate, ZERO * self.rate_scale
        if growth > tol:
            return "unstable"
        return "asymptotically stable" if growth < -tol else "marginal"

    @property
    def stable(self) -> bool:
        """Linearly stable: no growing mode."""
        return self.stability != "unstable"

    @property
    def frequencies(self) -> np.ndarray:
        """Angular frequencies |Im λ| of the oscillating modes (one per conjugate pair), ascending."""
        im = self.eigenvalues.imag
        return np.sort(im[im > ZERO * self.rate_scale])

    def modes(self) -> list[dict]:
        """One dict per eigenvalue: ``eigenvalue`` and ``shape`` (state label -> complex component)."""
        return [{"eigenvalue": lam, "shape": dict(zip(self.states, self.vectors[:, j]))}
                for j, lam in enumerate(self.eigenvalues)]

    def __repr__(self) -> str:
        values = np.array2string(self.eigenvalues, precision=6)
        return (f"SteadyLinearization(states={list(self.states)}, {self.stability}, eigenvalues={values}, "
                f"residual={self.residual:.2g})")


def linearize_steady(system, q, u=None, params: dict | None = None, *, t: float = 0.0,
                     independent=None, drop=(), inputs=None) -> SteadyLinearization:
    """Linearize about the steady motion (q, u) (an equilibrium when u = 0) on the constraint manifold.

    Parameters
    ----------
    system : Model, System or FirstOrderForm
        A compiled model, its System, or a first-order form (e.g. built from a
        KanesMethod).  Lagrange systems use u = q̇.
    q, u : sequence of float, or dict by name
        The point: coordinates and speeds (u defaults to zeros: an equilibrium).
        It must satisfy the constraints (`consistent_speeds` completes u).
    params : dict, optional
        Parameter values by name (defaults of the System filled in).
    independent : sequence of str, optional
        Names of independent coordinates and/or speeds (for either group not
        named, a pivoted QR of Φ_q or Ψ_u chooses).
    drop : sequence of str
        Ignorable coordinates and speeds to remove from the reduced state
        (cyclic coordinates that drift on the steady motion).
    inputs : dict, optional
        A number per input of the system (`lagcomp.Input` supplied at run time), by name: the inputs are
        held at these values (their derivatives 0), and `SteadyLinearization.B` is ∂ẏ/∂u there.

    Raises
    ------
    InitialConditionError
        The point is off the constraint manifold, or has the wrong size.
    LinearizationError
        A named independent set leaves a singular block, the constraints are
        singular at the point, or a dropped coordinate is not ignorable.
    """
    point = form_point(system, q, u, params, t, inputs)
    values = point.values
    choice = choose_states(point, independent, drop)
    A_full, reactions_x = _full_state_matrix(point)
    basis = _tangent_basis(point, choice)
    A = A_full[choice.rows] @ basis
    kept = [j for j, name in enumerate(choice.states) if name not in choice.dropped]
    gone = [j for j in range(len(choice.states)) if j not in kept]
    _check_ignorable(A, choice, kept)
    A_kept = A[np.ix_(kept, kept)]
    B_full, reactions_w = _full_input_matrix(point)
    B = B_full[choice.rows][kept]
    eigenvalues, vectors = linalg.eig(A_kept)
    order = np.lexsort((-eigenvalues.imag, -eigenvalues.real))
    rates = np.concatenate([values["N"][:, 0], point.acceleration])
    state_rates = rates[choice.rows]
    return SteadyLinearization(
        A=A_kept, states=tuple(choice.states[j] for j in kept), eigenvalues=eigenvalues[order],
        vectors=vectors[:, order], basis=basis[:, kept], full_states=point.full_states,
        q=point.q, u=point.u, t=point.t, params=point.params, dependent=choice.dependent,
        dropped=choice.dropped,
        residual=float(np.max(np.abs(state_rates[kept]), initial=0.0)),
        drift={choice.states[j]: float(state_rates[j]) for j in range(len(choice.states)) if j not in kept},
        dropped_eigenvalues=linalg.eigvals(A[np.ix_(gone, gone)]) if gone else np.zeros(0, dtype=complex),
        B=B, inputs=point.form.input_names, input_derivatives=point.form.input_derivatives,
        reactions=dict(zip(point.form.multiplier_names,
                           zip(reactions_x @ basis[:, kept], reactions_w, point.multipliers), strict=True)),
    )


def _full_state_matrix(point: FormPoint) -> tuple[np.ndarray, np.ndarray]:
    """A_full = [[N_q, N_u], [a_q, a_u]] with ∂(a, λ)/∂x = −J⁻¹ ∂G/∂x (module docstring), and ∂λ/∂x (k, n_q + n_u)."""
    v = point.values
    G_q, G_u = evaluator(point.form).residual_partials(point.q, point.u, point.acceleration, point.multipliers,
                                                     point.p, point.t)
    sensitivity = -linalg.solve(point.kkt, np.hstack([G_q, G_u]))
    n_u = point.form.n_u
    return np.block([[v["N_q"], v["N_u"]], [sensitivity[:n_u]]]), sensitivity[n_u:]


def _full_input_matrix(point: FormPoint) -> tuple[np.ndarray, np.ndarray]:
    """B_full = [[N_w], [a_w]], ∂(q̇, u̇)/∂w along the inputs w held constant, ∂(a, λ)/∂w = −J⁻¹ ∂G/∂w as for A, and
    ∂λ/∂w (k, U)."""
    N_w, G_w = evaluator(point.form).input_partials(point.q, point.u, point.acceleration, point.multipliers,
                                                  point.p, point.t)
    sensitivity = -linalg.solve(point.kkt, G_w) if G_w.size else np.zeros((point.kkt.shape[0], G_w.shape[1]))
    n_u = point.form.n_u
    return np.vstack([N_w, sensitivity[:n_u]]), sensitivity[n_u:]


def _tangent_basis(point: FormPoint, choice: Choice) -> np.ndarray:
    """P with δ(q, u) = P y on the tangent space of the constraint manifold, y = (δq_i, δu_i)."""
    v, form = point.values, point.form
    qi, qd, ui, ud = choice.q_independent, choice.q_dependent, choice.u_independent, choice.u_dependent
    B_q = np.zeros((form.n_q, len(qi)))
    B_q[qi, np.arange(len(qi))] = 1.0
    if qd:
        B_q[qd] = -linalg.solve(v["Phi_q"][:, qd], v["Phi_q"][:, qi])
    B_uq = np.zeros((form.n_u, len(qi)))
    B_uu = np.zeros((form.n_u, len(ui)))
    B_uu[ui, np.arange(len(ui))] = 1.0
    if ud:
        Psi_ud = v["Psi_u"][:, ud]
        B_uq[ud] = -linalg.solve(Psi_ud, v["Psi_q"] @ B_q)
        B_uu[ud] = -linalg.solve(Psi_ud, v["Psi_u"][:, ui])
    return np.block([[B_q, np.zeros((form.n_q, len(ui)))], [B_uq, B_uu]])


def balanced(A: np.ndarray) -> np.ndarray:
    """B = T⁻¹ A T balanced (LAPACK's gebal, as `scipy.linalg.eig` does before computing eigenvalues; no
    permutation, T diagonal, powers of two): its entries no longer depend on the units of A's states (a change of
    units is a diagonal similarity, which the balancing absorbs), and ε |B| is the eigenvalues' rounding."""
    return A if A.size == 0 else linalg.matrix_balance(A, permute=False)[0]


def _check_ignorable(A: np.ndarray, choice: Choice, kept: list) -> None:
    """Every dropped state's column of A must vanish in the kept rows."""
    scale = max(float(np.max(np.abs(A), initial=0.0)), 1e-300)
    for j, name in enumerate(choice.states):
        if name in choice.dropped:
            coupling = float(np.max(np.abs(A[kept, j]), initial=0.0))
            if coupling > ZERO * scale:
                worst = choice.states[kept[int(np.argmax(np.abs(A[kept, j])))]]
                raise LinearizationError(
                    f"`{name}` is not ignorable at this point: the rate of `{worst}` depends on it "
                    f"(∂/∂{name} = {coupling:.3g}, A's scale {scale:.3g}). Keep it (remove it from `drop`), or "
                    "drop the states whose rates depend on it too.")
