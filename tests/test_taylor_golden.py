"""Taylor runs and sweeps bitwise equal to those of the template drivers (tests/golden_taylor.py stored them)."""

import numpy as np
import pytest

from tests.golden_taylor import GOLDEN, runs


@pytest.fixture(scope="module")
def computed(tmp_path_factory):
    return runs(cache_dir=tmp_path_factory.mktemp("cache"))


def test_golden_taylor_results_are_bitwise_equal(computed):
    stored = np.load(GOLDEN)
    assert sorted(stored.files) == sorted(computed)
    different = [key for key in stored.files if not np.array_equal(stored[key], computed[key])]
    assert not different, f"Taylor results changed: {different}"
