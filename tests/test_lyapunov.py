"""Lyapunov exponents of the Hénon–Heiles system at the escape energy E = 1/6.

Initial states lie on the section x = 0 with ẏ = 0 and ẋ > 0 fixed by the
energy: ẋ = √(2E − y² + 2y³/3).  The orbit through y = −0.1 wanders in the
chaotic sea that fills most of the section at this energy; the one through
y = 0.1 lies on an invariant torus of the island around the stable periodic
orbit (see docs/figures/poincare.png).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lagcomp import analysis as an
from lagcomp.errors import ModelError, OptionError

E = 1 / 6


def _start(y0: float) -> tuple[list, list]:
    xd = math.sqrt(2 * E - y0**2 + 2 * y0**3 / 3)
    return [0.0, y0], [xd, 0.0]


@pytest.fixture(scope="module")
def hh(compiled):
    return compiled("henon_heiles")


def test_on_energy_surface_solves_the_energy_integral(hh):
    states, valid = an.on_energy_surface(hh, E, [[0.0, -0.1, 0.0, 0.0], [0.0, 0.1, 0.0, 0.2], [0.0, -0.6, 0.0, 0.0]],
                                         "x_dot")
    assert valid.tolist() == [True, True, False]
    assert states[0, 2] == pytest.approx(_start(-0.1)[1][0], rel=1e-14, abs=0)
    for row in states[:2]:
        assert hh.energy_function(row[:2], row[2:]) == pytest.approx(E, rel=1e-14, abs=0)


def test_chaotic_orbit_variational_and_two_trajectory_estimates_agree(hh):
    q0, qd0 = _start(-0.1)
    variational = an.lyapunov_exponents(hh, (0, 2000), q0, qd0, dt=0.02, progress=False)
    shadow = an.two_trajectory_lyapunov(hh, (0, 2000), q0, qd0, dt=0.02, d0=1e-9, renorm_every=5, progress=False)
    assert variational.status == 0 and shadow.status == 0
    assert variational.largest > 0.05
    assert abs(shadow.largest - variational.largest) < 0.1 * variational.largest
    # the trajectory itself is the same: both end at the same state
    np.testing.assert_allclose(shadow.final_state, variational.final_state, atol=1e-6)


def test_regular_orbit_estimate_falls_like_log_t_over_t(hh):
    q0, qd0 = _start(0.1)
    result = an.lyapunov_exponents(hh, (0, 10000), q0, qd0, dt=0.02, samples=60, progress=False)
    late = result.t >= 100
    t, lam = result.t[late], result.history[late, 0]
    # on a torus tangent vectors grow linearly, |δ| ~ c t, so λ(t) t = log t + log c: a line of slope 1 in log t
    growth, _ = np.polyfit(np.log(t), lam * t, 1)
    assert abs(growth - 1) < 0.05, growth  # measured 0.989
    ratio = lam * t / np.log(t)
    assert np.all((0.85 < ratio) & (ratio < 1.05)), ratio  # measured 0.893 .. 0.965
    slope = np.polyfit(np.log(t), np.log(lam), 1)[0]  # log(t)/t has local slope −1 + 1/ln t ≈ −0.85..−0.9
    assert -1.0 < slope < -0.75
    assert result.largest < 2e-3


def test_spectrum_comes_in_opposite_pairs(hh):
    """Hamiltonian flow: λ1 + λ4 = 0, λ2 = λ3 = 0 (the energy and the flow direction), Σ λ = 0.

    The sum is exact at any time (Σ log R_jj = log det of a symplectic flow = 0); the pairs only in the limit.
    """
    q0, qd0 = _start(-0.1)
    result = an.lyapunov_spectrum(hh, (0, 3000), q0, qd0, dt=0.02, progress=False)
    lam = result.exponents
    assert lam[0] > 0.05
    assert abs(lam[0] + lam[3]) < 0.01 * lam[0]  # finite-time QR estimates pair up only asymptotically
    assert abs(lam[1]) < 0.01 and abs(lam[2]) < 0.01
    assert abs(lam.sum()) < 1e-8


def test_chunked_run_equals_one_call(hh):
    q0, qd0 = _start(-0.1)
    once = an.lyapunov_exponents(hh, (0, 200), q0, qd0, dt=0.02, samples=1, progress=False)
    chunked = an.lyapunov_exponents(hh, (0, 200), q0, qd0, dt=0.02, samples=40, progress=False)
    assert len(once.t) == 1 and len(chunked.t) > 20 and chunked.t[-1] == pytest.approx(200.0)
    assert chunked.largest == pytest.approx(once.largest, rel=1e-9)
    with_transient = an.lyapunov_exponents(hh, (0, 200), q0, qd0, dt=0.02, transient=50, progress=False)
    assert with_transient.t[-1] == pytest.approx(150.0)


def test_bad_arguments_are_refused(hh, compiled):
    with pytest.raises(OptionError, match="`k`"):
        an.lyapunov_exponents(hh, (0, 10), k=5)
    with pytest.raises(OptionError, match="transient"):
        an.lyapunov_exponents(hh, (0, 10), transient=20)
    with pytest.raises(ModelError, match="unconstrained"):
        an.lyapunov_exponents(compiled("spherical_pendulum_cartesian"), (0, 1))
