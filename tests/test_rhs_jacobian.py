"""The exact Jacobian kernel ``rhs_jacobian``: out = ∂f/∂y of y' = f(t, y), as every generated module emits it.

(a) Against a reference nobody here wrote: f = (q̇, M⁻¹F) written out explicitly from the M and F of
    sympy.physics.mechanics (LagrangesMethod, with the Rayleigh forces added; KanesMethod's own
    ``mass_matrix_full`` and ``forcing_full``), differentiated by sympy and evaluated by mpmath with
    40 digits at random states: the double pendulum, a 3-link chain, a double pendulum with Rayleigh
    damping and quadratic drag (velocity-dependent forces, the sympy path with Abs), the driven pendulum
    (explicitly time-dependent), and the Chaplygin sleigh (a Kane model: q̇ ≠ u, M with a constraint row,
    not symmetric).  Tolerance (`_reference_tolerance`): the kernel evaluates the entries of M and of
    ∂(F − M ā)/∂y with rounding errors of a few ulps of their terms, and its solve by M is backward
    stable, so the forward error of M⁻¹R is bounded by about κ(M) times that relative size: we allow
    4 N ε κ₁(M) max|J| (N the state length); measured errors are 0.5-4.4 ε max|J|, 5-250 times
    below.  Times are drawn in [0, 0.01), where the driven pendulum's phase Ω t (Ω = 200) is O(1):
    at t ~ 1 the rounding of Ω t alone (ε |Ω t| absolute) moves its entries by ~1000 ulps, a
    conditioning of f itself that the tolerance does not model.
(b) Hypothesis over random small systems (`random_systems.random_mechanism`, one or two bodies, the
    emitted module run as plain Python as in test_properties): against central differences of the
    emitted ``rhs``, extrapolated to order h⁴, with a tolerance derived from the steps (`_differences`):
    about 1e-10 of the entries' scale.  Constrained
    systems among them too (the derivative of the augmented solve; tests/test_constrained_sensitivities.py
    has exact references for them).
(c) Where M is singular, ``rhs_jacobian`` returns the pivot ``rhs`` returns.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import sympy as sp
import sympy.physics.mechanics as me
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from random_systems import python_kernels, python_model_kernels, random_mechanism

import lagcomp as lc
from lagcomp.model import t

EPS = np.finfo(float).eps
DIGITS = 40


def _plain(system):
    """Plain symbols q, u for the coordinates and velocities of `system`, and the substitution to them."""
    n = len(system.coordinates)
    q, u = sp.symbols(f"q0:{n}", real=True), sp.symbols(f"u0:{n}", real=True)
    velocities = [c.diff(t) for c in system.coordinates]
    return q, u, {**dict(zip(velocities, u, strict=True)), **dict(zip(system.coordinates, q, strict=True))}


def lagrange_reference(system):
    """(t, y, p) -> ∂f/∂y with 40 digits, f = (u, M⁻¹(F + Q − ∂D/∂q̇)) from LagrangesMethod, by sympy and mpmath."""
    lm = me.LagrangesMethod(system.T - system.V, list(system.coordinates))
    lm.form_lagranges_equations()
    velocities = [c.diff(t) for c in system.coordinates]
    forcing = lm.forcing + sp.Matrix(system.forces) - sp.Matrix([system.dissipation.diff(v) for v in velocities])
    q, u, plain = _plain(system)
    M, F = lm.mass_matrix.xreplace(plain).xreplace(plain), forcing.xreplace(plain).xreplace(plain)
    return _explicit_jacobian(sp.Matrix([*u, *M.LUsolve(F)]), (*q, *u), system.parameters)


def kane_reference(km, parameters):
    """(t, y, p) -> ∂f/∂y with 40 digits, f = M_full⁻¹ F_full of `km` (state (q, u) in its order)."""
    q, u = list(km.q), list(km.u)
    plain_q, plain_u = sp.symbols(f"q0:{len(q)}", real=True), sp.symbols(f"u0:{len(u)}", real=True)
    plain = {x.diff(t): s for x, s in zip(q, plain_q, strict=True)}
    plain |= {**dict(zip(u, plain_u, strict=True)), **dict(zip(q, plain_q, strict=True))}
    M, F = km.mass_matrix_full.xreplace(plain), km.forcing_full.xreplace(plain)
    return _explicit_jacobian(M.LUsolve(F), (*plain_q, *plain_u), parameters)


def _explicit_jacobian(f, y, parameters):
    J = sp.lambdify((t, y, parameters), f.jacobian(list(y)), modules="mpmath")

    def at(time, state, p):
        with mpmath.workdps(DIGITS):  # float64 inputs are exact in mpmath: the reference sees the kernel's state
            mp = [mpmath.mpf(float(x)) for x in state], [mpmath.mpf(float(x)) for x in p]
            return np.array(mpmath.matrix(J(mpmath.mpf(float(time)), *mp)).tolist(), dtype=object)
    return at


def _reference_tolerance(J_reference, mass_matrix) -> float:
    """4 N ε κ₁(M) max|J|: a few ulps per entry of M and of the block, amplified by M's condition (module docstring)."""
    size = J_reference.shape[0]
    return 4 * size * EPS * np.linalg.cond(mass_matrix, 1) * float(np.max(np.abs(J_reference.astype(float))))


