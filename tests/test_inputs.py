"""Inputs u(t) (issue 23): tabulated signals read by the kernels from p, and feedback laws compiled with the model.

The references: the same system with the signal written as an expression of t (the difference is the
interpolant's error, whose scaling with the table's spacing is checked), the closed-loop polynomial of a
PD law, scipy's CubicSpline, and single runs for a sweep.
"""

from __future__ import annotations

import ast
import math
import subprocess
import sys

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from numba import njit
from numba.core import event as numba_event
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq

import lagcomp as lc
from lagcomp import analysis as an
from lagcomp.codegen.bindings import USER_NAMESPACE, user_local
from lagcomp.codegen.emit import emit
from lagcomp.codegen.lower import lower
from lagcomp.errors import ModelError, OptionError
from lagcomp.integrate.inputs import pack_inputs
from lagcomp.kernel_support.inputs import input_value
from lagcomp.mechanics.lagrange import derive

t = lc.t
th, x = lc.coordinates("theta x")
m, l, g, A, w, k = sp.symbols("m l g A omega k", positive=True)  # noqa: E741
Kp, Kd = sp.symbols("K_p K_d", positive=True)
AMPLITUDE, OMEGA, T_END = 0.1, 3.0, 10.0
PENDULUM = {"m": 1.0, "l": 1.0, "g": 9.81}


def _driven_pendulum(support, name: str, **defaults) -> lc.System:
    """A pendulum whose support moves along x by `support`(t): ẍ_s enters the forcing."""
    px, py = support + l * sp.sin(th), -l * sp.cos(th)
    return lc.System([th], T=m * (px.diff(t) ** 2 + py.diff(t) ** 2) / 2, V=m * g * py, name=name,
                     defaults={**PENDULUM, **defaults}, q0=(0.3,))


def _inverted_pendulum(torque, name: str, **options) -> lc.System:
    """m l² θ̈ = m g l sin θ + τ."""
    return lc.System([th], T=m * l**2 * th.diff(t) ** 2 / 2, V=m * g * l * sp.cos(th), forces=[torque], name=name,
                     defaults={**PENDULUM, "K_p": 30.0, "K_d": 8.0}, q0=(0.3,), **options)


@pytest.fixture(scope="module")
def driven(cache_dir):
    """(the pendulum with the support motion an Input, the same with x_s = A sin ωt written out)."""
    tabulated = lc.compile(_driven_pendulum(lc.Input("x_s"), "inputs_driven"), cache_dir=cache_dir)
    written = lc.compile(_driven_pendulum(A * sp.sin(w * t), "inputs_driven_expr", A=AMPLITUDE, omega=OMEGA),
                         cache_dir=cache_dir)
    return tabulated, written


@pytest.fixture(scope="module")
def tracking(cache_dir):
    """The inverted pendulum under τ = −Kp (θ − r) − Kd θ̇: a law, with the reference r(t) a tabulated input."""
    r = lc.Input("r")
    return lc.compile(_inverted_pendulum(lc.Input("tau", law=-Kp * (th - r) - Kd * th.diff(t)), "inputs_tracking"),
                      cache_dir=cache_dir)


def _support(spacing: float, kind: str = "cubic") -> lc.Tabulated:
    times = np.linspace(0.0, T_END, round(T_END / spacing) + 1)
    return lc.Tabulated(times, AMPLITUDE * np.sin(OMEGA * times), kind=kind)


# -- tabulated signals against the expression ----------------------------------------------


def test_the_support_motion_reads_its_second_derivative(driven):
    tabulated, _ = driven
    assert tabulated.inputs == ("x_s",) and tabulated.input_orders == (2,)
    assert tabulated.parameters == ("g", "l", "m")
    assert "INPUTS = ('x_s',)" in tabulated.source_path.read_text(encoding="utf-8")
    assert "<code>x_s</code> (up to d2/dt2)" in tabulated._repr_html_()


