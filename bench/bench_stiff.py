"""A stiff mechanical model: lagcomp's Radau IIA against scipy's Radau, numbalsoda's LSODA, and DOP853.

    PYTHONPATH=src python -m bench.bench_stiff [--rounds 5] [--t-end 10]

The model is the bundled ``stiff_spring_pendulum``: a bob on a critically damped spring with
k/m = 10⁶ s⁻² (the spring's eigenvalues −1000 s⁻¹, double) swinging with a period near 2 s, from
its default start (at rest, spring stretched to balance gravity, θ = 1), over t ∈ [0, t_end].

Every solver gets lagcomp's compiled kernels: scipy's ``solve_ivp(method="Radau")`` calls the
model's ``rhs`` and its exact ``rhs_jacobian`` (Python callables around the numba kernels),
numbalsoda's ``lsoda`` a cfunc around ``rhs`` (its own finite-difference Jacobian), lagcomp's
``radau`` and ``dop853`` run through ``Model.simulate``.  The rows "radau driver call" time
`radau_run` alone, called as ``simulate``'s first call calls it (kernels as `AddressedKernel`s, the
same steps and bits), keeping only the end state as LSODA does: the difference from the ``simulate``
rows is ``simulate``'s fixed cost, the same for every method (~0.06 ms per run in a loop of runs,
``python -m bench.bench_call_cost``; ~0.1-0.15 ms in this table's round-robin; more where a run needs more
than one driver call: its first output buffer holds 1024 rows, and each later call binds the kernels as
dispatchers, ~0.1 ms of numba unboxing).

Error: the max norm of the state at t_end against a reference from scipy's DOP853 at
rtol = atol = 1e-13 on the same rhs (an explicit method, independent of the Radau code; its own error
is estimated from the same at 1e-12 and printed).  "At equal error" compares each peer row with the
lagcomp ``radau`` rows at the peer's error: the last two columns are the peer's median time over radau's
through ``simulate`` and over the radau driver call's, interpolated log-log between the two radau rows
whose errors bracket the peer's (– outside them).  Rows are timed round-robin, scipy's rows (20-330 ms of
Python each) apart from the others: after one of them the Python of ``simulate`` runs with cold caches
(simulate's rows cost 0.10-0.12 ms more than the driver call's at 7d57512, ~0.06 ms in a loop of runs), which
LSODA's rows, timed one after the other, do not pay.
"""

from __future__ import annotations

import argparse
import functools
import statistics
import tempfile
import time

import numba
import numpy as np
from scipy.integrate import solve_ivp

import lagcomp as lc
from bench.harness import Table
from lagcomp import examples
from lagcomp.integrate.drivers.radau import new_carry
from lagcomp.integrate.drivers.run_state import COUNTER_SLOTS, NFEV
from lagcomp.integrate.drivers.sweep_rows import NO_PAUSE
from lagcomp.integrate.methods import METHODS

TOLERANCES = (1e-5, 1e-6, 1e-8, 1e-10)


def reference(model, y0, t_end: float, rtol: float) -> np.ndarray:
    """The state at t_end by scipy's DOP853 at rtol = atol = `rtol` on the model's compiled rhs."""
    fun, _ = scipy_callables(model)
    return solve_ivp(fun, (0.0, t_end), y0, method="DOP853", rtol=rtol, atol=rtol).y[:, -1]


def scipy_callables(model):
    """``fun(t, y)`` and ``jac(t, y)`` for solve_ivp around the model's numba kernels."""
    p, n = model.parameter_vector(), 2 * model.n

    def fun(t, y):
        out = np.empty(n)
        model.kernels.rhs(t, y, p, out)
        return out

    def jac(t, y):
        out = np.empty((n, n))
        model.kernels.rhs_jacobian(t, y, p, out)
        return out
    return fun, jac


def numbalsoda_lsoda(model):
    """A function (y0, t_end, tol) -> (state at t_end, f-evaluations) running numbalsoda's LSODA on the rhs."""
    from numbalsoda import lsoda, lsoda_sig

    n, rhs = 2 * model.n, model.kernels.rhs
    n_p = model.parameter_vector().shape[0]
    data = np.concatenate([model.parameter_vector(), [0.0]])   # parameters, then the call counter

    @numba.cfunc(lsoda_sig)
    def f(t, u, du, d):
        rhs(t, numba.carray(u, (n,)), numba.carray(d, (n_p,)), numba.carray(du, (n,)))
        d[n_p] += 1.0

    def run(y0, t_end, tol):
        data[n_p] = 0.0
        usol, success = lsoda(f.address, y0, np.array([0.0, t_end]), data=data, rtol=tol, atol=tol, mxstep=10**7)
        return usol[-1], int(data[n_p])
    return run


def radau_driver_call(model, y0, t_end: float):
    """A function tol -> (state at t_end, f-evaluations): one `radau_run` call as `simulate`'s first call makes it
    (kernels bound as `AddressedKernel`s), saving the end state only."""
    method = METHODS["radau"]
    driver, constants = method.bound_driver(model.kernels, addressed=True), method.driver_arguments()
    p, n = model.parameter_vector(), y0.size
    no_events = (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.empty(16), np.empty((16, n)),
                 np.empty(16, dtype=np.int64))
    ts, ys = np.empty(4), np.empty((4, n))

    def run(tol):
        y, clock, counters = y0.copy(), np.zeros(2), np.zeros(COUNTER_SLOTS, dtype=np.int64)
        status, _ = driver(y, clock, counters, p, 0, np.zeros(2), t_end, tol, np.full(y.size, tol), np.inf, 10**9,
                           NO_PAUSE, 10**9, np.empty(0), ts, ys, *no_events, *constants, n, *new_carry(n))
        if status != 0:
            raise RuntimeError(f"radau_run returned status {status}")
        return y, int(counters[NFEV])
    return run


