"""A run's memory is estimated before it starts (issue 24, item 2), with the logic sweeps use.

Before: ``method="rk4", dt=1e-7`` over 10 s allocated ~7 GB and failed with
MemoryError after 52 s of integration; a ``t_eval`` of 10⁹ points was killed
by the OOM killer.  Now both are refused at once with a message naming the
figure and the options that reduce it.
"""

from __future__ import annotations

import numpy as np
import pytest

import lagcomp as lc
from lagcomp import OptionError
from lagcomp.integrate.memory import MEMORY_LIMIT, run_bytes


@pytest.fixture(scope="module")
def pendulum(compiled):
    return compiled("simple_pendulum")


def test_a_run_too_large_for_memory_is_refused_before_it_starts(pendulum):
    with pytest.raises(OptionError) as info:
        pendulum.simulate((0, 10), method="rk4", dt=1e-7, progress=False)
    message = str(info.value)
    needed = run_bytes(10**8 + 1, pendulum.n, pendulum.k)
    assert needed > MEMORY_LIMIT
    assert f"{needed / 2**20:.1f} MiB" in message and "100,000,001 rows" in message
    for remedy in ("save_every", 'record="summary"', "t_eval", "memory_limit"):
        assert remedy in message


def test_a_billion_t_eval_points_are_refused_before_they_are_copied(pendulum):
    times = np.broadcast_to(np.float64(0.5), (10**9,))  # 8 GB if it were ever copied; 8 bytes here
    with pytest.raises(OptionError, match=r"1,000,000,000 `t_eval` times"):
        pendulum.simulate((0, 1), t_eval=times, progress=False)


def test_the_limit_is_an_option_and_the_remedies_work(pendulum):
    span = dict(t_span=(0, 1000), method="rk4", dt=1e-3, progress=False)
    with pytest.raises(OptionError, match=r"above the limit of 1\.0 MiB"):
        pendulum.simulate(**span, memory_limit=2**20)
    decimated = pendulum.simulate(**span, memory_limit=2**20, save_every=1000)
    assert decimated.t.size == 1001 and decimated.success
    summary = pendulum.simulate(**span, memory_limit=2**20, record="summary")
    assert summary.t.size == 2 and summary.summary.rows == 10**6 + 1
    np.testing.assert_array_equal(summary.q[-1], decimated.q[-1])
    with pytest.raises(OptionError, match="`memory_limit`"):
        pendulum.simulate(**span, memory_limit=-1)


def test_the_estimate_bounds_what_a_run_keeps(compiled):
    for model in (compiled("simple_pendulum"), compiled("spherical_pendulum_cartesian")):
        sol = model.simulate((0, 2), method="rk4", dt=1e-3, progress=False)
        kept = sum(a.nbytes for a in (sol.t, sol.q, sol.qd, sol.energy, sol.energy_function, sol.momenta))
        kept += sum(r.nbytes for r in sol.reactions.values())
        estimate = run_bytes(sol.t.size, model.n, model.k)
        assert kept <= estimate <= 3 * kept  # the estimate is the peak while rows are joined: ~2x what is kept


def test_an_adaptive_run_stops_at_the_limit_and_keeps_its_rows(pendulum):
    """Without t_eval an adaptive run's rows are not known up front: it stops when they reach the limit,
    with status -7 and every row computed so far (the same rows as an unlimited run, cut short)."""
    limit = 200 * run_bytes(1, pendulum.n, pendulum.k)  # 200 rows; the run saves about 1,460
    full = pendulum.simulate((0, 200), progress=False)
    cut = pendulum.simulate((0, 200), progress=False, memory_limit=limit)
    assert full.success and full.t.size > 1000
    assert cut.status == -7 and "memory_limit" in cut.message and cut.t[-1] < 200
    assert 200 < cut.t.size < full.t.size  # stopped after the output buffer that crossed the limit
    np.testing.assert_array_equal(cut.q, full.q[: cut.t.size])
    with pytest.raises(lc.IntegrationError) as info:
        pendulum.simulate((0, 200), progress=False, memory_limit=limit, throw=True)
    assert info.value.solution.t.size == cut.t.size
