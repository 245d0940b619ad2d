"""The exact parameter Jacobian kernel ``rhs_parameter_jacobian``: out = ∂f/∂p of y' = f(t, y, p), (N, P).

(a) Against a reference nobody here wrote twice: the equations of `lagcomp.accuracy.reference` (Lagrange's
    equations formed from T, V, Q, D by plain sympy, independent of `lagcomp.mechanics`; for a Kane model
    KanesMethod's own ``mass_matrix_full`` and ``forcing_full``), solved by mpmath and differentiated along
    each parameter by central differences at `DIGITS` digits with steps `STEP` × max(1, |p_j|): truncation
    (h² f'''/6) and rounding (10^−DIGITS/h) both ~1e-40 relative, far below float64's ε, so the reference
    is exact for the comparison.  Models: the double pendulum, a 3-link chain, the driven pendulum
    (parameters in an explicitly time-dependent forcing), a double pendulum with the parameters in the
    Rayleigh function D and in a drag force Q (c1, c2, k), the inverted pendulum under a PD law (its gains
    K_p, K_d are parameters and get columns), the Chaplygin sleigh (Kane: LU, M with a constraint row).
    Tolerance (`tolerance`): 4 N ε κ₁(M) (max|J| + max|M⁻¹ ∂M/∂p ā|): as test_rhs_jacobian's (its docstring),
    plus the term the kernel forms from the accelerations ā that `rhs` solved, which carry ~ε κ(M) relative
    error (where ∂a/∂m is exactly 0, the kernel's M⁻¹(∂F/∂m − ∂M/∂m ā) is that rounding: `@example` below).
    The tests also assert the error below 8 ε × that scale (the ulps of the entries' size); measured at
    these seeds: double pendulum 0.71, 3-link chain 1.11, driven pendulum 1.24, damped 0.88, PD law 0.27,
    sleigh 0.61 ulps; the random systems 0.17-2.3 ulps, at most 0.13 of the tolerance.
(b) Hypothesis over random small systems (`random_systems.random_mechanism`, the emitted module run as
    plain Python): the same 40-digit reference; constrained ones (which it does not cover) against central
    differences extrapolated as in (c) (tests/test_constrained_sensitivities.py has exact references for them).
(c) sympy's Whipple bicycle (Kane, velocity constraints among the rows of M, q̇ = N depending on p), run as
    plain Python, against central differences of its ``rhs`` along p extrapolated to order h⁴ (as
    test_rhs_jacobian's, whose error bound it reuses).
(d) Where M is singular, the kernel returns the pivot ``rhs`` returns; inputs read from tables get no
    column; every kind of kernel passes as `kernel_types.RHS_PARAMETER_JACOBIAN`; `Model.rhs_parameter_jacobian`.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from random_systems import python_kernels, python_model_kernels, random_mechanism
from test_inputs import Kd, Kp, _inverted_pendulum, th
from test_rhs_jacobian import (
    _differences,
    damped_double_pendulum,
    sleigh,  # noqa: F401 (a module fixture: the sleigh compiled once)
)

import lagcomp as lc
from lagcomp.accuracy.reference import reference_equations
from lagcomp.model import t

EPS = np.finfo(float).eps
DIGITS, STEP = 60, mpmath.mpf("1e-20")


def _central_differences(system, time, y, p, rows: int) -> tuple[np.ndarray, np.ndarray]:
    """∂x/∂p and the term A⁻¹ (∂A/∂p) x, both (N, P) float arrays, of the solution x of A(t, y, p) x = b(t, y, p),
    `system`(t, y, p) -> (A, b) in mpmath, by central differences at DIGITS digits (module docstring).

    x is written into rows `rows`.. (the accelerations below q̇ for a Lagrange model; the rows above are 0, which
    the caller checks against the kernel's exact zeros).  The second array is the size of the term the kernel
    forms from the accelerations `rhs` solved, which carry a relative error of about ε κ(M) (the tolerance).
    """
    J, term = np.zeros((y.size, p.size)), np.zeros((y.size, p.size))
    with mpmath.workdps(DIGITS):
        time, state = mpmath.mpf(float(time)), [mpmath.mpf(float(v)) for v in y]
        A, b = system(time, state, [mpmath.mpf(float(v)) for v in p])
        x = mpmath.lu_solve(A, b)
        for j in range(p.size):
            h = STEP * max(1, abs(float(p[j])))
            plus, minus = [mpmath.mpf(float(v)) for v in p], [mpmath.mpf(float(v)) for v in p]
            plus[j] += h
            minus[j] -= h
            (A_plus, b_plus), (A_minus, b_minus) = system(time, state, plus), system(time, state, minus)
            dx = (mpmath.lu_solve(A_plus, b_plus) - mpmath.lu_solve(A_minus, b_minus)) / (2 * h)
            dA_x = mpmath.lu_solve(A, (A_plus - A_minus) * x / (2 * h))
            for i in range(y.size - rows):
                J[rows + i, j], term[rows + i, j] = float(dx[i]), float(dA_x[i])
    return J, term


def lagrange_reference(system):
    """(t, y, p) -> (∂f/∂p, the ā term), (2n, P) each, from `lagcomp.accuracy.reference`'s equations."""
    equations, n = reference_equations(system), len(system.coordinates)

    def matrices(time, y, p):
        args = [time, *y, *p, mpmath.mpf(0), mpmath.mpf(0)]  # no constraints: the Baumgarte gains are unused
        return mpmath.matrix(equations.matrix(*args)), mpmath.matrix(equations.right(*args))

    return lambda time, y, p: _central_differences(matrices, time, y, p, rows=n)


def kane_reference(km, parameters):
    """(t, y, p) -> (∂f/∂p, the ū term) of f = M_full⁻¹ F_full of `km` (state (q, u) in its order)."""
    q, u = list(km.q), list(km.u)
    plain_q, plain_u = sp.symbols(f"q0:{len(q)}", real=True), sp.symbols(f"u0:{len(u)}", real=True)
    plain = {x.diff(t): s for x, s in zip(q, plain_q, strict=True)}
    plain |= {**dict(zip(u, plain_u, strict=True)), **dict(zip(q, plain_q, strict=True))}
    args = (t, *plain_q, *plain_u, *parameters)
    M = sp.lambdify(args, km.mass_matrix_full.xreplace(plain), modules="mpmath")
    F = sp.lambdify(args, km.forcing_full.xreplace(plain), modules="mpmath")

    def matrices(time, y, p):
        return mpmath.matrix(M(time, *y, *p)), mpmath.matrix(F(time, *y, *p))

    return lambda time, y, p: _central_differences(matrices, time, y, p, rows=0)


def tolerance(J_reference, term, mass_matrix) -> tuple[float, float]:
    """4 N ε κ₁(M) (max|J| + max|M⁻¹ ∂M/∂p ā|), and the scale in parentheses (module docstring)."""
    scale = float(np.max(np.abs(J_reference)) + np.max(np.abs(term)))
    return 4 * J_reference.shape[0] * EPS * np.linalg.cond(mass_matrix, 1) * scale, scale


def _kernel(kernels, time, y, p, width):
    out = np.full((y.size, width), np.nan)
    return kernels.rhs_parameter_jacobian(time, y, p, out), out


def _check(kernels, reference, p, width, mass_matrix, states, rng) -> float:
    """The kernel against `reference` at `states`, times in [0, 0.01) (test_rhs_jacobian says why); the largest
    error in ulps of the entries' size, ε × the scale of `tolerance`."""
    worst = 0.0
    for state in states:
        time = float(rng.uniform(0.0, 0.01))
        status, J = _kernel(kernels, time, state, p, width)
        assert status == 0
        J_reference, term = reference(time, state, p[:width])
        bound, scale = tolerance(J_reference, term, mass_matrix(time, state))
        error = float(np.max(np.abs(J - J_reference)))
        assert error <= bound
        worst = max(worst, error / (EPS * scale))
    return worst


def _check_lagrange(model, rng, system=None) -> float:
    p, n = model.parameter_vector(), model.n

    def mass_matrix(time, state):
        M = np.empty((n, n))
        model.kernels.mass_matrix(time, state, p, M)
        return M

    states = [rng.uniform(-2.0, 2.0, 2 * n) for _ in range(3)]
    ulps = _check(model.kernels, lagrange_reference(system or model.system), p, len(model.parameters), mass_matrix,
                  states, rng)
    for state in states:  # exactly 0 where q̇ sits
        assert not np.any(_kernel(model.kernels, 0.0, state, p, len(model.parameters))[1][:n])
    return ulps


@pytest.mark.parametrize(("name", "kwargs"),
                         [("double_pendulum", {}), ("n_link_pendulum", {"n": 3}), ("driven_pendulum", {})])
def test_lagrange_parameter_jacobian_agrees_with_the_40_digit_reference(name, kwargs, compiled, rng):
    assert _check_lagrange(compiled(name, **kwargs), rng) < 8


def test_parameters_in_dissipation_and_forces(cache_dir, rng):
    """c1, c2 in D = ½ c1 θ̇1² + ½ c2 (θ̇2 − θ̇1)², k in the drag −k θ̇2 |θ̇2|."""
    model = lc.compile(damped_double_pendulum(), cache_dir=cache_dir)
    assert _check_lagrange(model, rng) < 8


@pytest.fixture(scope="module")
def pd(cache_dir):
    """test_inputs' inverted pendulum under τ = −K_p θ − K_d θ̇ (the same cache key: compiled once per run)."""
    return lc.compile(_inverted_pendulum(lc.Input("tau", law=-Kp * th - Kd * th.diff(t)), "inputs_pd"),
                      cache_dir=cache_dir)


def test_a_laws_gains_are_parameters_with_columns(pd, rng):
    """m l² θ̈ = m g l sin θ − K_p θ − K_d θ̇: ∂θ̈/∂K_p = −θ/(m l²), ∂θ̈/∂K_d = −θ̇/(m l²), against the
    40-digit reference (the System holds the law substituted) and that closed form."""
    assert pd.parameters == ("K_d", "K_p", "g", "l", "m")
    assert _check_lagrange(pd, rng) < 8
    theta, omega = 0.3, -0.7
    J = pd.rhs_parameter_jacobian(0.0, [theta, omega], {"m": 2.0, "l": 0.5})
    np.testing.assert_allclose(J[1, :2], [-omega / 0.5, -theta / 0.5], rtol=4 * EPS)


def test_kane_parameter_jacobian_agrees_with_kanes_method(sleigh, rng):  # noqa: F811 (the fixture)
    km, model = sleigh
    form = model.first_order_form
    p = model.parameter_vector()

    def mass_matrix(time, state):
        at = {**dict(zip(form.parameters, p, strict=True)), **dict(zip(form.q, state[:form.n_q], strict=True))}
        return np.array(form.M.subs(at), dtype=float)

    states = [rng.uniform(-2.0, 2.0, model.state_size) for _ in range(3)]
    assert _check(model.kernels, kane_reference(km, form.parameters), p, len(form.parameters), mass_matrix,
                  states, rng) < 8


@settings(max_examples=6, deadline=None, derandomize=True, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1))
@example(seed=106537)  # ∂a/∂m = 0 exactly, the kernel's −4.6e-15 all from ā's rounding (the term of `tolerance`)
def test_random_systems_agree_with_the_40_digit_reference(seed):
    from lagcomp.codegen.emit import emit
    from lagcomp.codegen.lower import lower
    from lagcomp.mechanics.lagrange import derive

    mech = random_mechanism(seed, max_bodies=2)
    eom = derive(mech.system)
    module = python_kernels(emit(lower(eom)))
    n, width = eom.n, len(mech.values)
    p = np.concatenate([mech.values, np.zeros(2 if eom.k else 0)])
    y = np.concatenate([mech.q0, mech.qd0])
    out = np.full((2 * n, width), 7.0)
    assert "RHS_PARAMETER_JACOBIAN_REFUSED" not in module
    assert module["rhs_parameter_jacobian"](0.3, y, p, out) == 0
    if eom.k:  # the derivative of the augmented solve, against differences along the parameters (gains dropped)
        D, bound = _differences(module["rhs"], 0.3, y, p, h=1e-2, along="p")
        assert np.all(np.abs(out - D[:, :width]) <= bound[:, :width]), mech.description
        return
    J_reference, term = lagrange_reference(mech.system)(0.3, y, p)
    M = np.empty((n, n))
    module["mass_matrix"](0.3, y, p, M)
    assert np.max(np.abs(out - J_reference)) <= tolerance(J_reference, term, M)[0], mech.description


