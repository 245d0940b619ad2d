"""Integration speed: lagcomp's numba drivers vs scipy's solve_ivp on the same compiled kernel.

    python bench/bench_run.py [example ...]

Both sides integrate the same system (t ∈ [0, 100], rtol = atol = 1e-10) with
the same algorithm (DOP853, and RK45/DOPRI5), so they take the same steps;
scipy calls lagcomp's compiled `rhs` from Python at every stage.  Prints the
median of 5 warm runs of each, and the ratio (how many times faster lagcomp's
whole-loop-in-numba driver is), measured in the same process.
"""

from __future__ import annotations

import statistics
import sys
import tempfile
import time

import numpy as np
from scipy.integrate import solve_ivp

import lagcomp as lc
from lagcomp import examples


def median_time(run, repeats: int = 5) -> float:
    run()  # warm: numba compilation or cache load
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main(names: list[str]) -> None:
    print("| example | method | steps | lagcomp ms | scipy + compiled rhs ms | speed-up |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as cache_dir:
        for name in names:
            model = lc.compile(examples.get(name), cache_dir=cache_dir)
            y0 = model.initial_state()
            p = model.parameter_vector()
            out = np.empty(y0.size)

            def f(t, y):
                model.kernels.rhs(t, y, p, out)
                return out.copy()

            for ours, theirs in (("dop853", "DOP853"), ("dopri5", "RK45")):
                sol = model.simulate((0, 100), method=ours, rtol=1e-10, atol=1e-10)
                a = median_time(lambda: model.simulate((0, 100), method=ours, rtol=1e-10, atol=1e-10))
                b = median_time(lambda: solve_ivp(f, (0, 100), y0, method=theirs, rtol=1e-10, atol=1e-10), 3)
                print(f"| {name} | {ours} | {sol.nsteps} | {1e3 * a:.2f} | {1e3 * b:.1f} | {b / a:.0f}× |")


if __name__ == "__main__":
    main(sys.argv[1:] or ["double_pendulum", "rolling_disc"])
