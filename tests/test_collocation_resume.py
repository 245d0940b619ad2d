"""A Gauss–Legendre run does not depend on how it is cut into driver calls.

`simulate` cuts a long run into calls sized by time (`lagcomp.integrate.simulate.FIRST_BUDGET`, `CALL_SECONDS`, the
step rates it learns) and by output buffers; a sweep's loop calls the driver again each time its row buffer fills.
The collocation driver keeps what its step loop carries from step to step (x = (q, p) as continued, the summation's
compensation, the last stages and whether to extrapolate them) in a carry the caller holds, so a run cut into 16-step
calls is the run made in one call, bit for bit: the same evaluations and the same states, on a model and across a
ball joint's chart switches (where the driver rebuilds x in the new chart).
"""

from __future__ import annotations

import weakref

import numpy as np
import pytest

import lagcomp as lc
from lagcomp.examples.trees import spherical_chain
from lagcomp.integrate import simulate as simulate_module

METHODS = ("gauss1", "gauss2", "gauss3")
SOLVERS = ("fixed_point", "newton")
BALL_PARAMETERS = {"m0": 1.3, "c0": 0.7, "A0": 0.4, "B0": 0.3, "C0": 0.2, "g": 9.81}
TUMBLING = ([0.3, 0.1, 0.0], [1.0, -0.5, 2.0])   # (a shadow switch every ~0.7 s)


@pytest.fixture(scope="module")
def ball(cache_dir):
    """A rigid body on a ball joint (MRPs), whose tumbling switches charts."""
    return lc.compile(spherical_chain(1), cache_dir=cache_dir)


def _in_calls(monkeypatch, budget: int, rows: int, run):
    """`run()` with every driver call of `simulate` at most `budget` steps and `rows` output rows."""
    with monkeypatch.context() as patch:
        patch.setattr(simulate_module, "FIRST_BUDGET", budget)
        patch.setattr(simulate_module, "CALL_SECONDS", 1e-12)     # every later budget: the minimum, 16
        patch.setattr(simulate_module, "_STEP_RATES", weakref.WeakKeyDictionary())
        patch.setattr(simulate_module, "FIRST_CHUNK", rows)
        patch.setattr(simulate_module, "MAX_CHUNK", rows)
        return run()


def _assert_same_run(monkeypatch, run):
    """`run()` in one driver call and in 16-step calls (16-row buffers): the same run, bit for bit."""
    whole = _in_calls(monkeypatch, 1 << 40, 1 << 20, run)
    split = _in_calls(monkeypatch, 16, 16, run)
    assert whole.status == split.status == 0
    np.testing.assert_array_equal(split.t, whole.t)
    np.testing.assert_array_equal(split.y, whole.y)
    assert split.nfev == whole.nfev and split.nsteps == whole.nsteps
    return whole


@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("method", METHODS)
def test_a_gauss_run_cut_into_calls_is_the_run_in_one_call(compiled, monkeypatch, method, solver):
    model = compiled("double_pendulum")
    _assert_same_run(monkeypatch, lambda: model.simulate((0, 2), [1.2, -0.4], [0.3, 1.1], method=method, dt=0.01,
                                                         implicit_solver=solver, progress=False))


@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("method", METHODS)
def test_a_gauss_run_cut_into_calls_keeps_its_chart_switches(ball, monkeypatch, method, solver):
    """A call may begin right after a step that switched charts: the carry holds the switched x."""
    whole = _assert_same_run(monkeypatch, lambda: ball.simulate((0, 3), *TUMBLING, BALL_PARAMETERS, method=method,
                                                                dt=0.01, implicit_solver=solver, progress=False))
    switches = np.count_nonzero(np.einsum("ij,ij->i", whole.q[1:], whole.q[:-1]) < 0)   # σ' = −σ/|σ|²
    assert switches >= 3


@pytest.mark.parametrize("method", METHODS)
def test_a_gauss_sweep_ends_where_its_runs_end(ball, method):
    """The sweep loop calls the driver again whenever its 64-row buffer fills (a row per step for the energy error,
    300 steps here): each trajectory's final state is its own run's, bit for bit."""
    masses = (1.0, 1.3)
    sweep = ball.sweep((0, 3), {"m0": list(masses)}, q0=TUMBLING[0], qd0=TUMBLING[1], params=BALL_PARAMETERS,
                       method=method, dt=0.01, output=("energy",), progress=False)
    for k, mass in enumerate(masses):
        run = ball.simulate((0, 3), *TUMBLING, {**BALL_PARAMETERS, "m0": mass}, method=method, dt=0.01,
                            progress=False)
        assert sweep.status[k] == 0 and sweep.nfev[k] == run.nfev
        np.testing.assert_array_equal(sweep.final[k], run.y[-1])
