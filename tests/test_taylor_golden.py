"""Taylor runs and sweeps bitwise equal to those of the template drivers (tests/golden_taylor.py stored them).

The results are computed in a fresh process with a numba cache of its own: the double
pendulum's trajectories differ in the last bits when `lagcomp.kernel_support.trig` comes from
numba's cache (an opaque call from the kernels) rather than compiled in the same process (inlined
by LLVM), so the comparison would depend on the tests run before (measured on this commit; the
goldens hold the in-process compilation, as the template era had its sin in the module).
"""

import os
import pathlib
import subprocess
import sys

import numpy as np

from tests.golden_taylor import GOLDEN

ROOT = pathlib.Path(__file__).parent.parent


def test_golden_taylor_results_are_bitwise_equal(tmp_path):
    out = tmp_path / "computed.npz"
    environment = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    subprocess.run([sys.executable, "-m", "tests.golden_taylor", str(out), str(tmp_path / "cache")], cwd=ROOT,
                   check=True, capture_output=True, env=environment)
    stored, computed = np.load(GOLDEN), np.load(out)
    assert sorted(stored.files) == sorted(computed.files)
    different = [key for key in stored.files if not np.array_equal(stored[key], computed[key])]
    assert not different, f"Taylor results changed: {different}"
