"""method="radau" through the public API (`Model.simulate`, `Model.sweep`).

The driver itself is tested with hand-written kernels in tests/test_radau_driver.py; here the model's
emitted kernels drive it.  Checked:

* the stiff spring pendulum (`examples.stiff_spring_pendulum`, eigenvalues −1000 s⁻¹ next to a 2 s
  swing) against scipy's DOP853 at rtol = atol = 1e-13 on the same rhs (an explicit method that
  shares no code with Radau; its own error about 1e-13), with bounds about ten times the measured
  errors (7.4e-11 at rtol 1e-8, 3.1e-13 at 1e-10), so that a lost digit fails;
* the same steps as scipy's ``solve_ivp(method="Radau")`` given ``Model.rhs`` and ``Model.jacobian``
  (the exact ``rhs_jacobian`` kernel): accepted steps, f and Jacobian evaluations and LU factorizations;
* order 5 on a damped linear oscillator with its closed form, the steps forced by ``first_step`` and
  ``max_step`` (linear, so the simplified Newton iteration solves the stages to rounding whatever
  the tolerance, and only the method's own error is left);
* the refusal of a constrained model, naming what to use, and a sweep equal to the runs it sweeps.
"""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import lagcomp as lc

STIFF = "stiff_spring_pendulum"


@pytest.fixture(scope="module")
def stiff(compiled):
    return compiled(STIFF)


def test_stiff_spring_pendulum_agrees_with_an_explicit_reference(stiff):
    y0, t_end = stiff.initial_state(), 2.0
    reference = solve_ivp(stiff.rhs, (0.0, t_end), y0, method="DOP853", rtol=1e-13, atol=1e-13).y[:, -1]
    for tol, bound in ((1e-8, 1e-9), (1e-10, 3e-12)):    # measured 7.4e-11 and 3.1e-13
        s = stiff.simulate((0.0, t_end), method="radau", rtol=tol, atol=tol, progress=False)
        assert s.success and s.njev > 0 and s.nlu > 0
        error = np.max(np.abs(s.y[-1] - reference))
        assert error < bound, (tol, error)


def test_radau_takes_scipys_steps_on_the_same_kernels(stiff):
    s = stiff.simulate((0.0, 10.0), method="radau", rtol=1e-6, atol=1e-6, progress=False)
    r = solve_ivp(stiff.rhs, (0.0, 10.0), stiff.initial_state(), method="Radau", jac=stiff.jacobian, rtol=1e-6,
                  atol=1e-6)
    assert (s.nsteps, s.nfev, s.njev, s.nlu) == (r.t.size - 1, r.nfev, r.njev, r.nlu)
    np.testing.assert_allclose(s.y[-1], r.y[:, -1], rtol=0, atol=1e-12)


@pytest.fixture(scope="module")
def oscillator(cache_dir):
    """m ẍ + c ẋ + k x = 0 with m = k = 1, c = 0.2: ζ = 0.1, ω_d = √(1 − ζ²)."""
    (x,) = lc.coordinates("x")
    c = sp.Symbol("c", positive=True)
    system = lc.System(coordinates=(x,), T=x.diff(lc.t) ** 2 / 2, V=x**2 / 2, dissipation=c * x.diff(lc.t) ** 2 / 2,
                       parameters=(c,), name="radau_damped_oscillator", defaults={"c": 0.2}, q0=(1.0,), qd0=(0.0,))
    return lc.compile(system, cache_dir=cache_dir)


def damped_oscillator(t: float) -> np.ndarray:
    """(x, ẋ) from x = 1, ẋ = 0: x = e^(−ζt) (cos ω_d t + (ζ/ω_d) sin ω_d t), ẋ = −e^(−ζt) sin(ω_d t) / ω_d."""
    zeta = 0.1
    wd = np.sqrt(1 - zeta**2)
    decay = np.exp(-zeta * t)
    return np.array([decay * (np.cos(wd * t) + zeta / wd * np.sin(wd * t)), -decay * np.sin(wd * t) / wd])


def test_radau_is_of_order_5(oscillator):
    steps = (0.25, 0.125, 0.0625)     # powers of 2: the step times are exact, and so is the count
    errors = []
    for h in steps:
        s = oscillator.simulate((0.0, 4.0), method="radau", rtol=1e-3, atol=1e-3, first_step=h, max_step=h,
                                progress=False)
        assert s.success and s.nsteps == round(4.0 / h)
        errors.append(np.max(np.abs(s.y[-1] - damped_oscillator(4.0))))
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(orders - 5.0) < 0.02), (errors, orders)    # measured 4.997, 4.9995


def test_a_constrained_model_has_the_augmented_solves_jacobian(compiled):
    """radau solves it as a DAE (tests/test_radau_constrained.py), with the DAE's Jacobian; `Model.jacobian` is
    ∂f/∂y of its ODE form, the augmented solve differentiated (lagcomp.codegen.constrained_jacobian): against
    central differences of `Model.rhs` (truncation ~h², rounding ~ε/h: about 1e-10 relative at h = 1e-5)."""
    model = compiled("spherical_pendulum_cartesian")
    y = model.initial_state() + np.linspace(0.01, 0.06, 6) * np.array([1, 1, 1, 0, 0, 0])  # off the manifold too
    jacobian = model.jacobian(0.0, y)
    h = 1e-5
    differences = np.stack([(model.rhs(0.0, y + h * e) - model.rhs(0.0, y - h * e)) / (2 * h)
                            for e in np.eye(y.size)], axis=1)
    assert np.abs(jacobian - differences).max() <= 1e-8 * np.abs(jacobian).max()


def test_a_radau_sweep_is_bitwise_the_runs_it_sweeps(stiff):
    angles = [0.5, 1.0]
    swept = stiff.sweep((0.0, 1.0), {"theta": angles}, method="radau", rtol=1e-8, atol=1e-8, workers=1,
                        progress=False)
    assert np.all(swept.status == 0)
    r0 = stiff.initial_state()[0]
    for i, angle in enumerate(angles):
        s = stiff.simulate((0.0, 1.0), q0=(r0, angle), method="radau", rtol=1e-8, atol=1e-8, progress=False)
        assert np.array_equal(swept.final[i], s.y[-1])
