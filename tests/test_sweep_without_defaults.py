"""A sweep takes a swept parameter's values from its grid: a parameter without a default need not be in `params`.

The oscillator m ẍ = −k x from x = 1 at rest is x(t) = cos(√(k/m) t): each trajectory's final state is a
closed form, so the grid's values (not a placeholder) must be the ones each trajectory ran with.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.model import t

x = lc.coordinates("x")[0]
m, k = sp.symbols("m k", positive=True)
T_END = 1.5


@pytest.fixture(scope="module")
def model(tmp_path_factory):
    system = lc.System(coordinates=[x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, name="oscillator_no_defaults",
                       defaults={}, q0=(1.0,))
    return lc.compile(system, cache_dir=tmp_path_factory.mktemp("sweep_no_defaults"))


def closed_form(k_values, m_values):
    omega = np.sqrt(np.asarray(k_values) / np.asarray(m_values))
    return np.cos(omega * T_END), -omega * np.sin(omega * T_END)


def test_every_parameter_swept_needs_no_params(model):
    k_values, m_values = [1.0, 4.0, 9.0], [0.5, 2.0, 3.0]
    result = model.sweep((0.0, T_END), {"k": k_values, "m": m_values}, combine="zip", rtol=1e-12, atol=1e-12)
    x_end, v_end = closed_form(k_values, m_values)
    np.testing.assert_allclose(result.final[:, 0], x_end, rtol=0, atol=1e-10)
    np.testing.assert_allclose(result.final[:, 1], v_end, rtol=0, atol=1e-10)


def test_a_swept_parameter_beside_a_given_one(model):
    k_values = [1.0, 2.0]
    result = model.sweep((0.0, T_END), {k: k_values}, params={"m": 2.0}, rtol=1e-12, atol=1e-12)
    x_end, _ = closed_form(k_values, [2.0, 2.0])
    np.testing.assert_allclose(result.final[:, 0], x_end, rtol=0, atol=1e-10)


def test_a_parameter_neither_swept_nor_given_is_still_named(model):
    with pytest.raises(lc.ParameterError, match=r"Missing value.*\['m'\]"):
        model.sweep((0.0, T_END), {"k": [1.0, 2.0]})


def test_every_coordinate_swept_needs_no_q0(tmp_path):
    system = lc.System(coordinates=[x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, name="oscillator_no_q0",
                       defaults={"m": 1.0, "k": 4.0})
    model = lc.compile(system, cache_dir=tmp_path)
    starts = [0.5, -1.0, 2.0]
    result = model.sweep((0.0, T_END), {"x": starts}, rtol=1e-12, atol=1e-12)
    x_end, _ = closed_form([4.0] * 3, [1.0] * 3)
    np.testing.assert_allclose(result.final[:, 0], np.multiply(starts, x_end), rtol=0, atol=1e-10)
    with pytest.raises(lc.InitialConditionError, match="`q0` is required"):
        model.sweep((0.0, T_END), {"x_dot": [0.0, 1.0]})
