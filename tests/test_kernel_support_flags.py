"""Kernel results do not depend on which caller compiled `lagcomp.kernel_support` first, nor on numba's cache.

numba compiles a function called from another with the caller's fastmath flags unless it has its
own, and caches that version for every later caller (`lagcomp.kernel_support.trig`'s docstring).
Three processes share one numba cache (NUMBA_CACHE_DIR):

1. a fresh one runs the double pendulum by Taylor, then by DOP853 (sin first compiled by the
   Taylor kernel, whose flags have ``contract``), and caches everything;
2. one removes trig's cache files and calls sin and cos from Python (as tests/test_trig.py
   does), so numba caches them compiled outside any kernel;
3. one compiles the model again in a new cache directory (a new generated module, whose kernels
   link sin and cos from numba's cache) and runs the same.

Runs 1 and 3 must be bitwise equal (they differed in the last bits before sin and cos had
``fastmath=False``).  Process 1 starts from a copy of this process's numba cache of the drivers
(`copy_driver_cache`), which call sin and cos only through the kernels: without it, compiling the
Taylor and DOP853 drivers took 30 of the test's 36 s.  And every kernel_support function that numba
does not inline into its caller has flags of its own.

    python -m tests.test_kernel_support_flags runs OUT CACHE_DIR [DRIVER_CACHE]   # process 1 or 3
    python -m tests.test_kernel_support_flags trig                 # process 2
"""

from __future__ import annotations

import os
import pathlib
import shutil
import subprocess
import sys

import numpy as np

ROOT = pathlib.Path(__file__).parent.parent
OPTIONS = dict(q0=[1.2, -0.4], qd0=[0.3, 0.8], t_eval=np.linspace(0.0, 10.0, 101), progress=False)


def runs(cache_dir) -> dict[str, np.ndarray]:
    """The double pendulum over 10 s by Taylor and DOP853 (Taylor first): label -> states (2n, 101)."""
    import lagcomp as lc
    from lagcomp.examples import get

    model = lc.compile(get("double_pendulum"), cache_dir=cache_dir)
    return {method: model.simulate((0.0, 10.0), method=method, **OPTIONS).y for method in ("taylor", "dop853")}


DRIVERS = ROOT / "src" / "lagcomp" / "integrate" / "drivers" / "__init__.py"


def copy_driver_cache(source: str) -> None:
    """Copy the drivers' numba cache files (and the stamp of what they were compiled from) from `source`
    into this process's numba cache, before anything imports a driver."""
    from lagcomp import numba_cache

    if source and pathlib.Path(source).is_dir():
        shutil.copytree(source, numba_cache.cache_directory(DRIVERS), dirs_exist_ok=True)


def recompile_trig_outside_kernels() -> None:
    """Remove numba's cache files of trig's functions, then call sin and cos from Python (numba caches them)."""
    from lagcomp import numba_cache

    source = ROOT / "src" / "lagcomp" / "kernel_support" / "trig.py"
    for path in numba_cache.cache_directory(source).glob(f"{source.stem}.*"):
        path.unlink()
    from lagcomp.kernel_support import trig

    trig.sin(0.5), trig.cos(0.5)


def test_every_function_numba_does_not_inline_has_its_own_fastmath_flags():
    from numba.core.registry import CPUDispatcher

    from lagcomp.kernel_support import angles, inputs, linear_solvers, trig

    for module in (angles, inputs, linear_solvers, trig):
        for name, function in vars(module).items():
            if isinstance(function, CPUDispatcher) and function.targetoptions.get("inline") != "always":
                assert function.targetoptions.get("fastmath") is False, f"{module.__name__}.{name}"


def _run(tmp_path, *args):
    environment = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}
    subprocess.run([sys.executable, "-m", "tests.test_kernel_support_flags", *map(str, args)], cwd=ROOT,
                   check=True, capture_output=True, env=environment)


def test_runs_are_bitwise_equal_whoever_compiled_sin_and_cos(tmp_path):
    from lagcomp import numba_cache

    drivers_cache = numba_cache.cache_directory(DRIVERS) or ""
    _run(tmp_path, "runs", tmp_path / "first.npz", tmp_path / "cache_first", drivers_cache)
    _run(tmp_path, "trig")
    _run(tmp_path, "runs", tmp_path / "second.npz", tmp_path / "cache_second")
    first, second = np.load(tmp_path / "first.npz"), np.load(tmp_path / "second.npz")
    different = [method for method in first.files if not np.array_equal(first[method], second[method])]
    assert not different, f"results depend on numba's cache state: {different}"


if __name__ == "__main__":
    if sys.argv[1] == "trig":
        recompile_trig_outside_kernels()
    else:
        copy_driver_cache(sys.argv[4] if len(sys.argv) > 4 else "")
        np.savez(sys.argv[2], **runs(sys.argv[3]))
