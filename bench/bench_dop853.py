"""Where lagcomp's DOP853 stands against numbalsoda's: steps, driver alone, and through Model.simulate.

    PYTHONPATH=src python -m bench.bench_dop853 [--rounds 15]

The double pendulum from (2, 1, 0, 0), t ∈ [0, 100], rtol = atol = 1e-10, the
state reported at t = 10 and 100 (issue 8's DOP853 target).  Prints:

1. f-evaluations of each: lagcomp's counter, and numbalsoda's counted by its
   cfunc right-hand side (the hand-written numba one, bench/systems.py), so
   the two take the same steps or not;
2. wall time of lagcomp's DOP853 driver (``embedded_run``) called directly (no Python around
   it), of ``Model.simulate`` with its default options (the same driver plus
   the run's fixed cost), and of numbalsoda's dop853, timed round-robin;
   ratios are medians of per-round ratios against numbalsoda.

numbalsoda comes with the bench extra (``pip install '.[bench]'``, it needs gfortran).
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time

import numba
import numpy as np

import lagcomp as lc
from bench import systems
from lagcomp import examples
from lagcomp.integrate.methods import get_method

Y0 = np.array([2.0, 1.0, 0.0, 0.0])
GRID = np.array([0.0, 10.0, 100.0])
TOL = 1e-10


def numbalsoda_run():
    """numbalsoda's dop853 on the hand-written rhs; the cfunc counts its calls in data[5]."""
    from numbalsoda import dop853, lsoda_sig

    rhs = systems.double_pendulum_rhs

    @numba.cfunc(lsoda_sig)
    def f(t, u, du, data):
        rhs(t, numba.carray(u, (4,)), numba.carray(data, (5,)), numba.carray(du, (4,)))
        data[5] += 1.0

    data = np.array([1.0, 1.0, 1.0, 1.0, 9.81, 0.0])

    def run():
        data[5] = 0.0
        dop853(f.address, Y0, GRID, data=data, rtol=TOL, atol=TOL, mxstep=10**7)
        return int(data[5])
    return run


def driver_run(model):
    """The DOP853 driver called directly, as simulate calls it, in one call."""
    method = get_method("dop853")
    driver, arrays = method.bound_driver(model.kernels), method.driver_arguments()
    p = model.parameter_vector()
    no_events = (np.empty(0, np.int64), np.empty(0, np.int64), np.empty(1), np.empty((1, 4)), np.empty(1, np.int64))

    def run():
        y, clock, counters = Y0.copy(), np.zeros(2), np.zeros(6, dtype=np.int64)
        driver(y, clock, counters, p, 0, np.array([0.0, np.inf]), GRID[-1], TOL, TOL, np.inf,
               10**9, 10**9, 1, GRID[1:], np.empty(2), np.empty((2, 4)), *no_events, *arrays)
        return int(counters[0])
    return run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=15)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as cache_dir:
        model = lc.compile(examples.get("double_pendulum"), cache_dir=cache_dir)
        runners = {
            "lagcomp DOP853 driver, called directly": driver_run(model),
            "lagcomp Model.simulate": lambda: model.simulate((0, GRID[-1]), method="dop853", rtol=TOL, atol=TOL,
                                                             t_eval=GRID[1:]).nfev,
            "numbalsoda dop853": numbalsoda_run(),
        }
        evaluations = {name: run() for name, run in runners.items()}  # also compiles / loads everything
        times = {name: [] for name in runners}
        for _ in range(args.rounds):
            for name, run in runners.items():
                start = time.perf_counter()
                for _ in range(10):
                    run()
                times[name].append((time.perf_counter() - start) / 10 * 1e3)
    baseline = times["numbalsoda dop853"]
    print("| run | f evaluations | ms, median (min–max) | × numbalsoda (median of per-round ratios) |")
    print("|---|---|---|---|")
    for name, samples in times.items():
        ratio = statistics.median(a / b for a, b in zip(samples, baseline))
        print(f"| {name} | {evaluations[name]:,} | {statistics.median(samples):.2f} ({min(samples):.2f}–"
              f"{max(samples):.2f}) | {ratio:.2f}× |")


if __name__ == "__main__":
    main()
