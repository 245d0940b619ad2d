"""A user's names cannot change the answer (DESIGN.md, "Two contracts of the emitted code: Names").

Coordinates and parameters may be named like anything the emitted modules use themselves
(``k``, the Taylor program's order loop; ``X``, ``W``, its arrays; ``range``, ``math``, ``np``, ...):
every method must still integrate the system the user wrote.  The references are closed forms
(a harmonic oscillator x(t) = A cos ωt, ω² = k/m) and lagcomp's DOP853 at tight tolerance on a
model whose names collide with nothing.
"""

from __future__ import annotations

import ast
import builtins
import dataclasses
import keyword
import math
import re
from dataclasses import dataclass

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from sympy.physics.vector import ReferenceFrame

import lagcomp as lc
from lagcomp.cli import main
from lagcomp.codegen.bindings import INPUT_PREFIXES, USER_NAMESPACE
from lagcomp.codegen.taylor_lanes import taylor_lanes_module
from lagcomp.errors import ModelError


def _spring(stiffness: str, mass: str, length: str, coordinate: str) -> lc.System:
    """m x'' = −k (x − l) under the given names, x(0) = 1.2, ẋ(0) = 0: x(t) = l + (1.2 − l) cos(√(k/m) t)."""
    (x,) = lc.coordinates(coordinate)
    k, m, l = sp.symbols(f"{stiffness} {mass} {length}", positive=True, seq=True)
    return lc.System(coordinates=(x,), T=m * x.diff(lc.t) ** 2 / 2, V=k * (x - l) ** 2 / 2, parameters=(k, m, l),
                     name="spring", q0=(1.2,), qd0=(0.0,))


def test_a_spring_with_stiffness_k_integrated_by_taylor_follows_the_closed_form(cache_dir):
    # before the fix, the Taylor program's order loop `for k in range(order)` overwrote the stiffness:
    # x(3) = 2.388 instead of 1.2 cos(3·√(4/2.5)) = −0.0818 (issue 18, part 4)
    model = lc.compile(_spring("k", "m", "l", "x"), cache_dir=cache_dir)
    sol = model.simulate((0.0, 3.0), params={"k": 4.0, "m": 2.5, "l": 0.5}, method="taylor")
    assert sol.status == 0
    exact = 0.5 + 0.7 * math.cos(math.sqrt(4.0 / 2.5) * 3.0)
    assert abs(sol.q[-1, 0] - exact) < 1e-13  # measured 1.7e-16


def test_turn_indicator_by_taylor_agrees_with_dop853(compiled):
    # turn_indicator has a parameter `k` (the spring of the gimbal): taylor ended at θ = 1.1008
    # where dop853, rk4 and gauss2 agree on 0.16144
    model = compiled("turn_indicator")
    taylor = model.simulate((0.0, 10.0), method="taylor")
    reference = model.simulate((0.0, 10.0), rtol=1e-13, atol=1e-13)
    assert taylor.status == 0 and reference.status == 0
    assert abs(taylor.q[-1, 0] - reference.q[-1, 0]) < 1e-12  # measured 2.2e-16
    assert abs(reference.q[-1, 0] - 0.16143697) < 1e-7


def test_cli_run_turn_indicator_by_taylor(capsys, cache_dir, tmp_path):
    out_file = tmp_path / "taylor.npz"
    code = main(["--cache-dir", str(cache_dir), "run", "turn_indicator", "--method", "taylor", "--quiet",
                 "--out", str(out_file)])
    assert code == 0
    assert "theta=0.16143" in capsys.readouterr().out
    assert abs(np.load(out_file)["q"][-1, 0] - 0.16143697) < 1e-7


# -- every name the emitted modules use, as the user's names ---------------------------------

COMMON = ("k", "i", "j", "n", "t_", "y", "p", "out", "X", "W", "range", "order", "math", "np", "njit", "h",
          "dt", "status", "lambda_", "lambda", "for", "x0", "x1", "X0", "q_x", "qd_x", "p_k", "mom_x", "_c0", "_u1")


