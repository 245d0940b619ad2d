"""Periodic orbits by shooting (`lagcomp.analysis.periodic_orbit`): issue #22's nonlinear normal mode of the double
pendulum with its Floquet multipliers, a harmonic oscillator's orbit in closed form, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp import analysis as an
from lagcomp.model import t

x = lc.coordinates("x")[0]
m, k = sp.symbols("m k", positive=True)
OMEGA = 2.0                     # sqrt(k / m) with k = 4, m = 1


@pytest.fixture(scope="module")
def oscillator(cache_dir):
    system = lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, name="periodic_oscillator",
                       defaults={"m": 1.0, "k": OMEGA**2}, q0=(1.0,))
    return lc.compile(system, cache_dir=cache_dir)


@pytest.fixture(scope="module")
def pendulum(compiled):
    return compiled("double_pendulum")


@pytest.fixture(scope="module")
def in_phase(pendulum):
    """(ω, shape normalized to θ1 = 1) of the double pendulum's slower (in-phase) linear mode."""
    modes = an.normal_modes(pendulum, [0.0, 0.0])
    return modes.frequencies[0], modes.shapes[:, 0] / modes.shapes[0, 0]


def _normal_mode(pendulum, in_phase, amplitude):
    omega, shape = in_phase
    guess = np.concatenate([amplitude * shape, [0.0, 0.0]])        # the linear mode at rest: a rough guess
    return an.periodic_orbit(pendulum, guess, 2 * np.pi / omega)


def test_nonlinear_normal_mode_of_the_double_pendulum(pendulum, in_phase):
    orbit = _normal_mode(pendulum, in_phase, 0.3)
    assert orbit.residual <= 1e-10 and orbit.iterations <= 10     # measured 7e-15 in 6 iterations
    assert orbit.y0[0] == 0.3 and np.abs(orbit.y0[2:]).max() < 1e-10   # held amplitude; starts at rest
    assert orbit.y0[1] != pytest.approx(0.3 * in_phase[1][1], rel=1e-3)  # the shape changed: a nonlinear mode
    sol = orbit.solution
    assert sol.t[-1] == orbit.period and np.abs(sol.y[-1] - orbit.y0).max() <= 1e-10
    trivial, other = orbit.multipliers[np.argsort(np.abs(orbit.multipliers - 1))].reshape(2, 2)
    # the trivial pair (flow direction, energy) is a Jordan block: split by ~√(error of Φ), its mean exact
    assert np.abs(trivial - 1).max() < 1e-7 and abs(trivial.mean() - 1) < 1e-12    # measured 2.8e-8, 1e-15
    # the other pair: stable, on the unit circle, complex conjugate (μ and 1/μ = μ̄)
    assert np.abs(np.abs(other) - 1).max() < 1e-10                                  # measured 4e-13
    assert abs(other[0] - other[1].conjugate()) < 1e-12 and abs(other[0].imag) > 0.1
    assert orbit.stable


def test_normal_mode_period_tends_to_the_linear_one(pendulum, in_phase):
    linear = 2 * np.pi / in_phase[0]
    gaps = [_normal_mode(pendulum, in_phase, amplitude).period - linear for amplitude in (0.3, 0.1, 0.03)]
    assert all(gap > 0 for gap in gaps)                  # a softening pendulum: longer periods at larger amplitude
    # the period's correction is quadratic in the amplitude: ratios 9 and 11.1 for amplitudes 0.3 → 0.1 → 0.03
    assert gaps[0] / gaps[1] == pytest.approx(9.0, rel=0.05) and gaps[1] / gaps[2] == pytest.approx(100 / 9, rel=0.05)
    assert gaps[2] / linear < 1e-4


def test_harmonic_oscillator_orbit_is_exact(oscillator):
    orbit = an.periodic_orbit(oscillator, [0.7, 0.0], 3.5)         # a wrong starting period
    assert orbit.period == pytest.approx(2 * np.pi / OMEGA, abs=3e-12)                  # measured 5e-13
    assert np.abs(orbit.multipliers - 1).max() < 1e-10 and np.abs(orbit.monodromy - np.eye(2)).max() < 1e-10  # 7e-14
    assert orbit.y0[0] == 0.7 and abs(orbit.y0[1]) < 1e-12


