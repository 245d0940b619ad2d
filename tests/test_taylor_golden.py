"""Taylor runs and sweeps bitwise equal to those of the template drivers (tests/golden_taylor.py stored them).

The results are computed in a fresh process: in one that has called the model's
``taylor_coefficients`` from Python before (test_taylor.py does), the double pendulum's
trajectories differ in the last bits, with the template drivers as with the library ones
(measured on both at efc66f1 and after), so the comparison would depend on the tests run before.
"""

import pathlib
import subprocess
import sys

import numpy as np

from tests.golden_taylor import GOLDEN

ROOT = pathlib.Path(__file__).parent.parent


def test_golden_taylor_results_are_bitwise_equal(tmp_path):
    out = tmp_path / "computed.npz"
    subprocess.run([sys.executable, "-m", "tests.golden_taylor", str(out), str(tmp_path / "cache")], cwd=ROOT,
                   check=True, capture_output=True)
    stored, computed = np.load(GOLDEN), np.load(out)
    assert sorted(stored.files) == sorted(computed.files)
    different = [key for key in stored.files if not np.array_equal(stored[key], computed[key])]
    assert not different, f"Taylor results changed: {different}"
