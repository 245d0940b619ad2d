"""Runs of the systems built from bodies and moving frames, each against an independent reference.

The bundled examples are compiled once per session (shared with
test_acceptance); the two interop models add two compilations.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

import lagcomp as lc

import sympy_models

TIGHT = dict(method="dop853", rtol=1e-12, atol=1e-12)


# -- turn indicator ------------------------------------------------------------------------------


def turn_indicator_balance(theta, p):
    """k θ − I ω Ω cos β − ½ (I − I_X) ω² sin 2β, β = θ + α: zero at the steady tilt (derived in the example)."""
    beta = theta + p["alpha"]
    return (p["k"] * theta - p["I"] * p["omega"] * p["Omega"] * np.cos(beta)
            - (p["I"] - p["I_X"]) * p["omega"] ** 2 * np.sin(2 * beta) / 2)


@pytest.mark.parametrize("omega", [0.05, 0.2])
def test_turn_indicator_settles_on_the_balance_tilt(compiled, omega):
    model = compiled("turn_indicator")
    p = dict(model.system.defaults, omega=omega)
    sol = model.simulate((0, 12), q0=[0.0], qd0=[0.0], params=p, **TIGHT)
    assert sol.success
    tilt = sol.q[-1, 0]
    expected = brentq(turn_indicator_balance, -1.0, 1.5, args=(p,), xtol=1e-15)
    assert abs(tilt - expected) < 1e-8
    assert abs(sol.qd[-1, 0]) < 1e-8
    # first order in ω/Ω: the pilot's reading ω ≈ k θ/(I Ω cos(θ + α)); the neglected term is
    # ½ (I − I_X) ω² sin 2β, a relative error (I − I_X) ω sin β/(I Ω)
    reading = p["k"] * tilt / (p["I"] * p["Omega"] * np.cos(tilt + p["alpha"]))
    neglected = (p["I"] - p["I_X"]) * omega * np.sin(tilt + p["alpha"]) / (p["I"] * p["Omega"])
    assert abs(reading / omega - 1 - neglected) < 10 * neglected**2 + 1e-9
    assert abs(reading / omega - 1) < 1e-4


# -- Compton's disc ------------------------------------------------------------------------------


@pytest.mark.parametrize("latitude", [0.7, np.pi / 2])
def test_compton_disc_spins_up_by_omega_sin_latitude(compiled, latitude):
    model = compiled("compton_disc")
    p = dict(model.system.defaults, **{"lambda": latitude})
    period = 2 * np.pi / p["nu"]
    ts = np.linspace(0, period, 401)
    sol = model.simulate((0, period), q0=[0.0], qd0=[0.0], params=p, t_eval=ts, **TIGHT)
    assert sol.success
    theta = np.pi * (1 - np.cos(p["nu"] * ts)) / 2
    w = p["omega"] * np.sin(latitude)
    invariant = sol.qd[:, 0] + w * np.cos(theta)
    assert np.ptp(invariant) < 1e-10
    np.testing.assert_allclose(sol.qd[:, 0], w * (1 - np.cos(theta)), rtol=0, atol=1e-10)
    half = len(ts) // 2  # axis reversed at t = π/ν
    assert abs(sol.qd[half, 0] - 2 * w) < 1e-10
    assert np.ptp(sol.momenta[:, 0]) < 1e-10 * p["I_Y"]


# -- driven pendulum both ways -------------------------------------------------------------------


def test_driven_pendulum_inertial_and_support_frames_agree(compiled):
    inertial, support = compiled("driven_pendulum"), compiled("driven_pendulum_support")
    p = inertial.system.defaults
    ts = np.linspace(0, 3, 301)
    runs = [m.simulate((0, 3), q0=[2.9], qd0=[0.0], params=p, t_eval=ts, **TIGHT) for m in (inertial, support)]
    assert all(r.success for r in runs)
    np.testing.assert_allclose(runs[0].q, runs[1].q, rtol=0, atol=1e-10)
    # both satisfy θ̈ + (g + ḧ)/l sin θ = 0 with h = A cos Ωt, y up
    hdd = -p["A"] * p["Omega"] ** 2 * np.cos(p["Omega"] * ts)
    expected = -(p["g"] + hdd) / p["l"] * np.sin(runs[0].q[:, 0])
    for model, run in zip((inertial, support), runs):
        qdd = np.array([model.rhs(ti, yi, p)[1] for ti, yi in zip(ts, run.y)])
        np.testing.assert_allclose(qdd, expected, rtol=1e-12, atol=1e-9)
    # stays near the inverted position (Kapitza)
    assert np.all(np.abs(runs[0].q[:, 0] - np.pi) < 0.5)


# -- heavy symmetric top -------------------------------------------------------------------------


def top_constants(p, q0, qd0):
    """p_ψ, p_φ, E and the nutation bounds from the cubic f(u) = u̇² (derived in the example)."""
    psi_d, th, phi_d = qd0[0], q0[1], qd0[2]
    J = p["I1"] + p["M"] * p["l"] ** 2
    mgl = p["M"] * p["g"] * p["l"]
    p_phi = p["I3"] * (phi_d + psi_d * np.cos(th))
    p_psi = J * psi_d * np.sin(th) ** 2 + p_phi * np.cos(th)
    E = J * (qd0[1] ** 2 + psi_d**2 * np.sin(th) ** 2) / 2 + p_phi**2 / (2 * p["I3"]) + mgl * np.cos(th)
    Ep = E - p_phi**2 / (2 * p["I3"])
    # f(u) = (2/J)(E' − mgl u)(1 − u²) − (p_ψ − p_φ u)²/J², as a polynomial in u (highest power first)
    f = np.polysub(np.polymul([-2 * mgl / J, 2 * Ep / J], [-1, 0, 1]),
                   np.polymul([-p_phi, p_psi], [-p_phi, p_psi]) / J**2)
    roots = np.roots(f)
    roots = np.sort(np.real(roots[np.abs(np.imag(roots)) < 1e-12]))
    inside = roots[(roots >= -1) & (roots <= 1)]
    return p_psi, p_phi, E, np.arccos(inside[::-1])


def extremes(t, x, xd):
    """Turning points of x(t) from samples, by the cubic Hermite interpolant where ẋ changes sign."""
    found = []
    for i in np.flatnonzero(np.sign(xd[:-1]) != np.sign(xd[1:])):
        h = t[i + 1] - t[i]
        s = brentq(lambda s: _hermite_slope(s, h, x[i], x[i + 1], xd[i], xd[i + 1]), 0.0, 1.0, xtol=1e-15)
        found.append(_hermite(s, h, x[i], x[i + 1], xd[i], xd[i + 1]))
    return np.array(found)


def _hermite(s, h, x0, x1, d0, d1):
    return (2 * s**3 - 3 * s**2 + 1) * x0 + (s**3 - 2 * s**2 + s) * h * d0 + (-2 * s**3 + 3 * s**2) * x1 + (s**3 - s**2) * h * d1


def _hermite_slope(s, h, x0, x1, d0, d1):
    return (6 * s**2 - 6 * s) * x0 + (3 * s**2 - 4 * s + 1) * h * d0 + (-6 * s**2 + 6 * s) * x1 + (3 * s**2 - 2 * s) * h * d1


def run_top(model, periods, samples_per_period=None):
    s = model.system
    p = s.defaults
    nutation = 2 * np.pi * (p["I1"] + p["M"] * p["l"] ** 2) / (p["I3"] * s.qd0[2])  # fast-top estimate
    t_end = periods * nutation
    t_eval = None if samples_per_period is None else np.linspace(0, t_end, int(periods * samples_per_period) + 1)
    sol = model.simulate((0, t_end), q0=s.q0, qd0=s.qd0, params=p, t_eval=t_eval, **TIGHT)
    assert sol.success, sol.message
    return sol, top_constants(p, s.q0, s.qd0)


def check_top_invariants(sol, constants):
    p_psi, p_phi, E, _ = constants
    for value, exact in ((sol.momenta[:, 0], p_psi), (sol.momenta[:, 2], p_phi), (sol.energy, E)):
        assert np.max(np.abs(value - exact)) < 1e-10 * abs(exact)


def test_symmetric_top_conserves_its_momenta_and_energy_and_nutates_between_the_cubic_roots(compiled):
    model = compiled("symmetric_top")
    assert model.system.name == "symmetric_top"
    sol, constants = run_top(model, periods=300, samples_per_period=200)
    check_top_invariants(sol, constants)
    bounds = constants[3]
    assert len(bounds) == 2 and abs(bounds[0] - model.system.q0[1]) < 1e-12  # released at rest: a turning point
    turns = extremes(sol.t, sol.q[:, 1], sol.qd[:, 1])
    lows, highs = turns[::2], turns[1::2]  # the first turn after the release is the lowest point
    assert len(highs) > 250
    np.testing.assert_allclose(highs, bounds[1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(lows, bounds[0], rtol=0, atol=1e-9)


@pytest.mark.slow
def test_symmetric_top_long_run(compiled):
    sol, constants = run_top(compiled("symmetric_top"), periods=10_000)
    check_top_invariants(sol, constants)


# -- interop: compiled sympy.physics.mechanics models --------------------------------------------


@pytest.mark.parametrize("builder, native, kwargs", [
    (sympy_models.chain, "n_link_pendulum", {"n": 3}),
    (sympy_models.rolling_disc, "rolling_disc", {}),
])
def test_compiled_lagranges_method_gives_the_native_accelerations(compiled, cache_dir, rng, builder, native, kwargs):
    reference = compiled(native, **kwargs)
    built = builder(**kwargs)
    model = lc.compile(built["method"], cache_dir=cache_dir, name=f"sympy_{native}", parameters=built["parameters"])
    assert model.parameters == reference.parameters
    n = reference.n
    for _ in range(20):
        params = dict(zip(reference.parameters, rng.uniform(0.5, 1.5, len(reference.parameters))))
        y = np.concatenate([rng.uniform(-np.pi, np.pi, n), rng.uniform(-3, 3, n)])
        expected = reference.rhs(0.0, y, params)[n:]
        got = model.rhs(0.0, y, params)[n:]
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
