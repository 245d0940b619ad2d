"""The Hamiltonian form: H(q, p, t) and the Jacobian of the canonical equations.

References are built here from the Lagrangian alone, with an explicit
inverse of the mass matrix (fine for small systems, and independent of the
kernels' numerical solves): p = ∂L/∂q̇ = M q̇ + b, v = M⁻¹ (p − b),
H = p·v − L(q, v, t) = ½ (p − b)·v − L(q, 0, t) (L is quadratic in q̇), and
Hamilton's equations with forces, f = (∂H/∂p, −∂H/∂q + Q − ∂D/∂q̇) at q̇ = v.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.mechanics.lagrange import state_symbols, to_plain

t = lc.t


@pytest.fixture(scope="module")
def rotating_trap(cache_dir):
    """A particle in an anharmonic trap turning at rate Ω, damped along x, in the rotating frame.

    T = ½ m ((ẋ − Ω y)² + (ẏ + Ω x)²): momenta p = m q̇ + m Ω (−y, x), an offset
    b(q) ≠ 0, and gyroscopic forces, so every block of the Jacobian is non-zero.
    """
    x, y = lc.coordinates("x y")
    m, Omega, k1, k2, eps, c = sp.symbols("m Omega k1 k2 epsilon c", positive=True)
    xd, yd = x.diff(t), y.diff(t)
    system = lc.System(
        [x, y], T=m * ((xd - Omega * y) ** 2 + (yd + Omega * x) ** 2) / 2,
        V=(k1 * x**2 + k2 * y**2) / 2 + eps * x**2 * y, dissipation=c * xd**2 / 2, name="rotating_trap",
        defaults={"m": 1.3, "Omega": 0.7, "k1": 2.0, "k2": 3.0, "epsilon": 0.4, "c": 0.3},
    )
    return lc.compile(system, cache_dir=cache_dir)


def _model(request, compiled, name):
    return request.getfixturevalue(name) if name == "rotating_trap" else compiled(name)


_references: dict = {}


def _reference(system):
    """Lambdified H(q, p, t, params), f(q, p, t, params) and ∂f/∂x, each from L (and Q, D) alone."""
    if system.name not in _references:
        _references[system.name] = _derive_reference(system)
    return _references[system.name]


def _derive_reference(system):
    q, qd = state_symbols(system)
    n = len(q)

    def plain(expr):
        return to_plain(sp.sympify(expr), system, q, qd)

    L, D = plain(system.T - system.V), plain(system.dissipation)
    Q = sp.Matrix([plain(Qi) for Qi in system.forces])  # normalized to one per coordinate
    p = sp.Matrix(sp.symbols(f"p0:{n}", real=True))
    at_rest = {v: 0 for v in qd}
    momenta = sp.Matrix([L.diff(v) for v in qd])
    M = momenta.jacobian(qd)
    b = momenta.subs(at_rest)
    v = M.inv(method="ADJ") * (p - b)
    at_v = dict(zip(qd, v))
    # L = ½ q̇ᵀ M q̇ + bᵀ q̇ + L₀: H = p·v − L(q, v) = ½ (p − b)ᵀ v − L₀ (smaller to differentiate)
    H = ((p - b).T * v)[0] / 2 - L.subs(at_rest)
    forces = (Q - sp.Matrix([D.diff(vi) for vi in qd])).subs(at_v)
    f = sp.Matrix.vstack(sp.Matrix([H.diff(pi) for pi in p]), sp.Matrix([-H.diff(qi) for qi in q]) + forces)
    args = (q, tuple(p), t, system.parameters)
    return tuple(sp.lambdify(args, e, "numpy", cse=True) for e in (H, f, f.jacobian((*q, *p))))


def _states(model, rng, count=5):
    """Random (t, x) with x = (q, p), p the momenta of random velocities."""
    for _ in range(count):
        q, qd, time = rng.uniform(-1.5, 1.5, model.n), rng.uniform(-2, 2, model.n), rng.uniform(0, 5)
        yield time, model.canonical_state(q, qd, time)


def _canonical_rhs(model, time, x, p):
    """f(x) = (q̇, ṗ) from the kernels the integrator uses (``velocities``, ``momentum_rate``)."""
    n = model.n
    v, rate = np.empty(n), np.empty(n)
    assert model.kernels.velocities(time, x, p, v) == 0
    model.kernels.momentum_rate(time, np.concatenate([x[:n], v]), p, rate)
    return np.concatenate([v, rate])


SYSTEMS = ["double_pendulum", "driven_pendulum", "rotating_trap"]


@pytest.mark.parametrize("name", SYSTEMS)
def test_hamiltonian_is_the_legendre_transform(request, compiled, rng, name):
    model = _model(request, compiled, name)
    H, _, _ = _reference(model.system)
    p = model.parameter_vector()
    for time, x in _states(model, rng):
        n = model.n
        expected = float(H(x[:n], x[n:], time, p))
        assert model.hamiltonian(time, x) == pytest.approx(expected, rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("name", SYSTEMS)
def test_canonical_jacobian_matches_sympy_and_finite_differences(request, compiled, rng, name):
    model = _model(request, compiled, name)
    _, f, jacobian = _reference(model.system)
    p, n = model.parameter_vector(), model.n
    for time, x in _states(model, rng):
        J = model.canonical_jacobian(time, x)
        scale = np.abs(J).max()
        # the kernels' canonical equations are Hamilton's equations with forces ...
        np.testing.assert_allclose(_canonical_rhs(model, time, x, p), np.ravel(f(x[:n], x[n:], time, p)),
                                   rtol=1e-12, atol=1e-12)
        # ... and J is their Jacobian
        np.testing.assert_allclose(J, np.asarray(jacobian(x[:n], x[n:], time, p), dtype=float),
                                   rtol=1e-11, atol=1e-12 * scale)
        step = 1e-6 * (1 + np.abs(x))
        columns = [(_canonical_rhs(model, time, x + e * h, p) - _canonical_rhs(model, time, x - e * h, p)) / (2 * h)
                   for e, h in zip(np.eye(2 * n), step)]
        np.testing.assert_allclose(J, np.array(columns).T, rtol=0, atol=1e-8 * scale)


def test_canonical_state_and_hamiltonian_agree_with_the_energy_function(compiled, rng):
    model = compiled("driven_pendulum")  # b(q, t) ≠ 0: p is not M q̇
    for _ in range(3):
        q, qd, time = rng.uniform(-2, 2, 1), rng.uniform(-2, 2, 1), rng.uniform(0, 1)
        x = model.canonical_state(q, qd, time)
        np.testing.assert_array_equal(x, np.concatenate([q, model.momenta(q, qd, time)]))
        assert model.hamiltonian(time, x) == pytest.approx(model.energy_function(q, qd, time), rel=1e-13, abs=1e-13)


def test_hamiltonian_errors(compiled):
    model = compiled("double_pendulum")
    # m1 = 0 and θ1 = θ2: the two masses move as one, M is singular
    with pytest.raises(lc.SingularMassMatrixError, match="singular at t=0"):
        model.canonical_jacobian(0.0, [0.3, 0.3, 1.0, 1.0], params={"m1": 0.0})
    with pytest.raises(lc.SingularMassMatrixError, match="pivot 2"):
        model.hamiltonian(0.0, [0.3, 0.3, 1.0, 1.0], params={"m1": 0.0})
    with pytest.raises(lc.InitialConditionError, match=r"shape \(4,\)"):
        model.hamiltonian(0.0, [0.3, 0.3, 1.0])
    with pytest.raises(lc.ModelError, match="unconstrained system"):
        compiled("spherical_pendulum_cartesian").canonical_jacobian(0.0, np.zeros(6))
