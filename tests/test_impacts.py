"""The impact solver of kernel_support: Newton's restitution for simultaneous frictionless impacts, one frictional
impact (Coulomb's law on a point mass, in closed form) and the touching test.

References nobody here wrote: the closed forms of one contact and of a three-ball chain, and, for
random Delassus matrices, scipy's non-negative least squares (for a positive definite W the
complementarity problem is the minimum of ½ zᵀ W z + qᵀ z over z ≥ 0, i.e. ‖Lᵀ z + L⁻¹ q‖ with
W = L Lᵀ).
"""

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from lagcomp.integrate.contacts import touching as contacts_touching
from lagcomp.kernel_support.impacts import (
    CLOSED_GAP,
    IMPACT_DEPENDENT_CONTACTS,
    IMPACT_SINGULAR_MASS,
    IMPACT_SOLVED,
    frictional_impact,
    impact_velocities,
    solve_lcp,
    touching,
)


def _impact(M, G, v_minus, e, qd):
    qd = np.array(qd, dtype=float)
    impulses = np.empty(len(v_minus))
    status = impact_velocities(np.array(M, float), np.array(G, float), np.array(v_minus, float),
                               np.array(e, float), qd, impulses)
    return status, qd, impulses


@pytest.mark.parametrize("e", [0.0, 0.3, 0.9, 1.0])
def test_one_contact_reverses_the_normal_velocity_by_e(e):
    # A ball of mass 2 on a plane inclined by 30°: gap g = y cos a − x sin a, q = (x, y).
    a = np.pi / 6
    G = [[-np.sin(a), np.cos(a)]]
    qd_minus = np.array([1.5, -2.0])
    v_minus = np.dot(G[0], qd_minus)
    status, qd, impulses = _impact(2.0 * np.eye(2), G, [v_minus], [e], qd_minus)
    assert status == IMPACT_SOLVED
    assert np.dot(G[0], qd) == pytest.approx(-e * v_minus, rel=1e-15, abs=1e-15)
    assert impulses[0] == pytest.approx(-(1 + e) * v_minus * 2.0, rel=1e-15, abs=0)
    tangent = [np.cos(a), np.sin(a)]
    assert np.dot(tangent, qd) == pytest.approx(np.dot(tangent, qd_minus), rel=1e-15, abs=0)   # frictionless


def test_three_ball_chain_newton_restitution():
    # Balls of unit mass touching in a row, the first arriving at speed 1; gaps x2 − x1 − d, x3 − x2 − d.
    G = [[-1.0, 1.0, 0.0], [0.0, -1.0, 1.0]]
    for e, expected in ((1.0, [-1 / 3, 2 / 3, 2 / 3]), (0.0, [1 / 3, 1 / 3, 1 / 3])):
        status, qd, impulses = _impact(np.eye(3), G, [-1.0, 0.0], [e, e], [1.0, 0.0, 0.0])
        assert status == IMPACT_SOLVED
        np.testing.assert_allclose(qd, expected, rtol=1e-15, atol=1e-15)
        assert qd.sum() == pytest.approx(1.0, rel=1e-15, abs=0)                     # momentum
        if e == 1.0:
            assert 0.5 * qd @ qd == pytest.approx(0.5, rel=1e-15, abs=0)            # energy
        assert (impulses > 0).all()


def test_a_separating_contact_does_not_push():
    # The second ball already leaves the third: only the first contact pushes.
    G = [[-1.0, 1.0, 0.0], [0.0, -1.0, 1.0]]
    status, qd, impulses = _impact(np.eye(3), G, [-1.0, 2.0], [1.0, 1.0], [1.0, 0.0, 2.0])
    assert status == IMPACT_SOLVED
    assert impulses[1] == 0.0
    np.testing.assert_allclose(qd, [0.0, 1.0, 2.0], rtol=1e-15, atol=1e-15)