def test_singular_mass_matrix_gives_the_status_of_rhs(compiled):
    model = compiled("double_pendulum")
    y = np.array([0.3, -0.2, 0.5, 0.1])
    for masses, pivot in (((1.0, 0.0), 2), ((0.0, 0.0), 1)):
        p = model.parameter_vector({"m1": masses[0], "m2": masses[1]})
        assert _kernel(model.kernels, 0.0, y, p, 5)[0] == pivot
        with pytest.raises(lc.SingularMassMatrixError):
            model.rhs_parameter_jacobian(0.0, y, {"m1": masses[0], "m2": masses[1]})


def test_a_model_without_parameters_has_an_empty_parameter_jacobian():
    """P = 0: out is (N, 0), and the kernel still returns the status of `rhs` (emitted module run as plain Python)."""
    from lagcomp.codegen.emit import emit
    from lagcomp.codegen.lower import lower
    from lagcomp.mechanics.lagrange import derive

    (x,) = lc.coordinates("x")
    module = python_kernels(emit(lower(derive(lc.System(coordinates=(x,), T=x.diff(t) ** 2 / 2, V=x**4 / 4,
                                                        name="quartic")))))
    assert module["rhs_parameter_jacobian"](0.0, np.array([0.5, 0.1]), np.empty(0), np.empty((2, 0))) == 0


