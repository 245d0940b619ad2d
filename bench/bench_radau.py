"""lagcomp's Radau IIA driver against scipy's Radau and numbalsoda's LSODA on stiff problems, at equal error.

    PYTHONPATH=src python -m bench.bench_radau [--rounds 5]

Problems (hand-written kernels with exact Jacobians, tests/stiff_kernels.py):

* ``vdp``: Van der Pol in Hairer's scaling, ε = 1e-6 (very stiff), y0 = (2, 0), t ∈ [0, 2];
* ``robertson``: Robertson's kinetics, y0 = (1, 0, 0), t ∈ [0, 1e5], atol = 1e-3 rtol (y1 ~ 1e-5).

For each rtol (atol = rtol, Robertson 1e-3 rtol) the same kernels run in

1. lagcomp: `radau_run` called directly (one call, no Python around the step loop; the kernels passed
   as `AddressedKernel`, as `simulate`'s first call passes them);
2. scipy: ``solve_ivp(method="Radau")`` with the numba kernels as ``fun`` and ``jac``;
3. numbalsoda's ``lsoda`` on a cfunc of the same rhs (its own finite-difference Jacobian);
4. for contrast, lagcomp's DOP853 (``embedded_run``) on the same rhs, on the Van der Pol problem.

Error: the max-norm difference at t_end from a reference, numbalsoda's LSODA at rtol = 1e-12 (atol 1e-12,
Robertson 1e-15; an independent method, BDF/Adams), scaled by max(1, |y_ref|) per component; the script
prints how far lagcomp's Radau at the same tolerance is from it.  Times: best of ``--rounds`` warm runs
(scipy: one warm run); ratios are time / lagcomp's Radau time at the same error, each contender's time
interpolated log-log in its error (rtol sweep).  Errors within 100 times the two references' distance are
marked: there the reference, not the method, limits the comparison.
"""

from __future__ import annotations

import argparse
import time

import numba
import numpy as np
from scipy.integrate import solve_ivp

from lagcomp.integrate.drivers.embedded import embedded_run
from lagcomp.integrate.drivers.kernel_types import EVENTS, RHS, RHS_JACOBIAN, AddressedKernel
from lagcomp.integrate.drivers.radau import new_carry, radau_run
from lagcomp.integrate.drivers.run_state import NFEV, NJEV, NLU, NSTEPS
from lagcomp.integrate.methods import get_method
from lagcomp.integrate.radau import RADAU5
from tests import driver_kernels, stiff_kernels

PROBLEMS = {
    "vdp": dict(p=[1.0, 1e-6], y0=[2.0, 0.0], t_end=2.0, atol_factor=1.0),
    "robertson": dict(p=[2.0], y0=[1.0, 0.0, 0.0], t_end=1e5, atol_factor=1e-3),
}
RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
#: LSODA's errors at equal rtol are 10-1000 times Radau's: it runs to tighter tolerances too.
LSODA_TIGHTER = (1e-11,)
#: DOP853 for contrast, where it finishes in about a second (on Robertson it took 74 s and 1.5e8 steps at
#: rtol = 1e-4, measured once: not run here).
DOP853_RTOLS = {"vdp": (1e-3, 1e-5)}
NO_EVENTS = np.zeros(0, dtype=np.int64)
#: The kernels as `simulate`'s first call passes them (cheap for numba to unbox: ~0.1 ms less per call).
RADAU_KERNELS = (AddressedKernel(stiff_kernels.rhs, RHS), AddressedKernel(stiff_kernels.rhs_jacobian, RHS_JACOBIAN),
                 AddressedKernel(driver_kernels.event_values, EVENTS))


def best(run, rounds: int):
    """(best wall time of `rounds` runs after a warm-up, the last run's result)."""
    result = run()
    times = []
    for _ in range(rounds):
        start = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - start)
    return min(times), result


def lagcomp_radau(problem, rtol, atol):
    p, y0, t_end = np.array(problem["p"]), np.array(problem["y0"]), problem["t_end"]
    n = y0.size
    constants = RADAU5.driver_arguments()

    def run():
        y, clock, counters = y0.copy(), np.zeros(2), np.zeros(8, dtype=np.int64)
        status, _ = radau_run(*RADAU_KERNELS, y, clock, counters, p, 0, np.zeros(1), t_end, rtol, atol, np.inf,
                              10**9, 10**9, 10**9, np.empty(0), np.empty(1), np.empty((1, n)), NO_EVENTS, NO_EVENTS,
                              np.empty(1), np.empty((1, n)), np.empty(1, np.int64), *constants, *new_carry(n))
        assert status == 0, status
        return y, f"steps {counters[NSTEPS]}, f {counters[NFEV]}, J {counters[NJEV]}, LU {counters[NLU]}"
    return run