def test_refusals():
    status, qd, _ = _impact([[1.0, 0.0], [0.0, 0.0]], [[1.0, 0.0]], [-1.0], [1.0], [-1.0, 0.0])
    assert status == IMPACT_SINGULAR_MASS
    assert qd.tolist() == [-1.0, 0.0]
    status, _, _ = _impact(np.eye(2), [[1.0, 0.0], [2.0, 0.0]], [-1.0, -2.0], [1.0, 1.0], [-1.0, 0.0])
    assert status == IMPACT_DEPENDENT_CONTACTS
    status, _, _ = _impact(np.eye(2), [[0.0, 0.0]], [-1.0], [1.0], [-1.0, 0.0])
    assert status == IMPACT_DEPENDENT_CONTACTS


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 7), st.integers(0, 2**32 - 1))
def test_lcp_against_nonnegative_least_squares(c, seed):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(c, c + 2))
    W = A @ A.T / (c + 2) + 0.05 * np.eye(c)
    q = rng.normal(size=c)
    z = np.empty(c)
    w = np.empty(c)
    assert solve_lcp(W, q, z, w) == IMPACT_SOLVED
    scale = np.abs(q).max()
    assert (z >= 0).all() and (w >= -1e-14 * scale).all()
    np.testing.assert_allclose(w, W @ z + q, atol=1e-13 * scale * np.linalg.cond(W))
    assert np.abs(z * w).max() <= 1e-13 * scale * max(np.abs(z).max(), 1.0)
    L = scipy.linalg.cholesky(W, lower=True)
    reference, _ = scipy.optimize.nnls(L.T, -scipy.linalg.solve_triangular(L, q, lower=True))
    np.testing.assert_allclose(z, reference, atol=1e-10 * scale * np.linalg.cond(W))


@settings(max_examples=100, deadline=None)
@given(st.integers(1, 6), st.integers(0, 2**32 - 1))
def test_elastic_impacts_conserve_energy_and_push_along_the_normals(n, seed):
    # ΔT = ½ Pᵀ(v⁺ + v⁻) = ½ Pᵀ w = 0 for e = 1, whatever the set of pushing contacts.
    rng = np.random.default_rng(seed)
    c = int(rng.integers(1, n + 1))
    A = rng.normal(size=(n, n))
    M = A @ A.T + 0.1 * np.eye(n)
    G = rng.normal(size=(c, n))
    qd_minus = rng.normal(size=n)
    status, qd, impulses = _impact(M, G, G @ qd_minus, np.ones(c), qd_minus)
    assert status == IMPACT_SOLVED
    energy = 0.5 * qd_minus @ M @ qd_minus
    assert 0.5 * qd @ M @ qd == pytest.approx(energy, rel=1e-11 * np.linalg.cond(M), abs=0)
    np.testing.assert_allclose(M @ (qd - qd_minus), G.T @ impulses, atol=1e-12 * np.abs(M).max() * np.abs(qd).max())
    v_plus = G @ qd
    pushing = impulses > 0
    np.testing.assert_allclose(v_plus[pushing], -(G @ qd_minus)[pushing], atol=1e-10 * np.abs(qd).max())


# -- one contact with Coulomb friction (frictional_impact) -----------------------------------------------------------


def _frictional(m, angle, v_n, v_t, e, mu_s, mu_k):
    """A point mass m hitting a floor inclined by `angle` (gap along n = (−sin, cos), sliding along s = (cos, sin)),
    normal and tangential velocities v_n < 0, v_t before; its (v_n⁺, v_t⁺) after `frictional_impact`."""
    normal, slip = np.array([-np.sin(angle), np.cos(angle)]), np.array([np.cos(angle), np.sin(angle)])
    qd = v_n * normal + v_t * slip
    status = frictional_impact(m * np.eye(2), normal, v_n, e, slip, v_t, mu_s, mu_k, qd)
    assert status == IMPACT_SOLVED
    return normal @ qd, slip @ qd


def _coulomb_point_mass(v_n, v_t, e, mu_s, mu_k):
    """The closed form for a point mass (W_nt = 0, W_nn = W_tt = 1/m): the normal impulse is m (1 + e)|v_n|; sticking
    takes a tangential impulse m |v_t|, allowed while it is within μs times the normal one; else the slip impulse
    μk m (1 + e)|v_n| opposes v_t (and cannot reverse it: |v_t| > μs (1 + e)|v_n| ≥ μk (1 + e)|v_n|)."""
    reach = (1 + e) * abs(v_n)
    return -e * v_n, (0.0 if abs(v_t) <= mu_s * reach else v_t - mu_k * reach * np.sign(v_t))