def damped_double_pendulum() -> lc.System:
    """The double pendulum with Rayleigh damping D = ½ c1 θ̇1² + ½ c2 (θ̇2 − θ̇1)² and drag −k θ̇2 |θ̇2| on θ2."""
    th1, th2 = lc.coordinates("theta1 theta2")
    m1, m2, l1, l2, g, c1, c2, k = sp.symbols("m1 m2 l1 l2 g c1 c2 k", positive=True)
    x1, y1 = l1 * sp.sin(th1), -l1 * sp.cos(th1)
    x2, y2 = x1 + l2 * sp.sin(th2), y1 - l2 * sp.cos(th2)
    speed2 = lambda x, y: x.diff(t) ** 2 + y.diff(t) ** 2  # noqa: E731
    w1, w2 = th1.diff(t), th2.diff(t)
    return lc.System(
        coordinates=(th1, th2), T=m1 * speed2(x1, y1) / 2 + m2 * speed2(x2, y2) / 2, V=g * (m1 * y1 + m2 * y2),
        forces=(0, -k * w2 * sp.Abs(w2)), dissipation=c1 * w1**2 / 2 + c2 * (w2 - w1) ** 2 / 2,
        parameters=(m1, m2, l1, l2, g, c1, c2, k), name="damped_double_pendulum",
        defaults={"m1": 1.3, "m2": 0.7, "l1": 1.1, "l2": 0.9, "g": 9.81, "c1": 0.4, "c2": 0.25, "k": 0.6},
    )


@pytest.fixture(scope="module")
def sleigh(cache_dir):
    """The Chaplygin sleigh of test_kane_interop, compiled (the same cache key as there)."""
    from test_kane_interop import SLEIGH, chaplygin_sleigh

    km = chaplygin_sleigh()
    return km, lc.compile(km, cache_dir=cache_dir, name="chaplygin_sleigh", defaults=SLEIGH)


def _states(rng, size, count=3):
    return [rng.uniform(-2.0, 2.0, size) for _ in range(count)]


def _jacobian(kernels, time, y, p):
    out = np.full((y.size, y.size), np.nan)
    return kernels.rhs_jacobian(time, y, p, out), out


LAGRANGE_MODELS = [("double_pendulum", {}), ("n_link_pendulum", {"n": 3}), ("driven_pendulum", {})]


@pytest.mark.parametrize(("name", "kwargs"), LAGRANGE_MODELS)
def test_lagrange_jacobian_agrees_with_sympy_to_40_digits(name, kwargs, compiled, rng):
    model = compiled(name, **kwargs)
    _check_lagrange(model, lagrange_reference(model.system), rng)


def test_velocity_dependent_forces_and_damping_agree_with_sympy_to_40_digits(cache_dir, rng):
    system = damped_double_pendulum()
    _check_lagrange(lc.compile(system, cache_dir=cache_dir), lagrange_reference(system), rng)


def _check_lagrange(model, reference, rng):
    p, n = model.parameter_vector(), model.n
    for state in _states(rng, 2 * n):
        time = float(rng.uniform(0.0, 0.01))
        status, J = _jacobian(model.kernels, time, state, p)
        assert status == 0
        J_reference = reference(time, state, p)
        M = np.empty((n, n))
        model.kernels.mass_matrix(time, state, p, M)
        error = float(np.max(np.abs(J - J_reference.astype(float))))
        assert error <= _reference_tolerance(J_reference, M), (model.name, error)
        assert np.array_equal(J[:n], np.hstack([np.zeros((n, n)), np.eye(n)]))  # exactly [0 | I]


