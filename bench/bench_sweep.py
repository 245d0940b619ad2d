"""Sweep throughput: trajectories per second on 1 and 2 threads, against a Python loop of scipy solve_ivp.

    python -m bench.bench_sweep [--side 100] [--repeats 3]      (from the repository root)

The double pendulum from a side × side grid of (θ1, θ2) ∈ [−3, 3]², at rest,
to t = 10.  Accuracy is the median over the grid of the endpoint error (max
norm of the state) against a reference sweep by the Taylor method at machine
precision (about 1e-11 at t = 10 on this chaotic system; a DOP853 reference
at 1e-13 errs by ~1e-8 itself), so methods are compared at equal accuracy,
not equal nominal tolerance.  The
scipy baseline integrates a subsample of the grid one trajectory at a time
with the same compiled rhs (called from Python) and the same algorithm.
The peers, when installed (the ``bench`` extra), run the same grid:
heyoka's SIMD batch mode on the hand-reduced ODE (``taylor_adaptive_batch``,
``recommended_simd_size()`` trajectories per batch, one integrator per
thread: ``propagate_until`` releases the GIL), and numbalsoda's dop853 on a
hand-written numba rhs in a numba ``prange`` loop.
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
from bench import systems
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


def starts_of(side: int) -> np.ndarray:
    """(θ1, θ2) of the grid's trajectories in the sweep's order (θ1 the outer axis)."""
    angles = np.linspace(-3, 3, side)
    return np.column_stack([np.repeat(angles, side), np.tile(angles, side)])


def heyoka_batch(starts: np.ndarray, p: np.ndarray, tol: float):
    """heyoka's batch mode over `starts`: run(workers) returns the final states, (N, 4)."""
    import copy
    import threading

    import heyoka as hy

    th1, th2, w1, w2 = hy.make_vars("th1", "th2", "w1", "w2")
    m1, m2, l1, l2, g = (hy.par[i] for i in range(5))
    a1, a2 = systems.double_pendulum_reduced(hy.sin, hy.cos, th1, th2, w1, w2, m1, m2, l1, l2, g)
    width = hy.recommended_simd_size()
    first = hy.taylor_adaptive_batch([(th1, w1), (th2, w2), (w1, a1), (w2, a2)], np.zeros((4, width)),
                                     pars=np.repeat(p[:, None], width, axis=1), tol=tol)
    integrators = [first, copy.deepcopy(first)]

    def integrate(ta, rows, out):
        for a in range(0, len(rows), width):
            batch = rows[a:a + width]
            state = np.zeros((4, width))
            state[:2, :len(batch)] = starts[batch].T
            ta.set_time(0.0)
            ta.state[:] = state
            ta.propagate_until(T_END)
            out[batch] = ta.state[:, :len(batch)].T

    def run(workers):
        out = np.empty((len(starts), 4))
        parts = np.array_split(np.arange(len(starts)), workers)
        threads = [threading.Thread(target=integrate, args=(ta, rows, out)) for ta, rows in zip(integrators, parts)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
        return out
    return run


def numbalsoda_prange(starts: np.ndarray, p: np.ndarray, tol: float):
    """numbalsoda's dop853 in a numba prange loop: run(workers) returns the final states, (N, 4)."""
    import numba
    from numbalsoda import dop853, lsoda_sig

    rhs = systems.double_pendulum_rhs

    @numba.cfunc(lsoda_sig)
    def f(t, u, du, data):
        rhs(t, numba.carray(u, (4,)), numba.carray(data, (5,)), numba.carray(du, (4,)))

    @numba.njit(parallel=True)
    def loop(address, starts, p, times, tol, out):
        for i in numba.prange(starts.shape[0]):
            u0 = np.array([starts[i, 0], starts[i, 1], 0.0, 0.0])
            usol, ok = dop853(address, u0, times, data=p, rtol=tol, atol=tol)
            for c in range(4):
                out[i, c] = usol[-1, c] if ok else np.nan

    def run(workers):
        numba.set_num_threads(workers)
        out = np.empty((len(starts), 4))
        loop(f.address, starts, p, np.array([0.0, T_END]), tol, out)
        return out
    return run


def peer_cases(starts: np.ndarray, p: np.ndarray, args) -> list:
    """(name, setting, run(workers)) of the installed peers; a skipped row for the others."""
    cases = []
    for name, module, make, tolerances in (
            ("heyoka batch, reduced ODE", "heyoka", heyoka_batch, args.heyoka_tolerances),
            ("numbalsoda dop853, prange", "numbalsoda", numbalsoda_prange, args.dop853_tolerances[-2:])):
        try:
            __import__(module)
        except ImportError:
            cases.append((name, "skipped: not installed", None))
            continue
        cases += [(name, f"tol {tol:g}", make(starts, p, tol)) for tol in tolerances]
    return cases


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--side", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--scipy-samples", type=int, default=20)
    parser.add_argument("--dop853-tolerances", type=float, nargs="+", default=[1e-8, 1e-10, 1e-12, 1e-13])
    parser.add_argument("--taylor-tolerances", type=float, nargs="+", default=[1e-10, 1e-12, 1e-14])
    parser.add_argument("--heyoka-tolerances", type=float, nargs="+", default=[1e-10, 1e-12])
    args = parser.parse_args()
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
                starts = starts_of(args.side)[samples]
                seconds, _ = timed(scipy_loop(model, starts, scipy_method, options), 1)
                versus = f"{rates[1] / (len(samples) / seconds):.0f}×"
            print(f"| {method} | {setting} | {error:.1e} | {rates[0]:,.0f} | {rates[1]:,.0f} | "
                  f"{rates[1] / rates[0]:.2f} | {versus} |")
        flat_reference = reference.reshape(-1, reference.shape[-1])
        for name, setting, run in peer_cases(starts_of(args.side), model.parameter_vector(), args):
            if run is None:
                print(f"| {name} | {setting} |  |  |  |  |  |")
                continue
            rates = []
            for workers in (1, 2):
                seconds, final = timed(lambda: run(workers), args.repeats)
                rates.append(n / seconds)
            error = np.median(np.max(np.abs(final - flat_reference), axis=-1))
            print(f"| {name} | {setting} | {error:.1e} | {rates[0]:,.0f} | {rates[1]:,.0f} | "
                  f"{rates[1] / rates[0]:.2f} |  |")


if __name__ == "__main__":
    main()