def test_inputs_read_from_tables_are_not_parameters(cache_dir):
    """The inverted pendulum tracking r(t), a tabulated input, under τ = −K_p (θ − r) − K_d θ̇: P = 5 columns (no
    column for r, whose table follows the parameters in p), ∂θ̈/∂K_p = −(θ − r(t))/(m l²) with r read there."""
    r = lc.Input("r")
    model = lc.compile(_inverted_pendulum(lc.Input("tau", law=-Kp * (th - r) - Kd * th.diff(t)), "inputs_tracking"),
                       cache_dir=cache_dir)
    module = python_model_kernels(model)
    assert model.parameters == ("K_d", "K_p", "g", "l", "m") and model.inputs == ("r",)
    times = np.linspace(0.0, 2.0, 9)
    p = model.parameter_vector(inputs={"r": lc.Tabulated(times, 0.25 * times, kind="linear")}, span=(0.0, 2.0))
    out = np.full((2, 5), np.nan)
    theta, omega, time = 0.3, -0.7, 1.0
    assert module["rhs_parameter_jacobian"](time, np.array([theta, omega]), p, out) == 0
    np.testing.assert_allclose(out[1, :2], [-omega, -(theta - 0.25 * time)], rtol=4 * EPS)  # m = l = 1
    assert np.all(out[0] == 0.0)