def test_kane_jacobian_agrees_with_kanes_method_to_40_digits(sleigh, rng):
    km, model = sleigh
    form = model.first_order_form
    reference = kane_reference(km, form.parameters)
    p, size = model.parameter_vector(), model.state_size
    for state in _states(rng, size):
        time = float(rng.uniform(0.0, 0.01))
        status, J = _jacobian(model.kernels, time, state, p)
        assert status == 0
        J_reference = reference(time, state, p)
        at = {**dict(zip(form.parameters, p, strict=True)), **dict(zip(form.q, state[:form.n_q], strict=True))}
        M = np.array(form.M.subs(at), dtype=float)
        error = float(np.max(np.abs(J - J_reference.astype(float))))
        assert error <= _reference_tolerance(J_reference, M), error


def _differences(rhs, time, y, p, h, along="y") -> tuple[np.ndarray, np.ndarray]:
    """Central differences of `rhs` extrapolated (Richardson) to order h⁴, and a bound on their error, both (N, N);
    with ``along="p"`` along the parameters, both (N, len(p)) (test_parameter_jacobian).

    With D(h) the central difference, R(h) = D(h/2) + (D(h/2) − D(h))/3 errs by c h⁴ + O(h⁶), so
    R(h/2) errs by about |R(h) − R(h/2)|/15: we allow the whole difference.  Rounding: f is evaluated
    with relative error ≲ 64 ε (its CSE'd sums and the solve), which a difference quotient at step
    h/4 divides by h/4 and the extrapolations multiply by at most 5/3 twice: 3 × 64 ε max|f| / (h/4).
    """
    size, x = y.size, (y if along == "y" else p)
    scale = np.ones(size)
    arguments = (lambda v: (v, p)) if along == "y" else (lambda v: (y, v))

    def central(step):
        D = np.empty((size, x.size))
        for j in range(x.size):
            plus, minus, f_plus, f_minus = x.copy(), x.copy(), np.empty(size), np.empty(size)
            plus[j] += step
            minus[j] -= step
            assert rhs(time, *arguments(plus), f_plus) == 0 and rhs(time, *arguments(minus), f_minus) == 0
            D[:, j] = (f_plus - f_minus) / (2 * step)
            scale[:] = np.maximum(scale, np.maximum(np.abs(f_plus), np.abs(f_minus)))
        return D
    D1, D2, D4 = central(h), central(h / 2), central(h / 4)
    coarse, fine = D2 + (D2 - D1) / 3, D4 + (D4 - D2) / 3
    return fine, np.abs(coarse - fine) + 3 * 64 * EPS * scale[:, None] / (h / 4)


@settings(max_examples=6, deadline=None, derandomize=True, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1))
def test_random_systems_jacobian_agrees_with_central_differences(seed):
    from lagcomp.codegen.emit import emit
    from lagcomp.codegen.lower import lower
    from lagcomp.mechanics.lagrange import derive

    mech = random_mechanism(seed, max_bodies=2)
    eom = derive(mech.system)
    module = python_kernels(emit(lower(eom)))
    n = eom.n
    p = np.concatenate([mech.values, np.zeros(2 if eom.k else 0)])
    y = np.concatenate([mech.q0, mech.qd0])
    out = np.full((2 * n, 2 * n), 7.0)
    assert "RHS_JACOBIAN_REFUSED" not in module
    assert module["rhs_jacobian"](0.3, y, p, out) == 0
    D, tolerance = _differences(module["rhs"], 0.3, y, p, h=1e-2)
    excess = np.abs(out - D) - tolerance
    assert np.all(excess <= 0), f"{mech.description}: off by {np.max(excess):.3g} beyond the tolerance"


def test_singular_mass_matrix_gives_the_status_of_rhs(compiled):
    model = compiled("double_pendulum")
    y = np.array([0.3, -0.2, 0.5, 0.1])
    for masses, pivot in (((1.0, 0.0), 2), ((0.0, 0.0), 1)):  # m2 = 0: pivot 2 of M vanishes; both: pivot 1
        p = model.parameter_vector({"m1": masses[0], "m2": masses[1]})
        assert model.kernels.rhs(0.0, y, p, np.empty(4)) == pivot
        status, J = _jacobian(model.kernels, 0.0, y, p)
        assert status == pivot


