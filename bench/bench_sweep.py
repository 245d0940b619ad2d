"""Sweep throughput: trajectories per second on 1 and 2 threads, against a Python loop of scipy solve_ivp.

    python bench/bench_sweep.py [--side 100] [--repeats 3]

The double pendulum from a side × side grid of (θ1, θ2) ∈ [−3, 3]², at rest,
to t = 10.  Accuracy is the median over the grid of the endpoint error (max
norm of the state) against a reference sweep by the Taylor method at machine
precision (about 1e-11 at t = 10 on this chaotic system; a DOP853 reference
at 1e-13 errs by ~1e-8 itself), so methods are compared at equal accuracy,
not equal nominal tolerance.  The
scipy baseline integrates a subsample of the grid one trajectory at a time
with the same compiled rhs (called from Python) and the same algorithm.
Times are medians of `repeats` warm runs, measured in this process.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time

import numpy as np
from scipy.integrate import solve_ivp

import lagcomp as lc
from lagcomp import examples

T_END = 10.0


def timed(run, repeats: int) -> tuple[float, object]:
    result = run()  # warm: numba compilation or cache load
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - start)
    return statistics.median(times), result


def grid(side: int) -> dict:
    """The side × side grid of (θ1, θ2) ∈ [−3, 3]² swept here."""
    angles = np.linspace(-3, 3, side)
    return {"theta1": angles, "theta2": angles}


def scipy_loop(model, starts, method: str, options: dict):
    """A Python loop of solve_ivp over `starts` (θ1, θ2), with the model's compiled rhs called from Python."""
    p = model.parameter_vector()
    out = np.empty(4)

    def f(t, y):
        model.kernels.rhs(t, y, p, out)
        return out.copy()

    def loop():
        for a, b in starts:
            solve_ivp(f, (0, T_END), [a, b, 0.0, 0.0], method=method, **options)

    return loop


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--side", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--scipy-samples", type=int, default=20)
    parser.add_argument("--dop853-tolerances", type=float, nargs="+", default=[1e-8, 1e-10, 1e-12, 1e-13])
    parser.add_argument("--taylor-tolerances", type=float, nargs="+", default=[1e-10, 1e-12, 1e-14])
    args = parser.parse_args()
    angles = np.linspace(-3, 3, args.side)
    n = args.side**2
    with tempfile.TemporaryDirectory() as cache_dir:
        model = lc.compile(examples.get("double_pendulum"), cache_dir=cache_dir)

        def sweep(workers, **options):
            return model.sweep((0, T_END), grid(args.side), qd0=[0, 0], workers=workers, progress=False, **options)

        reference = sweep(2, method="taylor").final
        print(f"double pendulum, {args.side}×{args.side} grid, t = {T_END:g}; median endpoint error vs taylor at "
              "machine precision\n")
        print("| method | setting | median error | traj/s, 1 thread | traj/s, 2 threads | 2 vs 1 | vs scipy loop |")
        print("|---|---|---|---|---|---|---|")
        rng = np.random.default_rng(0)
        samples = rng.choice(n, size=min(args.scipy_samples, n), replace=False)

        cases = [("dop853", dict(rtol=tol, atol=tol), f"tol {tol:g}", "DOP853")
                 for tol in args.dop853_tolerances]
        cases += [("dop853 batched", dict(rtol=tol, atol=tol, batched=True), f"tol {tol:g}, SIMD lanes", None)
                  for tol in args.dop853_tolerances[-1:]]
        cases += [("taylor", dict(method="taylor", rtol=tol, atol=tol), f"tol {tol:g}", None)
                  for tol in args.taylor_tolerances]
        cases += [("taylor batched", dict(method="taylor", rtol=tol, atol=tol, batched=True),
                   f"tol {tol:g}, SIMD lanes", None) for tol in args.taylor_tolerances]
        cases += [("rk4", dict(method="rk4", dt=0.01), "dt 0.01 (1000 steps)", None),
                  ("rk4 batched", dict(method="rk4", dt=0.01, batched=True), "dt 0.01, SIMD lanes", None)]
        for method, options, setting, scipy_method in cases:
            rates = []
            for workers in (1, 2):
                seconds, result = timed(lambda: sweep(workers, **options), args.repeats)
                rates.append(n / seconds)
            error = np.median(np.max(np.abs(result.final - reference), axis=-1))
            versus = ""
            if scipy_method:
                starts = np.column_stack([np.repeat(angles, args.side), np.tile(angles, args.side)])[samples]
                seconds, _ = timed(scipy_loop(model, starts, scipy_method, options), 1)
                versus = f"{rates[1] / (len(samples) / seconds):.0f}×"
            print(f"| {method} | {setting} | {error:.1e} | {rates[0]:,.0f} | {rates[1]:,.0f} | "
                  f"{rates[1] / rates[0]:.2f} | {versus} |")


if __name__ == "__main__":
    main()
