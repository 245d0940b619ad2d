"""Lyapunov exponents on a tree with a ball joint: the variational and two-trajectory loops switch the joint's MRPs σ
to their shadow past |σ| = 1, the tangent vectors through the switch's derivative
(`lagcomp.integrate.drivers.lyapunov`, module docstring: the switch in (q, p) in closed form).

References nobody here wrote: the model's own reset and momenta kernels (the switch in (q, q̇) from
`lagcomp.multibody.shadow`, then p = ∂L/∂q̇ there), extrapolated central differences of the closed-form switch, the
symplectic form Ω it must keep, and the closed forms of a Hamiltonian flow: its exponents sum to zero (the tangent flow
keeps volume, and so does a symplectic switch), and those of an integrable one (a torque-free body about a fixed
point: Euler–Poinsot) are zero, estimates falling like log(t)/t.
"""

from __future__ import annotations

import numpy as np
import pytest

import lagcomp as lc
from lagcomp import analysis as an
from lagcomp.examples.trees import spherical_chain
from lagcomp.integrate.drivers.lyapunov import _shadow_state, _shadow_tangents

BALL_PARAMETERS = {"m0": 1.3, "c0": 0.7, "A0": 0.4, "B0": 0.3, "C0": 0.2, "g": 9.81}
TUMBLING = ([0.3, 0.1, 0.0], [1.0, -0.5, 2.0])     # a spin about the vertical: a shadow switch every ~0.7 s
SIGMA = np.array([0, 1, 2], dtype=np.int64)


@pytest.fixture(scope="module")
def ball(cache_dir):
    return lc.compile(spherical_chain(1), cache_dir=cache_dir)


def _switched(x):
    out = x.copy()
    _shadow_state(out, SIGMA)
    return out


def test_the_closed_form_switch_is_the_models_reset_and_its_derivative_is_symplectic(ball):
    """At random states just past |σ| = 1: the switch of x = (σ, π) in closed form equals (σ', P(σ', σ̇')) from the
    model's ``event_reset`` and ``momenta`` kernels (to 1e-14 of |π|); `_shadow_tangents` equals the extrapolated
    central differences of the switch (1e-9), and that derivative D keeps the symplectic form, Dᵀ Ω D = Ω (1e-13)."""
    k, p = ball.kernels, ball.parameter_vector(BALL_PARAMETERS)
    rng = np.random.default_rng(5)
    omega = np.block([[np.zeros((3, 3)), np.eye(3)], [-np.eye(3), np.zeros((3, 3))]])
    for _ in range(5):
        y = rng.uniform(-1.5, 1.5, 6)
        y[:3] *= rng.uniform(1.0, 1.2) / np.linalg.norm(y[:3])
        x, after, momenta = np.empty(6), np.empty(6), np.empty(3)
        k.momenta(0.0, y, p, momenta)
        x[:3], x[3:] = y[:3], momenta
        assert k.event_reset(0.0, y, p, 0, after) == 0
        k.momenta(0.0, after, p, momenta)
        ours = _switched(x)
        assert np.max(np.abs(ours[:3] - after[:3])) <= 4e-16 * np.max(np.abs(after[:3]))
        assert np.max(np.abs(ours[3:] - momenta)) <= 1e-14 * np.max(np.abs(momenta))
        D = np.eye(6)
        _shadow_tangents(x, D, SIGMA)
        for j in range(6):
            def central(step, j=j, x=x):
                e = np.zeros(6)
                e[j] = step
                return (_switched(x + e) - _switched(x - e)) / (2 * step)
            d1, d2, d4 = central(1e-2), central(5e-3), central(2.5e-3)
            expected = (16 * ((4 * d4 - d2) / 3) - ((4 * d2 - d1) / 3)) / 15
            assert np.max(np.abs(D[:, j] - expected)) <= 1e-9 * max(np.max(np.abs(expected)), 1.0)
        assert np.max(np.abs(D.T @ omega @ D - omega)) <= 1e-13 * np.max(np.abs(D)) ** 2


def test_a_torque_free_tumbling_body_has_the_exponents_of_an_integrable_flow(ball):
    """No gravity: a free rigid body about its fixed point, integrable, all exponents zero.  Tumbling through
    hundreds of shadow switches in 200 s, the spectrum sums to zero within RK4's volume error (measured 1.4e-7, order
    dt⁴ times a constant; -2.6e-3 when the loop stepped across |σ| → ∞ without switching), and the largest estimate
    falls like log(t)/t, not to a constant: from t ≈ 30 to 200 to at most 1.5 × (log 200/200)/(log 30/30) ≈ 0.35 of
    its value (measured 0.19; 0.40 without the switches; a chaotic orbit's would stay near 1)."""
    params = {**BALL_PARAMETERS, "g": 0.0}
    spectrum = an.lyapunov_spectrum(ball, (0, 200), *TUMBLING, params, samples=5, progress=False)
    switches = ball.simulate((0, 200), *TUMBLING, params, method="gauss2", dt=0.01).events["link0_shadow"].t.size
    assert switches > 200
    assert abs(spectrum.exponents.sum()) <= 1e-6
    row = int(np.argmin(np.abs(spectrum.t - 30.0)))
    t_early, early, late = spectrum.t[row], spectrum.history[row, 0], spectrum.exponents[0]
    assert 20.0 <= t_early <= 40.0
    log_over_t = (np.log(spectrum.t[-1]) / spectrum.t[-1]) / (np.log(t_early) / t_early)
    assert 0.0 < late <= 1.5 * log_over_t * early


def test_the_two_estimates_agree_across_the_switches(ball):
    """The heavy top tumbling (hundreds of switches in 200 s): the two-trajectory estimate (the shadow trajectory
    switched with the trajectory, one chart for both) and the variational one, along the same trajectory, agree
    to 5% (measured 2%), and end at the same state, bit for bit."""
    variational = an.lyapunov_exponents(ball, (0, 200), *TUMBLING, BALL_PARAMETERS, progress=False)
    divergence = an.two_trajectory_lyapunov(ball, (0, 200), *TUMBLING, BALL_PARAMETERS, progress=False)
    assert np.array_equal(variational.final_state, divergence.final_state)
    assert np.linalg.norm(variational.final_state[:3]) <= 1.0
    assert abs(divergence.largest / variational.largest - 1) <= 0.05