def test_kane_singular_mass_matrix_gives_the_status_of_rhs(sleigh):
    _, model = sleigh
    p = model.parameter_vector({"m": 0.0})  # M = [[m, 0, 0], ...]: pivot 1 vanishes
    y = np.array([0.1, 0.2, 0.3, -0.5, 1.5, 0.0])
    status = model.kernels.rhs(0.0, y, p, np.empty(6))
    assert status > 0
    assert _jacobian(model.kernels, 0.0, y, p)[0] == status


def test_kernels_are_values_of_the_drivers_jacobian_type(compiled, sleigh):
    """Each kind of rhs_jacobian (LDLᵀ, LU, KKT) passes as `kernel_types.RHS_JACOBIAN`, as a driver takes it."""
    from numba import njit, types

    from lagcomp.integrate.drivers.kernel_types import FLOAT, MATRIX, RHS_JACOBIAN, VECTOR

    @njit(types.int64(RHS_JACOBIAN, FLOAT, VECTOR, VECTOR, MATRIX))
    def call(jacobian, time, y, p, out):
        return jacobian(time, y, p, out)

    rng = np.random.default_rng(7)
    for model in (compiled("double_pendulum"), sleigh[1], compiled("spherical_pendulum_cartesian")):
        y, p = rng.uniform(-1.0, 1.0, model.state_size), model.parameter_vector()
        expected, out = _jacobian(model.kernels, 0.0, y, p)
        via_type = np.full_like(out, np.nan)
        assert call(model.kernels.rhs_jacobian, 0.0, y, p, via_type) == expected
        assert np.array_equal(via_type, out, equal_nan=True)


def test_rhs_with_jacobian_is_rhs_and_rhs_jacobian_bitwise(compiled, sleigh):
    """``rhs_with_jacobian`` (the sensitivities' kernel: f and J in one call) writes what ``rhs`` and
    ``rhs_jacobian`` write, bitwise, with their statuses, called as `kernel_types.RHS_WITH_JACOBIAN` as the
    augmented rhs does: Lagrange (LDLᵀ) and Kane (LU) modules, a singular M, and a constrained module (KKT)."""
    from numba import njit, types

    from lagcomp.integrate.drivers.kernel_types import FLOAT, MATRIX, RHS_WITH_JACOBIAN, VECTOR

    @njit(types.int64(RHS_WITH_JACOBIAN, FLOAT, VECTOR, VECTOR, VECTOR, MATRIX))
    def call(kernel, time, y, p, ydot, out):
        return kernel(time, y, p, ydot, out)

    rng = np.random.default_rng(11)
    singular = compiled("double_pendulum").parameter_vector({"m2": 0.0})
    for model in (compiled("double_pendulum"), sleigh[1], compiled("spherical_pendulum_cartesian")):
        for p in (model.parameter_vector(), singular if model.name == "double_pendulum" else None):
            if p is None:
                continue
            for _ in range(5):
                y = rng.uniform(-1.0, 1.0, model.state_size)
                f, J = np.full(y.size, np.nan), np.full((y.size, y.size), np.nan)
                status = model.kernels.rhs(0.0, y, p, f)
                expected = model.kernels.rhs_jacobian(0.0, y, p, J)
                f2, J2 = np.full_like(f, np.nan), np.full_like(J, np.nan)
                assert call(model.kernels.rhs_with_jacobian, 0.0, y, p, f2, J2) == expected
                assert np.array_equal(f2, f, equal_nan=True)
                if status == 0:
                    assert np.array_equal(J2, J)


def test_whipple_bicycle_jacobian_agrees_with_central_differences(whipple_bicycle):
    """sympy's test_kane3 bicycle (the session's model; its module run as plain Python): M with the
    differentiated velocity constraints among its rows, the dependent coordinate q4, CRAMER's quotients."""
    _, model = whipple_bicycle
    module = python_model_kernels(model)
    p, rng = model.parameter_vector(), np.random.default_rng(3)
    y = rng.uniform(-0.3, 0.3, model.state_size)
    out = np.full((y.size, y.size), np.nan)
    assert module["rhs_jacobian"](0.0, y, p, out) == 0
    D, tolerance = _differences(module["rhs"], 0.0, y, p, h=1e-2)
    excess = np.abs(out - D) - tolerance
    assert np.all(excess <= 0), f"off by {np.max(excess):.3g} beyond the tolerance"
