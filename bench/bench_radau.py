"""lagcomp's Radau IIA driver against scipy's Radau and numbalsoda's LSODA on stiff problems, at equal error.

    PYTHONPATH=src python -m bench.bench_radau [--rounds 5] [--parts]

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

``--parts`` instead splits one run into its parts (`parts`): where a run of the bundled
``stiff_spring_pendulum`` (4 components, bench/bench_stiff.py's model) at rtol = atol = 1e-8 spends its time.
"""

from __future__ import annotations

import argparse
import tempfile
import time

import numba
import numpy as np
from numba import njit
from scipy.integrate import solve_ivp

from bench.harness import no_events
from lagcomp.integrate.drivers import radau as radau_driver
from lagcomp.integrate.drivers.embedded import embedded_run
from lagcomp.integrate.drivers.kernel_types import EVENTS, RHS, RHS_JACOBIAN, AddressedKernel
from lagcomp.integrate.drivers.radau import new_carry, radau_run
from lagcomp.integrate.drivers.run_state import NFEV, NJEV, NLU, NSTEPS
from lagcomp.integrate.methods import get_method
from lagcomp.integrate.radau import RADAU5
from lagcomp.kernel_support.linear_solvers import lu_substitute
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
        status, _ = radau_run(*RADAU_KERNELS, y, clock, counters, p, 0, np.zeros(1), t_end, rtol, np.full(n, atol),
                              np.inf, 10**9, 10**9, 10**9, np.empty(0), np.empty(1), np.empty((1, n)), NO_EVENTS,
                              NO_EVENTS, np.empty(1), np.empty((1, n)), np.empty(1, np.int64), *constants, n,
                              *new_carry(n))
        assert status == 0, status
        return y, f"steps {counters[NSTEPS]}, f {counters[NFEV]}, J {counters[NJEV]}, LU {counters[NLU]}"
    return run


def lagcomp_dop853(problem, rtol, atol):
    p, y0, t_end = np.array(problem["p"]), np.array(problem["y0"]), problem["t_end"]
    n = y0.size
    method = get_method("dop853")
    arrays, events = method.driver_arguments(), no_events(method, n)

    def run():
        y, clock, counters = y0.copy(), np.zeros(2), np.zeros(8, dtype=np.int64)
        status, _ = embedded_run(stiff_kernels.rhs, driver_kernels.project, driver_kernels.constraint_residual,
                                 driver_kernels.event_values, driver_kernels.event_reset, y, clock, counters, p, 0,
                                 np.zeros(1), t_end, rtol, np.full(n, atol), np.inf, 10**9, 10**9, 10**9, np.empty(0),
                                 np.empty(1), np.empty((1, n)), *events, *arrays)
        assert status == 0, status
        return y, f"steps {counters[NSTEPS]}, f {counters[NFEV]}"
    return run


def scipy_radau(problem, rtol, atol):
    y0, t_end = np.array(problem["y0"]), problem["t_end"]
    fun, jac = stiff_kernels.scipy_functions(problem["p"])

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


@njit(error_model="numpy")
def _newton_calls(rhs, rhs_jacobian, y, p, h, C, T, TI, MU, calls):
    """`calls` Newton iterations of one step (h) from zero starting values; returns the iterations made."""
    n = y.shape[0]
    jacobian = np.empty((n, n))
    rhs_jacobian(0.0, y, p, jacobian)
    lu_real, lu_complex = np.empty((n, n)), np.empty((n, n), np.complex128)
    pivots_real, pivots_complex = np.empty(n, np.int64), np.empty(n, np.int64)
    radau_driver._factor(jacobian, h, MU, n, lu_real, pivots_real, lu_complex, pivots_complex)
    Z, W, F = np.zeros((3, n)), np.empty((3, n)), np.empty((3, n))
    ytmp, f_stage, d_real, d_complex = np.empty(n), np.empty(n), np.empty(n), np.empty(n, np.complex128)
    scale = 1e-8 + np.abs(y) * 1e-8
    iterations = 0
    for _ in range(calls):
        Z[:] = 0.0
        iterations += radau_driver._newton(rhs, 0.0, y, h, p, C, T, TI, MU, n, Z, W, F, ytmp, f_stage, d_real,
                                           d_complex, lu_real, pivots_real, lu_complex, pivots_complex, scale, 1e-4)[2]
    return iterations


@njit(error_model="numpy")
def _kernel_calls(rhs, rhs_jacobian, y, p, h, MU, calls, part):
    """`calls` calls of one part: 0 rhs, 1 rhs_jacobian, 2 the pair of LU factorisations, 3 the real
    substitution, 4 the real and the complex one interleaved (each input nudged so nothing is hoisted)."""
    n = y.shape[0]
    ytmp, out, jacobian = y.copy(), np.empty(n), np.empty((n, n))
    rhs_jacobian(0.0, y, p, jacobian)
    lu_real, lu_complex = np.empty((n, n)), np.empty((n, n), np.complex128)
    pivots_real, pivots_complex = np.empty(n, np.int64), np.empty(n, np.int64)
    radau_driver._factor(jacobian, h, MU, n, lu_real, pivots_real, lu_complex, pivots_complex)
    d_real, d_complex = np.empty(n), np.empty(n, np.complex128)
    acc = 0.0
    for k in range(calls):
        ytmp[0] = y[0] + k * 1e-15
        if part == 0:
            rhs(0.0, ytmp, p, out)
            acc += out[0]
        elif part == 1:
            rhs_jacobian(0.0, ytmp, p, jacobian)
            acc += jacobian[0, 0]
        elif part == 2:
            radau_driver._factor(jacobian, h * (1.0 + k * 1e-15), MU, n, lu_real, pivots_real, lu_complex,
                                 pivots_complex)
            acc += lu_real[0, 0]
        else:
            for i in range(n):
                d_real[i] = ytmp[i]
                d_complex[i] = complex(ytmp[i], 1.0)
            if part == 3:
                lu_substitute(lu_real, pivots_real, d_real)
            else:
                radau_driver._substitute_pair(lu_real, pivots_real, d_real, lu_complex, pivots_complex, d_complex)
            acc += d_real[0]
    return acc