def test_a_tabulated_support_motion_equals_the_expression_to_the_interpolants_error(driven):
    """The difference shrinks as the table's spacing Δ does, at the rate of the interpolant.

    ẍ_s of a cubic spline is within O(Δ²) of the signal's (its largest error drops 4× when Δ halves);
    the trajectory integrates that error twice over many pieces and, the local errors alternating in
    sign, it drops about 16× (Δ⁴): measured 2.16e-4, 1.36e-5, 8.5e-7 at Δ = 0.1, 0.05, 0.025.
    """
    tabulated, written = driven
    reference = written.simulate((0.0, T_END), rtol=1e-12, atol=1e-12)
    differences, accelerations = [], []
    probe = np.linspace(0.0, T_END, 2001)
    for spacing in (0.1, 0.05, 0.025):
        signal = _support(spacing)
        sol = tabulated.simulate((0.0, T_END), inputs={"x_s": signal}, rtol=1e-12, atol=1e-12)
        assert sol.status == 0
        differences.append(float(np.max(np.abs(sol.q[-1] - reference.q[-1]))))
        p = pack_inputs(("x_s",), (2,), {"x_s": signal}, None, 0)
        kernel = np.array([input_value(s, p, 0, 2) for s in probe])
        accelerations.append(float(np.max(np.abs(kernel + AMPLITUDE * OMEGA**2 * np.sin(OMEGA * probe)))))
    assert differences[-1] < 2e-6
    for coarse, fine in zip(differences[:-1], differences[1:], strict=True):
        assert 12 < coarse / fine < 20  # Δ⁴: measured 15.9, 16.0
    for coarse, fine in zip(accelerations[:-1], accelerations[1:], strict=True):
        assert 3.5 < coarse / fine < 4.5  # Δ²: ẍ_s of the spline


def test_every_kind_of_method_takes_a_tabulated_input(driven):
    tabulated, written = driven
    signal = _support(0.01)
    for method, options in (("rk4", {"dt": 1e-3}), ("gauss2", {"dt": 1e-3}), ("verlet", {"dt": 1e-3}),
                            ("radau", {"rtol": 1e-10, "atol": 1e-10})):
        sol = tabulated.simulate((0.0, 2.0), inputs={"x_s": signal}, method=method, progress=False, **options)
        reference = written.simulate((0.0, 2.0), method=method, progress=False, **options)
        assert sol.status == 0
        assert abs(sol.q[-1, 0] - reference.q[-1, 0]) < 1e-6, method  # the table's error (measured < 3e-7)


def _pushed(force, name: str) -> lc.System:
    """m ẍ = −k x + force, with an event where x passes a tenth of the force (an input in an event too)."""
    return lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, forces=[force], name=name,
                     events=[lc.Event("passes", x - force / 10)], defaults={"m": 1.0, "k": 4.0},
                     q0=(0.0,))


def test_a_linear_table_of_a_force(cache_dir):
    """m ẍ = −k x + u(t) with u a linear table of u = c t (exact for a linear table) equals the force c t."""
    force = lc.Input("push")
    tabulated = lc.compile(_pushed(force, "inputs_push"), cache_dir=cache_dir)
    written = lc.compile(_pushed(0.5 * t, "inputs_push_expr"), cache_dir=cache_dir)
    assert tabulated.input_orders == (0,)
    times = np.linspace(0.0, 5.0, 7)
    sol = tabulated.simulate((0.0, 5.0), inputs={"push": lc.Tabulated(times, 0.5 * times, kind="linear")},
                             rtol=1e-12, atol=1e-12)
    reference = written.simulate((0.0, 5.0), rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(sol.y[-1] - reference.y[-1])) < 1e-11
    crossings = sol.events["passes"].t
    assert len(crossings) == len(reference.events["passes"].t) > 0
    assert np.max(np.abs(crossings - reference.events["passes"].t)) < 1e-10
    by_input = tabulated.simulate((0.0, 5.0), inputs={force: (times, 0.5 * times)}, rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(by_input.y[-1] - reference.y[-1])) < 1e-11  # keyed by the Input itself; cubic, exact too
    constant = tabulated.simulate((0.0, 1.0), inputs={"push": 0.0}, rtol=1e-12, atol=1e-12)
    assert abs(constant.q[-1, 0]) == 0.0  # at rest, no force: stays at rest


# -- changing an input recompiles nothing ----------------------------------------------------


