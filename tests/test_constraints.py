"""Constraints and reactions on small systems whose answers are known in closed form."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.model import Holonomic, Nonholonomic

t = lc.t
m, g, l, R, w, alpha = sp.symbols("m g l R omega alpha", positive=True)


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("constraints-cache")


@pytest.fixture(scope="module")
def planar_pendulum(cache):
    """Bob at (x, y), y up, on a rod of length l from the origin: Φ = x² + y² − l²."""
    x, y = lc.coordinates("x y")
    system = lc.System([x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=m * g * y,
                       constraints=[Holonomic("rod", x**2 + y**2 - l**2)], name="planar_pendulum",
                       defaults={"m": 1.5, "g": 9.81, "l": 0.8})
    return lc.compile(system, cache_dir=cache)


def _polar_state(theta, theta_dot, length):
    """Cartesian state of a bob at angle θ from the downward vertical."""
    q = length * np.array([np.sin(theta), -np.cos(theta)])
    qd = length * theta_dot * np.array([np.cos(theta), np.sin(theta)])
    return np.concatenate([q, qd])


def test_rod_tension_sign_and_size(planar_pendulum, rng):
    # Λ = 2(x, y): the rod pulls the bob with 2λ r, so the tension is −2λl = m g cos θ + m l θ̇²
    d = planar_pendulum.system.defaults
    for theta, theta_dot in rng.uniform([-3, -4], [3, 4], (10, 2)):
        y = _polar_state(theta, theta_dot, d["l"])
        lam = planar_pendulum.reactions(0.0, y)["rod"]
        tension = d["m"] * d["g"] * np.cos(theta) + d["m"] * d["l"] * theta_dot**2
        assert -2 * lam * d["l"] == pytest.approx(tension, rel=1e-12, abs=1e-12)
        # the accelerations are those of the pendulum equation θ̈ = −(g/l) sin θ
        theta_ddot = -d["g"] / d["l"] * np.sin(theta)
        ax = d["l"] * (theta_ddot * np.cos(theta) - theta_dot**2 * np.sin(theta))
        ay = d["l"] * (theta_ddot * np.sin(theta) + theta_dot**2 * np.cos(theta))
        np.testing.assert_allclose(planar_pendulum.rhs(0.0, y)[2:], [ax, ay], rtol=1e-11, atol=1e-11)


def test_turning_rod_constraint_with_explicit_time(cache):
    # bead on a rod turning at ω in a horizontal plane: Φ = x sin ωt − y cos ωt (the ∂/∂t terms matter)
    x, y = lc.coordinates("x y")
    system = lc.System([x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2,
                       constraints=[Holonomic("rod", x * sp.sin(w * t) - y * sp.cos(w * t))],
                       name="turning_rod", defaults={"m": 0.3, "omega": 2.0})
    model = lc.compile(system, cache_dir=cache)
    a, omega, mass = 0.1, 2.0, 0.3
    ts = np.linspace(0, 2, 21)
    sol = model.simulate((0, 2), q0=[a, 0.0], qd0=[0.0, a * omega], t_eval=ts, method="dop853", rtol=1e-12, atol=1e-14)
    rho = np.hypot(sol.q[:, 0], sol.q[:, 1])
    np.testing.assert_allclose(rho, a * np.cosh(omega * ts), rtol=1e-9)
    # normal force 2mωρ̇ along n = (−sin ωt, cos ωt); Λ = (sin ωt, −cos ωt) = −n, so λ = −2mωρ̇
    np.testing.assert_allclose(sol.reactions["rod"], -2 * mass * omega * a * omega * np.sinh(omega * ts), rtol=1e-8, atol=1e-12)
    assert sol.constraint_residual < 1e-9


def test_singular_mass_matrix_with_regular_constraints(cache):
    # massless hoop rolling down a slope, a point mass at its centre: M = diag(m, 0) is singular,
    # the rolling constraint ẋ = R θ̇ makes the augmented system regular
    x, theta = lc.coordinates("x theta")
    system = lc.System([x, theta], T=m * x.diff(t) ** 2 / 2, V=-m * g * sp.sin(alpha) * x,
                       constraints=[Nonholonomic("rolling", x.diff(t) - R * theta.diff(t))],
                       name="massless_hoop", defaults={"m": 2.0, "g": 9.81, "R": 0.5, "alpha": 0.3})
    model = lc.compile(system, cache_dir=cache)
    sol = model.simulate((0, 1), q0=[0.0, 0.0], qd0=[0.4, 0.8], method="dop853", rtol=1e-12, atol=1e-12)
    accel = 9.81 * np.sin(0.3)
    assert sol.q[-1, 0] == pytest.approx(0.4 + accel / 2, rel=1e-12, abs=0)
    assert sol.qd[-1, 1] == pytest.approx((0.4 + accel) / 0.5, rel=1e-12, abs=0)
    np.testing.assert_allclose(sol.reactions["rolling"], 0.0, atol=1e-12)  # a massless hoop needs no friction


def test_inconsistent_initial_state_is_refused_or_projected(planar_pendulum):
    with pytest.raises(lc.InitialConditionError, match=r"constraint `rod` at position level by 0\.08"):
        planar_pendulum.simulate((0, 1), q0=[0.6, -0.6], qd0=[0, 0])  # x² + y² − l² = 0.72 − 0.64 ≈ 0.08
    with pytest.raises(lc.InitialConditionError, match=r"constraint `rod` at velocity level"):
        planar_pendulum.simulate((0, 1), q0=[0.0, -0.8], qd0=[0.0, 1.0])
    sol = planar_pendulum.simulate((0, 1), q0=[0.6, -0.6], qd0=[0.0, 1.0], project_initial=True)
    start = sol.projected_initial_state
    assert np.hypot(start[0], start[1]) == pytest.approx(0.8, rel=1e-14, abs=0)
    assert start[0] * start[2] + start[1] * start[3] == pytest.approx(0.0, abs=1e-14)
    assert sol.success and sol.constraint_residual < 1e-8


def test_projection_holds_the_constraint_over_a_million_rk4_steps(planar_pendulum):
    y0 = _polar_state(1.2, 0.0, 0.8)
    sol = planar_pendulum.simulate((0, 1000), q0=y0[:2], qd0=y0[2:], method="rk4", dt=1e-3, save_every=10_000)
    assert sol.nsteps == 1_000_000 and sol.success
    assert sol.constraint_residual < 1e-10
    free = planar_pendulum.simulate((0, 1000), q0=y0[:2], qd0=y0[2:], method="rk4", dt=1e-3, save_every=10_000,
                                    projection=False)
    assert free.constraint_residual > 1e-8  # drift is reported, not hidden
    stabilized = planar_pendulum.simulate((0, 1000), q0=y0[:2], qd0=y0[2:], method="rk4", dt=1e-3,
                                          save_every=10_000, projection=False, baumgarte=(5.0, 5.0))
    assert stabilized.constraint_residual < free.constraint_residual / 10


def test_bad_constraints_are_refused():
    x, y = lc.coordinates("x y")
    with pytest.raises(lc.ModelError, match="contains velocities"):
        lc.System([x, y], T=m * x.diff(t) ** 2, constraints=[Holonomic("c", x.diff(t))], name="s")
    with pytest.raises(lc.ModelError, match="unique"):
        lc.System([x, y], T=m * x.diff(t) ** 2, constraints=[Holonomic("c", x), Holonomic("c", y)], name="s")
    from lagcomp.mechanics.lagrange import derive

    quadratic = lc.System([x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2), constraints=[Nonholonomic("c", x.diff(t) ** 2)], name="s")
    with pytest.raises(lc.ModelError, match="not linear in the velocities"):
        derive(quadratic)
    redundant = lc.System([x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2),
                          constraints=[Holonomic("a", x - y), Holonomic("b", 2 * x - 2 * y)], name="s")
    with pytest.raises(lc.SingularMassMatrixError, match="redundant"):
        derive(redundant)


@pytest.mark.parametrize("singular_mass", [False, True])
def test_augmented_solver_matches_numpy(rng, singular_mass):
    # Schur complement where M is positive definite, LU with pivoting where it is singular
    from lagcomp.kernel_support.linear_solvers import kkt_solve

    n, k = 5, 2
    for _ in range(20):
        B = rng.normal(size=(n, n))
        M = B @ B.T + 0.1 * np.eye(n)
        if singular_mass:
            M[:, -1] = M[-1, :] = 0.0
        C = rng.normal(size=(k, n))
        rhs = rng.normal(size=n + k)
        A = np.block([[M, -C.T], [C, np.zeros((k, k))]])
        packed = np.hstack([A, rhs[:, None]])
        assert kkt_solve(packed, n) == 0
        np.testing.assert_allclose(packed[:, -1], np.linalg.solve(A, rhs), rtol=1e-9, atol=1e-10)
    redundant = np.hstack([np.block([[M, -np.vstack([C[0], C[0]]).T], [np.vstack([C[0], C[0]]), np.zeros((k, k))]]),
                           rhs[:, None]])
    assert kkt_solve(redundant, n) > 0