def parts(rounds: int) -> None:
    """Print where a radau run of the stiff spring pendulum (rtol = atol = 1e-8, t in [0, 10]) spends its time.

    Each part is timed alone in a numba loop (ns per call, best of `rounds`) and multiplied by its count in
    the run (Newton iterations: (f evaluations − steps − 2) / 3, the other evaluations being the first f,
    the starting-step probe and one f per accepted step); "other" is the driver call's time less those.
    """
    import lagcomp as lc
    from lagcomp import examples
    from lagcomp.integrate.methods import METHODS

    with tempfile.TemporaryDirectory() as cache_dir:   # (kept while the model's kernels load and compile)
        _split(lc.compile(examples.get("stiff_spring_pendulum"), cache_dir=cache_dir), METHODS["radau"], rounds)


def _split(model, method, rounds: int) -> None:
    """`parts` for a compiled model."""
    tol, t_end, calls = 1e-8, 10.0, 100_000
    kernels, y0, p = model.kernels, model.initial_state(None, None), model.parameter_vector()
    n = y0.size
    driver, constants = method.bound_driver(kernels, addressed=True), method.driver_arguments()
    C, T, TI, MU = constants[:4]
    no_events = (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.empty(16), np.empty((16, n)),
                 np.empty(16, dtype=np.int64))
    ts, ys = np.empty(4), np.empty((4, n))

    def run():
        y, clock, counters = y0.copy(), np.zeros(2), np.zeros(8, dtype=np.int64)
        driver(y, clock, counters, p, 0, np.zeros(2), t_end, tol, np.full(n, tol), np.inf, 10**9, 10**9, 10**9,
               np.empty(0), ts, ys, *no_events, *constants, n, *new_carry(n))
        return counters

    driver_seconds, counters = best(run, rounds)
    simulate_seconds, _ = best(lambda: model.simulate((0.0, t_end), method="radau", rtol=tol, atol=tol,
                                                      progress=False), rounds)
    fixed_seconds, _ = best(lambda: model.simulate((0.0, 1e-9), method="radau", rtol=tol, atol=tol,
                                                   progress=False), rounds)
    steps = int(counters[NSTEPS])
    iterations = (int(counters[NFEV]) - steps - 2) / 3
    h = 1e-3   # the run's typical step: two Newton iterations per step
    per_iteration = best(lambda: _newton_calls(kernels.rhs, kernels.rhs_jacobian, y0, p, h, C, T, TI, MU, calls),
                         rounds)
    per_iteration = per_iteration[0] / per_iteration[1]

    def per_call(part):
        return best(lambda: _kernel_calls(kernels.rhs, kernels.rhs_jacobian, y0, p, h, MU, calls, part),
                    rounds)[0] / calls

    rhs, jacobian, factor, substitute, pair = (per_call(part) for part in range(5))
    rows = [
        ("Newton iterations (all of each: 3 f, the interleaved substitutions, norms)", per_iteration, iterations),
        ("  of which f (3 per iteration)", 3 * rhs, iterations),
        ("  of which the real and complex substitution, interleaved", pair, iterations),
        ("f at each accepted step (and the first two)", rhs, steps + 2),
        ("error estimate's real substitution", substitute, steps),
        ("Jacobian evaluations", jacobian, counters[NJEV]),
        ("LU factorisations (real and complex 4x4, per pair)", factor, counters[NLU] / 2),
    ]
    accounted = sum(seconds * count for _, seconds, count in rows[:1] + rows[3:])
    print(f"stiff_spring_pendulum, radau, rtol = atol = {tol:g}, t in [0, {t_end:g}]: {steps} steps, "
          f"{counters[NFEV]} f, {counters[NJEV]} J, {counters[NLU]} LU; ~{iterations:.0f} Newton iterations\n")
    print("| part | ns per call | calls | µs per run | share of the driver call |")
    print("|---|---|---|---|---|")
    for label, seconds, count in rows:
        print(f"| {label} | {seconds * 1e9:.0f} | {count:,.0f} | {seconds * count * 1e6:.0f} | "
              f"{seconds * count / driver_seconds:.0%} |")
    other = driver_seconds - accounted
    print(f"| other per-step work (start values, error norm, controller, dense rows, output) | "
          f"{other / steps * 1e9:.0f} | {steps:,} | {other * 1e6:.0f} | {other / driver_seconds:.0%} |")
    print(f"| **the driver call** | | 1 | {driver_seconds * 1e6:.0f} | 100% |")
    print(f"| `Model.simulate`, the same run | | 1 | {simulate_seconds * 1e6:.0f} | "
          f"{simulate_seconds / driver_seconds:.0%} |")
    print(f"| `Model.simulate` over t in [0, 1e-9] (its fixed cost, warm) | | 1 | {fixed_seconds * 1e6:.0f} | "
          f"{fixed_seconds / driver_seconds:.0%} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--parts", action="store_true", help="split a run of the stiff spring pendulum instead")
    args = parser.parse_args()
    if args.parts:
        parts(args.rounds)
        return
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