def test_a_new_table_compiles_nothing(driven):
    tabulated, _ = driven
    tabulated.simulate((0.0, 1.0), inputs={"x_s": _support(0.1)}, progress=False)
    with numba_event.install_recorder("numba:compile") as recorder:
        other = lc.Tabulated(np.linspace(-1.0, 3.0, 57), np.cos(np.linspace(-1.0, 3.0, 57)))  # other values, length
        sol = tabulated.simulate((0.0, 1.0), inputs={"x_s": other}, progress=False)
    assert sol.status == 0
    assert recorder.buffer == []
    with numba_event.install_recorder("numba:compile") as recorder:  # the recorder does see a compilation
        njit(lambda a: a + 1.0)(1.0)
    assert recorder.buffer


#: A later process: the model by name from the cache, a table it never saw, numba's compile events counted.
LATER_PROCESS = """
import sys
import numpy as np
from numba.core import event
import lagcomp as lc
model = lc.load("inputs_driven", cache_dir=sys.argv[1])
times = np.linspace(0.0, 2.0, 33)
with event.install_recorder("numba:compile") as recorder:
    sol = model.simulate((0.0, 1.0), inputs={"x_s": (times, np.sin(times))}, progress=False)
print(sol.status, len(recorder.buffer))
"""


def test_a_later_process_runs_a_new_table_without_compiling(driven, cache_dir):
    driven[0].simulate((0.0, 1.0), inputs={"x_s": _support(0.1)}, progress=False)  # numba's cache is written
    out = subprocess.run([sys.executable, "-c", LATER_PROCESS, str(cache_dir)], capture_output=True, text=True,
                         check=True)
    assert out.stdout.split() == ["0", "0"]


# -- feedback laws -----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def pd(cache_dir):
    return lc.compile(_inverted_pendulum(lc.Input("tau", law=-Kp * th - Kd * th.diff(t)), "inputs_pd"),
                      cache_dir=cache_dir)


def test_a_pd_law_settles_the_inverted_pendulum(pd):
    assert pd.inputs == () and pd.parameters == ("K_d", "K_p", "g", "l", "m")  # the gains are parameters
    sol = pd.simulate((0.0, 20.0), q0=[0.3], rtol=1e-10, atol=1e-12)
    assert sol.status == 0 and abs(sol.q[-1, 0]) < 1e-12 and abs(sol.qd[-1, 0]) < 1e-12


def test_the_closed_loop_eigenvalues_are_the_linearized_ones(pd):
    """Roots of m l² λ² + Kd λ + (Kp − m g l) = 0, from lagcomp's linearization of the compiled law."""
    for gains in ({"K_p": 30.0, "K_d": 8.0}, {"K_p": 12.0, "K_d": 1.5}):
        params = {**PENDULUM, **gains}
        modes = an.normal_modes(pd, [0.0], params)
        exact = np.roots([params["m"] * params["l"] ** 2, params["K_d"],
                          params["K_p"] - params["m"] * params["g"] * params["l"]])
        found = np.sort_complex(np.asarray(modes.eigenvalues))
        assert np.max(np.abs(found - np.sort_complex(exact))) < 1e-12 * np.max(np.abs(exact))
        assert modes.stability == "asymptotically stable"


def test_a_law_with_velocities_in_t_is_refused():
    law = lc.Input("lift", law=-Kd * th.diff(t))
    with pytest.raises(ModelError, match="lift"):
        lc.System([th], T=m * (l + law) ** 2 * th.diff(t) ** 2 / 2, name="inputs_bad")
    with pytest.raises(ModelError, match="lift"):
        lc.System([th, x], T=m * (th.diff(t) ** 2 + x.diff(t) ** 2) / 2, name="inputs_bad",
                  constraints=[lc.Holonomic("rail", x - law)])


def test_a_law_of_q_in_t_is_a_moving_support():
    """A law without velocities may drive T: x_s = c θ makes M depend on θ (derived as if written out)."""
    c = sp.Symbol("c")
    by_law = derive(_driven_pendulum(lc.Input("x_s", law=c * th), "inputs_law_support"))
    written = derive(_driven_pendulum(c * th, "inputs_law_support"))
    assert sp.simplify(by_law.M[0, 0] - written.M[0, 0]) == 0 and sp.simplify(by_law.F[0] - written.F[0]) == 0


def test_a_replaced_system_keeps_its_laws_and_bodies_once():
    """`dataclasses.replace` of a System with bodies and a law: the totals are recognized, not counted twice."""
    import dataclasses

    tau = lc.Input("tau", law=-Kp * x)
    system = lc.System([x], bodies=[lc.Particle(m, (x, 0, 0))], loads=[lc.Force((tau, 0, 0), (x, 0, 0))],
                       name="inputs_replaced")
    again = dataclasses.replace(system, name="inputs_replaced_again")
    assert again.T == system.T and again.forces == system.forces == (-Kp * x,)


