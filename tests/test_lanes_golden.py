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
