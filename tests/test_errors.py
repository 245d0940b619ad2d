"""Every documented bad input raises a LagcompError subclass whose message names the culprit."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.model import t

x, y = lc.coordinates("x y")
m, k = sp.symbols("m k", positive=True)


def oscillator(**overrides):
    spec = dict(coordinates=[x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, name="oscillator",
                defaults={"m": 1.0, "k": 1.0}, q0=(1.0,))
    spec.update(overrides)
    return lc.System(**spec)


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    return lc.compile(oscillator(), cache_dir=tmp_path_factory.mktemp("errors-cache"))


def test_undeclared_symbol_is_named():
    stray = sp.Symbol("stray")
    with pytest.raises(lc.UndeclaredSymbolError, match="stray"):
        oscillator(V=k * x**2 / 2 + stray * x, parameters=(m, k))


def test_undeclared_function_of_time_is_named():
    phi = sp.Function("phi")(t)
    with pytest.raises(lc.UndeclaredSymbolError, match=r"phi\(t\).*not a coordinate"):
        oscillator(V=k * (x - phi) ** 2 / 2)


def test_plain_symbol_as_coordinate_is_refused():
    with pytest.raises(lc.ModelError, match="not a function of t"):
        lc.System([sp.Symbol("x")], T=sp.Symbol("x") ** 2, name="bad")


def test_singular_mass_matrix_detected_symbolically(tmp_path):
    # y has no inertia at all: its row of M is zero
    with pytest.raises(lc.SingularMassMatrixError, match="`y`"):
        lc.compile(lc.System([x, y], T=m * x.diff(t) ** 2 / 2, V=k * y**2, name="no_inertia"), cache_dir=tmp_path)
    # rank one: only x + y moves
    with pytest.raises(lc.SingularMassMatrixError, match="singular at every state"):
        lc.compile(lc.System([x, y], T=m * (x.diff(t) + y.diff(t)) ** 2 / 2, name="rank_one"), cache_dir=tmp_path)


def test_mass_matrix_singular_at_a_state_is_reported_with_the_state(tmp_path):
    # M = m x², singular only at x = 0
    model = lc.compile(lc.System([x], T=m * x**2 * x.diff(t) ** 2 / 2, name="degenerate"), cache_dir=tmp_path)
    with pytest.raises(lc.SingularMassMatrixError, match=r"x=0"):
        model.rhs(0.0, [0.0, 1.0], params={"m": 1.0})
    # singular at the initial state itself: bad input, refused before the run (docs/errors.md)
    with pytest.raises(lc.SingularMassMatrixError, match=r"initial state t=0, x=0"):
        model.simulate((0, 1), q0=[0.0], qd0=[1.0], params={"m": 1.0}, method="rk4", dt=0.1)


def test_not_quadratic_kinetic_energy():
    with pytest.raises(lc.ModelError, match="not quadratic"):
        lc.compile(oscillator(T=m * x.diff(t) ** 4))


def test_velocity_dependent_potential():
    with pytest.raises(lc.ModelError, match="potential V depends on velocities"):
        lc.compile(oscillator(V=k * x.diff(t) * x))


@pytest.mark.parametrize(
    "params, match",
    [({"m": 1.0, "k": 1.0, "c": 2.0}, "Unknown parameter.*'c'"),
     ({"m": math.nan}, "`m` is nan"),
     ({"k": "soft"}, "`k` must be a number")],
)
def test_bad_parameter_values(model, params, match):
    with pytest.raises(lc.ParameterError, match=match):
        model.simulate((0, 1), params=params)


def test_missing_parameter_value(tmp_path):
    model = lc.compile(oscillator(defaults={}), cache_dir=tmp_path)
    with pytest.raises(lc.ParameterError, match=r"Missing value.*\['k', 'm'\]"):
        model.simulate((0, 1))


@pytest.mark.parametrize(
    "kwargs, error, match",
    [(dict(q0=[1.0, 2.0]), lc.InitialConditionError, "`q0` has 2 value"),
     (dict(qd0=[math.inf]), lc.InitialConditionError, "`qd0`.*not finite"),
     (dict(t_span=(1.0, 1.0)), lc.OptionError, "empty"),
     (dict(t_span=(0.0, math.nan)), lc.OptionError, "finite"),
     (dict(method="rk4", dt=0.0), lc.OptionError, "`dt` must be positive"),
     (dict(method="rk4", dt=-1e-3), lc.OptionError, "`dt` must be positive"),
     (dict(method="rk4"), lc.OptionError, "give the step `dt`"),
     (dict(rtol=0.0), lc.OptionError, "`rtol` must be positive"),
     (dict(atol=-1e-9), lc.OptionError, "`atol` must be positive"),
     (dict(method="euler"), lc.OptionError, "Unknown method 'euler'"),
     (dict(t_eval=[0.5, 0.2]), lc.OptionError, "strictly increasing"),
     (dict(save_every=0), lc.OptionError, "`save_every`"),
     (dict(max_steps=0), lc.OptionError, "`max_steps` must be a positive integer"),
     (dict(method="rk4", dt=1e-3, max_steps=10), lc.OptionError, "exceed `max_steps`"),
     (dict(dt=0.1), lc.OptionError, "chooses its own")],
)
def test_bad_run_options(model, kwargs, error, match):
    t_span = kwargs.pop("t_span", (0.0, 1.0))
    with pytest.raises(error, match=match):
        model.simulate(t_span, **kwargs)


def test_nan_stops_the_run_and_returns_the_partial_solution(tmp_path):
    # ẍ = 1/(1 − t)² ... blows up: the force is finite until t = 1, inf there, NaN after
    force = 1 / sp.sqrt(1 - t)
    model = lc.compile(oscillator(V=0, forces=[force], name="blow_up", defaults={"m": 1.0}), cache_dir=tmp_path)
    sol = model.simulate((0, 2), q0=[0.0], qd0=[0.0], method="rk4", dt=0.01)
    assert sol.status == -1 and not sol.success
    assert 0.95 <= sol.t_failure < 1.0
    assert "non-finite" in sol.message and f"t = {sol.t_failure:.10g}" in sol.message
    assert sol.t[-1] == sol.t_failure and np.all(np.isfinite(sol.q))
    with pytest.raises(lc.IntegrationError, match="non-finite") as info:
        model.simulate((0, 2), q0=[0.0], qd0=[0.0], method="rk4", dt=0.01, throw=True)
    assert info.value.solution.status == -1
    adaptive = model.simulate((0, 2), q0=[0.0], qd0=[0.0], method="dop853")
    assert adaptive.status in (-1, -3) and adaptive.t_failure < 1.0 + 1e-9
    assert np.all(np.isfinite(adaptive.q))


def test_step_limit_returns_the_partial_solution(model):
    sol = model.simulate((0, 100), max_steps=5)
    assert sol.status == -4 and sol.nsteps == 5 and len(sol.t) == 6
    assert "maximum number of steps" in sol.message and sol.t_failure == sol.t[-1] < 100


def test_compile_refuses_what_is_not_a_system():
    from lagcomp import examples
    from lagcomp.errors import ModelError

    with pytest.raises(ModelError, match="needs a lagcomp System"):
        lc.compile("double_pendulum")
    with pytest.raises(ModelError, match="only with a sympy method object"):
        lc.compile(examples.get("simple_pendulum"), name="other")