def test_a_law_may_use_other_inputs_with_laws_or_without():
    c = sp.Symbol("c")
    reference = lc.Input("r")
    inner = lc.Input("a", law=c * (th - reference))
    outer = lc.Input("b", law=-2 * inner - Kd * th.diff(t))
    system = lc.System([th], T=m * th.diff(t) ** 2 / 2, forces=[outer], name="inputs_nested")
    assert system.forces == (-2 * c * (th - reference) - Kd * th.diff(t),) and system.inputs == (reference,)


def test_an_input_named_like_a_parameter_is_refused():
    with pytest.raises(ModelError, match=r"\['m'\]"):
        _driven_pendulum(lc.Input("m"), "inputs_clash")


# -- sweeps ------------------------------------------------------------------------------------


def test_a_sweep_over_gains_with_a_table_matches_single_runs_bitwise(tracking):
    assert tracking.inputs == ("r",) and tracking.input_orders == (0,)
    times = np.linspace(0.0, 5.0, 21)
    reference = lc.Tabulated(times, 0.2 * np.tanh(times - 1.0), kind="linear")
    gains = [20.0, 30.0, 45.0]
    result = tracking.sweep((0.0, 5.0), {"K_p": gains}, inputs={"r": reference}, workers=1, progress=False)
    assert np.all(result.status == 0)
    for i, gain in enumerate(gains):
        single = tracking.simulate((0.0, 5.0), params={"K_p": gain}, inputs={"r": reference}, progress=False)
        assert np.array_equal(result.final[i], single.y[-1])
    # it holds the reference's end value r, offset by gravity: m g l sin θ = Kp (θ − r)
    r_end = 0.2 * math.tanh(4.0)
    steady = brentq(lambda q: PENDULUM["g"] * math.sin(q) - gains[-1] * (q - r_end), 0.0, 1.0)
    assert abs(result.final[-1, 0] - steady) < 1e-3


# -- refusals ----------------------------------------------------------------------------------


@pytest.mark.parametrize("inputs, culprit", [
    ({}, "Missing input(s) ['x_s']"),
    ({"x_s": (np.linspace(0, 2, 5), np.zeros(5)), "y_s": 0.0}, "Unknown input(s) ['y_s']"),
    ({"x_s": (np.array([0.0, 1.0, 1.0, 2.0]), np.zeros(4))}, "strictly increasing"),
    ({"x_s": (np.array([0.0, np.nan, 2.0]), np.zeros(3))}, "non-finite"),
    ({"x_s": (np.linspace(0, 2, 5), np.zeros(4))}, "5 times but 4 values"),
    ({"x_s": (np.linspace(0, 0.5, 5), np.zeros(5))}, "not the run's time span"),
    ({"x_s": lc.Tabulated(np.linspace(0, 2, 5), np.zeros(5), kind="linear")}, "second derivative"),
])
def test_bad_inputs_are_refused(driven, inputs, culprit):
    with pytest.raises(OptionError) as err:
        driven[0].simulate((0.0, 1.0), inputs=inputs)
    assert culprit in str(err.value)


def test_a_batched_sweep_is_refused_with_a_tabulated_input(driven):
    with pytest.raises(OptionError, match="with inputs"):
        driven[0].sweep((0.0, 1.0), {"theta": [0.1, 0.2]}, inputs={"x_s": _support(0.1)}, batched=True)


def test_taylor_is_refused_with_a_tabulated_input(driven):
    with pytest.raises(OptionError, match="inputs supplied at run time"):
        driven[0].simulate((0.0, 1.0), inputs={"x_s": _support(0.1)}, method="taylor")


def test_a_one_state_evaluation_says_it_needs_the_tables(driven):
    with pytest.raises(OptionError, match=r"reads the input\(s\) \['x_s'\]"):
        driven[0].rhs(0.0, [0.1, 0.0])


def test_inputs_for_a_model_without_inputs_are_refused(pd):
    with pytest.raises(OptionError, match="has no inputs"):
        pd.simulate((0.0, 1.0), inputs={"tau": 1.0})


