"""What `Model.simulate` keeps from run to run to cut its fixed cost (the default parameter vector and initial
state, the methods' coefficient arrays) never shows: a change to the defaults takes effect at the next run, and
mutating anything a run or a call returned does not reach the next one."""

from __future__ import annotations

import numpy as np
import pytest

from lagcomp.errors import OptionError, ParameterError
from lagcomp.integrate.methods import METHODS
from lagcomp.integrate.options import run_options


def _same(a, b) -> bool:
    return np.array_equal(a.t, b.t) and np.array_equal(a.y, b.y) and a.nfev == b.nfev


def test_returned_inputs_are_fresh(compiled):
    model = compiled("double_pendulum")
    p, y = model.parameter_vector(), model.initial_state()
    p_kept, y_kept = p.copy(), y.copy()
    p[:], y[:] = np.nan, np.nan
    np.testing.assert_array_equal(model.parameter_vector(), p_kept)
    np.testing.assert_array_equal(model.initial_state(), y_kept)


def test_changed_defaults_take_effect(compiled):
    model = compiled("double_pendulum")
    before = model.simulate((0.0, 0.5), progress=False)
    g, q0 = model.defaults["g"], model.q0
    try:
        model.defaults["g"] = 2.0 * g
        model.q0 = (0.3, -0.1)
        changed = model.simulate((0.0, 0.5), progress=False)
        assert changed.params["g"] == 2.0 * g
        assert _same(changed, model.simulate((0.0, 0.5), q0=[0.3, -0.1], params={"g": 2.0 * g}, progress=False))
        model.defaults["g"] = "heavy"
        with pytest.raises(ParameterError, match="must be a number"):
            model.parameter_vector()
    finally:
        model.defaults["g"], model.q0 = g, q0
    assert _same(before, model.simulate((0.0, 0.5), progress=False))


def test_given_inputs_do_not_replace_the_defaults(compiled):
    model = compiled("double_pendulum")
    default = model.simulate((0.0, 0.5), progress=False)
    model.simulate((0.0, 0.5), q0=[1.2, -0.4], params={"m1": 3.0}, progress=False)
    model.simulate((0.0, 0.5), q0=[1.2, -0.4], qd0=[0.3, 0.8], progress=False)
    assert _same(default, model.simulate((0.0, 0.5), progress=False))
    np.testing.assert_array_equal(model.initial_state(), [*model.q0, *(model.qd0 or (0.0,) * model.n)])


def test_mutating_a_solution_does_not_leak(compiled):
    model = compiled("stiff_spring_pendulum")
    first = model.simulate((0.0, 0.01), method="radau", progress=False)
    reference = (first.t.copy(), first.y.copy())
    first.t[:], first.q[:], first.qd[:] = np.nan, np.nan, np.nan
    again = model.simulate((0.0, 0.01), method="radau", progress=False)
    assert np.array_equal(again.t, reference[0]) and np.array_equal(again.y, reference[1])


@pytest.mark.parametrize("method", ["dop853", "radau", "gauss2", "taylor"])
def test_coefficient_arrays_are_fresh_copies(compiled, method):
    model = compiled("double_pendulum")
    options = run_options(model, (0.0, 1.0), method=method, dt=None if METHODS[method].adaptive else 0.01,
                          memory_limit=2**30)
    first = options.driver_arguments()
    for value in first:
        if isinstance(value, np.ndarray):
            value[...] = np.nan
    for fresh, made in zip(options.driver_arguments(), METHODS[method].driver_arguments(options.implicit_solver),
                           strict=True):
        if isinstance(made, np.ndarray):
            assert fresh.flags.c_contiguous and fresh.flags.writeable
        np.testing.assert_array_equal(fresh, made)


def test_constrained_gains_checked_at_every_call(compiled):
    model = compiled("spherical_pendulum_cartesian")
    plain = model.parameter_vector()
    np.testing.assert_array_equal(model.parameter_vector(baumgarte=(1.0, 2.0))[-2:], [1.0, 2.0])
    np.testing.assert_array_equal(model.parameter_vector(baumgarte=(1.0, 2.0))[:-2], plain[:-2])
    with pytest.raises(OptionError, match="baumgarte"):
        model.parameter_vector(baumgarte=(-1.0, 0.0))
