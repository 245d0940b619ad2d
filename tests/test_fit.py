"""`Model.fit` (`lagcomp.fitting`): parameter identification of a damped double pendulum (issue #22's target).

Data: the model's own run at the true parameters (rtol 1e-12), plus Gaussian noise σ = 1e-3 of fixed seed.
Oracles: the true parameters (within 3 reported standard errors; to 1e-8 without noise), and a Monte-Carlo
of 100 noisy fits for the reported covariance (its empirical standard deviations within a chi-square band).
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from scipy.stats import chi2

import lagcomp as lc
from lagcomp.model import t

TRUE = {"c1": 0.3, "c2": 0.2, "m2": 0.8, "l2": 0.7}
#: A rough start: every parameter 20–30 % off, in both directions.
START = {"c1": 0.39, "c2": 0.15, "m2": 1.0, "l2": 0.56}
SIGMA = 1e-3
TIMES = np.linspace(0.0, 10.0, 201)
MONTE_CARLO = 100


def damped_double_pendulum() -> lc.System:
    """The double pendulum (absolute angles θ1, θ2) with viscous joints: D = c1 θ̇1²/2 + c2 (θ̇2 − θ̇1)²/2."""
    th1, th2 = lc.coordinates("theta1 theta2")
    m1, m2, l1, l2, g, c1, c2 = sp.symbols("m1 m2 l1 l2 g c1 c2", positive=True)
    x1, y1 = l1 * sp.sin(th1), -l1 * sp.cos(th1)
    x2, y2 = x1 + l2 * sp.sin(th2), y1 - l2 * sp.cos(th2)

    def speed2(*xyz):
        return sum(c.diff(t) ** 2 for c in xyz)

    return lc.System([th1, th2], T=m1 * speed2(x1, y1) / 2 + m2 * speed2(x2, y2) / 2, V=g * (m1 * y1 + m2 * y2),
                     dissipation=c1 * th1.diff(t) ** 2 / 2 + c2 * (th2.diff(t) - th1.diff(t)) ** 2 / 2,
                     name="fit_damped_double_pendulum", q0=(1.0, 0.5), qd0=(0.0, 0.0),
                     defaults=dict(m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=9.81, c1=0.1, c2=0.1))


@pytest.fixture(scope="module")
def model(cache_dir):
    return lc.compile(damped_double_pendulum(), cache_dir=cache_dir)


def _truth(model, q0=None, qd0=None) -> np.ndarray:
    """The exact trajectory (m, 4) at the data times."""
    sol = model.simulate((0.0, TIMES[-1]), q0, qd0, TRUE, t_eval=TIMES, rtol=1e-12, atol=1e-12, progress=False)
    return sol.y


def _noisy(exact: np.ndarray, seed: int) -> np.ndarray:
    return exact + SIGMA * np.random.default_rng(seed).standard_normal(exact.shape)


def test_noisy_fit_recovers_the_parameters_within_three_standard_errors(model):
    data = _noisy(_truth(model)[:, :2], seed=22)
    fit = model.fit(TIMES, data, START, sigma=SIGMA)
    assert fit.success and fit.names == tuple(START) and fit.observe == ("theta1", "theta2")
    assert fit.njev <= 20, fit.njev                       # measured 7 (nfev 8)
    for name, value in TRUE.items():
        assert abs(fit.estimates[name] - value) < 3 * fit.standard_errors[name], name
    assert fit.residuals[0].shape == data.shape
    # the weighted cost is a χ² of m K − P = 398 degrees of freedom over 2
    assert chi2.ppf(1e-4, data.size - 4) < 2 * fit.cost < chi2.ppf(1 - 1e-4, data.size - 4)


def test_noise_free_fit_recovers_the_parameters_to_1e_8(model):
    fit = model.fit(TIMES, _truth(model)[:, :2], START)
    relative = max(abs(fit.estimates[name] / value - 1) for name, value in TRUE.items())
    assert fit.success and relative < 1e-8, relative      # measured 1.9e-10


def test_two_experiments_at_once_with_velocities_observed(model):
    starts = [((1.0, 0.5), (0.0, 0.0)), ((-0.3, 0.8), (1.0, 0.0))]
    experiments = [(TIMES, _truth(model, q0, qd0)[:, [1, 2]], q0, qd0) for q0, qd0 in starts]
    fit = model.fit(params0=START, experiments=experiments, observe=("theta2", "theta1_dot"))
    relative = max(abs(fit.estimates[name] / value - 1) for name, value in TRUE.items())
    assert fit.success and relative < 1e-8, relative
    assert len(fit.residuals) == 2 and all(r.shape == (TIMES.size, 2) for r in fit.residuals)


def test_initial_state_fitted_with_the_parameters(model):
    starts = [((1.0, 0.5), (0.0, 0.0)), ((-0.3, 0.8), (1.0, 0.0))]
    experiments = [(TIMES, _truth(model, q0, qd0)[:, :2], np.add(q0, 0.05), qd0) for q0, qd0 in starts]
    fit = model.fit(params0=START, experiments=experiments, fit_initial=("theta1", "theta2", "theta1_dot"))
    assert fit.names == tuple(START) + ("q0:theta1[0]", "q0:theta2[0]", "qd0:theta1_dot[0]",
                                        "q0:theta1[1]", "q0:theta2[1]", "qd0:theta1_dot[1]")
    for e, (q0, qd0) in enumerate(starts):
        assert fit.estimates[f"q0:theta1[{e}]"] == pytest.approx(q0[0], abs=1e-9)
        assert fit.estimates[f"qd0:theta1_dot[{e}]"] == pytest.approx(qd0[0], abs=1e-9)
        assert np.allclose(fit.experiments[e].y0, np.concatenate([q0, qd0]), atol=1e-9, rtol=0)
    relative = max(abs(fit.estimates[name] / value - 1) for name, value in TRUE.items())
    assert fit.success and relative < 1e-8, relative
    alone = model.fit(TIMES, experiments[0][1], q0=(0.9, 0.6), fit_initial=("theta1", "theta2"), fixed=TRUE)
    assert alone.names == ("q0:theta1", "q0:theta2") and np.allclose(alone.experiments[0].y0[:2], (1.0, 0.5))


def test_covariance_without_sigma_is_scaled_by_the_reduced_chi_square(model):
    data = _noisy(_truth(model)[:, :2], seed=5)
    weighted = model.fit(TIMES, data, START, sigma=SIGMA)
    scaled = model.fit(TIMES, data, START)
    reduced = 2 * weighted.cost / (data.size - 4)
    np.testing.assert_allclose(scaled.covariance, weighted.covariance * reduced, rtol=1e-6, atol=0)  # entries ~1e-8
    np.testing.assert_allclose(np.diag(scaled.correlation), 1.0, rtol=1e-14, atol=0)


def test_bounds_hold_the_estimates(model):
    fit = model.fit(TIMES, _truth(model)[:, :2], {**START, "c1": 0.2}, bounds={"c1": (0.0, 0.25)})
    assert fit.estimates["c1"] <= 0.25 and fit.estimates["c1"] == pytest.approx(0.25, abs=1e-6)


def test_reported_covariance_against_a_monte_carlo_of_noisy_fits(model):
    exact = _truth(model)[:, :2]
    reference = model.fit(TIMES, exact, TRUE, sigma=SIGMA)           # J at the truth: the linearised covariance
    estimates = np.array([[f.estimates[name] for name in TRUE] for f in
                          (model.fit(TIMES, _noisy(exact, seed), START, sigma=SIGMA) for seed in range(MONTE_CARLO))])
    reported = np.sqrt(np.diag(reference.covariance))
    empirical = estimates.std(axis=0, ddof=1)
    # (n − 1) s²/σ² is χ²(n − 1) for Gaussian estimates: a two-sided band of probability 1 − 1e-4 per parameter
    low, high = np.sqrt(chi2.ppf([5e-5, 1 - 5e-5], MONTE_CARLO - 1) / (MONTE_CARLO - 1))
    ratio = empirical / reported
    assert np.all((low < ratio) & (ratio < high)), (ratio, low, high)   # measured 0.93–1.04 in [0.73, 1.28]
    bias = (estimates.mean(axis=0) - np.array(list(TRUE.values()))) / (reported / np.sqrt(MONTE_CARLO))
    assert np.all(np.abs(bias) < 4), bias
    empirical_correlation = np.corrcoef(estimates, rowvar=False)
    assert np.abs(empirical_correlation - reference.correlation).max() < 0.3   # measured 0.13


def test_plot_shows_data_and_fit(model):
    pytest.importorskip("matplotlib")
    fit = model.fit(TIMES, _noisy(_truth(model)[:, :2], seed=1), START, sigma=SIGMA)
    fig = fit.plot(points=50)
    assert len(fig.axes) == 2 and all(len(axis.lines) == 2 for axis in fig.axes)