# -- the kernel's interpolation and the input's names ----------------------------------------


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(0.01, 2.0), min_size=1, max_size=30), st.lists(st.floats(-1e3, 1e3), min_size=31,
       max_size=31), st.floats(0.0, 1.0), st.lists(st.floats(0.0, 1.0), min_size=1, max_size=20))
def test_the_kernel_interpolates_as_scipys_cubic_spline(gaps, values, start, fractions):
    """input_value at random times equals CubicSpline's value and derivatives to a few ulps of its terms."""
    times = start + np.concatenate([[0.0], np.cumsum(gaps)])
    samples = np.asarray(values[: times.size])
    spline = CubicSpline(times, samples)
    p = np.concatenate([[1.5, -2.0], pack_inputs(("u",), (2,), {"u": spline}, None, 2)])  # after two parameters
    for fraction in fractions:
        s = times[0] + fraction * (times[-1] - times[0])
        piece = min(max(np.searchsorted(times, s, side="right") - 1, 0), times.size - 2)
        d = s - times[piece]
        for order in range(4):
            # a few ulps of the sum of the |terms| of the derivative's polynomial: c_j (3 − j)!/(3 − j − order)! d^…
            powers = [math.perm(3 - j, order) * d ** (3 - j - order) if 3 - j >= order else 0.0 for j in range(4)]
            tolerance = 8 * np.finfo(float).eps * (np.abs(spline.c[:, piece]) @ np.array(powers)) + 1e-300
            assert abs(input_value(s, p, 2, order) - spline(s, order)) <= tolerance, (s, order)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(0.01, 2.0), min_size=2, max_size=30), st.lists(st.floats(-1e3, 1e3), min_size=31,
       max_size=31), st.floats(0.0, 1.0))
def test_at_a_breakpoint_the_kernel_reads_the_piece_that_starts_there(gaps, values, start):
    """Exactly at an interior breakpoint x_k the table is read on piece k (x_k ≤ t < x_(k+1)), as scipy's PPoly
    does: a cubic's third derivative (which jumps there) is 6 a_k, a linear table's slope that of [x_k, x_(k+1)]."""
    times = start + np.concatenate([[0.0], np.cumsum(gaps)])
    samples = np.asarray(values[: times.size])
    spline = CubicSpline(times, samples)
    p = pack_inputs(("u",), (3,), {"u": spline}, None, 0)
    linear = pack_inputs(("u",), (1,), {"u": lc.Tabulated(times, samples, kind="linear")}, None, 0)
    for k in range(1, times.size - 1):
        for order in range(4):
            assert input_value(times[k], p, 0, order) == spline(times[k], order), (k, order)
        slope = (samples[k + 1] - samples[k]) / (times[k + 1] - times[k])
        assert input_value(times[k], linear, 0, 1) == pytest.approx(slope, rel=4 * np.finfo(float).eps, abs=0), k
        assert input_value(times[k], linear, 0, 0) == samples[k]


RISKY = ("k", "t", "p", "y", "out", "x.1", "u_k", "ud_k", "_c0", "input_value", "range")


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.one_of(st.sampled_from(RISKY), st.text(st.characters(categories=("L", "N", "Pc")), min_size=1, max_size=6)))
def test_an_input_may_have_any_name(name):
    """The input's locals are in the user namespace and bound from input_value, whatever its name."""
    force = lc.Input(name)
    (q,) = lc.coordinates("q_" if name == "q" else "q")
    system = lc.System([q], T=q.diff(t) ** 2 / 2, V=sp.Symbol("c") * q**2 / 2, forces=[force * q.diff(t)],
                       name="inputs_names")
    assert system.input_names == (name,)
    source = emit(lower(derive(system)))
    loads = [node for node in ast.walk(ast.parse(source)) if isinstance(node, ast.Assign)
             and isinstance(node.value, ast.Call) and getattr(node.value.func, "id", "") == "input_value"]
    assert loads and all(USER_NAMESPACE.match(node.targets[0].id) for node in loads)
    assert {node.targets[0].id for node in loads} == {user_local("u", name, 0)}  # u_<name>, or u0_<its letters>


