"""Batched sweeps bitwise equal to those of the template lane loops they replace (tests/golden_lanes.py stored them)."""

import numpy as np
import pytest

from tests.golden_lanes import GOLDEN, runs


@pytest.fixture(scope="module")
def computed(tmp_path_factory):
    return runs(cache_dir=tmp_path_factory.mktemp("cache"))


def test_batched_sweeps_are_bitwise_equal(computed):
    stored = np.load(GOLDEN)
    assert sorted(stored.files) == sorted(computed)
    different = [key for key in stored.files if not np.array_equal(stored[key], computed[key])]
    assert not different, f"batched sweeps changed: {different}"


@pytest.mark.parametrize("options", [{"method": "rk4", "dt": 0.01, "output": "energy"},
                                     {"method": "dop853", "rtol": 1e-9, "atol": 1e-9, "output": "energy"}])
def test_blocks_of_lanes_do_not_change_a_trajectory(compiled, options):
    """Full and partial blocks of any width (the golden grids fit in one block): 300 trajectories at once
    give bitwise what the same trajectories give in sweeps of 45 (each its own partial block)."""
    model = compiled("double_pendulum")
    angles = np.linspace(-2.0, 2.0, 300)
    whole = model.sweep((0, 2), {"theta1": angles}, qd0=[0.3, -0.2], batched=True, workers=1, **options)
    for a in range(0, 300, 45):
        part = model.sweep((0, 2), {"theta1": angles[a:a + 45]}, qd0=[0.3, -0.2], batched=True, workers=1, **options)
        for key in ("final", "t_final", "status", "nfev", "nsteps", "nrejected", "energy_error"):
            np.testing.assert_array_equal(getattr(part, key), getattr(whole, key)[a:a + 45])
