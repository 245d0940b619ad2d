"""The DAE kernels of constrained Lagrange modules: ``dae_residual`` G(t, z) and ``dae_jacobian`` ∂G/∂z.

The formulation (Gear–Gupta–Leimkuhler, index 2; `lagcomp.codegen.lower.dae_residual`): z = (q, v, w, λ, μ),
Mdae z' = G(t, z), Mdae = diag(1 × 2n, 0 × (n + k + kh)), G = (v + Λ_hᵀ μ, w, M w − F − Λᵀ λ, Λ v + b, Φ).
Examples: the four-bar linkage (two holonomic rows, a closed loop), the free axle (two nonholonomic rows and
a holonomic one, n = 5) and the hoop bead with its hoop released (a time-dependent holonomic drive).

(a) At a consistent state, (q, v) projected onto the constraints, w = q̈ from `rhs` and λ from `reactions`
    (Baumgarte gains 0), μ = 0: the differential rows of G are (v, w) exactly, the algebraic rows vanish
    to a few ε times the sum of the magnitudes of their terms.
(b) Against sympy: G assembled here from the M, F, Λ, b, Φ that `lagcomp.mechanics` derives, differentiated
    by sympy (`Matrix.jacobian`) and evaluated by mpmath with 40 digits at random z and t; and a rod
    pendulum with Coulomb friction and drag (sign, Abs: the sympy path), its derivative taken away from the jump.
(c) Hypothesis over random constrained systems (`random_systems.random_mechanism`, plus a drawn
    nonholonomic or time-dependent constraint; the module run as plain Python): ``dae_jacobian`` against
    Richardson-extrapolated central differences of ``dae_residual``.
(d) The kernels pass as values of the drivers' kernel types, and ``dae_jacobian`` writes every entry.
"""

from __future__ import annotations

import dataclasses

import mpmath
import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from random_systems import python_kernels, random_mechanism
from test_rhs_jacobian import _differences as extrapolated_differences

import lagcomp as lc
from lagcomp.mechanics.lagrange import derive
from lagcomp.model import t

EPS = np.finfo(float).eps
DIGITS = 40
MODELS = ("four_bar_linkage", "free_axle", "hoop_bead_reaction")


@dataclasses.dataclass(frozen=True)
class Reference:
    """G of one model, assembled by sympy from lagcomp's derived equations, as functions of (t, z, p)."""

    size: int
    differential: int
    residual: object   # (t, z, p) -> G, mpmath
    jacobian: object   # (t, z, p) -> ∂G/∂z, mpmath
    term_sizes: object  # (t, z, p) -> Σ |terms| of each row of G, floats


def reference(system: lc.System) -> Reference:
    """G = (v + Λ_hᵀ μ, w, M w − F − Λᵀ λ, Λ v + b, Φ) from `derive(system)`, its Jacobian by sympy."""
    eom = derive(system)
    n, k, kh = eom.n, eom.k, len(eom.Phi)
    w, lam, mu = (sp.Matrix([sp.Dummy(f"{stem}{i}", real=True) for i in range(count)])
                  for stem, count in (("w", n), ("lam", k), ("mu", kh)))
    Lambda_h = sp.Matrix([eom.C.row(c) for c in range(k) if eom.holonomic[c]])
    v = sp.Matrix(eom.qd)
    G = sp.Matrix.vstack(v + Lambda_h.T * mu, w, eom.M * w - eom.F - eom.C.T * lam, eom.C * v + eom.b, eom.Phi)
    z = [*eom.q, *eom.qd, *w, *lam, *mu]
    args = (t, z, eom.parameters)
    residual = sp.lambdify(args, G, modules="mpmath", dummify=True)
    away_from_jumps = G.jacobian(z).replace(sp.DiracDelta, lambda *args: sp.S.Zero)  # sign(v)' = 0 for v ≠ 0
    jacobian = sp.lambdify(args, away_from_jumps, modules="mpmath", dummify=True)
    sizes = sp.lambdify(args, [sum(sp.Abs(term) for term in sp.Add.make_args(g)) for g in G], dummify=True)

    def exact(function):
        def at(time, state, p):
            with mpmath.workdps(DIGITS):  # float64 inputs are exact in mpmath: the reference sees the kernel's z
                values = [mpmath.mpf(float(x)) for x in state], [mpmath.mpf(float(x)) for x in p[:len(eom.parameters)]]
                return np.array(mpmath.matrix(function(mpmath.mpf(float(time)), *values)).tolist(), dtype=object)
        return at
    return Reference(size=3 * n + k + kh, differential=2 * n, residual=exact(residual), jacobian=exact(jacobian),
                     term_sizes=lambda time, state, p: np.array(sizes(time, state, p[:len(eom.parameters)]), float))


