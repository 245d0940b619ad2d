r"""Small oscillations about an equilibrium: linearization, normal modes, stability.

Near an equilibrium q* (F(q*, 0, t) = 0, so q̈ = 0 there and the variation of
M multiplies a vanishing q̈), M q̈ = F(q, q̇, t) becomes, for q = q* + δq,

    M₀ δq̈ + (G₀ + D₀) δq̇ + K₀ δq = 0,

    M₀ = M(q*, t),   K₀ = −∂F/∂q,   C₀ = −∂F/∂q̇ = G₀ + D₀   at (q*, 0, t),

G₀ = (C₀ − C₀ᵀ)/2 the gyroscopic (skew) part — Coriolis forces of a rotating
frame or an imposed rotation — and D₀ = (C₀ + C₀ᵀ)/2 the damping.  For a
conservative system K₀ is the Hessian of the (effective) potential and is
symmetric; a non-symmetric K₀ means circulatory forces.

Without G₀ and D₀ and with K₀ symmetric, δq = v cos(ω t) gives the
generalized symmetric eigenproblem K₀ v = ω² M₀ v (`scipy.linalg.eigh`): real
ω² whose signs decide stability, M₀-orthonormal mode shapes.  Otherwise
δq = v e^{λt} gives the quadratic eigenproblem (λ² M₀ + λ C₀ + K₀) v = 0,
solved through its first-order companion form; frequencies are |Im λ|, and
stability needs every Re λ ≤ 0 (gyroscopic stabilization is only ever
linear, "marginal", stability: Re λ = 0).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import linalg

from lagcomp.analysis._common import RestForces, coordinates_vector, relative_residual
from lagcomp.analysis.body_outputs import point_rows
from lagcomp.analysis.statics import RESIDUAL_TOLERANCE
from lagcomp.errors import LinearizationError, ModelError

#: Relative size below which G₀, D₀, asymmetry and Re λ count as zero.
ZERO = 1e-10


@dataclass(frozen=True)
class Linearization:
    """M₀ δq̈ + (G₀ + D₀) δq̇ + K₀ δq = 0 about the configuration `q` (module docstring).

    Attributes
    ----------
    q : ndarray, shape (n,)
    t : float
    M, K, G, D : ndarray, shape (n, n)
        Mass, stiffness, gyroscopic and damping matrices at (q, 0, t).
    residual : float
        max |F(q, 0, t)|: the linearization is about an equilibrium only when it is ~0.
    force : ndarray, shape (n,)
        F(q, 0, t).
    force_scale : ndarray, shape (n,)
        The size of the terms each F_i balances (`lagcomp.analysis._common.RestForces.force_scale`), what
        "F = 0" is judged against.
    coordinates : tuple of str
    params : dict
    inputs : tuple of str
        The model's inputs (`lagcomp.Input` supplied at run time), held at the values `linearize` was given.
    H : ndarray, shape (n, U), or None
        ∂F/∂u at the point: the generalized forces per unit of each input (M₀ δq̈ + ... = H δu); None without
        inputs, or where the equations read an input's derivatives (`input_refused` says so).
    input_refused : str or None
    outputs : tuple of str or None
        The outputs `linearize` was asked for: `state_space`'s default.
    output_rows : dict of str to (ndarray (2n,), ndarray (U,))
        The rows of C and D of the points of bodies among `outputs` (`lagcomp.analysis.body_outputs`).
    """

    q: np.ndarray
    t: float
    M: np.ndarray
    K: np.ndarray
    G: np.ndarray
    D: np.ndarray
    residual: float
    force: np.ndarray
    force_scale: np.ndarray
    coordinates: tuple
    params: dict = field(default_factory=dict)
    inputs: tuple = ()
    H: np.ndarray | None = None
    input_refused: str | None = None
    outputs: tuple | None = None
    output_rows: dict = field(default_factory=dict)

    def state_space(self, outputs=None):
        """ẋ = A x + B w, z = C x + D w (`lagcomp.analysis.StateSpace`) with x = (δq, δq̇), w = δu:
        A = [[0, I], [−M₀⁻¹K₀, −M₀⁻¹C₀]], B = [[0], [M₀⁻¹H]]; z what `outputs` names: states (coordinates,
        ``<coordinate>_dot``) and the points of bodies `linearize` was asked for (`output_rows`); by default the
        outputs given to `linearize`, else every state.  LinearizationError where no B exists (`input_refused`)."""
        from lagcomp.analysis.state_space import StateSpace

        if self.input_refused:
            raise LinearizationError(f"No input matrix B: {self.input_refused}")
        n = len(self.coordinates)
        A = np.block([[np.zeros((n, n)), np.eye(n)],
                      [-linalg.solve(self.M, self.K, assume_a="sym"), -linalg.solve(self.M, self.C, assume_a="sym")]])
        H = np.zeros((n, 0)) if self.H is None else self.H
        B = np.vstack([np.zeros_like(H), linalg.solve(self.M, H, assume_a="sym")])
        states = (*self.coordinates, *(f"{c}_dot" for c in self.coordinates))
        return StateSpace.of_states(A, B, states, self.inputs, self.outputs if outputs is None else outputs,
                                    rows=self.output_rows)

    @property
    def C(self) -> np.ndarray:
        """The whole velocity matrix G + D = −∂F/∂q̇."""
        return self.G + self.D

    def normalized(self, a: np.ndarray) -> np.ndarray:
        """``a`` (n, n) in the coordinates' own units: D a D with D = diag(1/√M_ii), so that D M D has a unit
        diagonal, D K D is in 1/time², D C D in 1/time, whatever the units of each coordinate."""
        d = 1.0 / np.sqrt(np.abs(np.diag(self.M)))
        return d[:, None] * a * d[None, :]

    @property
    def rate_scale(self) -> float:
        """A rate (1/time) for judging Re λ and the velocity terms: √max|D K D| + max|D C D| (`normalized`), in
        the units of time only (0 when K and C vanish)."""
        return float(np.sqrt(np.max(np.abs(self.normalized(self.K)))) + np.max(np.abs(self.normalized(self.C))))

    def _small(self, a: np.ndarray, power: int) -> bool:
        """Whether ``a`` is negligible against the rate scale to ``power`` (1 for G, D; 2 for a stiffness),
        in the normalized coordinates (the same verdict in any units)."""
        return float(np.max(np.abs(self.normalized(a)))) <= ZERO * self.rate_scale ** power

    def __repr__(self) -> str:
        where = ", ".join(f"{c}={v:.8g}" for c, v in zip(self.coordinates, self.q))
        kind = "conservative" if self.conservative else "with gyroscopic/damping/circulatory terms"
        return f"Linearization({where}, t={self.t:g}, {kind}, residual={self.residual:.2g})"

    @property
    def conservative(self) -> bool:
        """No gyroscopic or damping terms and a symmetric stiffness: the eigh case."""
        return self._small(self.G, 1) and self._small(self.D, 1) and self._small(self.K - self.K.T, 2)


@dataclass(frozen=True)
class Modes:
    """Normal modes of a `Linearization`.

    Attributes
    ----------
    frequencies : ndarray, shape (m,)
        Angular frequencies ω of the oscillating modes, ascending.
    shapes : ndarray, shape (n, m)
        Their mode shapes (columns): real and M₀-orthonormal in the
        conservative case, complex otherwise (the v of λ = iω).
    omega2 : ndarray, shape (n,), or None
        Conservative case: all eigenvalues ω² of K₀ v = ω² M₀ v, ascending
        (negative: exponential divergence at rate √−ω²).
    eigenvalues : ndarray of complex, shape (2n,)
        λ of (λ² M₀ + λ C₀ + K₀) v = 0, by decreasing real part.
    growth_rate : float
        Largest Re λ.
    stability : str
        "asymptotically stable" (every Re λ < 0), "stable" (conservative,
        every ω² > 0), "marginal" (some Re λ = 0 or ω² = 0, others stable:
        linear theory cannot decide), or "unstable" (some Re λ > 0).
    linearization : Linearization
    """

    frequencies: np.ndarray
    shapes: np.ndarray
    omega2: np.ndarray | None
    eigenvalues: np.ndarray
    growth_rate: float
    stability: str
    linearization: Linearization

    @property
    def stable(self) -> bool:
        """Linearly stable: no growing mode ("stable", "asymptotically stable" or "marginal" with Re λ = 0)."""
        return self.stability != "unstable"

    def __repr__(self) -> str:
        return (f"Modes({self.stability}, frequencies={np.array2string(self.frequencies, precision=6)}, "
                f"growth_rate={self.growth_rate:.3g})")


def linearize(model, q, params: dict | None = None, *, t: float = 0.0, inputs=None, outputs=None) -> Linearization:
    """M₀, K₀, G₀, D₀ about the configuration `q` (an equilibrium, e.g. `find_equilibrium(...).q`).

    A model with inputs (`lagcomp.Input` supplied at run time) is linearized with them held at `inputs`
    (a number per input, by name), and `Linearization.H` = ∂F/∂u there gives the input matrix of
    `Linearization.state_space` (the exact ``rhs_input_jacobian`` kernel, built on first use).

    `outputs` names the outputs of `Linearization.state_space`: states (``x``, ``x_dot``) and points of the
    System's bodies, ``"<body>.x"`` (``.y``, ``.z``; ``.vx``, ``.vy``, ``.vz`` for the velocity), whose rows of C
    are the exact derivatives of the body's position there (`lagcomp.analysis.body_outputs`).

    Constrained systems, and steady motions (q̇ ≠ 0), are linearized by
    `lagcomp.analysis.linearize_steady` (a first-order state matrix on the
    constraint manifold); this function refuses them with a pointer there.
    """
    if model.k:
        raise ModelError(
            f"linearize (M₀, K₀, G₀, D₀) needs an unconstrained system: {model.name!r} has constraints "
            f"{list(model.constraints)}. Use lagcomp.analysis.linearize_steady(model, q, qd), which reduces the "
            "linearization to independent coordinates and speeds on the constraints."
        )
    q = coordinates_vector(model, q)
    rest = RestForces(model, params, t, inputs)
    F_q, F_v = rest.partials(q)
    C, M = -F_v, rest.mass_matrix(q)
    H, refused = _input_forces(model, q, M, rest, inputs)
    force = rest.force(q)
    outputs = None if outputs is None else ((outputs,) if isinstance(outputs, str) else tuple(outputs))
    return Linearization(
        q=q, t=float(t), M=M, K=-F_q, G=(C - C.T) / 2, D=(C + C.T) / 2,
        residual=float(np.max(np.abs(force))), force=force, force_scale=rest.force_scale(q, force, RESIDUAL_TOLERANCE),
        coordinates=model.coordinates, params=rest.params, inputs=model.inputs, H=H, input_refused=refused,
        outputs=outputs, output_rows=point_rows(model, q, float(t), rest.params, outputs or ()),
    )


def _input_forces(model, q, M, rest: RestForces, inputs) -> tuple[np.ndarray | None, str | None]:
    """(H = ∂F/∂u at (q, 0), None) from the ``rhs_input_jacobian`` kernel (M ∂q̈/∂u), or (None, why not)."""
    if not model.inputs:
        return None, None
    y = np.concatenate([q, np.zeros(model.n)])
    try:
        jacobian = model.rhs_input_jacobian(rest.t, y, rest.params_given, inputs)
    except ModelError as err:
        return None, str(err)
    return M @ jacobian[model.n:], None


def normal_modes(model_or_linearization, q=None, params: dict | None = None, *, t: float = 0.0) -> Modes:
    """Normal-mode frequencies and shapes and the stability verdict at an equilibrium.

    Pass a `Linearization`, or a model and the equilibrium coordinates `q`
    (with `params`, `t`).  See the module docstring for the two cases.  A q
    that is no equilibrium is a LinearizationError (`_check_equilibrium`): the
    modes of the linearization about it say nothing of the motion there.
    """
    lin = model_or_linearization
    if not isinstance(lin, Linearization):
        lin = linearize(lin, q, params, t=t)
    _check_equilibrium(lin)
    quadratic = _quadratic_eigenvalues(lin)
    growth = float(np.max(quadratic.real))
    scale = lin.rate_scale
    if lin.conservative:
        K = (lin.K + lin.K.T) / 2
        omega2, vectors = linalg.eigh(K, lin.M)
        tiny = np.abs(omega2) <= ZERO * max(float(np.max(np.abs(omega2))), 1e-300)
        oscillating = (omega2 > 0) & ~tiny
        if np.any((omega2 < 0) & ~tiny):
            stability = "unstable"
        elif np.any(tiny):
            stability = "marginal"
        else:
            stability = "stable"
        return Modes(frequencies=np.sqrt(omega2[oscillating]), shapes=vectors[:, oscillating], omega2=omega2,
                     eigenvalues=quadratic, growth_rate=growth, stability=stability, linearization=lin)
    if growth > ZERO * scale:
        stability = "unstable"
    elif growth < -ZERO * scale:
        stability = "asymptotically stable"
    else:
        stability = "marginal"
    # one eigenvalue of each conjugate pair (Im λ > 0), ascending in frequency
    upper = np.flatnonzero(quadratic.imag > ZERO * scale)
    order = upper[np.argsort(quadratic.imag[upper])]
    vectors = _quadratic_vectors(lin, quadratic[order])
    return Modes(frequencies=quadratic.imag[order], shapes=vectors, omega2=None, eigenvalues=quadratic,
                 growth_rate=growth, stability=stability, linearization=lin)


def _check_equilibrium(lin: Linearization) -> None:
    """Refuse a linearization about a q where F(q, 0, t) ≠ 0.

    "F = 0" is judged as `find_equilibrium` judges it: each |F_i| against its own force scale
    (`RestForces.force_scale`: Σ_j |K₀_ij| |q_j|, and the parameters' terms where needed, in F_i's units), with
    the same `RESIDUAL_TOLERANCE`, so every equilibrium it reports as found passes, in any units.
    """
    ratio, worst = relative_residual(lin.force, lin.force_scale)
    scale = lin.force_scale[worst]
    if not ratio <= RESIDUAL_TOLERANCE:
        point = ", ".join(f"{name}={value:.6g}" for name, value in zip(lin.coordinates, lin.q))
        raise LinearizationError(
            f"q = ({point}) is not an equilibrium: max |F(q, 0, t)| = {lin.residual:.3g}; the worst force is "
            f"{ratio:.3g} times its scale {scale:.3g} (Σ_j |∂F_i/∂q_j| |q_j| + Σ_m |∂F_i/∂p_m| |p_m|, the size of the "
            "forces that balance), "
            f"above the {RESIDUAL_TOLERANCE:g} that counts as zero, so the bodies accelerate there and its normal "
            "modes would describe no motion. Find an equilibrium with lagcomp.analysis.find_equilibrium (or "
            "equilibria), or for a steady motion use linearize_steady.")


def _quadratic_eigenvalues(lin: Linearization) -> np.ndarray:
    """λ of (λ² M + λ C + K) v = 0 from the companion form [[0, I], [−M⁻¹K, −M⁻¹C]], by decreasing Re λ."""
    n = lin.M.shape[0]
    MK = linalg.solve(lin.M, lin.K, assume_a="sym")
    MC = linalg.solve(lin.M, lin.C, assume_a="sym")
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-MK, -MC]])
    values = linalg.eigvals(A)
    return values[np.lexsort((-values.imag, -values.real))]


def _quadratic_vectors(lin: Linearization, values: np.ndarray) -> np.ndarray:
    """Null vectors of λ² M + λ C + K for each λ (smallest singular vector), unit 2-norm."""
    shapes = np.empty((lin.M.shape[0], values.size), dtype=complex)
    for j, lam in enumerate(values):
        _, _, vh = linalg.svd(lam**2 * lin.M + lam * lin.C + lin.K)
        shapes[:, j] = vh[-1].conj()
    return shapes


# -- symbolic --------------------------------------------------------------------------


def linearize_symbolic(system, q, *, subs: dict | None = None, eom=None, simplify: bool = True) -> dict:
    """M₀, K₀, G₀, D₀ as sympy matrices at the configuration `q`, and the frequency equation.

    Parameters
    ----------
    system : System
    q : sequence of expressions, or dict
        The equilibrium: one sympy expression per coordinate (in the
        parameters, e.g. ``acos(-g/(R*Omega**2))``), or a mapping from
        coordinate names to them.
    subs : dict, optional
        Parameter values (by name or symbol) to substitute first, e.g.
        ``{"epsilon": 0}`` to make an imposed motion steady.

    Returns
    -------
    dict
        ``M``, ``K``, ``G``, ``D`` (sympy Matrices), ``omega2`` (the symbol
        ω² of the frequency equation), ``characteristic`` (det(K − ω² M), a
        polynomial in ω², meaningful when G = D = 0) and ``omega2_roots``
        (its roots, for n ≤ 2; the general quadratic eigenproblem has no
        closed form to offer).
    """
    import sympy as sp

    from lagcomp.mechanics.lagrange import derive, rest_partials

    eom = derive(system) if eom is None else eom
    values = [q[name] for name in system.coordinate_names] if isinstance(q, dict) else list(q)
    by_name = {s.name: s for s in eom.parameters}
    given = {(by_name[k] if isinstance(k, str) else k): sp.sympify(v) for k, v in (subs or {}).items()}
    at = {**given, **{qi: sp.sympify(v).xreplace(given) for qi, v in zip(eom.q, values)}}
    tidy = sp.simplify if simplify else (lambda e: e)
    F_q, F_v = (m.xreplace(at).doit() for m in rest_partials(eom))
    C = -F_v
    result = {
        "M": eom.M.xreplace(at).applyfunc(tidy), "K": (-F_q).applyfunc(tidy),
        "G": ((C - C.T) / 2).applyfunc(tidy), "D": ((C + C.T) / 2).applyfunc(tidy),
    }
    w2 = sp.Symbol("omega2")
    result["omega2"] = w2
    result["characteristic"] = sp.expand((result["K"] - w2 * result["M"]).det())
    result["omega2_roots"] = [tidy(r) for r in sp.solve(result["characteristic"], w2)] if eom.n <= 2 else None
    return result