def _identifiers(source: str) -> set[str]:
    """Every identifier of a module's source: names, arguments, functions, imports and attributes."""
    found = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Name):
            found.add(node.id)
        elif isinstance(node, ast.arg):
            found.add(node.arg)
        elif isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            found.add(node.name)
        elif isinstance(node, ast.alias):
            found.add(node.asname or node.name)
        elif isinstance(node, ast.Attribute):
            found.add(node.attr)
    return found


def _probes() -> tuple[lc.System, ...]:
    """Small systems whose modules hold every kind of emitted code: events, a contact, friction, Taylor, lanes;
    constraints (with a contact: the constrained impact and resting code); bodies (the `geometry` kernel); an input read with its first two derivatives (a support s(t)
    under a spring)."""
    x, z = lc.coordinates("x z")
    a, b = sp.symbols("a b", positive=True)
    free = lc.System(coordinates=(x, z), T=(x.diff(lc.t) ** 2 + z.diff(lc.t) ** 2) / 2, V=a * x**2 + b * z**2,
                     events=[lc.Event("hit", x), lc.Event("kick", z, reset={z.diff(lc.t): -a * z.diff(lc.t)}),
                             lc.Contact("wall", z + b, restitution=a)],
                     name="probe_free")
    rubbing = lc.System(coordinates=(x, z), T=(x.diff(lc.t) ** 2 + z.diff(lc.t) ** 2) / 2, V=a * x**2 + b * z**2,
                        events=[lc.Event("hit", x),
                                lc.Friction("rub", x.diff(lc.t) - b, normal=a * z**2, static=b, kinetic=a)],
                        name="probe_friction")
    rod = lc.System(coordinates=(x, z), T=(x.diff(lc.t) ** 2 + z.diff(lc.t) ** 2) / 2, V=a * z,
                    constraints=[lc.Holonomic("rod", x**2 + z**2 - b**2)], events=[lc.Contact("floor", z + b, restitution=a)],
                    name="probe_rod")
    N = ReferenceFrame("N")
    bodies = lc.System(coordinates=(x, z), bodies=[lc.Particle(a, (x, z, 0), name="bob"),
                                                   lc.RigidBody(b, (0, 0, x), (1, 1, 1), lc.rotated(N, (z, "z")))],
                       frame=N, name="probe_bodies")
    s = lc.Input("s")
    driven = lc.System(coordinates=(x, z), T=((x.diff(lc.t) + s.diff(lc.t)) ** 2 + z.diff(lc.t) ** 2) / 2,
                       V=a * (x - s) ** 2 + b * z**2, name="probe_driven")
    return free, rubbing, rod, bodies, driven


def _sources(model: lc.Model) -> list[str]:
    """The model's eager module, its companion modules (the on-demand kernels, every kind, built here) and, when
    it has a Taylor program, the batched Taylor module (written at sweep time)."""
    source = model.source_path.read_text(encoding="utf-8")
    companions = [entry.path.read_text(encoding="utf-8") for entry in model.on_demand_entries.values()]
    program = model._taylor_program
    return [source, *companions] + ([taylor_lanes_module(source, program, order=3)] if program is not None else [])


def _user_locals(model: lc.Model) -> set[str]:
    """The locals the kernels bind the model's symbols to (lagcomp.codegen.lower, docstring), identifiers only."""
    prefixes = ("q", "qd") if model.k else ("q", "qd", "mom")  # momenta: `velocities`, unconstrained only
    inputs = {f"{INPUT_PREFIXES[k]}_{name}" for name, order in zip(model.inputs, model.input_orders, strict=True)
              for k in range(order + 1)}  # the probe reads s, ṡ and s̈
    return ({f"{prefix}_{name}" for name in model.coordinates for prefix in prefixes}
            | {f"p_{name}" for name in model.parameters} | inputs)


@pytest.fixture(scope="module")
def probes(cache_dir) -> list[lc.Model]:
    return [lc.compile(system, cache_dir=cache_dir) for system in _probes()]  # emitted; numba compiles nothing yet


