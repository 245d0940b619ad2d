"""Collocation, canonical and Lyapunov results bitwise equal to the template code's (tests/golden_implicit.py)."""

import numpy as np
import pytest

from tests.golden_implicit import GOLDEN, runs


@pytest.fixture(scope="module")
def computed(tmp_path_factory):
    return runs(cache_dir=tmp_path_factory.mktemp("cache"))


def test_implicit_and_canonical_results_are_bitwise_equal(computed):
    stored = np.load(GOLDEN)
    assert sorted(stored.files) == sorted(computed)
    different = [key for key in stored.files if not np.array_equal(stored[key], computed[key], equal_nan=True)]
    assert not different, f"results changed: {different}"
