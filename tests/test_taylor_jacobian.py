"""The variational kernel from the series of J's entries (`codegen.taylor_jacobian`) against forward mode.

Oracle: `codegen.taylor_variational.forward_source`'s kernel (the program differentiated in forward mode, itself
checked against DOP853, finite differences and closed forms in test_taylor_sensitivities, whose runs of the
double pendulum take the new kernel: `variational_source` picks it there).  The coefficients X of both, at
random states and directions: the state's rows bitwise equal, the columns' to rounding, every order.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lagcomp.cache import Cache, load_module, source_key
from lagcomp.codegen.taylor_jacobian import jacobian_products, jacobian_source
from lagcomp.codegen.taylor_variational import forward_products, forward_source, variational_source
from lagcomp.integrate.taylor_sensitivities import values_import
from tests.test_taylor_sensitivities import zoo  # noqa: F401  (the fixture: every operation, time, parameters)

ORDER = 16


def _kernel(model, source_of, k: int, parameters: tuple[int, ...]):
    """``taylor_variational_coefficients`` of `source_of` (forward_source or jacobian_source) for `model`."""
    source = (model.source_path.read_text(encoding="utf-8") + f"from {values_import(model)} import taylor_coefficients\n"
              + source_of(model._taylor_program, k, parameters, 1.0))
    entry = Cache(str(model.source_path.parent.parent)).store(f"variational-{source_key(source)}", source,
                                                              model.name, {})
    module = load_module(entry)
    return module.taylor_variational_coefficients, module.VARIATIONAL_WORK


def _coefficients(kernel, y: np.ndarray, p: np.ndarray, k: int) -> np.ndarray:
    function, work = kernel
    X = np.full((y.size, ORDER + 1), np.nan)
    W = np.full((work, ORDER + 1), np.nan)       # (no coefficient is read before it is written)
    assert function(0.7, y, p, X, W) == 0
    return X


def _agree(model, kernels, y: np.ndarray, k: int) -> None:
    p = np.array([model.defaults[name] for name in model.parameters])
    forward, jacobian = (_coefficients(kernel, y, p, k) for kernel in kernels)
    n = model._taylor_program["n_state"]
    assert np.array_equal(forward[:n], jacobian[:n])
    scale = np.abs(forward[n:]).max(axis=0)      # per order
    assert (np.abs(forward[n:] - jacobian[n:]) <= 1e-13 * scale).all()


def _states(n: int, k: int):
    """y = (x, S): the state near the model's regular motions, the directions anywhere."""
    return st.tuples(st.lists(st.floats(-1.0, 1.0), min_size=n, max_size=n),
                     st.lists(st.floats(-2.0, 2.0), min_size=n * k, max_size=n * k)).map(
        lambda pair: np.array(pair[0] + pair[1]))


@pytest.fixture(scope="module")
def pendulum(compiled):
    return compiled("double_pendulum")


@pytest.mark.parametrize("k, parameters", [
    (1, ()), (4, ()),
    pytest.param(9, (0, 1, 2, 3, 4), marks=pytest.mark.slow),  # 60 s of CPU: numba compiling its two kernels cold
])
def test_double_pendulum_coefficients_match_forward_mode(pendulum, k, parameters):
    kernels = [_kernel(pendulum, source_of, k, parameters) for source_of in (forward_source, jacobian_source)]

    @settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
    @given(_states(4, k))
    def agree(y):
        _agree(pendulum, kernels, y, k)
    agree()


@pytest.mark.slow  # 40 s: two kernels of their own, compiled cold
def test_every_operation_matches_forward_mode(zoo, monkeypatch):  # noqa: F811
    # the quotient, root, power and log keep their recurrences (one column each); time; parameters' partials.
    # Forward mode in its loop over blocks of 4 columns (test_taylor_sensitivities' block test runs the zoo's
    # choice, this kernel), this kernel with its 7 columns in one pass
    from lagcomp.codegen import taylor_kernel_frame

    jacobian = _kernel(zoo, jacobian_source, 7, (0, 1, 2))
    monkeypatch.setattr(taylor_kernel_frame, "UNROLLED_COLUMNS", 2)
    assert "_b in range(0, 8, 4)" in forward_source(zoo._taylor_program, 7, (0, 1, 2))
    kernels = [_kernel(zoo, forward_source, 7, (0, 1, 2)), jacobian]
    rng = np.random.default_rng(5)
    for _ in range(20):
        _agree(zoo, kernels, np.concatenate([rng.uniform(-0.5, 0.5, 4), rng.normal(size=4 * 7)]), 7)


def test_the_faster_kernel_is_chosen(pendulum, compiled):
    program = pendulum._taylor_program     # J: identity rows, two rows of 4 entries (8 convolutions per column)
    assert jacobian_products(program, 4) < forward_products(program, 4)
    assert variational_source(program, 4) == jacobian_source(program, 4)
    # J dense (36 convolutions per column): forward mode for one column (1.15-1.6x faster), not for 4 (0.89x)
    bodies = compiled("pythagorean_three_body")._taylor_program
    assert variational_source(bodies, 1) == forward_source(bodies, 1)
    assert variational_source(bodies, 4) == jacobian_source(bodies, 4)
    assert variational_source(bodies, 12) == jacobian_source(bodies, 12)
