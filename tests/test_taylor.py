"""The Taylor-series integrator (method="taylor"): its recurrences, its accuracy, its events.

References are independent of lagcomp's Taylor code: sympy series for each
recurrence, a numpy long-double Taylor integration of the double pendulum's
hand-derived equations (eps ≈ 1e-19), Kepler's conserved quantities, and
lagcomp's own DOP853 for the Hénon–Heiles section.
"""

from __future__ import annotations

import dataclasses
import math

import mpmath
import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
import lagcomp.examples
from lagcomp.codegen.taylor import Unsupported, decompose
from lagcomp.codegen.taylor_ops import Op, convolution_loop
from lagcomp.errors import OptionError
from lagcomp.integrate.status import Status
from lagcomp.model import t

ORDER = 12


# -- the recurrences against sympy series ---------------------------------------------------

@pytest.fixture(scope="module")
def pendulum(compiled):
    return compiled("double_pendulum")


A = [0.7, -0.3, 0.25, 0.1, -0.05]  # a(τ) = Σ A[k] τ^k, a(0) > 0
B = [1.3, 0.2, -0.4, 0.0, 0.15]


def _reference(f, order=ORDER):
    """Normalized Taylor coefficients at τ = 0 of f(a(τ), b(τ)), by mpmath at 40 digits.

    (mpmath.taylor differentiates numerically at high precision; sympy's series of sin(a(τ)) to
    order 12 takes half a minute.)
    """
    with mpmath.workdps(40):
        a = lambda tau: mpmath.polyval(A[::-1], tau)  # noqa: E731
        b = lambda tau: mpmath.polyval(B[::-1], tau)  # noqa: E731
        coefficients = mpmath.taylor(lambda tau: f(a(tau), b(tau)), 0, order)
        return np.array([float(c) for c in coefficients])


def _padded(coefficients, order=ORDER):
    out = np.zeros(order + 1)
    out[: len(coefficients)] = coefficients
    return out


CASES = {  # operation: (f(a, b) in mpmath, the operation on the series a, b into w (sin_cos: s, c))
    "mul": (lambda a, b: a * b, Op("mul", ("w",), ("a", "b"))),
    "square": (lambda a, b: a**2, Op("square", ("w",), ("a",))),
    "div": (lambda a, b: a / b, Op("div", ("w",), ("a", "b"))),
    "rdiv": (lambda a, b: 2.5 / b, Op("rdiv", ("w",), ("b",), "2.5")),
    "sqrt": (lambda a, b: mpmath.sqrt(a), Op("sqrt", ("w",), ("a",))),
    "pow": (lambda a, b: a ** mpmath.mpf(-1.5), Op("pow", ("w",), ("a",), "-1.5")),
    "exp": (lambda a, b: mpmath.exp(a), Op("exp", ("w",), ("a",))),
    "log": (lambda a, b: mpmath.log(a), Op("log", ("w",), ("a",))),
    "sin_cos": (None, Op("sin_cos", ("s", "c"), ("a",))),
}


def _recurrence(name):
    """The emitted loop of operation `name` (`convolution_loop`), run for k = 0..ORDER in plain Python."""
    _, loop = convolution_loop(CASES[name][1], lambda series, index: f"{series}[{index}]")
    body = "\n".join("        " + line for line in loop)
    namespace = {"math": math, "sin": math.sin, "cos": math.cos}
    prelude = "        _ik = 1.0/k if k > 0 else 0.0\n"  # as at the top of taylor_coefficients' loop
    exec(f"def run(a, b, c, w, s):\n    for k in range({ORDER + 1}):\n{prelude}{body}\n", namespace)
    return namespace["run"]