@pytest.fixture(scope="module")
def emitted_names(probes) -> list[str]:
    """The identifiers of emitted modules (read back with `ast`), Python's builtins and keywords, common names."""
    names = set(dir(builtins)) | set(keyword.kwlist) | set(COMMON)
    for model in probes:
        for source in _sources(model):
            names |= _identifiers(source)
    return sorted(names - {"t"})  # t is lagcomp's time (a symbol named t is refused: test below)


@dataclass(frozen=True)
class Oscillators:
    """Uncoupled oscillators under the user's names: m_j c_j'' = −κ_j c_j, κ_j the sum of the group j.

    T = Σ_j m_j ċ_j²/2 and V = Σ_j Σ_{a ∈ groups[j]} a c_j²/2, one term per parameter, so that every
    parameter multiplies a state in the kernels (inside the Taylor program's order loop too).
    From c_j(0) = A_j, ċ_j(0) = 0: c_j(t) = A_j cos(ω_j t), ω_j² = κ_j/m_j; an event at each zero
    of c_0, t = (2i + 1) π/(2 ω_0).
    """

    coordinates: tuple[str, ...]
    masses: tuple[str, ...]
    groups: tuple[tuple[str, ...], ...]
    event: str = "crossing"

    def system(self) -> lc.System:
        c = lc.coordinates(" ".join(self.coordinates))
        m = [sp.Symbol(name, positive=True) for name in self.masses]
        groups = [[sp.Symbol(name, positive=True) for name in group] for group in self.groups]
        return lc.System(
            coordinates=c, T=sum(mj * cj.diff(lc.t) ** 2 / 2 for mj, cj in zip(m, c)),
            V=sp.Add(*(a * cj**2 / 2 for group, cj in zip(groups, c) for a in group)),
            parameters=(*m, *(a for group in groups for a in group)),
            events=[lc.Event(self.event, c[0], direction=0)], name="names_oscillators",
        )

    def values(self) -> tuple[dict, np.ndarray, np.ndarray]:
        """Parameter values, amplitudes A and frequencies ω (ω_j from 0.7 to 1.9, ω_0 = 1.3)."""
        n = len(self.coordinates)
        omega = np.linspace(0.7, 1.9, n) if n > 1 else np.array([1.3])
        omega = np.roll(omega, -int(np.argmin(np.abs(omega - 1.3))))
        params = {}
        for j, (mass, group) in enumerate(zip(self.masses, self.groups)):
            params[mass] = 0.5 + 0.25 * j
            weights = np.arange(1, len(group) + 1, dtype=float)
            params.update(zip(group, params[mass] * omega[j] ** 2 * weights / weights.sum()))
        return params, 1.0 - 0.1 * np.arange(n), omega


T_END = 2.0
#: method: (options, largest |c_j(T_END) − A_j cos(ω_j T_END)| allowed); measured errors in comments.
METHODS = {
    "dop853": (dict(rtol=1e-12, atol=1e-12), 1e-10),
    "dopri5": (dict(rtol=1e-10, atol=1e-12), 1e-8),
    "taylor": ({}, 1e-13),
    "rk4": (dict(dt=1e-3), 1e-11),
    "verlet": (dict(dt=1e-3), 1e-5),
    "yoshida4": (dict(dt=1e-3), 1e-10),
    "yoshida6": (dict(dt=1e-3), 1e-12),
    "gauss1": (dict(dt=1e-3), 1e-5),
    "gauss2": (dict(dt=1e-3), 1e-11),
    "gauss3": (dict(dt=1e-3), 1e-12),
    "radau": (dict(rtol=1e-12, atol=1e-12), 1e-13),
}


def _every_method_follows_the_closed_form(model: lc.Model, spec: Oscillators, methods=METHODS) -> dict:
    """Run each method to T_END; assert the closed form (and the events' times); return the errors."""
    params, amplitude, omega = spec.values()
    exact = amplitude * np.cos(omega * T_END)
    errors = {}
    for method in methods:
        options, tolerance = METHODS[method]
        sol = model.simulate((0.0, T_END), q0=amplitude, qd0=np.zeros(len(amplitude)), params=params,
                             method=method, progress=False, **options)
        assert sol.status == 0, (method, sol.message)
        errors[method] = float(np.max(np.abs(sol.q[-1] - exact)))
        assert errors[method] < tolerance, (method, errors[method])
        if method in ("dop853", "taylor"):  # the drivers that locate events
            crossings = sol.events[spec.event].t
            assert np.allclose(crossings, np.pi / (2 * omega[0]) * (1 + 2 * np.arange(len(crossings))), atol=1e-9)
            assert len(crossings) == int(omega[0] * T_END / np.pi + 0.5)
    return errors