def test_kernels_are_values_of_the_drivers_parameter_jacobian_type(compiled, sleigh):  # noqa: F811
    """Each kind (LDLᵀ, LU, KKT) passes as `kernel_types.RHS_PARAMETER_JACOBIAN`, as a driver takes it."""
    from numba import njit, types

    from lagcomp.integrate.drivers.kernel_types import FLOAT, MATRIX, RHS_PARAMETER_JACOBIAN, VECTOR

    @njit(types.int64(RHS_PARAMETER_JACOBIAN, FLOAT, VECTOR, VECTOR, MATRIX))
    def call(jacobian, time, y, p, out):
        return jacobian(time, y, p, out)

    rng = np.random.default_rng(7)
    for model in (compiled("double_pendulum"), sleigh[1], compiled("spherical_pendulum_cartesian")):
        y, p = rng.uniform(-1.0, 1.0, model.state_size), model.parameter_vector()
        expected, out = _kernel(model.kernels, 0.0, y, p, len(model.parameters))
        via_type = np.full_like(out, np.nan)
        assert call(model.kernels.rhs_parameter_jacobian, 0.0, y, p, via_type) == expected
        assert np.array_equal(via_type, out, equal_nan=True)
        if expected == 0:
            assert np.array_equal(model.rhs_parameter_jacobian(0.0, y), out)


def test_whipple_bicycle_parameter_jacobian_agrees_with_central_differences(whipple_bicycle):
    """The bicycle's ∂f/∂p against test_rhs_jacobian's extrapolated central differences, taken along p."""
    _, model = whipple_bicycle
    module = python_model_kernels(model)
    p, y = model.parameter_vector(), np.random.default_rng(3).uniform(-0.3, 0.3, model.state_size)
    out = np.full((y.size, p.size), np.nan)
    assert module["rhs_parameter_jacobian"](0.0, y, p, out) == 0
    D, bound = _differences(module["rhs"], 0.0, y, p, h=1e-2, along="p")
    excess = np.abs(out - D) - bound
    assert np.all(excess <= 0), f"off by {np.max(excess):.3g} beyond the tolerance"
