"""Sensitivities with the Taylor method (`lagcomp.integrate.taylor_sensitivities`, `codegen.taylor_variational`).

Oracles: a linear oscillator's closed form; DOP853's sensitivities and Richardson-extrapolated central
differences of Taylor runs for the double pendulum at t = 10 (issue #22: 1e-8 relative); DOP853's for a system
whose program holds every operation with a tangent recurrence (div, sqrt, pow, exp, log, sin/cos, time), and
for parameter columns.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.model import t

x, y = lc.coordinates("x y")
m, k = sp.symbols("m k", positive=True)
OMEGA = 2.0
#: A regular motion of the double pendulum (finite differences converge there), as in test_sensitivities.
PENDULUM_STATE = np.array([0.5, 0.3, 0.0, 0.0])
TAYLOR = dict(method="taylor", progress=False)


@pytest.fixture(scope="module")
def oscillator(cache_dir):
    system = lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, name="taylor_sensitivity_oscillator",
                       defaults={"m": 1.0, "k": OMEGA**2}, q0=(1.0,), qd0=(0.5,))
    return lc.compile(system, cache_dir=cache_dir)


@pytest.fixture(scope="module")
def pendulum(compiled):
    return compiled("double_pendulum")


@pytest.fixture(scope="module")
def zoo(cache_dir):
    """Every operation with a tangent recurrence: a mass matrix depending on y (div, LDLᵀ), sqrt, a real power,
    exp, log, sin and cos, and time (a forcing in V); parameters in scalars of several kinds."""
    a, b, c = sp.symbols("a b c", positive=True)
    T = ((c + sp.cos(y)) * x.diff(t) ** 2 + y.diff(t) ** 2 + x.diff(t) * y.diff(t) * sp.sin(y)) / 2
    V = (a * sp.exp(x / 3) + sp.sqrt(b + y**2) + x * sp.log(2 + x**2) + (3 + x * y) ** sp.Rational(1, 3)
         + x * sp.cos(t) / (4 * a * b))
    system = lc.System([x, y], T=T, V=V, name="taylor_sensitivity_zoo", defaults={"a": 1.0, "b": 1.5, "c": 2.0},
                       q0=(0.3, -0.2), qd0=(0.1, 0.4))
    return lc.compile(system, cache_dir=cache_dir)


def test_oscillator_matches_the_closed_form(oscillator):
    sol = oscillator.simulate((0.0, 10.0), sensitivities=("q0", "qd0"), **TAYLOR)
    assert sol.success and sol.sensitivity_names == ("q0:x", "qd0:x_dot")
    c, s = np.cos(OMEGA * sol.t), np.sin(OMEGA * sol.t)
    exact = np.stack([np.stack([c, s / OMEGA], axis=-1), np.stack([-OMEGA * s, c], axis=-1)], axis=1)
    assert np.abs(sol.sensitivities - exact).max() < 1e-14       # measured 6.7e-16
    assert np.array_equal(sol.sensitivities[0], np.eye(2))


def _pendulum_run(model, y0, **options):
    return model.simulate((0.0, 10.0), y0[:2], y0[2:], **options)


def test_double_pendulum_against_dop853_and_extrapolated_differences(pendulum):
    sol = _pendulum_run(pendulum, PENDULUM_STATE, sensitivities=("q0", "qd0"), **TAYLOR)
    dop853 = _pendulum_run(pendulum, PENDULUM_STATE, sensitivities=("q0", "qd0"), method="dop853", rtol=1e-13,
                           atol=1e-13, progress=False)
    scale = np.abs(sol.sensitivities[-1]).max()
    assert np.abs(sol.sensitivities[-1] - dop853.sensitivities[-1]).max() < 1e-10 * scale   # measured 3.1e-12
    # (against heyoka's variational run in long double, bench.bench_taylor_sensitivities: 2.9e-16)

    def end(y0):
        return _pendulum_run(pendulum, y0, **TAYLOR).y[-1]

    def differences(h):
        columns = []
        for j in range(4):
            e = np.zeros(4)
            e[j] = h
            columns.append((end(PENDULUM_STATE + e) - end(PENDULUM_STATE - e)) / (2 * h))
        return np.stack(columns, axis=1)

    reference = (4 * differences(1.25e-4) - differences(2.5e-4)) / 3   # (h = 1e-3, 5e-4: 5.4e-11, 3.3e-12)
    relative = np.abs(sol.sensitivities[-1] - reference).max() / np.abs(reference).max()
    assert relative < 1e-10, relative           # measured 1.2e-12 (DOP853 at 1e-13: 4.1e-12)


def test_state_control_keeps_the_plain_run_bitwise(pendulum):
    plain = _pendulum_run(pendulum, PENDULUM_STATE, rtol=1e-12, atol=1e-12, **TAYLOR)
    # (the four columns of test_a_column_alone_is_the_same_column_of_all: one variational kernel for both tests)
    sol = _pendulum_run(pendulum, PENDULUM_STATE, rtol=1e-12, atol=1e-12, sensitivities=("q0", "qd0"),
                        sensitivity_control="state", **TAYLOR)
    assert np.array_equal(sol.t, plain.t) and np.array_equal(sol.y, plain.y)
    assert sol.sensitivities.shape == (sol.t.size, 4, 4) and sol.nfev == plain.nfev


def test_a_column_alone_is_the_same_column_of_all(pendulum):
    # under "state" both take the plain run's steps (under "both" each its own)
    full = _pendulum_run(pendulum, PENDULUM_STATE, sensitivities=("q0", "qd0"), sensitivity_control="state", **TAYLOR)
    one = _pendulum_run(pendulum, PENDULUM_STATE, sensitivities="theta2_dot", sensitivity_control="state",
                        **TAYLOR)    # a kernel of its own (k = 1)
    assert one.sensitivity_names == ("qd0:theta2_dot",) and np.array_equal(one.t, full.t)
    scale = np.abs(full.sensitivities).max()
    assert np.abs(one.sensitivities[:, :, 0] - full.sensitivities[:, :, 3]).max() < 1e-14 * scale


def test_both_control_takes_more_steps_and_agrees(pendulum):
    # (the columns, and so the variational kernels, of the tests above: k = 4 under each control)
    state = _pendulum_run(pendulum, PENDULUM_STATE, rtol=1e-12, atol=1e-12, sensitivities=("q0", "qd0"),
                          sensitivity_control="state", **TAYLOR)
    both = _pendulum_run(pendulum, PENDULUM_STATE, rtol=1e-12, atol=1e-12, sensitivities=("q0", "qd0"),
                         sensitivity_control="both", **TAYLOR)
    assert both.nsteps > state.nsteps
    assert np.abs(both.y[-1] - state.y[-1]).max() < 1e-10
    scale = np.abs(state.sensitivities).max()
    assert np.abs(both.sensitivities[-1] - state.sensitivities[-1]).max() < 1e-9 * scale


@pytest.mark.parametrize("control", [pytest.param("state", marks=pytest.mark.slow), "both"])  # 25 s each, cold
def test_every_operation_against_dop853_with_t_eval(zoo, control):
    t_eval = np.linspace(0.0, 5.0, 11)
    columns = ("q0", "qd0", "params")
    sol = zoo.simulate((0.0, 5.0), sensitivities=columns, sensitivity_control=control, t_eval=t_eval, **TAYLOR)
    ops = {op["kind"] for op in zoo._taylor_program["body"]}
    assert {"div", "sqrt", "pow", "exp", "log", "sin_cos", "mul", "square"} <= ops and zoo._taylor_program["uses_t"]
    dop853 = zoo.simulate((0.0, 5.0), sensitivities=columns, t_eval=t_eval, method="dop853", rtol=1e-13,
                          atol=1e-13, progress=False)
    assert sol.sensitivity_names[4:] == ("p:a", "p:b", "p:c")
    error = np.abs(sol.sensitivities - dop853.sensitivities).max(axis=(0, 1))
    assert (error < 1e-10 * np.abs(dop853.sensitivities).max(axis=(0, 1))).all(), error   # measured ≤ 1.4e-12


def test_parameter_columns_of_the_double_pendulum(pendulum):
    sol = _pendulum_run(pendulum, PENDULUM_STATE, sensitivities="params", **TAYLOR)
    dop853 = _pendulum_run(pendulum, PENDULUM_STATE, sensitivities="params", method="dop853", rtol=1e-13, atol=1e-13,
                           progress=False)
    assert sol.sensitivity_names == ("p:m1", "p:m2", "p:l1", "p:l2", "p:g")
    error = np.abs(sol.sensitivities[-1] - dop853.sensitivities[-1]).max(axis=0)
    assert (error < 1e-10 * np.abs(dop853.sensitivities[-1]).max(axis=0)).all(), error   # measured ≤ 5.1e-12

    p0 = np.array([pendulum.defaults[name] for name in pendulum.parameters])

    def differences(h):     # relative steps h p_j
        columns = []
        for j in range(p0.size):
            e = np.zeros(p0.size)
            e[j] = h * p0[j]
            ends = [_pendulum_run(pendulum, PENDULUM_STATE, params=dict(zip(pendulum.parameters, p0 + s * e,
                                                                            strict=True)), **TAYLOR).y[-1]
                    for s in (1, -1)]
            columns.append((ends[0] - ends[1]) / (2 * e[j]))
        return np.stack(columns, axis=1)

    reference = (4 * differences(1.25e-4) - differences(2.5e-4)) / 3
    relative = np.abs(sol.sensitivities[-1] - reference).max() / np.abs(reference).max()
    assert relative < 1e-10, relative           # measured 2.7e-12 (DOP853 at 1e-13: 6.6e-12)


def test_event_sensitivities_match_dop853(compiled):
    model = compiled("henon_heiles")
    sol = model.simulate((0.0, 30.0), sensitivities=("q0", "qd0"), **TAYLOR)
    dop853 = model.simulate((0.0, 30.0), sensitivities=("q0", "qd0"), method="dop853", rtol=1e-13, atol=1e-13,
                            progress=False)
    for name in ("section", "y_turn"):
        ours, theirs = sol.event_sensitivities[name], dop853.event_sensitivities[name]
        assert ours.t.shape == theirs.t.shape and ours.t.shape[0] > 0
        # measured 1.0e-12 and 1.9e-12 (section), 2.6e-12 and 2.7e-12 (y_turn)
        assert np.abs(ours.t - theirs.t).max() < 1e-9 * np.abs(theirs.t).max()
        assert np.abs(ours.y - theirs.y).max() < 1e-9 * np.abs(theirs.y).max()


def test_refusals(pendulum, compiled, monkeypatch):
    older = {key: value for key, value in pendulum._taylor_program.items() if key != "parameter_partials"}
    # a program stored before the partials (a property of the model: the companion module's entry keeps it)
    monkeypatch.setattr(type(pendulum), "_taylor_program", property(lambda model: older))
    with pytest.raises(lc.OptionError, match="compile the model again"):
        pendulum.simulate((0.0, 1.0), sensitivities=("q0", "params"), **TAYLOR)
    monkeypatch.undo()
    with pytest.raises(lc.OptionError, match="constraints"):    # as Taylor refuses such models without them
        compiled("spherical_pendulum_cartesian").simulate((0.0, 1.0), sensitivities="q0", **TAYLOR)


@pytest.mark.slow  # 20 s: a kernel of its own, compiled cold
def test_the_loop_over_blocks_of_columns_agrees(zoo, monkeypatch):
    from lagcomp.codegen import taylor_kernel_frame, taylor_variational
    from lagcomp.integrate import taylor_sensitivities

    columns = ("q0", "qd0", "params")
    unrolled = zoo.simulate((0.0, 5.0), sensitivities=columns, **TAYLOR)      # 7 columns in one pass
    monkeypatch.setattr(taylor_kernel_frame, "UNROLLED_COLUMNS", 2)            # blocks of 4: 8 columns, one padding
    monkeypatch.setattr(taylor_sensitivities, "_MODULES", {})                  # (so that the kernel is written anew)
    monkeypatch.setattr(taylor_sensitivities, "_KERNELS", {})
    assert "_b in range(0, 8, 4)" in taylor_variational.variational_source(zoo._taylor_program, 7, (0, 1, 2))
    looped = zoo.simulate((0.0, 5.0), sensitivities=columns, **TAYLOR)
    assert np.array_equal(looped.y, unrolled.y)
    scale = np.abs(unrolled.sensitivities).max()
    assert np.abs(looped.sensitivities - unrolled.sensitivities).max() < 1e-13 * scale
