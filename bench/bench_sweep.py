"""Sweep throughput at equal accuracy: trajectories per second on 1 and 2 threads, beside the peers.

    python -m bench.bench_sweep [--side 100] [--repeats 3]      (from the repository root)

scans the tolerances; ``python -m bench`` runs a subset as its section
"ensembles" (`SECTION_SCANS`).

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
from bench.harness import Table, fmt
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


def lagcomp_cases(model, side: int, scans: dict) -> list:
    """(name, setting, run(workers) -> final states (N, 4)) of lagcomp's sweeps; `scans` gives the tolerances."""
    def case(name, setting, **options):
        def run(workers):
            sweep = model.sweep((0, T_END), grid(side), qd0=[0, 0], workers=workers, progress=False, **options)
            return sweep.final.reshape(-1, 4)
        return name, setting, run
    cases = [case("dop853", f"tol {tol:g}", rtol=tol, atol=tol) for tol in scans["dop853"]]
    cases += [case("dop853 batched", f"tol {tol:g}, SIMD lanes", rtol=tol, atol=tol, batched=True)
              for tol in scans["dop853 batched"]]
    cases += [case("taylor", f"tol {tol:g}", method="taylor", rtol=tol, atol=tol) for tol in scans["taylor"]]
    cases += [case("taylor batched", f"tol {tol:g}, SIMD lanes", method="taylor", rtol=tol, atol=tol, batched=True)
              for tol in scans["taylor batched"]]
    if scans.get("rk4"):
        cases += [case("rk4", "dt 0.01 (1000 steps)", method="rk4", dt=0.01),
                  case("rk4 batched", "dt 0.01, SIMD lanes", method="rk4", dt=0.01, batched=True)]
    return cases


def peer_cases(starts: np.ndarray, p: np.ndarray, scans: dict) -> list:
    """The same for the installed peers; run None (a skipped row) for the others."""
    cases = []
    for name, module, make in (("heyoka batch, reduced ODE", "heyoka", heyoka_batch),
                               ("numbalsoda dop853, prange", "numbalsoda", numbalsoda_prange)):
        try:
            __import__(module)
        except ImportError:
            cases.append((name, "skipped: not installed", None))
            continue
        cases += [(name, f"tol {tol:g}", make(starts, p, tol)) for tol in scans[module]]
    return cases


def equal_accuracy_table(side: int, repeats: int, scans: dict, cache_dir: str, scipy_samples: int = 20) -> Table:
    """Every case of `scans` on the side × side grid: median error, traj/s on 1 and 2 threads, × a scipy loop."""
    model = lc.compile(examples.get("double_pendulum"), cache_dir=cache_dir)
    n = side * side
    reference = model.sweep((0, T_END), grid(side), qd0=[0, 0], method="taylor", progress=False).final.reshape(-1, 4)
    starts = starts_of(side)
    sample = starts[np.random.default_rng(0).choice(n, size=min(scipy_samples, n), replace=False)]
    scipy_tol = scans["dop853"][0]
    seconds, _ = timed(scipy_loop(model, sample, "DOP853", dict(rtol=scipy_tol, atol=scipy_tol)), 1)
    scipy_rate = len(sample) / seconds
    table = Table(
        f"Sweeps at equal accuracy: double pendulum, {side}×{side} grid of (θ1, θ2) at rest, t = {T_END:g}",
        ["method", "setting", "median error", "traj/s, 1 thread", "traj/s, 2 threads", "2 vs 1", "× scipy loop"],
        note="The median error is the median over the grid of the endpoint error (max norm of the state) against "
             "a Taylor sweep at machine precision, so rows compare at equal accuracy, not equal nominal tolerance. "
             f"Rates are medians of {repeats} warm runs. Baseline: a Python loop of scipy solve_ivp (DOP853, tol "
             f"{scipy_tol:g}, lagcomp's compiled rhs) over {len(sample)} grid points, {fmt(scipy_rate)} traj/s. "
             "heyoka runs its batch mode (taylor_adaptive_batch, recommended_simd_size() trajectories per batch, "
             "one integrator per thread) on the hand-reduced ODE; numbalsoda its dop853 on a hand-written numba "
             "rhs in a numba prange.",
    )
    for name, setting, run in lagcomp_cases(model, side, scans) + peer_cases(starts, model.parameter_vector(), scans):
        if run is None:
            table.add(name, setting, "", "", "", "", "")
            continue
        rates = []
        for workers in (1, 2):
            seconds, final = timed(lambda: run(workers), repeats)
            rates.append(n / seconds)
        error = np.median(np.max(np.abs(final - reference), axis=-1))
        table.add(name, setting, f"{error:.1e}", fmt(rates[0]), fmt(rates[1]), f"{rates[1] / rates[0]:.2f}",
                  f"{rates[1] / scipy_rate:,.0f}×")
    return table


#: The rows `python -m bench` runs (the CLI below scans more tolerances by default).
SECTION_SCANS = {"dop853": [1e-12], "dop853 batched": [1e-13], "taylor": [1e-10], "taylor batched": [1e-10, 1e-12],
                 "heyoka": [1e-10, 1e-12], "numbalsoda": [1e-12]}


def section(ctx) -> Table:
    """`python -m bench`'s section: the grid of issue 6 (100×100; 20×20 with --quick)."""
    return equal_accuracy_table(20 if ctx.quick else 100, min(ctx.repeats, 3), SECTION_SCANS, ctx.cache_dir)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--side", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--scipy-samples", type=int, default=20)
    parser.add_argument("--dop853-tolerances", type=float, nargs="+", default=[1e-8, 1e-10, 1e-12, 1e-13])
    parser.add_argument("--taylor-tolerances", type=float, nargs="+", default=[1e-10, 1e-12, 1e-14])
    parser.add_argument("--heyoka-tolerances", type=float, nargs="+", default=[1e-10, 1e-12])
    args = parser.parse_args()
    scans = {"dop853": args.dop853_tolerances, "dop853 batched": args.dop853_tolerances[-1:],
             "taylor": args.taylor_tolerances, "taylor batched": args.taylor_tolerances, "rk4": True,
             "heyoka": args.heyoka_tolerances, "numbalsoda": args.dop853_tolerances[-2:]}
    with tempfile.TemporaryDirectory() as cache_dir:
        print(equal_accuracy_table(args.side, args.repeats, scans, cache_dir, args.scipy_samples).markdown())


if __name__ == "__main__":
    main()