def _batched_sweep_follows_the_closed_form(model: lc.Model, spec: Oscillators, method: str) -> float:
    """A batched sweep over c_0's amplitude: every trajectory's final state against the closed form."""
    params, amplitude, omega = spec.values()
    starts = np.linspace(0.4, 1.2, 5)
    result = model.sweep((0.0, T_END), {spec.coordinates[0]: starts}, q0=amplitude, qd0=np.zeros(len(amplitude)),
                         params=params, method=method, batched=True, rtol=1e-12, atol=1e-12,
                         **({"dt": 1e-3} if method == "rk4" else {}), workers=1, progress=False)
    assert np.all(result.status == 0)
    exact = starts * np.cos(omega[0] * T_END)
    return float(np.max(np.abs(result.final[:, 0] - exact)))


def _many_names(pool: list[str], coordinates: tuple[str, ...]) -> Oscillators:
    """`coordinates` and, as parameters, every other name of `pool`: masses first, the rest in groups."""
    n = len(coordinates)
    rest = [name for name in pool if name not in coordinates and name not in {f"{c}_dot" for c in coordinates}]
    return Oscillators(coordinates, tuple(rest[:n]), tuple(tuple(rest[n + j::n]) for j in range(n)))


RISKY_COORDINATES = ("k", "X", "range", "order", "i", "W")


@pytest.fixture(scope="module")
def many_names(emitted_names, cache_dir) -> tuple[lc.Model, Oscillators]:
    """One system with every name of `emitted_names`: six coordinates, the rest (about 360) as parameters."""
    spec = _many_names(emitted_names, RISKY_COORDINATES)
    used = {*spec.coordinates, *spec.masses, *(name for group in spec.groups for name in group)}
    assert used == set(emitted_names) - {f"{c}_dot" for c in RISKY_COORDINATES}  # all of them, not a sample
    return lc.compile(spec.system(), cache_dir=cache_dir), spec


def test_no_emitted_name_is_in_the_user_namespace(probes, many_names):
    """The invariant of lagcomp.codegen.lower (its docstring): user locals and lagcomp's own names are disjoint."""
    for model in [*probes, many_names[0]]:
        found = set().union(*map(_identifiers, _sources(model)))
        assert {name for name in found if USER_NAMESPACE.match(name)} == _user_locals(model)
    assert not [name for name in dir(builtins) if USER_NAMESPACE.match(name)]


def test_every_emitted_name_as_a_user_name(many_names):
    """Every kind of kernel that binds user names (rhs, taylor_coefficients, the canonical kernels of the
    Gauss methods, radau's rhs_jacobian, events), run under ~670 colliding names, against the closed form."""
    model, spec = many_names
    errors = _every_method_follows_the_closed_form(model, spec, methods=("taylor", "rk4", "gauss2", "radau"))
    assert set(errors) == {"taylor", "rk4", "gauss2", "radau"}  # measured 1.4e-16, 2.0e-13, 3.4e-14, 2.3e-15


def test_the_parameter_jacobian_under_every_emitted_name(many_names):
    """``rhs_parameter_jacobian`` (the kernel of the sensitivities, whose locals are among the names) under the
    ~670 colliding names, against the closed form of c̈_j = −κ_j c_j/m_j: ∂c̈_j/∂m_j = κ_j c_j/m_j²,
    ∂c̈_j/∂a = −c_j/m_j for a in the group of j, 0 elsewhere.  Run as plain Python: numba would compile a
    (12, ~360) kernel for the same names."""
    from random_systems import python_model_kernels

    model, spec = many_names
    params, amplitude, _ = spec.values()
    module = python_model_kernels(model)
    n, column = len(spec.coordinates), {name: j for j, name in enumerate(model.parameters)}
    c = amplitude + 0.125
    out, expected = np.full((2 * n, len(column)), np.nan), np.zeros((2 * n, len(column)))
    y = np.concatenate([c, np.linspace(-0.5, 0.5, n)])
    assert module["rhs_parameter_jacobian"](0.0, y, model.parameter_vector(params), out) == 0
    for j, (mass, group) in enumerate(zip(spec.masses, spec.groups, strict=True)):
        expected[n + j, column[mass]] = sum(params[a] for a in group) * c[j] / params[mass] ** 2
        for a in group:
            expected[n + j, column[a]] = -c[j] / params[mass]
    np.testing.assert_allclose(out, expected, rtol=1e-14, atol=0)


