"""The variational kernel's size (issue 35): its values are the model's ``taylor_coefficients``, and a kernel too
large for numba is refused (`lagcomp.codegen.taylor_kernel_frame`).

Oracles: ``taylor_coefficients`` itself (the state rows of the variational kernel's X, and the values' rows of W,
bitwise its, at random states and orders); the refusal's message and that it comes before any numba compile.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.codegen import taylor_kernel_frame
from lagcomp.codegen.taylor_jacobian import jacobian_source
from lagcomp.codegen.taylor_variational import forward_source
from lagcomp.examples.trees import planar_chain
from lagcomp.integrate import taylor_sensitivities


@pytest.fixture(scope="module")
def pendulum(compiled):
    return compiled("double_pendulum")


@pytest.mark.parametrize("source_of", [forward_source, jacobian_source])
def test_the_kernel_calls_taylor_coefficients_for_the_values(pendulum, source_of):
    source = source_of(pendulum._taylor_program, 4)
    # the double pendulum's values hold sin and cos of the angles: in taylor_coefficients only
    assert f"{taylor_kernel_frame.VALUES}(t, y, p, X, W)" in source and "sin(" not in source


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.floats(-1.5, 1.5), min_size=4, max_size=4), st.integers(1, 24),
       st.sampled_from([(4, ()), (9, (0, 1, 2, 3, 4))]))
def test_state_and_value_rows_are_taylor_coefficients_bitwise(pendulum, x, order, columns):
    k, parameters = columns
    module = taylor_sensitivities.variational_module(pendulum, k, parameters, 1.0)
    p = np.array([pendulum.defaults[name] for name in pendulum.parameters])
    y = np.concatenate([x, np.eye(4, k).T.reshape(-1)])
    X, W = np.full((4 * (1 + k), order + 1), np.nan), np.full((module.VARIATIONAL_WORK, order + 1), np.nan)
    assert module.taylor_variational_coefficients(0.4, y, p, X, W) == 0
    kernels = pendulum.kernels
    X0, W0 = np.full((4, order + 1), np.nan), np.full((kernels.TAYLOR_WORK, order + 1), np.nan)
    assert kernels.taylor_coefficients(0.4, np.array(x), p, X0, W0) == 0
    # (W's values of order `order` are not computed: NaN in both)
    assert np.array_equal(X[:4], X0) and np.array_equal(W[:kernels.TAYLOR_WORK], W0, equal_nan=True)
    assert np.isfinite(X).all()      # (every column's row written, every order)


def test_a_kernel_above_the_limit_is_refused(pendulum, monkeypatch):
    program = pendulum._taylor_program
    forward_source(program, 4)       # within the limit
    monkeypatch.setattr(taylor_kernel_frame, "KERNEL_LINES_MAX", 40)
    for source_of in (forward_source, jacobian_source):
        with pytest.raises(lc.OptionError, match="`taylor_variational_coefficients` for 4 sensitivity columns"):
            source_of(program, 4)


def test_a_large_tree_is_refused_before_numba_compiles(tmp_path):
    model = lc.compile(planar_chain(6), cache_dir=tmp_path, progress=False)
    params = dict.fromkeys(model.parameters, 1.0)
    start = time.process_time()
    with pytest.raises(lc.OptionError) as info:
        model.simulate((0.0, 0.1), [0.1] * 6, [0.0] * 6, params=params, method="taylor",
                       sensitivities=("q0", "qd0"), progress=False)
    message = str(info.value)
    assert "`taylor_variational_coefficients` for 12 sensitivity columns" in message and "method='dop853'" in message
    assert time.process_time() - start < 20.0      # (measured 0.5 s; numba would take tens of minutes)
    assert not any(key[0] is model.kernels for key in taylor_sensitivities._MODULES)
