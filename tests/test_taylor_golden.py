"""Taylor runs and sweeps bitwise equal to the stored ones (tests/golden_taylor.py stored them, see its docstring)."""

import numpy as np

from tests.golden_taylor import GOLDEN, runs


def test_golden_taylor_results_are_bitwise_equal(tmp_path):
    stored, computed = np.load(GOLDEN), runs(cache_dir=tmp_path / "cache")
    assert sorted(stored.files) == sorted(computed)
    different = [key for key in stored.files if not np.array_equal(stored[key], computed[key])]
    assert not different, f"Taylor results changed: {different}"