@pytest.fixture(scope="module")
def models(compiled) -> dict[str, tuple[lc.Model, Reference]]:
    return {name: (compiled(name), reference(compiled(name).system)) for name in MODELS}


def consistent_state(model: lc.Model, time: float, rng) -> np.ndarray:
    """z = (q, v, q̈, λ, 0) at a state near the default one, projected onto the constraints."""
    n, p = model.n, model.parameter_vector()  # Baumgarte gains (0, 0)
    y = model.initial_state() + rng.uniform(-0.05, 0.05, 2 * model.n)
    assert model.kernels.project(time, y, p) == 0
    accelerations = model.rhs(time, y)[n:]
    multipliers = list(model.reactions(time, y).values())
    return np.concatenate([y, accelerations, multipliers, np.zeros(model.kernels.DAE_SIZE - 3 * n - model.k)])


@pytest.mark.parametrize("name", MODELS)
def test_residual_vanishes_at_a_consistent_state(name, models, rng):
    model, ref = models[name]
    n, p = model.n, model.parameter_vector()
    assert model.kernels.DAE_SIZE == ref.size
    worst = 0.0
    for time in (0.0, 0.37):
        z = consistent_state(model, time, rng)
        G = np.full(ref.size, np.nan)
        assert model.kernels.dae_residual(time, z, p, G) == 0
        assert np.array_equal(G[:2 * n], z[n:3 * n])  # q' = v, v' = w: μ = 0 adds exact zeros
        sizes = ref.term_sizes(time, z, p)[2 * n:]
        assert np.all(G[2 * n:][sizes == 0] == 0)  # rows with no terms here (Φ = φ − φ(t) at an exact φ)
        worst = max(worst, float(np.max(np.abs(G[2 * n:]) / (EPS * np.maximum(sizes, np.finfo(float).tiny)))))
    assert worst <= 8.0, (name, worst)  # measured 0.42 (four-bar), 3.2 (free axle), 0.42 (hoop bead)


@pytest.mark.parametrize("name", MODELS)
def test_residual_and_jacobian_agree_with_sympy_to_40_digits(name, models, rng):
    model, ref = models[name]
    p = model.parameter_vector(baumgarte=(3.0, 5.0))  # the gains are in p; the DAE kernels ignore them
    for _ in range(3):
        time, z = float(rng.uniform(0.0, 0.5)), rng.uniform(-2.0, 2.0, ref.size)
        G, J = np.full(ref.size, np.nan), np.full((ref.size, ref.size), np.nan)
        assert model.kernels.dae_residual(time, z, p, G) == 0
        assert model.kernels.dae_jacobian(time, z, p, J) == 0
        G_exact, J_exact = ref.residual(time, z, p).astype(float).ravel(), ref.jacobian(time, z, p).astype(float)
        sizes = ref.term_sizes(time, z, p)
        assert np.all(np.abs(G - G_exact) <= 4 * EPS * sizes), name  # measured ≤ 0.78 ε Σ|terms|
        assert np.max(np.abs(J - J_exact)) <= 4 * EPS * np.max(np.abs(J_exact)), name  # measured ≤ 0.95 ε max|J|