def test_the_directional_and_full_jacobian_kernels_under_every_emitted_name(many_names):
    """``rhs_directional``, its tangent kernels and ``rhs_with_full_jacobian`` (the sensitivities' kernels, whose
    locals ``_dy<i>``, ``_dp<j>``, ``_g<i>``, ``_part<r>_<j>`` and arguments ``v``, ``w`` are among the names) under
    the ~670 colliding names, against the closed form of c̈_j = −κ_j c_j/m_j, κ_j the sum of group j.  Plain
    Python, as the parameter Jacobian's."""
    from random_systems import python_model_kernels

    model, spec = many_names
    params, amplitude, _ = spec.values()
    module = python_model_kernels(model)
    n, column = len(spec.coordinates), {name: j for j, name in enumerate(model.parameters)}
    N, P = 2 * n, len(column)
    c, cd = amplitude + 0.125, np.linspace(-0.5, 0.5, n)
    y, p = np.concatenate([c, cd]), model.parameter_vector(params)
    expected = np.zeros((N, N + P))
    expected[np.arange(n), n + np.arange(n)] = 1.0
    for j, (mass, group) in enumerate(zip(spec.masses, spec.groups, strict=True)):
        kappa = sum(params[a] for a in group)
        expected[n + j, j] = -kappa / params[mass]
        expected[n + j, N + column[mass]] = kappa * c[j] / params[mass] ** 2
        for a in group:
            expected[n + j, N + column[a]] = -c[j] / params[mass]
    f = np.concatenate([cd, [-sum(params[a] for a in group) * c[j] / params[mass]
                             for j, (mass, group) in enumerate(zip(spec.masses, spec.groups, strict=True))]])
    ydot, out = np.full(N, np.nan), np.full((N, N + P), np.nan)
    assert module["rhs_with_full_jacobian"](0.0, y, p, ydot, out) == 0
    np.testing.assert_allclose(ydot, f, rtol=1e-14, atol=0)
    np.testing.assert_allclose(out, expected, rtol=1e-14, atol=0)
    v, w = np.linspace(-1.0, 1.0, N), np.linspace(0.5, -0.5, P)
    ydot, derivative = np.full(N, np.nan), np.full(N, np.nan)
    assert module["rhs_directional"](0.0, y, p, v, w, ydot, derivative) == 0
    np.testing.assert_allclose(ydot, f, rtol=1e-14, atol=0)
    np.testing.assert_allclose(derivative, expected @ np.concatenate([v, w]), rtol=1e-12, atol=1e-14)
    tangent = np.full(2 * N, np.nan)  # (one column's augmented rhs: y = (x, v), w at the end of p, or none)
    assert module["rhs_tangent_parameters"](0.0, np.concatenate([y, v]), np.concatenate([p, w]), tangent) == 0
    assert np.array_equal(tangent, np.concatenate([ydot, derivative]))
    assert module["rhs_tangent"](0.0, np.concatenate([y, v]), p, tangent) == 0
    np.testing.assert_allclose(tangent, np.concatenate([f, expected[:, :N] @ v]), rtol=1e-12, atol=1e-14)
    # many columns (locals _part<r>_<j>, _col, _at, _columns, _j): S = (v, −v), the second the last parameter's
    S, columns = np.stack([v, -v], axis=1), np.full(3 * N, np.nan)
    assert module["rhs_tangents_parameters"](0.0, np.concatenate([y, S.T.ravel()]),
                                             np.concatenate([p, [-1.0, P - 1.0, 0.5]]), columns) == 0
    derivatives = expected[:, :N] @ S
    derivatives[:, 1] += 0.5 * expected[:, N + P - 1]
    np.testing.assert_allclose(columns, np.concatenate([f, derivatives.T.ravel()]), rtol=1e-12, atol=1e-14)
    assert module["rhs_tangents"](0.0, np.concatenate([y, S.T.ravel()]), p, columns) == 0
    np.testing.assert_allclose(columns, np.concatenate([f, (expected[:, :N] @ S).T.ravel()]), rtol=1e-12,
                               atol=1e-14)