@pytest.mark.parametrize("v_t", [2.5, -2.5, 2.0, 3.3])
def test_an_oblique_impact_between_the_kinetic_and_static_limits_sticks(v_t):
    """e = 0.5, μs = 0.5, μk = 0.3, v_n = −√(2 g): the tangential speeds (1.99, 3.32) where μk would slip the mass
    and μs sticks it.  It sticks: v_t⁺ = 0 (a μk test would leave v_t − 1.99 sign v_t, 0.51 at 2.5)."""
    v_n = -np.sqrt(2 * 9.81)
    assert 0.3 * 1.5 * -v_n < abs(v_t) < 0.5 * 1.5 * -v_n
    after_n, after_t = _frictional(2.0, 0.0, v_n, v_t, 0.5, 0.5, 0.3)
    assert after_n == pytest.approx(-0.5 * v_n, rel=1e-15, abs=0)
    assert abs(after_t) <= 4e-16 * abs(v_t)


@settings(max_examples=300, deadline=None)
@given(st.floats(0.1, 10.0), st.floats(-1.5, 1.5), st.floats(-10.0, -0.1), st.floats(-1.5, 1.5), st.floats(0.0, 1.0),
       st.floats(0.0, 1.0), st.floats(0.0, 1.0))
def test_the_frictional_impact_of_a_point_mass_follows_coulombs_law(m, angle, v_n, ratio, e, mu_k, extra):
    """The impact map over v_t = ratio (1 + e)|v_n|, across stick (|ratio| ≤ μs), the window μk < |ratio| ≤ μs
    where only μs decides, and slip: against the closed form `_coulomb_point_mass`."""
    mu_s = mu_k + extra
    assume(abs(abs(ratio) - mu_s) > 1e-9)                   # not on the stick/slip boundary itself
    v_t = ratio * (1 + e) * abs(v_n)
    expected_n, expected_t = _coulomb_point_mass(v_n, v_t, e, mu_s, mu_k)
    after_n, after_t = _frictional(m, angle, v_n, v_t, e, mu_s, mu_k)
    scale = 8 * np.finfo(float).eps * (abs(v_t) + (1 + e) * abs(v_n))     # a few roundings of the terms
    assert abs(after_n - expected_n) <= scale
    assert abs(after_t - expected_t) <= scale


# -- the touching test -----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("gradient", [[1.0], [2.0, -3.0], [0.0, 1e-3, 5.0]])
def test_near_the_origin_a_contact_touches_within_a_rounding_of_a_unit_length(gradient):
    """At q = 0 (an angle near 0, bodies at the origin) the scale is Σ_j |∂g/∂q_j| × 1, not 0: a gap a rounding
    above 0 still touches, one twice `CLOSED_GAP` that scale does not."""
    gradients, q = np.array([gradient]), np.zeros(len(gradient))
    scale = np.abs(gradients).sum()
    assert touching(0.5 * CLOSED_GAP * scale, gradients, 0, q)
    assert not touching(2.0 * CLOSED_GAP * scale, gradients, 0, q)


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 5), st.integers(0, 2**32 - 1), st.floats(0.0, 0.99), st.floats(1.01, 10.0))
def test_the_kernels_touching_test_is_the_drivers(n, seed, below, above):
    """`kernel_support.impacts.touching` and `integrate.contacts.touching` (its matrix form, used outside the
    kernels) draw the line at the same gap, for coordinates of any size, 0 included."""
    rng = np.random.default_rng(seed)
    gradients = rng.normal(size=(2, n))
    q = rng.normal(size=n) * 10.0 ** rng.integers(-3, 4, size=n) * rng.integers(0, 2, size=n)  # some exactly 0
    limits = contacts_touching(gradients, q)
    for row in range(2):
        assert touching(below * limits[row], gradients, row, q)
        assert not touching(above * limits[row], gradients, row, q)
