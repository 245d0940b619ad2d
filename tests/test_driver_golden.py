"""Trajectories bitwise equal to those of the drivers they replace (tests/golden_runs.py stored them)."""

import numpy as np
import pytest

from tests.golden_runs import SETS, runs


@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("cache")


@pytest.mark.parametrize("name", list(SETS))
def test_golden_trajectories_are_bitwise_equal(name, cache_dir):
    path, states, options_by_label = SETS[name]
    computed = runs(cache_dir=cache_dir, states=states, options_by_label=options_by_label)
    stored = np.load(path)
    assert sorted(stored.files) == sorted(computed)
    different = [key for key in stored.files if not np.array_equal(stored[key], computed[key])]
    assert not different, f"trajectories changed: {different}"