def test_risky_input_names_integrate(cache_dir):
    """Inputs named like kernel names (k, t, p, y, out) next to a parameter k: each read from its own table."""
    names = ("t", "p", "y", "out")
    forces = [lc.Input(name) for name in names]
    system = lc.System([x], T=x.diff(t) ** 2 / 2, V=k * x**2 / 2, forces=[sum(forces)], name="inputs_risky",
                       defaults={"k": 1.0}, q0=(0.0,))
    model = lc.compile(system, cache_dir=cache_dir)
    assert model.inputs == tuple(sorted(names))
    pushes = {name: float(i + 1) for i, name in enumerate(names)}
    sol = model.simulate((0.0, 2.0), inputs=pushes, rtol=1e-12, atol=1e-12)
    total = sum(pushes.values())  # ẍ = −x + 10 from rest: x = 10 (1 − cos t)
    assert abs(sol.q[-1, 0] - total * (1 - math.cos(2.0))) < 1e-10


def test_an_input_may_move_a_frame():
    """A frame accelerated by a(t) (an Input) gives the equations of the same frame accelerated by A sin ωt."""
    def system(acceleration):
        frame = lc.MovingFrame(acceleration=(acceleration, 0, 0))
        return lc.System([x], bodies=[lc.Particle(m, (x, 0, 0))], loads=[lc.Force((-k * x, 0, 0), (x, 0, 0))],
                         frame=frame, name="inputs_frame")
    signal = lc.Input("a")
    by_input, written = derive(system(signal)), derive(system(A * sp.sin(w * t)))
    assert system(signal).input_names == ("a",)
    assert sp.simplify(by_input.F[0].xreplace({signal: A * sp.sin(w * t)}) - written.F[0]) == 0


def test_an_input_in_a_constraint_reads_its_table_after_the_baumgarte_gains(driven, cache_dir):
    """The support as a coordinate held on the input by a constraint, x_c − x_s(t) = 0: the same motion as the
    support written into T, through the augmented solve (dop853) and the DAE (radau)."""
    xc = lc.coordinates("x_c")[0]
    support = lc.Input("x_s")
    px, py = xc + l * sp.sin(th), -l * sp.cos(th)
    held = lc.compile(lc.System([xc, th], T=m * (px.diff(t) ** 2 + py.diff(t) ** 2) / 2, V=m * g * py,
                                constraints=[lc.Holonomic("hold", xc - support)], name="inputs_held",
                                defaults=PENDULUM, q0=(0.0, 0.3), qd0=(AMPLITUDE * OMEGA, 0.0)), cache_dir=cache_dir)
    assert held.inputs == ("x_s",)
    _, written = driven
    signal = _support(0.01)
    reference = written.simulate((0.0, 2.0), rtol=1e-12, atol=1e-12)
    for method in ("dop853", "radau"):
        sol = held.simulate((0.0, 2.0), inputs={"x_s": signal}, method=method, rtol=1e-10, atol=1e-10,
                            progress=False, project_initial=True)  # (the spline's ẋ_s(0) is Aω to 4e-8)
        assert sol.status == 0
        assert abs(sol.q[-1, 1] - reference.q[-1, 0]) < 1e-6, method  # the table's error (measured 3.3e-8, 3.5e-11)


# -- inputs in the pictures: equations and bodies -------------------------------------------------------


@pytest.fixture(scope="module")
def bob_on_support(cache_dir):
    """The driven pendulum built from a Particle, its support x_s an input: the geometry kernel reads the table."""
    x_s = lc.Input("x_s")
    bob = lc.Particle(m, (x_s + l * sp.sin(th), -l * sp.cos(th), 0), name="bob")
    system = lc.System([th], bodies=[bob], V=-m * g * l * sp.cos(th), name="inputs_bob", defaults=PENDULUM,
                       q0=(0.3,))
    return lc.compile(system, cache_dir=cache_dir)


def test_the_equations_write_an_input_and_its_derivatives_like_a_coordinate(bob_on_support):
    equations = bob_on_support.equations()
    motion = equations.part("motion")[0]
    assert r"\ddot{x}_{s} l m \cos{\left(\theta \right)}" in motion.rhs
    assert "x_s_ddot*l*m*cos(theta)" in motion.text
    assert "Derivative" not in str(equations) and r"\frac{d" not in equations.latex