def test_the_event_gradients_under_every_emitted_name(many_names):
    """``event_gradients`` (the events' partials, for their times' sensitivities) under the ~670 colliding names:
    the event g = c_0 has ∂g/∂y = e_0 and no ∂g/∂t, ∂g/∂p.  Plain Python, as the parameter Jacobian's test."""
    from random_systems import python_kernels

    model, spec = many_names
    params, amplitude, _ = spec.values()
    module = python_kernels(model.source_path.read_text(encoding="utf-8"))
    n = len(spec.coordinates)
    out = np.full((1, 2 * n + 1 + len(model.parameters)), np.nan)
    y = np.concatenate([amplitude, np.zeros(n)])
    assert module["event_gradients"](0.0, y, model.parameter_vector(params), out) == 0
    expected = np.zeros_like(out)
    expected[0, 0] = 1.0
    np.testing.assert_array_equal(out, expected)


def test_the_event_reset_under_every_emitted_name(emitted_names, cache_dir):
    """``event_reset`` under the ~670 colliding names: the oscillators' event on c_0 resets ċ_0 to −m_0 ċ_0 and c_1
    to the sum of c_1's group times c_0, reading state, parameters and t (as the kernels' ``t``).  Plain Python,
    as the parameter Jacobian's test."""
    from random_systems import python_kernels

    spec = _many_names(emitted_names, RISKY_COORDINATES)
    system = spec.system()
    c = system.coordinates
    m0 = next(s for s in system.parameters if s.name == spec.masses[0])
    group = [s for s in system.parameters if s.name in spec.groups[1]]
    reset = {c[0].diff(lc.t): -m0 * c[0].diff(lc.t), c[1]: sp.Add(*group) * c[0] + lc.t}
    event = lc.Event(spec.event, c[0], reset=reset)
    model = lc.compile(dataclasses.replace(system, events=[event], name="names_reset"), cache_dir=cache_dir)
    params, amplitude, _ = spec.values()
    module = python_kernels(model.source_path.read_text(encoding="utf-8"))
    n = len(c)
    y = np.concatenate([amplitude, np.linspace(-0.5, 0.5, n)])
    out = np.full(2 * n, np.nan)
    assert module["event_reset"](0.25, y, model.parameter_vector(params), 0, out) == 0
    expected = y.copy()
    expected[n] = -params[spec.masses[0]] * y[n]
    expected[1] = sum(params[a] for a in spec.groups[1]) * y[0] + 0.25
    np.testing.assert_allclose(out, expected, rtol=1e-15, atol=0)


@pytest.mark.slow
def test_every_emitted_name_as_a_user_name_every_method(many_names):
    model, spec = many_names
    errors = _every_method_follows_the_closed_form(model, spec)
    assert set(errors) == set(METHODS)
    for method in ("dop853", "rk4"):
        assert _batched_sweep_follows_the_closed_form(model, spec, method) < 1e-10  # measured 4.4e-14 (dop853)


