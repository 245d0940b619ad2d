"""The kernels' own sin and cos (`lagcomp.kernel_support.trig`) and the printer's powers without pow.

References: numpy's sin/cos (libm) and ``**`` at float64.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp

from lagcomp.codegen.printer import to_code
from lagcomp.kernel_support import trig


@pytest.fixture(scope="module")
def kernels(compiled):
    return compiled("double_pendulum").kernels


def _ulps(ours, exact):
    ulps = np.abs(ours - exact) / np.spacing(np.abs(exact))
    return np.max(ulps[np.abs(exact) > 1e-300])


ARGUMENTS = np.concatenate([np.linspace(-20, 20, 20001), np.random.default_rng(1).uniform(-1e5, 1e5, 4000),
                            [0.0, np.pi / 2, np.pi, -np.pi / 4, 1e-300, 1e5, -1e5]])


@pytest.mark.parametrize("vectorizable", [False, True])
def test_sin_cos_are_within_two_ulp_of_libm(vectorizable):
    sin, cos = (trig.vsin, trig.vcos) if vectorizable else (trig.sin, trig.cos)
    assert _ulps(np.array([sin(v) for v in ARGUMENTS]), np.sin(ARGUMENTS)) <= 2
    assert _ulps(np.array([cos(v) for v in ARGUMENTS]), np.cos(ARGUMENTS)) <= 2


def test_huge_and_non_finite_arguments_go_to_libm():
    huge = np.array([1.0e5 + 0.5, -3.7e6, 1e12, 1e300])
    np.testing.assert_array_equal([trig.sin(v) for v in huge], np.sin(huge))
    np.testing.assert_array_equal([trig.cos(v) for v in huge], np.cos(huge))
    for bad in (math.nan, math.inf, -math.inf):
        assert math.isnan(trig.sin(bad)) and math.isnan(trig.cos(bad))


def test_kernels_call_them(kernels):
    import inspect

    eager = inspect.getsource(inspect.getmodule(kernels.rhs.py_func))
    companion = inspect.getsource(inspect.getmodule(kernels.taylor_coefficients.py_func))   # built on demand
    for source in (eager, companion):
        assert "from lagcomp.kernel_support.trig import cos, sin" in source
    start = eager.index("def rhs(")
    rhs = eager[start:eager.index("\n@", start)]
    assert "*sin(" in rhs and "*cos(" in rhs and "math.sin" not in rhs and "_sin(" not in rhs
    taylor = companion[companion.index("def taylor_coefficients("):companion.index("TAYLOR_WORK =")]
    assert " sin(" in taylor and " cos(" in taylor and "math.sin" not in taylor and "_sin(" not in taylor


@pytest.mark.parametrize("k", [-7, -5, -3, -1, 1, 3, 5, 7])
def test_half_integer_powers_print_without_pow(k):
    x = sp.Symbol("x", positive=True)
    code = to_code(x ** sp.Rational(k, 2))
    assert "**0." not in code and "**(" not in code and "math.sqrt(x)" in code
    for value in (0.3, 1.0, 2.5, 1e3):
        got = eval(code, {"math": math, "x": value})
        assert abs(got / value ** (k / 2) - 1) < 4e-16


def test_half_integer_powers_inside_products_and_quotients():
    """As sympy prints them: a factor r**(-3/2) goes to the denominator as r**(3/2), which must stay whole."""
    x, y, mu = sp.symbols("x y mu", positive=True)
    r2 = x**2 + y**2
    for expr in (-mu * x * r2 ** sp.Rational(-3, 2), mu / r2 ** sp.Rational(5, 2), x * r2 ** sp.Rational(3, 2) / y):
        values = {"x": 0.7, "y": -1.3, "mu": 2.5}
        got = eval(to_code(expr), {"math": math, **values})
        exact = float(expr.subs({x: values['x'], y: values['y'], mu: values['mu']}))
        assert abs(got / exact - 1) < 1e-15, (expr, to_code(expr))