def test_a_body_moved_by_an_input_is_drawn_where_the_table_puts_it(bob_on_support, animations_freed_quietly):
    pytest.importorskip("matplotlib")
    times = np.linspace(0.0, 2.0, 41)
    values = AMPLITUDE * np.sin(OMEGA * times)
    sol = bob_on_support.simulate((0.0, 2.0), inputs={"x_s": (times, values)}, t_eval=np.linspace(0.0, 2.0, 21))
    anim = sol.animate(fps=5, dpi=30)
    support = CubicSpline(times, values)
    l_ = PENDULUM["l"]
    for k, time in enumerate(anim.frame_times):
        anim.draw(k)
        angle = np.interp(time, sol.t, sol.q[:, 0])
        expected = (support(time) + l_ * np.sin(angle), -l_ * np.cos(angle))
        assert np.max(np.abs(np.array(anim.markers["bob"].get_data(), dtype=float)[:, 0] - expected)) < 1e-12


# -- a user's numba function as an input (kind (c)) --------------------------------------------------------


@njit
def pd_torque(t, y, p):
    """τ = −Kp θ − Kd θ̇, the gains read from p = (K_d, K_p, g, l, m) (the `fn_pd` model's declared order)."""
    return -p[1] * y[0] - p[0] * y[1]


@njit
def tanh_reference(t, y, p):
    return 0.2 * math.tanh(t - 1.0)


@njit
def waving_anchor(t, y, p):
    return AMPLITUDE * math.sin(OMEGA * t)


@pytest.fixture(scope="module")
def fn_pd(cache_dir):
    """The inverted pendulum with τ an input supplied at run time; its gains declared as parameters (unused by the
    equations) so that a function can read them from p, and a sweep sweep them."""
    return lc.compile(_inverted_pendulum(lc.Input("tau"), "inputs_fn_pd", parameters=(Kd, Kp, g, l, m)),
                      cache_dir=cache_dir)


@pytest.mark.parametrize("method, options", [("dop853", {"rtol": 1e-10, "atol": 1e-12}), ("rk4", {"dt": 1e-3})])
def test_a_numba_pd_function_equals_the_compiled_law(pd, fn_pd, method, options):
    assert fn_pd.inputs == ("tau",) and fn_pd.input_orders == (0,) and fn_pd.parameters == pd.parameters
    law = pd.simulate((0.0, 5.0), method=method, progress=False, **options)
    function = fn_pd.simulate((0.0, 5.0), inputs={"tau": pd_torque}, method=method, progress=False, **options)
    assert function.status == 0 and function.nsteps == law.nsteps
    assert np.max(np.abs(function.y - law.y)) < 1e-12  # (measured 0: the same arithmetic)
    assert np.max(np.abs(function.energy - law.energy)) < 1e-12


def test_a_function_of_t_equals_a_fine_table_of_it(tracking):
    times = np.linspace(0.0, 5.0, 501)
    table = lc.Tabulated(times, 0.2 * np.tanh(times - 1.0))
    options = dict(rtol=1e-12, atol=1e-12, progress=False)
    by_table = tracking.simulate((0.0, 5.0), inputs={"r": table}, **options)
    by_function = tracking.simulate((0.0, 5.0), inputs={"r": tanh_reference}, **options)
    assert by_function.status == 0
    # the cubic table's error at Δ = 0.01 (measured difference of the runs 6e-13)
    assert np.max(np.abs(by_function.y[-1] - by_table.y[-1])) < 1e-9


def test_a_function_input_in_v_gives_the_energies_of_each_saved_row(cache_dir):
    """m ẍ = −k (x − a(t)): a(t) in V, so the energies after the run read the function too (row by row)."""
    anchor = lc.Input("anchor")
    model = lc.compile(lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * (x - anchor) ** 2 / 2, name="inputs_anchor",
                                 defaults={"m": 1.0, "k": 4.0}, q0=(0.0,)), cache_dir=cache_dir)
    times = np.linspace(0.0, 3.0, 3001)
    options = dict(rtol=1e-12, atol=1e-12, t_eval=np.linspace(0.0, 3.0, 31), progress=False)
    by_function = model.simulate((0.0, 3.0), inputs={"anchor": waving_anchor}, **options)
    by_table = model.simulate((0.0, 3.0), inputs={"anchor": (times, AMPLITUDE * np.sin(OMEGA * times))}, **options)
    assert np.all(np.isfinite(by_function.energy))
    # the table's error at Δ = 0.001 (measured 5e-14 in the energy, 1.2e-13 in y)
    assert np.max(np.abs(by_function.energy - by_table.energy)) < 1e-10
    assert np.max(np.abs(by_function.y - by_table.y)) < 1e-10