def test_fixed_period_finds_the_same_orbit(pendulum, in_phase):
    amplitude = _normal_mode(pendulum, in_phase, 0.1)
    omega, shape = in_phase
    guess = np.concatenate([0.1 * shape, [0.0, 0.0]])
    fixed = an.periodic_orbit(pendulum, guess, amplitude.period, fix="period")
    assert fixed.period == amplitude.period and fixed.fix == "period"
    assert np.abs(fixed.y0 - amplitude.y0).max() < 1e-8


def test_refusals(pendulum, compiled):
    with pytest.raises(lc.OptionError, match="'spherical_pendulum_cartesian'"):
        an.periodic_orbit(compiled("spherical_pendulum_cartesian"), np.zeros(6), 1.0)
    with pytest.raises(lc.OptionError, match="4 numbers"):
        an.periodic_orbit(pendulum, [0.3, 0.4], 2.6)
    with pytest.raises(lc.OptionError, match="'theta3'"):
        an.periodic_orbit(pendulum, [0.3, 0.4, 0.0, 0.0], 2.6, fix="theta3")
    with pytest.raises(lc.OptionError, match="`period`"):
        an.periodic_orbit(pendulum, [0.3, 0.4, 0.0, 0.0], -1.0)
    with pytest.raises(lc.OptionError, match="did not converge: max"):
        an.periodic_orbit(pendulum, [0.3, 0.4, 0.0, 0.0], 2.6, max_iterations=1)


def test_figure_eight_choreography_of_three_bodies(compiled):
    """Chenciner and Montgomery's figure eight (equal masses, G = 1) from a rough guess: Simó's initial state with the
    positions 10 % too far out and the velocities 10 % too slow, at its period held."""
    bodies, unit = compiled("pythagorean_three_body"), dict(G=1.0, m1=1.0, m2=1.0, m3=1.0)
    r1, v3 = np.array([0.97000436, -0.24308753]), np.array([-0.93240737, -0.86473146])
    q, qd = np.concatenate([r1, -r1, [0.0, 0.0]]), np.concatenate([-v3 / 2, -v3 / 2, v3])
    period = 6.32591398
    orbit = an.periodic_orbit(bodies, np.concatenate([1.1 * q, 0.9 * qd]), period, fix="period", params=unit)
    assert orbit.residual <= 1e-10 and orbit.period == period                      # measured 2.7e-14
    # the orbit Simó's 8 digits describe: its energy (−1.28714199) to their precision (measured 4e-9)
    energy = bodies.energy(orbit.y0[:6], orbit.y0[6:], params=unit)
    assert energy == pytest.approx(bodies.energy(q, qd, params=unit), abs=1e-7)
    # a choreography: after a third of the period each body is where the one before it started
    third = bodies.simulate((0.0, period), orbit.y0[:6], orbit.y0[6:], unit, t_eval=[period / 3], rtol=1e-12,
                            atol=1e-12, progress=False).q[0].reshape(3, 2)
    assert np.abs(third - np.roll(orbit.y0[:6].reshape(3, 2), 1, axis=0)).max() < 1e-9
    # 8 trivial multipliers (energy, time, translations, momenta, rotation, angular momentum, scaling): Jordan
    # blocks split by ~√(error of Φ) about 1; the other four on the unit circle (linearly stable, Simó 2002)
    by_distance = orbit.multipliers[np.argsort(np.abs(orbit.multipliers - 1))]
    trivial, other = by_distance[:8], by_distance[8:]
    assert np.abs(trivial - 1).max() < 1e-4                                           # measured 6e-6
    assert np.abs(np.abs(other) - 1).max() < 1e-10 and np.abs(other - 1).min() > 0.05   # measured 3e-12
