"""Inputs that used to end in a raw traceback or a misleading message (issue 24, items 3 and 4).

Each test reproduces the issue's report and checks the answer now: accepted
and right (a single coordinate, parameters keyed by Symbol, coordinates `x`
and `x_dot`, a 300-character name) or refused with a `LagcompError` that
names the culprit (the imaginary unit, `name=None`, strings).
"""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.mechanics.lagrange import derive
from lagcomp.model import t

x, y = lc.coordinates("x x_dot")
m, k = sp.symbols("m k", positive=True)


def _oscillator(**overrides) -> lc.System:
    spec = dict(coordinates=[x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, name="refusal_oscillator",
                defaults={"m": 1.0, "k": 4.0}, q0=(1.0,))
    spec.update(overrides)
    return lc.System(**spec)


@pytest.fixture(scope="module")
def oscillator(cache_dir):
    return lc.compile(_oscillator(), cache_dir=cache_dir)


def test_params_keyed_by_symbols_are_taken_by_name(oscillator):
    by_symbol = oscillator.parameter_vector({m: 2.0, k: 8.0})  # two Symbols: sorting them raised a TypeError
    np.testing.assert_array_equal(by_symbol, oscillator.parameter_vector({"m": 2.0, "k": 8.0}))
    with pytest.raises(lc.ParameterError, match="`m` twice"):
        oscillator.parameter_vector({m: 2.0, "m": 3.0})
    with pytest.raises(lc.ParameterError, match=r"`params` keys .* got 3"):
        oscillator.parameter_vector({3: 1.0})
    assert _oscillator(defaults={m: 2.0, k: 1.0}).defaults == {"m": 2.0, "k": 1.0}


def test_imaginary_unit_is_refused_when_the_system_is_built():
    with pytest.raises(lc.ModelError, match="T contains the imaginary unit"):
        lc.compile(_oscillator(T=sp.I * m * x.diff(t) ** 2 / 2))
    with pytest.raises(lc.ModelError, match="V contains zoo"):
        _oscillator(V=k / sp.S.Zero * x)


def test_name_none_and_non_sequences_are_refused_by_name():
    with pytest.raises(lc.ModelError, match="System name None"):
        _oscillator(name=None)
    with pytest.raises(lc.ModelError, match="`coordinates` must be a sequence"):
        lc.System(3, T=m * x.diff(t) ** 2)
    with pytest.raises(lc.ModelError, match="`events` must be a sequence"):
        _oscillator(events=lc.Event("origin", x))


def test_a_single_coordinate_is_a_sequence_of_one():
    assert _oscillator(coordinates=x).fingerprint() == _oscillator().fingerprint()


def test_a_300_character_name_gets_a_hashed_file_name(tmp_path):
    name = "a" * 300
    with warnings.catch_warnings():
        warnings.simplefilter("error", lc.CacheWarning)  # it used to report the cache unwritable, then fail
        model = lc.compile(_oscillator(name=name), cache_dir=tmp_path)
    assert len(model.source_path.name) < 100 and model.source_path.parent == tmp_path / "modules"
    assert model.energy([1.0], [0.0]) == 2.0  # V = k x²/2 with k = 4
    assert lc.load(name, cache_dir=tmp_path).source_path == model.source_path


def test_coordinates_x_and_x_dot_are_distinct_from_the_velocity_of_x():
    """Two unit masses joined by a spring k between coordinates x and x_dot: M = diag(m, m),
    F = (−k (x − x_dot), k (x − x_dot)); it used to say "The potential V depends on velocities"."""
    system = lc.System([x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=k * (x - y) ** 2 / 2,
                       name="refusal_x_dot")
    eom = derive(system)
    a, b = sp.symbols("a b")
    state = dict(zip(eom.q, (a, b)))
    assert eom.M == sp.diag(m, m)
    assert sp.simplify(eom.F.xreplace(state) - sp.Matrix([-k * (a - b), k * (a - b)])) == sp.zeros(2, 1)
    assert not eom.F.has(*eom.qd)


def test_a_parameter_named_like_a_velocity_stays_a_parameter():
    """V = x_dot·x with x_dot a parameter (a constant force): F = −x_dot, not the velocity."""
    x_dot = sp.Symbol("x_dot")
    eom = derive(_oscillator(V=x_dot * x, defaults={}))
    assert eom.F == sp.Matrix([-x_dot]) and not eom.F.has(*eom.qd)


@pytest.mark.parametrize("field, build", [
    ("`T` is the string", lambda: _oscillator(T="m*x_dot**2/2")),
    ("`forces[0]` is the string", lambda: _oscillator(forces=["-k*x"])),
    ("Event `apex`: the expression is the string", lambda: _oscillator(events=[lc.Event("apex", "x - 1")])),
    ("Constraint `c`: Phi is the string", lambda: lc.Holonomic("c", "x - 1")),
    ("Constraint `r`: the expression is the string", lambda: lc.Nonholonomic("r", "x")),
])
def test_expressions_written_as_strings_are_refused(field, build):
    """A string's `x` would become a parameter named x, not the coordinate: refused, naming the field."""
    with pytest.raises(lc.ModelError, match=re.escape(field)):
        build()