def lagcomp_dop853(problem, rtol, atol):
    p, y0, t_end = np.array(problem["p"]), np.array(problem["y0"]), problem["t_end"]
    n = y0.size
    arrays = get_method("dop853").driver_arguments()

    def run():
        y, clock, counters = y0.copy(), np.zeros(2), np.zeros(8, dtype=np.int64)
        status, _ = embedded_run(stiff_kernels.rhs, driver_kernels.project, driver_kernels.constraint_residual,
                                 driver_kernels.event_values, y, clock, counters, p, 0, np.zeros(1), t_end, rtol,
                                 atol, np.inf, 10**9, 10**9, 10**9, np.empty(0), np.empty(1), np.empty((1, n)),
                                 NO_EVENTS, NO_EVENTS, np.empty(1), np.empty((1, n)), np.empty(1, np.int64), *arrays)
        assert status == 0, status
        return y, f"steps {counters[NSTEPS]}, f {counters[NFEV]}"
    return run


def scipy_radau(problem, rtol, atol):
    p, y0, t_end = np.array(problem["p"]), np.array(problem["y0"]), problem["t_end"]

    def fun(t, y):
        out = np.empty(y.size)
        stiff_kernels.rhs(t, y, p, out)
        return out

    def jac(t, y):
        out = np.empty((y.size, y.size))
        stiff_kernels.rhs_jacobian(t, y, p, out)
        return out

    def run():
        sol = solve_ivp(fun, (0.0, t_end), y0, method="Radau", rtol=rtol, atol=atol, jac=jac)
        assert sol.status == 0, sol.message
        return sol.y[:, -1], f"steps {sol.t.size - 1}, f {sol.nfev}, J {sol.njev}, LU {sol.nlu}"
    return run


def numbalsoda_lsoda(problem, rtol, atol):
    from numbalsoda import lsoda, lsoda_sig

    p, y0, t_end = np.array(problem["p"]), np.array(problem["y0"]), problem["t_end"]
    n, n_p = y0.size, len(problem["p"])
    rhs = stiff_kernels.rhs

    @numba.cfunc(lsoda_sig)
    def f(t, u, du, data):
        rhs(t, numba.carray(u, (n,)), numba.carray(data, (n_p,)), numba.carray(du, (n,)))
        data[n_p] += 1.0

    data = np.concatenate([p, [0.0]])
    grid = np.array([0.0, t_end])

    def run():
        data[n_p] = 0.0
        usol, success = lsoda(f.address, y0, grid, data=data, rtol=rtol, atol=atol, mxstep=10**7)
        assert success
        return usol[-1], f"f {int(data[n_p])} (with its finite-difference Jacobian)"
    return run


def sweep(label, make, problem, rtols, rounds, reference, scale) -> list[tuple[float, float, float]]:
    """Run `make` at each rtol; print and return (rtol, seconds, error) per run."""
    points = []
    for rtol in rtols:
        seconds, (y, counts) = best(make(problem, rtol, rtol * problem["atol_factor"]), rounds)
        error = float(np.max(np.abs(y - reference) / scale))
        points.append((rtol, seconds, error))
        print(f"    {label:18s} rtol {rtol:7.0e}  {1e3 * seconds:10.2f} ms  error {error:8.1e}  {counts}")
    return points


def time_at_error(points, error: float) -> float | None:
    """A contender's time at `error`, interpolated log-log between its runs (None outside their range)."""
    errors = np.log([e for _, _, e in points])
    times = np.log([t for _, t, _ in points])
    order = np.argsort(errors)
    if not errors.min() <= np.log(error) <= errors.max():
        return None
    return float(np.exp(np.interp(np.log(error), errors[order], times[order])))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    for name, problem in PROBLEMS.items():
        tight = 1e-12
        reference, _ = numbalsoda_lsoda(problem, tight, tight * problem["atol_factor"])()
        scale = np.maximum(1.0, np.abs(reference))
        check, _ = lagcomp_radau(problem, tight, tight * problem["atol_factor"])()
        print(f"\n{name}: reference LSODA rtol={tight:g}: y(t_end) = {reference}; lagcomp radau at rtol={tight:g} "
              f"differs by {np.max(np.abs(check - reference) / scale):.1e}")
        runs = {
            "lagcomp radau": sweep("lagcomp radau", lagcomp_radau, problem, RTOLS, args.rounds, reference, scale),
            "scipy Radau": sweep("scipy Radau", scipy_radau, problem, RTOLS[:-2], 1, reference, scale),
            "numbalsoda LSODA": sweep("numbalsoda LSODA", numbalsoda_lsoda, problem, RTOLS + LSODA_TIGHTER,
                                      args.rounds, reference, scale),
        }
        if name in DOP853_RTOLS:
            sweep("lagcomp dop853", lagcomp_dop853, problem, DOP853_RTOLS[name], 1, reference, scale)
        print("  at equal error (time / lagcomp radau's, interpolated log-log):")
        limit = 100 * np.max(np.abs(check - reference) / scale)
        for rtol, seconds, error in runs["lagcomp radau"]:
            ratios = [] if error > limit else ["(reference-limited)"]
            for label in ("scipy Radau", "numbalsoda LSODA"):
                other = time_at_error(runs[label], error)
                ratios.append(f"{label} x{other / seconds:6.1f}" if other is not None else f"{label}   (n/a)")
            print(f"    error {error:8.1e} (radau rtol {rtol:5.0e}, {1e3 * seconds:8.2f} ms): {', '.join(ratios)}")


if __name__ == "__main__":
    main()