def _compiled(recorder) -> set:
    """(module, qualname) of every function numba compiled while `recorder` listened."""
    return {(e.data["dispatcher"].py_func.__module__, e.data["dispatcher"].py_func.__qualname__)
            for _, e in recorder.buffer}


def test_a_function_input_compiles_only_its_wrappers_and_itself(fn_pd):
    fn_pd.simulate((0.0, 1.0), inputs={"tau": pd_torque}, progress=False)
    with numba_event.install_recorder("numba:compile") as recorder:
        fn_pd.simulate((0.0, 1.0), inputs={"tau": pd_torque}, params={"K_p": 40.0}, progress=False)
    assert recorder.buffer == []

    @njit
    def stiffer(t, y, p):
        return -2.0 * p[1] * y[0] - p[0] * y[1]

    with numba_event.install_recorder("numba:compile") as recorder:
        sol = fn_pd.simulate((0.0, 1.0), inputs={"tau": stiffer}, progress=False)
    assert sol.status == 0
    compiled = _compiled(recorder)
    assert (__name__, "test_a_function_input_compiles_only_its_wrappers_and_itself.<locals>.stiffer") in compiled
    others = compiled - {(__name__, "test_a_function_input_compiles_only_its_wrappers_and_itself.<locals>.stiffer")}
    assert others and all(module == "lagcomp.integrate.function_inputs" and ".<locals>.wrapped" in qualname
                          for module, qualname in others), others


def test_a_sweep_over_gains_read_by_a_function_matches_single_runs_bitwise(fn_pd):
    gains = [20.0, 30.0, 45.0, 60.0]
    result = fn_pd.sweep((0.0, 5.0), {"K_p": gains}, inputs={"tau": pd_torque}, workers=2, output="energy",
                         progress=False)  # two threads, each writing the value into its trajectories' rows of P
    assert np.all(result.status == 0)
    for i, gain in enumerate(gains):
        single = fn_pd.simulate((0.0, 5.0), params={"K_p": gain}, inputs={"tau": pd_torque}, progress=False)
        assert np.array_equal(result.final[i], single.y[-1])
    assert np.all(np.isfinite(result.energy_error))


@njit
def two_arguments(t, y):
    return t


@njit
def returns_the_state(t, y, p):
    return y


@pytest.mark.parametrize("function, culprit", [
    (lambda t, y, p: 0.0, "not a numba function: decorate it with @numba.njit"),
    (two_arguments, "does not compile for u(t: float64, y: float64[::1], p: float64[::1]) -> float64"),
    (returns_the_state, "returns array(float64, 1d, C), not a number"),
])
def test_a_function_that_is_not_a_numba_function_of_the_signature_is_refused(fn_pd, function, culprit):
    with pytest.raises(OptionError) as err:
        fn_pd.simulate((0.0, 1.0), inputs={"tau": function})
    assert culprit in str(err.value) and "`tau`" in str(err.value)


def test_a_function_for_an_input_whose_derivative_enters_is_refused(driven):
    with pytest.raises(OptionError, match="derivative of order 2, which a function does not give"):
        driven[0].simulate((0.0, 1.0), inputs={"x_s": waving_anchor})


@pytest.mark.parametrize("call, culprit", [
    (lambda model: model.simulate((0.0, 1.0), inputs={"tau": pd_torque}, method="radau"), "exact Jacobian"),
    (lambda model: model.simulate((0.0, 1.0), inputs={"tau": pd_torque}, method="taylor"),
     "inputs supplied at run time"),
    (lambda model: model.sweep((0.0, 1.0), {"theta": [0.1]}, inputs={"tau": pd_torque}, method="radau"),
     "exact Jacobian"),
    (lambda model: model.sweep((0.0, 1.0), {"theta": [0.1]}, inputs={"tau": pd_torque}, batched=True), "with inputs"),
    (lambda model: model.sweep((0.0, 1.0), {"theta": [0.1]}, inputs={"tau": pd_torque}, client=object()),
     "cannot send to its workers"),
])
def test_methods_and_sweeps_that_cannot_take_a_function_input_are_refused(fn_pd, call, culprit):
    with pytest.raises(OptionError, match=culprit):
        call(fn_pd)