def friction_rod() -> lc.System:
    """A bob on a rod in Cartesian coordinates (x, z), with Coulomb friction −c sign(ẋ) and drag −k ż |ż|:
    forces that symengine does not differentiate (the sympy path of `lagcomp.codegen.lower.dae_jacobian`)."""
    x, z = lc.coordinates("x z")
    m, g, length, c, k = sp.symbols("m g l c k", positive=True)
    xd, zd = x.diff(t), z.diff(t)
    return lc.System(coordinates=(x, z), T=m * (xd**2 + zd**2) / 2, V=m * g * z,
                     forces=(-c * sp.sign(xd), -k * zd * sp.Abs(zd)),
                     constraints=[lc.Holonomic("rod", x**2 + z**2 - length**2)],
                     parameters=(m, g, length, c, k), name="friction_rod",
                     defaults={"m": 1.3, "g": 9.81, "l": 0.8, "c": 0.4, "k": 0.25})


def test_coulomb_friction_jacobian_agrees_with_sympy_away_from_the_jump(rng):
    from lagcomp.codegen.emit import emit
    from lagcomp.codegen.lower import lower

    system = friction_rod()
    module, ref = python_kernels(emit(lower(derive(system)))), reference(system)
    p = np.array([1.3, 9.81, 0.8, 0.4, 0.25, 0.0, 0.0])
    for _ in range(3):
        z = rng.uniform(-2.0, 2.0, ref.size)
        G, J = np.full(ref.size, np.nan), np.full((ref.size, ref.size), np.nan)
        assert module["dae_residual"](0.0, z, p, G) == 0 and module["dae_jacobian"](0.0, z, p, J) == 0
        G_exact, J_exact = ref.residual(0.0, z, p).astype(float).ravel(), ref.jacobian(0.0, z, p).astype(float)
        assert np.all(np.abs(G - G_exact) <= 4 * EPS * ref.term_sizes(0.0, z, p))
        assert np.max(np.abs(J - J_exact)) <= 4 * EPS * np.max(np.abs(J_exact))
        assert J[4, 2] == 0.0  # row M w − F − Λᵀλ of x, column ẋ: c sign(ẋ) is flat away from ẋ = 0
        assert abs(J[5, 3] - 2 * 0.25 * abs(z[3])) <= 2 * EPS * J[5, 3]  # ∂(k ż |ż|)/∂ż = 2 k |ż|


def test_jacobian_blocks_are_those_of_the_formulation(models, rng):
    """Four-bar linkage (n = 3, k = kh = 2): the identities and zeros of the block structure, exactly."""
    model, ref = models["four_bar_linkage"]
    n, k, p = 3, 2, model.parameter_vector()
    z = rng.uniform(-1.0, 1.0, ref.size)
    J = np.full((ref.size, ref.size), np.nan)
    assert model.kernels.dae_jacobian(0.2, z, p, J) == 0
    q, v, w, lam, mu = (slice(a, b) for a, b in ((0, n), (n, 2 * n), (2 * n, 3 * n), (3 * n, 3 * n + k),
                                                  (3 * n + k, 3 * n + 2 * k)))
    identity, zero = np.eye(n), lambda rows, cols: np.zeros((rows.stop - rows.start, cols.stop - cols.start))  # noqa: E731
    assert np.array_equal(J[q, v], identity) and np.array_equal(J[v, w], identity)
    for rows, cols in ((q, w), (q, lam), (v, q), (v, v), (v, lam), (v, mu), (w, mu), (lam, w), (lam, lam),
                       (lam, mu), (mu, v), (mu, w), (mu, lam), (mu, mu)):
        assert np.array_equal(J[rows, cols], zero(rows, cols)), (rows, cols)
    C = np.empty((k, n + 1))
    model.kernels.constraint_matrix(0.2, z[:2 * n], p, C)
    M = np.empty((n, n))
    model.kernels.mass_matrix(0.2, z[:2 * n], p, M)
    np.testing.assert_allclose(J[q, mu], C[:, :n].T, rtol=2 * EPS, atol=0)  # Λ_hᵀ: both rows holonomic
    np.testing.assert_allclose(J[w, lam], -C[:, :n].T, rtol=2 * EPS, atol=0)
    np.testing.assert_allclose(J[lam, v], C[:, :n], rtol=2 * EPS, atol=0)
    np.testing.assert_allclose(J[mu, q], C[:, :n], rtol=2 * EPS, atol=0)
    np.testing.assert_allclose(J[w, w], M, rtol=2 * EPS, atol=0)