@pytest.mark.parametrize("name", list(CASES))
def test_each_recurrence_against_an_independent_expansion(name):
    """The loop taylor_coefficients runs for each operation, against mpmath's expansion."""
    a, b = _padded(A), _padded(B)
    w, s, c = np.zeros(ORDER + 1), np.zeros(ORDER + 1), np.zeros(ORDER + 1)
    run = _recurrence(name)
    if name == "sin_cos":
        run(a, None, c, None, s)
        np.testing.assert_allclose(s, _reference(lambda a, b: mpmath.sin(a)), rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(c, _reference(lambda a, b: mpmath.cos(a)), rtol=1e-13, atol=1e-15)
        return
    run(a, b, None, w, None)
    np.testing.assert_allclose(w, _reference(CASES[name][0]), rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize("name", list(CASES))
def test_each_unrolled_recurrence_against_an_independent_expansion(name):
    """The straight-line form of each operation (batched Taylor sweeps, taylor_lanes), against mpmath."""
    from lagcomp.codegen.taylor_lanes import _operation, _series

    lines = [line for k in range(ORDER + 1) for line in _operation(CASES[name][1], k)]
    namespace = {"math": math, "vsin": math.sin, "vcos": math.cos}
    for series, coefficients in (("a", A), ("b", B)):
        namespace.update({_series(series, k): x for k, x in enumerate(_padded(coefficients))})
    exec("\n".join(lines), namespace)
    got = lambda w: np.array([namespace[_series(w, k)] for k in range(ORDER + 1)])  # noqa: E731
    if name == "sin_cos":
        np.testing.assert_allclose(got("s"), _reference(lambda a, b: mpmath.sin(a)), rtol=1e-13, atol=1e-15)
        np.testing.assert_allclose(got("c"), _reference(lambda a, b: mpmath.cos(a)), rtol=1e-13, atol=1e-15)
        return
    np.testing.assert_allclose(got("w"), _reference(CASES[name][0]), rtol=1e-13, atol=1e-15)


def test_coefficients_are_the_derivatives_of_the_solution(pendulum):
    """X[:, 1] = f(y), and the series agrees with the solution a small step later."""
    kernels = pendulum.kernels
    p = pendulum.parameter_vector()
    y = np.array([2.0, 1.0, 0.3, -0.7])
    X, W = np.empty((4, 21)), np.empty((kernels.TAYLOR_WORK, 21))
    assert kernels.taylor_coefficients(0.0, y, p, X, W) == 0
    np.testing.assert_allclose(X[:, 0], y)
    np.testing.assert_allclose(X[:, 1], pendulum.rhs(0.0, y), rtol=1e-14)
    h = 0.05
    series = np.polynomial.polynomial.polyval(h, X.T)
    run = pendulum.simulate((0.0, h), y[:2], y[2:], method="dop853", rtol=1e-13, atol=1e-15, progress=False)
    np.testing.assert_allclose(series, run.y[-1], rtol=0, atol=1e-13)


def test_decomposition_refuses_what_it_cannot_expand(compiled):
    from lagcomp.codegen.lower import lower
    from lagcomp.examples import get
    from lagcomp.mechanics.lagrange import derive

    ir = lower(derive(get("rope_friction")))
    with pytest.raises(Unsupported, match="Piecewise"):
        decompose(ir.kernel("rhs"), ir.n)
    model = compiled("rope_friction")
    with pytest.raises(OptionError, match="`taylor` cannot integrate 'rope_friction'"):
        model.simulate((0, 1), method="taylor")
    from lagcomp.benchmark import applicable_methods

    assert "taylor" not in [m.name for m in applicable_methods(model)]
    assert "taylor_coefficients" not in model.operations


def test_operation_count_is_reported(pendulum):
    """`lagcomp bench` lists model.operations: the Taylor kernel's series operations per order too."""
    assert 20 <= pendulum.operations["taylor_coefficients"] <= 60


# -- accuracy --------------------------------------------------------------------------------

def _jet_reference(y0, t_end, params, order=30, fraction=0.25):
    """The double pendulum at t_end in numpy long double, by a Taylor method written from scratch.

    Equations from the example's docstring (δ = θ1 − θ2), solved by Cramer's rule:
    (m1 + m2) l1 θ̈1 + m2 l2 cos δ θ̈2 = −m2 l2 θ̇2² sin δ − (m1 + m2) g sin θ1,
    l1 cos δ θ̈1 + l2 θ̈2 = l1 θ̇1² sin δ − g sin θ2.
    Each step is `fraction` of the radius of convergence estimated from the last two
    coefficients, so the truncation error is about fraction^order (1e-18 by default).
    """
    L = np.longdouble
    m1, m2, l1, l2, g = (L(params[k]) for k in ("m1", "m2", "l1", "l2", "g"))
    a11, a22 = (m1 + m2) * l1, l2
    y = np.array(y0, dtype=L)
    j = np.arange(order + 2, dtype=L)
    names = ("th1", "th2", "w1", "w2", "d", "S1", "C1", "S2", "C2", "Sd", "Cd", "w1sq", "w2sq", "b1", "b2",
             "det", "x1", "x2")

    def conv(a, b, k):
        return np.dot(a[: k + 1], b[k::-1])

    t_now = L(0)
    compensation = np.zeros(4, dtype=L)
    while t_now < t_end:
        s = {name: np.zeros(order + 1, dtype=L) for name in names}
        for i, name in enumerate(("th1", "th2", "w1", "w2")):
            s[name][0] = y[i]
        for k in range(order):
            s["d"][k] = s["th1"][k] - s["th2"][k]
            for arg, S, C in (("th1", "S1", "C1"), ("th2", "S2", "C2"), ("d", "Sd", "Cd")):
                if k == 0:
                    s[S][0], s[C][0] = np.sin(s[arg][0]), np.cos(s[arg][0])
                else:
                    ja = j[1: k + 1] * s[arg][1: k + 1]
                    s[S][k] = np.dot(ja, s[C][k - 1:: -1]) / k
                    s[C][k] = -np.dot(ja, s[S][k - 1:: -1]) / k
            s["w1sq"][k] = conv(s["w1"], s["w1"], k)
            s["w2sq"][k] = conv(s["w2"], s["w2"], k)
            s["b1"][k] = -m2 * l2 * conv(s["w2sq"], s["Sd"], k) - (m1 + m2) * g * s["S1"][k]
            s["b2"][k] = l1 * conv(s["w1sq"], s["Sd"], k) - g * s["S2"][k]
            s["det"][k] = (a11 * a22 if k == 0 else 0) - m2 * l2 * l1 * conv(s["Cd"], s["Cd"], k)
            n1 = a22 * s["b1"][k] - m2 * l2 * conv(s["Cd"], s["b2"], k)
            n2 = a11 * s["b2"][k] - l1 * conv(s["Cd"], s["b1"], k)
            for x, num in (("x1", n1), ("x2", n2)):
                s[x][k] = (num - (np.dot(s["det"][1: k + 1], s[x][k - 1:: -1]) if k else 0)) / s["det"][0]
            for name, rate in (("th1", "w1"), ("th2", "w2"), ("w1", "x1"), ("w2", "x2")):
                s[name][k + 1] = s[rate][k] / (k + 1)
        last = [max(abs(s[name][m]) for name in ("th1", "th2", "w1", "w2")) for m in (order - 1, order)]
        rho = min(last[0] ** (L(-1) / (order - 1)), last[1] ** (L(-1) / order))
        step = min(fraction * rho, L(t_end) - t_now)
        _advance(y, compensation, [s[name] for name in ("th1", "th2", "w1", "w2")], step)
        t_now += step
    return y


def _advance(state, compensation, series, step):
    """state[i] += Σ_{k≥1} series[i][k] step^k (Horner), with compensated (Kahan) summation, in place."""
    for i, coefficients in enumerate(series):
        acc = np.longdouble(0)
        for c in coefficients[:0:-1]:
            acc = (acc + c) * step
        increment = acc - compensation[i]
        new = state[i] + increment
        compensation[i] = (new - state[i]) - increment
        state[i] = new


@pytest.fixture(scope="module")
def reference(pendulum):
    params = pendulum.system.defaults
    y0 = (2.0, 1.0, 0.0, 0.0)
    return _jet_reference(y0, 10.0, params, order=36, fraction=0.2)


def test_long_double_reference_is_converged(pendulum, reference):
    """Two settings far from truncation agree to 1e-13 at t = 10 (rounding at 1e-19, grown ~1e5-fold)."""
    other = _jet_reference((2.0, 1.0, 0.0, 0.0), 10.0, pendulum.system.defaults, order=44, fraction=0.12)
    assert float(np.max(np.abs(other - reference))) < 1e-13


def test_error_at_t10_falls_with_the_tolerance(pendulum, reference):
    errors = []
    for tol in (1e-6, 1e-8, 1e-10, 1e-12, 1e-14, 2.220446049250313e-16):
        run = pendulum.simulate((0, 10), method="taylor", rtol=tol, progress=False, record="summary")
        errors.append(float(np.max(np.abs(run.y[-1] - reference.astype(float)))))
    assert all(b < a for a, b in zip(errors[:5], errors[1:5])), errors
    assert errors[0] < 1e-1 and errors[2] < 1e-6
    # Rounding errors of 1e-16 grow about 1e5-fold by t = 10 on this chaotic orbit (the long-double
    # reference shows it too), so 1e-11 is about the floor of any float64 integration (measured:
    # 0.5-2e-11 at the default tolerance, depending on the rounding of the code; heyoka 3e-10;
    # DOP853 at rtol 2.3e-14: 2.6e-9).
    assert errors[-1] < 1e-10, errors


def test_energy_at_default_tolerance(pendulum):
    run = pendulum.simulate((0, 200), method="taylor", progress=False, record="summary")
    assert run.success and run.method == "taylor" and run.nrejected == 0
    drift = run.summary.energy_error if hasattr(run.summary, "energy_error") else run.energy_drift()
    assert drift < 1e-12


def test_time_dependent_system_matches_dop853(compiled):
    model = compiled("driven_pendulum")
    a = model.simulate((0, 5), method="taylor", progress=False)
    b = model.simulate((0, 5), method="dop853", rtol=1e-13, atol=1e-14, progress=False)
    np.testing.assert_allclose(a.y[-1], b.y[-1], atol=1e-9)
    # and against an independent derivation: scipy on LagrangesMethod's equations
    from reference import lagranges_method_rhs
    from scipy.integrate import solve_ivp

    theirs = solve_ivp(lagranges_method_rhs(model.system), (0, 5), model.initial_state(), method="DOP853",
                       rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(a.y[-1], theirs.y[:, -1], rtol=0, atol=2e-10)  # measured 4.3e-11


def test_dense_output_is_the_series(pendulum):
    t_eval = np.linspace(0.0, 3.0, 301)
    dense = pendulum.simulate((0, 3), method="taylor", t_eval=t_eval, progress=False)
    np.testing.assert_array_equal(dense.t, t_eval)
    tight = pendulum.simulate((0, 3), method="dop853", rtol=1e-13, atol=1e-15, t_eval=t_eval, progress=False)
    np.testing.assert_allclose(dense.y, tight.y, rtol=0, atol=1e-10)
    steps = pendulum.simulate((0, 3), method="taylor", progress=False)
    assert dense.nsteps == steps.nsteps  # t_eval does not change the steps
    np.testing.assert_array_equal(dense.y[-1], steps.y[-1])


def test_chunked_run_equals_one_call(pendulum):
    whole = pendulum.simulate((0, 20), method="taylor", progress=False, save_every=7)
    from lagcomp.integrate.drivers.taylor import taylor_run

    kernels = pendulum.kernels
    model_parts = (kernels.taylor_coefficients, kernels.event_values, kernels.event_reset, kernels.TAYLOR_PERIODIC,
                   kernels.TAYLOR_WORK)
    y = np.array([2.0, 1.0, 0.0, 0.0])
    clock, counters = np.array([0.0, 0.0]), np.zeros(6, dtype=np.int64)
    p = pendulum.parameter_vector()
    rows = []
    empty = (np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64), np.empty(16), np.empty((16, 4)),
             np.empty(16, dtype=np.int64), np.empty((16, 4)), np.empty(0, dtype=np.int64))
    eps = 2.220446049250313e-16
    carry = np.zeros(4)
    while True:
        ts, ys = np.empty(5), np.empty((5, 4))
        status, n = taylor_run(*model_parts, y, clock, counters, p, 0, np.zeros(1), 20.0, eps, np.full(4, eps),
                               math.inf, 10**9, counters[1] + 13, 7, np.empty(0), ts, ys, *empty, carry)
        rows.append(ys[:n].copy())
        if not Status(status).call_again:
            break
    assert status == 0
    np.testing.assert_array_equal(np.vstack(rows), whole.y[1:])  # bitwise: the carry is kept across calls


# -- Kepler -----------------------------------------------------------------------------------

def kepler() -> lc.System:
    x, y = lc.coordinates("x y")
    mu = sp.Symbol("mu", positive=True)
    return lc.System(coordinates=(x, y), T=(x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=-mu / sp.sqrt(x**2 + y**2),
                     parameters=(mu,), defaults={"mu": 1.0}, name="kepler_taylor",
                     q0=(0.1, 0.0), qd0=(0.0, math.sqrt(1.9 / 0.1)))  # pericentre of a = 1, e = 0.9


@pytest.fixture(scope="module")
def kepler_model(cache_dir):
    return lc.compile(kepler(), cache_dir=cache_dir)


def _kepler_invariants(run):
    x, y, vx, vy = run.y.T
    energy = (vx**2 + vy**2) / 2 - 1 / np.hypot(x, y)
    return energy, x * vy - y * vx


@pytest.mark.parametrize("orbits", [20, pytest.param(10_000, marks=pytest.mark.slow)])
def test_kepler_invariants_at_round_off(kepler_model, orbits):
    run = kepler_model.simulate((0, 2 * math.pi * orbits), method="taylor", progress=False,
                                t_eval=2 * math.pi * np.arange(1, orbits + 1))
    assert run.success
    energy, momentum = _kepler_invariants(run)
    e0, l0 = -0.5, math.sqrt(1.9 * 0.1)
    assert np.max(np.abs(energy / e0 - 1)) < 2e-15 * math.sqrt(orbits) * 10
    assert np.max(np.abs(momentum / l0 - 1)) < 2e-15 * math.sqrt(orbits) * 10
    # back at the pericentre after each whole orbit
    assert np.max(np.abs(run.q[:, 0] - 0.1)) < 1e-12 * orbits


# -- events on the series ---------------------------------------------------------------------

def _henon_heiles_section_reference(y0, t_end, lam, order=30, fraction=0.2):
    """Times of the upward crossings of x = 0 for t in (0, t_end], by a numpy long-double Taylor jet.

    ẍ = −x − 2λxy, ÿ = −y − λ(x² − y²), written out by hand (independent of lagcomp's
    decomposition); steps of `fraction` of the radius of convergence estimated from the last
    two coefficients (truncation about fraction^order); each crossing by Newton's method on the
    step's series of x, in long double.
    """
    L = np.longdouble
    lam = L(lam)
    state = np.array(y0, dtype=L)
    compensation = np.zeros(4, dtype=L)

    def conv(a, b, k):
        return np.dot(a[: k + 1], b[k::-1])

    crossings, t_now = [], L(0)
    while t_now < t_end:
        X, Y, U, V = (np.zeros(order + 1, dtype=L) for _ in range(4))
        X[0], Y[0], U[0], V[0] = state
        for k in range(order):
            X[k + 1], Y[k + 1] = U[k] / (k + 1), V[k] / (k + 1)
            U[k + 1] = (-X[k] - 2 * lam * conv(X, Y, k)) / (k + 1)
            V[k + 1] = (-Y[k] - lam * (conv(X, X, k) - conv(Y, Y, k))) / (k + 1)
        series = (X, Y, U, V)
        last = [max(abs(c[m]) for c in series) for m in (order - 1, order)]
        rho = min(last[0] ** (L(-1) / (order - 1)), last[1] ** (L(-1) / order))
        step = min(fraction * rho, L(t_end) - t_now)
        x_end = np.polynomial.polynomial.polyval(step, X)
        if X[0] < 0 <= x_end:
            tau = step * -X[0] / (x_end - X[0])
            derivative = X[1:] * np.arange(1, order + 1, dtype=L)
            for _ in range(40):
                tau -= np.polynomial.polynomial.polyval(tau, X) / np.polynomial.polynomial.polyval(tau, derivative)
            crossings.append(t_now + tau)
        _advance(state, compensation, series, step)
        t_now += step
    return np.array(crossings)


def test_henon_heiles_section_to_1e13_in_t(compiled):
    """32 section crossings to t = 200 within 1e-13 of a long-double reference, and the same number as
    DOP853 finds.  (Farther on, float64 itself fixes them less closely: runs from starts 1 ulp apart
    spread by 5.7e-14 at t = 200 and 1.1e-12 at t = 2000, bench/bench_taylor.py section 4.)"""
    model = compiled("henon_heiles")
    taylor = model.simulate((0, 200), method="taylor", progress=False, record="summary")
    dop = model.simulate((0, 200), method="dop853", rtol=1e-13, atol=1e-15, progress=False, record="summary")
    a, b = taylor.events["section"], dop.events["section"]
    y0 = (*model.q0, *model.qd0)
    reference = _henon_heiles_section_reference(y0, 200.0, model.parameter_vector()[0])
    other = _henon_heiles_section_reference(y0, 200.0, model.parameter_vector()[0], order=36, fraction=0.12)
    assert np.max(np.abs(reference - other)) < 1e-15  # converged (measured 7e-17)
    assert len(a) == len(b) == len(reference) == 32
    # measured: 2.8e-14 (DOP853 at rtol 1e-13: 2.6e-12)
    assert np.max(np.abs(a.t - reference.astype(float))) < 1e-13
    np.testing.assert_allclose(a.q[:, 1], b.q[:, 1], rtol=0, atol=1e-9)
    assert np.max(np.abs(a.q[:, 0])) < 1e-13  # on the section x = 0 (Brent: 2 eps |t| in time)


def test_terminal_event_stops_on_the_series(compiled, cache_dir):
    """λ = 0: y = 0.1 cos t + 0.05 sin t peaks at t = atan(1/2) (as in test_events), found on the series."""
    system = lc.examples.get("henon_heiles")
    section, y_turn = system.events
    terminal = dataclasses.replace(system, events=(section, dataclasses.replace(y_turn, terminal=True)),
                                   name="henon_heiles_terminal")  # its own name: lc.load("henon_heiles") elsewhere
    model = lc.compile(terminal, cache_dir=cache_dir)
    run = model.simulate((0, 50), qd0=[0.3, 0.05], params={"lam": 0.0}, method="taylor", progress=False)
    t_peak = np.arctan(0.5)
    assert run.status == 1 and "y_turn" in run.message
    assert run.t[-1] == run.events["y_turn"].t[0]
    assert abs(run.t[-1] - t_peak) < 1e-14
    np.testing.assert_allclose(run.q[-1], [0.3 * np.sin(t_peak), np.hypot(0.1, 0.05)], rtol=0, atol=1e-15)


def test_sweep_equals_separate_runs(pendulum):
    """sweep(method="taylor") runs the same driver per trajectory (sweep_taylor): the same final states."""
    angles = np.array([1.0, 1.5, 2.0])
    sweep = pendulum.sweep((0, 5), {"theta1": angles}, method="taylor", progress=False, workers=1)
    assert sweep.method == "taylor" and np.all(sweep.status == 0)
    for i, angle in enumerate(angles):
        run = pendulum.simulate((0, 5), q0=[angle, 1.0], method="taylor", progress=False)
        np.testing.assert_array_equal(sweep.final[i], run.y[-1])