SCIPY, LSODA = "scipy Radau (lagcomp's rhs and Jacobian)", "numbalsoda lsoda"
RADAU, RADAU_CALL = "lagcomp radau", "lagcomp radau driver call (no simulate)"


def measure(t_end: float = 10.0, rounds: int = 5, use_peers: bool = True,
            cache_dir: str | None = None) -> tuple[Table, dict]:
    """Every row of the comparison as a markdown `Table`, and for the targets a dict mapping (solver, tol) to
    the solver's time over radau's (through simulate) at equal error (NaN outside radau's rows)."""
    system = examples.get("stiff_spring_pendulum")
    with tempfile.TemporaryDirectory() as scratch:
        model = lc.compile(system, cache_dir=cache_dir or scratch)
        y0 = np.concatenate([system.q0, system.qd0]).astype(float)
        fun, jac = scipy_callables(model)
        exact = reference(model, y0, t_end, 1e-13)
        reference_error = np.max(np.abs(reference(model, y0, t_end, 1e-12) - exact))

        def lagcomp_run(method, tol):
            def run():
                s = model.simulate((0.0, t_end), method=method, rtol=tol, atol=tol, progress=False)
                return s.y[-1], s.nfev
            return run

        def scipy_run(tol):
            def run():
                r = solve_ivp(fun, (0.0, t_end), y0, method="Radau", jac=jac, rtol=tol, atol=tol)
                return r.y[:, -1], r.nfev
            return run

        lsoda_run = None
        if use_peers:
            try:
                lsoda_run = numbalsoda_lsoda(model)
            except ImportError:
                pass
        runs = {}
        driver_run = radau_driver_call(model, y0, t_end)
        for tol in TOLERANCES:
            runs[(RADAU, tol)] = lagcomp_run("radau", tol)
            runs[(RADAU_CALL, tol)] = functools.partial(driver_run, tol)
            runs[(SCIPY, tol)] = scipy_run(tol)
        for tol in (*TOLERANCES, 1e-12) if lsoda_run is not None else ():
            runs[(LSODA, tol)] = functools.partial(lsoda_run, y0, t_end, tol)
        runs[("lagcomp dop853 (explicit, for contrast)", 1e-8)] = lagcomp_run("dop853", 1e-8)
        results = {key: run() for key, run in runs.items()}          # compiles and loads everything
        times = {key: [] for key in runs}
        slow = [key for key in runs if key[0] == SCIPY]
        for group in ([key for key in runs if key not in slow], slow):
            for _ in range(rounds):
                for key in group:
                    start = time.perf_counter()
                    runs[key]()
                    times[key].append(time.perf_counter() - start)
    errors = {key: float(np.max(np.abs(results[key][0] - exact))) for key in runs}
    bases = [sorted((errors[key], statistics.median(times[key])) for key in runs if key[0] == name)
             for name in (RADAU, RADAU_CALL)]
    table = Table(f"Stiff: radau on stiff_spring_pendulum, t in [0, {t_end:g}] (issue 20)",
                  ["solver", "rtol = atol", "f-evaluations", "ms, median", "error at t_end",
                   "at equal error: × lagcomp radau (simulate)", "× radau driver call"],
                  note=f"{__doc__.split(chr(10) + chr(10), 2)[2].strip()}  Reference: scipy DOP853 at 1e-13 (its "
                       f"distance from the same at 1e-12: {reference_error:.1e}); {rounds} rounds. "
                       "`python -m bench.bench_stiff` runs this table alone.")
    at_equal_error = {}
    for key, samples in times.items():
        name, tol = key
        ratios = [statistics.median(samples) / radau_time_at(base, errors[key]) for base in bases]
        at_equal_error[key] = ratios[0]
        table.add(name, f"{tol:.0e}", f"{results[key][1]:,}", f"{statistics.median(samples) * 1e3:.3g}",
                  f"{errors[key]:.1e}", *("–" if np.isnan(r) else f"{r:.3g}×" for r in ratios))
    return table, at_equal_error


def section(ctx) -> Table:
    """`python -m bench` section ``stiff``: the table, and issue 20's two speed targets from it."""
    table, at_equal_error = measure(rounds=ctx.repeats, use_peers=ctx.use_peers, cache_dir=ctx.cache_dir)
    for target, solver in (("radau_scipy", SCIPY), ("radau_lsoda", LSODA)):
        ratios = [r for (name, _), r in at_equal_error.items() if name == solver and not np.isnan(r)]
        t = ctx.target(target)
        if ratios:
            t.measured = (f"{solver} takes {min(ratios):.3g}–{max(ratios):.3g}× radau's time at equal error "
                          f"(through simulate)")
            t.met = min(ratios) >= (20.0 if target == "radau_scipy" else 1.0)
    return table


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--t-end", type=float, default=10.0)
    args = parser.parse_args()
    print(measure(args.t_end, args.rounds)[0].markdown())


def radau_time_at(points: list[tuple[float, float]], error: float) -> float:
    """lagcomp radau's time at `error`, interpolated log-log between its rows (error, time) sorted by error;
    NaN outside them."""
    for (e0, t0), (e1, t1) in zip(points, points[1:], strict=False):
        if e0 <= error <= e1:
            if e1 == e0:
                return t0
            x = np.log(error / e0) / np.log(e1 / e0)
            return float(t0 * (t1 / t0) ** x)
    return float("nan")


if __name__ == "__main__":
    main()