def test_kernels_are_values_of_the_drivers_kernel_types(models):
    """``dae_residual`` and ``dae_jacobian`` have the signatures of ``rhs`` and ``rhs_jacobian``
    (`kernel_types.RHS`, `RHS_JACOBIAN`), as the radau driver takes them; every entry of `out` is written."""
    from numba import njit, types

    from lagcomp.integrate.drivers.kernel_types import FLOAT, MATRIX, RHS, RHS_JACOBIAN, VECTOR

    @njit(types.int64(RHS, RHS_JACOBIAN, FLOAT, VECTOR, VECTOR, VECTOR, MATRIX))
    def call(residual, jacobian, time, z, p, G, J):
        return residual(time, z, p, G) + jacobian(time, z, p, J)

    model, ref = models["free_axle"]
    z, p = np.linspace(-1.0, 1.0, ref.size), model.parameter_vector()
    G, J = np.full(ref.size, np.nan), np.full((ref.size, ref.size), np.nan)
    assert call(model.kernels.dae_residual, model.kernels.dae_jacobian, 0.1, z, p, G, J) == 0
    assert np.all(np.isfinite(G)) and np.all(np.isfinite(J))
    J_again = np.full_like(J, 7.0)  # reused arrays: the zeros are written too
    assert model.kernels.dae_jacobian(0.1, z, p, J_again) == 0
    assert np.array_equal(J_again, J)


def _extra_constraint(kind: str, mech, rng) -> lc.Holonomic | lc.Nonholonomic:
    """A random constraint on the mechanism's coordinates: linear in q̇ with q- and t-dependent coefficients
    (nonholonomic), or a holonomic relation with an explicit time dependence (rheonomic)."""
    q = mech.coordinates
    c = [sp.Float(round(float(x), 3)) for x in rng.uniform(0.5, 1.5, 2 * len(q) + 2)]
    if kind == "nonholonomic":
        expr = sum(((c[j] + c[len(q) + j] * sp.sin(q[(j + 1) % len(q)])) * q[j].diff(t) for j in range(len(q))),
                   c[-1] * sp.cos(c[-2] * t))
        return lc.Nonholonomic("skate", expr)
    start = dict(zip(q, mech.q0, strict=True))
    relation = c[0] * sp.sin(q[0]) + c[1] * q[-1] ** 2 * sp.cos(c[2] * t)
    return lc.Holonomic("driven", relation - float(relation.xreplace(start).xreplace({t: 0}).evalf()))


@settings(max_examples=8, deadline=None, derandomize=True, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1),
       extra=st.sampled_from([("nonholonomic",), ("rheonomic",), ("nonholonomic", "rheonomic")]))
def test_random_constrained_systems_jacobian_agrees_with_central_differences(seed, extra):
    """The mechanism's holonomic constraints and the `extra` ones, as many as k ≤ n allows."""
    from lagcomp.codegen.emit import emit
    from lagcomp.codegen.lower import lower

    mech, rng = random_mechanism(seed), np.random.default_rng(seed)
    constraints = list(mech.system.constraints)
    for kind in extra:
        if len(constraints) < len(mech.coordinates):
            constraints.append(_extra_constraint(kind, mech, rng))
    eom = derive(dataclasses.replace(mech.system, constraints=tuple(constraints)))
    module = python_kernels(emit(lower(eom)))
    size = module["DAE_SIZE"]
    assert size == 3 * eom.n + eom.k + len(eom.Phi)
    z = np.concatenate([mech.q0, mech.qd0, rng.uniform(-1.0, 1.0, size - 2 * eom.n)])
    p = np.concatenate([mech.values, [0.7, 0.3]])  # Baumgarte gains, ignored
    J = np.full((size, size), np.nan)
    assert module["dae_jacobian"](0.3, z, p, J) == 0
    D, tolerance = extrapolated_differences(module["dae_residual"], 0.3, z, p, h=1e-2)
    excess = np.abs(J - D) - tolerance  # measured |J − D| ≤ 4e-11, 10-30 times below the tolerance
    assert np.all(excess <= 0), f"{mech.description} + {extra}: off by {np.max(excess):.3g} beyond the tolerance"