@pytest.mark.slow
@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                  HealthCheck.too_slow])
@given(data=st.data())
def test_names_drawn_from_the_emitted_ones_every_method(emitted_names, cache_dir, data):
    """Hypothesis draws the coordinates' and parameters' names; every method and a batched Taylor sweep
    (the unrolled program, `taylor_lanes`) against the closed form.  About a minute per example."""
    n = data.draw(st.integers(1, 3), label="coordinates")
    names = data.draw(st.lists(st.sampled_from(emitted_names), min_size=3 * n, max_size=3 * n + 4, unique=True))
    coordinates = tuple(names[:n])
    assume(not {f"{c}_dot" for c in coordinates} & set(names))  # the velocities' names (refused: test below)
    rest = names[2 * n:]
    spec = Oscillators(coordinates, tuple(names[n:2 * n]), tuple(tuple(rest[j::n]) for j in range(n)),
                       event=data.draw(st.sampled_from([name for name in emitted_names if name.isidentifier()])))
    model = lc.compile(spec.system(), cache_dir=cache_dir)
    _every_method_follows_the_closed_form(model, spec)
    assert _batched_sweep_follows_the_closed_form(model, spec, "taylor") < 1e-12


def _value(model: lc.Model, q, qd, params, t=0.0) -> np.ndarray:
    return model.rhs(t, np.concatenate([q, qd]), params)


def test_names_python_would_not_read_back_as_written(cache_dir):
    """Symbols whose names are no identifiers, or identifiers Python normalizes (NFKC: "ﬁ" is "fi"), keywords,
    quotes and backslashes (printed into docstrings), a coordinate named t and one named like a parameter."""
    odd = ["x.1", "x_1", "ﬁ", "fi", "lambda", "1st", 'say """hi"""\\', "θ"]
    symbols = [sp.Symbol(name, positive=True) for name in odd]
    tau, x = lc.coordinates("t x")  # a coordinate named t, not the time lc.t
    shared = sp.Symbol("x", positive=True)  # a parameter named like the coordinate x
    weights = np.arange(1, len(odd) + 1, dtype=float)
    V = sum(w * s for w, s in zip(weights, symbols)) * tau**2 / 2 + shared * x**2 / 2 - tau * sp.cos(lc.t)
    system = lc.System(coordinates=(tau, x), T=(tau.diff(lc.t) ** 2 + x.diff(lc.t) ** 2) / 2, V=V,
                       name="odd_names", description='A description with """quotes""" and a \\ backslash.')
    model = lc.compile(system, cache_dir=cache_dir)
    values = dict(zip(odd, 10.0 ** -np.arange(len(odd))), x=5.0)
    stiffness = sum(w * values[name] for w, name in zip(weights, odd))
    got = _value(model, [2.0, 3.0], [0.0, 0.0], values, t=0.5)
    np.testing.assert_allclose(got[2:], [-stiffness * 2.0 + math.cos(0.5), -5.0 * 3.0], rtol=1e-15)
    docstrings = [line for line in model.source_path.read_text(encoding="utf-8").splitlines() if "say" in line]
    assert any('say """hi"""' in line.encode().decode("unicode_escape") for line in docstrings)


def test_a_parameter_named_like_a_baumgarte_gain(cache_dir):
    """A pendulum on a rod (x, y), gravity named like lagcomp's own Baumgarte gain: at rest at angle θ from
    the downward vertical, ẍ = −g sin θ cos θ, ÿ = −g sin² θ."""
    x, y = lc.coordinates("x y")
    g = sp.Symbol("_baumgarte_alpha", positive=True)
    system = lc.System(coordinates=(x, y), T=(x.diff(lc.t) ** 2 + y.diff(lc.t) ** 2) / 2, V=g * y,
                       constraints=[lc.Holonomic("rod", x**2 + y**2 - 1)], name="gain_named")
    model = lc.compile(system, cache_dir=cache_dir)
    theta = 0.6
    got = _value(model, [math.sin(theta), -math.cos(theta)], [0.0, 0.0], {"_baumgarte_alpha": 9.8})
    expected = [-9.8 * math.sin(theta) * math.cos(theta), -9.8 * math.sin(theta) ** 2]
    np.testing.assert_allclose(got[2:], expected, rtol=1e-14)


@pytest.mark.parametrize("names", [("_w0", "_mu0", "_lam0"), ("_w0_", "_lam0_", "_jac"), ("out", "y", "DAE_SIZE")])
def test_parameters_named_like_the_dae_kernels_locals(cache_dir, names):
    """The rod pendulum of mass m, gravity g, length l under names the DAE kernels use themselves (their locals
    for w, λ, μ, the fresh symbols' names, the work array): G and ∂G/∂z against closed forms, exactly (dyadic z).

    Φ = x² + z² − l², Λ = (2x, 2z), M = m I, F = (0, −m g); z = (x, z, vx, vz, wx, wz, λ, μ):
    G = (vx + 2x μ, vz + 2z μ, wx, wz, m wx − 2x λ, m wz + m g − 2z λ, 2x vx + 2z vz, x² + z² − l²).
    """
    from random_systems import python_model_kernels

    x, z = lc.coordinates("x z")
    mass, gravity, length = (sp.Symbol(name, positive=True) for name in names)
    system = lc.System(coordinates=(x, z), T=mass * (x.diff(lc.t) ** 2 + z.diff(lc.t) ** 2) / 2, V=mass * gravity * z,
                       constraints=[lc.Holonomic("rod", x**2 + z**2 - length**2)], parameters=(mass, gravity, length),
                       name="dae_named")
    module = python_model_kernels(lc.compile(system, cache_dir=cache_dir))
    M, G_, L = 1.5, 9.75, 1.25
    X, Z, VX, VZ, WX, WZ, LAM, MU = 0.75, -1.0, 0.5, 0.375, -2.25, 0.125, 3.5, -0.0625
    p = np.array([M, G_, L, 0.0, 0.0])
    G, J = np.empty(8), np.empty((8, 8))
    state = np.array([X, Z, VX, VZ, WX, WZ, LAM, MU])
    assert module["dae_residual"](0.0, state, p, G) == 0 and module["dae_jacobian"](0.0, state, p, J) == 0
    np.testing.assert_array_equal(G, [VX + 2 * X * MU, VZ + 2 * Z * MU, WX, WZ, M * WX - 2 * X * LAM,
                                      M * WZ + M * G_ - 2 * Z * LAM, 2 * X * VX + 2 * Z * VZ, X**2 + Z**2 - L**2])
    np.testing.assert_array_equal(J, [
        [2 * MU, 0, 1, 0, 0, 0, 0, 2 * X], [0, 2 * MU, 0, 1, 0, 0, 0, 2 * Z],
        [0, 0, 0, 0, 1, 0, 0, 0], [0, 0, 0, 0, 0, 1, 0, 0],
        [-2 * LAM, 0, 0, 0, M, 0, -2 * X, 0], [0, -2 * LAM, 0, 0, 0, M, -2 * Z, 0],
        [2 * VX, 2 * VZ, 2 * X, 2 * Z, 0, 0, 0, 0], [2 * X, 2 * Z, 0, 0, 0, 0, 0, 0]])


@pytest.mark.parametrize("make, culprit", [
    (lambda x, k: dict(V=k * x**2 + sp.Symbol("k") * x), "['k']"),  # two symbols named k
    (lambda x, k: dict(V=k * x**2 + sp.Symbol("t", real=True) * x), "symbol named t"),  # t is time
])
def test_ambiguous_names_are_refused(make, culprit):
    (x,) = lc.coordinates("x")
    k = sp.Symbol("k", positive=True)
    with pytest.raises(ModelError, match=re.escape(culprit)):
        lc.System(coordinates=(x,), T=x.diff(lc.t) ** 2 / 2, name="ambiguous", **make(x, k))


def test_a_coordinate_named_like_a_velocity_compiles_to_the_right_rhs(cache_dir):
    """Coordinates x and x_dot (unit masses, a spring of stiffness 3 between them): the velocity of x gets
    a symbol of its own name, so ẍ = −3 (x − x_dot) and the velocities are read where they are stored."""
    x, x_dot = lc.coordinates("x x_dot")
    system = lc.System(coordinates=(x, x_dot), T=(x.diff(lc.t) ** 2 + x_dot.diff(lc.t) ** 2) / 2,
                       V=3 * (x - x_dot) ** 2 / 2, name="dots")
    model = lc.compile(system, cache_dir=cache_dir)
    y = np.array([0.5, -0.25, 2.0, 7.0])
    np.testing.assert_array_equal(model.rhs(0.0, y), [2.0, 7.0, -2.25, 2.25])
