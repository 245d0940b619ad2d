"""Where lagcomp's DOP853 stands against numbalsoda's: steps, driver alone, and through Model.simulate.

    PYTHONPATH=src python -m bench.bench_dop853 [--rounds 15] [--system double_pendulum|chain10] [--smoke]
                                                [--cache-dir DIR]

``double_pendulum`` (the default): from (2, 1, 0, 0), t ∈ [0, 100], rtol = atol = 1e-10, the state
reported at t = 10 and 100 (issue 8's DOP853 target).  ``chain10``: the 10-link chain
(``examples.n_link_pendulum(10)``, unit masses and lengths) from θ = 0.5, θ̇ = 0, t ∈ [0, 10], the state
reported at t = 1 and 10, numbalsoda on the hand-written closed form (`systems.chain_rhs_ws`, its
scratch in numbalsoda's data array after the parameters).  Prints:

1. f-evaluations of each: lagcomp's counter, and numbalsoda's counted by its
   cfunc right-hand side (the hand-written numba one, bench/systems.py), so
   the two take the same steps or not;
2. wall time of lagcomp's DOP853 driver (``embedded_run``) called directly (no Python around
   it), of the model's specialised driver called the same way (`lagcomp.integrate.specialize`: the library
   driver compiled with the model's kernels as compile-time callees; compiled or loaded before the timing, and
   left out with ``--smoke``), of ``Model.simulate`` with its default options but ``specialize=False`` (the
   library driver plus the run's fixed cost; by default a run takes the specialised driver once it is loaded in
   the process, as it is here for the row before), and of numbalsoda's dop853, timed round-robin;
   ratios are medians of per-round ratios against numbalsoda;
3. where the time goes: each right-hand side alone, called in a compiled loop through a function
   value as the drivers call it (ns per call), and what is left per f-evaluation for the rest of
   each integrator (its run time over its f-evaluations, less one rhs call); numbalsoda's row for the
   double pendulum only (the chain's hand-written rhs takes its scratch from numbalsoda's data array).  The run of a
   driver with no cost of its own would take f-evaluations × rhs: that bound, over numbalsoda's
   time, is the last column.

numbalsoda comes with the bench extra (``pip install '.[bench]'``, it needs gfortran); without it its rows
say so and the ratios are against lagcomp's driver.  ``--smoke``: one round of one run each, and the
rhs loops short (tests/test_bench_scripts.py runs it so, to catch a driver signature that moved on).
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
from bench.harness import no_events, peer
from lagcomp import examples
from lagcomp.integrate import specialize
from lagcomp.integrate.drivers.kernel_types import RHS, VECTOR
from lagcomp.integrate.drivers.run_state import CLOCK_SLOTS, COUNTER_SLOTS
from lagcomp.integrate.methods import get_method

TOL = 1e-10
#: The chain's number of links.
CHAIN = 10


#: The row of the model's specialised driver (`lagcomp.integrate.specialize`), called as the library's.
SPECIALISED = "lagcomp DOP853 specialised driver, called directly"
#: numbalsoda's rows when it is not installed.
NOT_INSTALLED = "numbalsoda dop853 (not installed)"


class Case:
    """One benchmark problem: the lagcomp system, the initial state, the output times (the first is the
    start), and numbalsoda's right-hand side: a cfunc of the hand-written numba rhs (bench/systems.py) that
    counts its calls in ``data[counter]``; ``hand_written_rhs`` that rhs as ``rhs(t, y, p, out)``, where it is one."""

    def __init__(self, name: str):
        if name == "double_pendulum":
            self.system = examples.get("double_pendulum")
            self.y0 = np.array([2.0, 1.0, 0.0, 0.0])
            self.grid = np.array([0.0, 10.0, 100.0])
            self.data = np.array([1.0, 1.0, 1.0, 1.0, 9.81, 0.0])   # m1, m2, l1, l2, g; the call counter
            self.counter = 5
            rhs = systems.double_pendulum_rhs
            self.hand_written_rhs = rhs

            def f(t, u, du, data):
                rhs(t, numba.carray(u, (4,)), numba.carray(data, (5,)), numba.carray(du, (4,)))
                data[5] += 1.0
        elif name == "chain10":
            n, n_p = CHAIN, 2 * CHAIN + 1
            self.system = examples.n_link_pendulum(n)
            self.y0 = np.concatenate([np.full(n, 0.5), np.zeros(n)])
            self.grid = np.array([0.0, 1.0, 10.0])
            # m1..mn, l1..ln, g; the call counter; the scratch a (n, n), f (n,), mu (n,) of chain_rhs_ws
            self.data = np.concatenate([np.ones(2 * n), [9.81, 0.0], np.zeros(n * n + 2 * n)])
            self.counter = n_p
            rhs, n_data = systems.chain_rhs_ws, self.data.shape[0]
            self.hand_written_rhs = None    # its scratch is numbalsoda's data: no rhs(t, y, p, out) alone

            def f(t, u, du, data):
                values = numba.carray(data, (n_data,))
                work = values[n_p + 1:]
                rhs(t, numba.carray(u, (2 * n,)), values[:n_p], numba.carray(du, (2 * n,)),
                    work[:n * n].reshape((n, n)), work[n * n:n * n + n], work[n * n + n:])
                data[n_p] += 1.0
        else:
            raise ValueError(f"unknown system {name!r}")
        self.numbalsoda_f = f   # compiled as numbalsoda's cfunc by `numbalsoda_run`, where it is installed


def numbalsoda_run(case: Case):
    """numbalsoda's dop853 on the case's hand-written rhs (returns its number of rhs calls), None when numbalsoda
    is not installed."""
    numbalsoda = peer("numbalsoda")
    if numbalsoda is None:
        return None
    dop853 = numbalsoda.dop853
    data, counter = case.data, case.counter
    address = numba.cfunc(numbalsoda.lsoda_sig)(case.numbalsoda_f).address

    def run():
        data[counter] = 0.0
        dop853(address, case.y0, case.grid, data=data, rtol=TOL, atol=TOL, mxstep=10**7)
        return int(data[counter])
    return run


def driver_run(model, case: Case, specialised: bool = False):
    """The DOP853 driver called directly, with the arguments `lagcomp.integrate.simulate` gives it, in one call:
    the library driver, or with `specialised` the model's specialised one (`lagcomp.integrate.specialize`, compiled
    or loaded first), which takes the same arguments after the kernels."""
    method = get_method("dop853")
    if specialised:
        specialize.prepare(model, method)
    driver = specialize.driver(model, method) if specialised else method.bound_driver(model.kernels)
    arrays = method.driver_arguments()
    p = model.parameter_vector()
    n = case.y0.shape[0]
    events = no_events(method, n)

    def run():
        y, clock, counters = case.y0.copy(), np.zeros(CLOCK_SLOTS), np.zeros(COUNTER_SLOTS, dtype=np.int64)
        driver(y, clock, counters, p, 0, np.array([0.0, np.inf]), case.grid[-1], TOL, np.full(y.size, TOL), np.inf,
               10**9, 10**9, 1, case.grid[1:], np.empty(2), np.empty((2, n)), *events, *arrays)
        return int(counters[0])
    return run


@numba.njit(numba.float64(RHS, VECTOR, VECTOR, numba.int64))
def _rhs_loop(rhs, y0, p, calls):
    """``calls`` calls of ``rhs`` through a function value at states that differ in y[0] (no call folded)."""
    y, out, total = y0.copy(), np.empty_like(y0), 0.0
    for i in range(calls):
        y[0] = y0[0] + 1e-9 * i
        rhs(0.0, y, p, out)
        total += out[-1]
    return total


def rhs_nanoseconds(rhs, y0, p, rounds: int, calls: int = 200_000) -> float:
    """Median ns per call of ``rhs(t, y, p, out)`` in `_rhs_loop`."""
    _rhs_loop(rhs, y0, p, 10)
    samples = []
    for _ in range(rounds):
        start = time.perf_counter()
        _rhs_loop(rhs, y0, p, calls)
        samples.append((time.perf_counter() - start) / calls * 1e9)
    return statistics.median(samples)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=15)
    parser.add_argument("--system", choices=("double_pendulum", "chain10"), default="double_pendulum")
    parser.add_argument("--smoke", action="store_true", help="one round of one run each: does it run")
    parser.add_argument("--cache-dir", help="compile the model into this cache (default: a fresh temporary one)")
    args = parser.parse_args(argv)
    rounds, runs_per_round, calls = (1, 1, 1000) if args.smoke else (args.rounds, 10, 200_000)
    case = Case(args.system)
    with tempfile.TemporaryDirectory() as scratch:
        model = lc.compile(case.system, cache_dir=args.cache_dir or scratch)
        runners = {
            "lagcomp DOP853 driver, called directly": driver_run(model, case),
            SPECIALISED: None if args.smoke else driver_run(model, case, specialised=True),
            "lagcomp Model.simulate": lambda: model.simulate((0, case.grid[-1]), *np.split(case.y0, 2),
                                                             method="dop853", rtol=TOL, atol=TOL,
                                                             t_eval=case.grid[1:], specialize=False).nfev,
            "numbalsoda dop853": numbalsoda_run(case),
        }
        # (numbalsoda: not installed; the specialised driver with --smoke: its compile takes 10-30 s, and its
        # arguments are the library row's, which a smoke run calls)
        runners = {name: run for name, run in runners.items() if run is not None}
        evaluations = {name: run() for name, run in runners.items()}  # also compiles / loads everything
        times = {name: [] for name in runners}
        for _ in range(rounds):
            for name, run in runners.items():
                start = time.perf_counter()
                for _ in range(runs_per_round):
                    run()
                times[name].append((time.perf_counter() - start) / runs_per_round * 1e3)
        rhs_ns = {"lagcomp DOP853 driver, called directly":
                  rhs_nanoseconds(model.kernels.rhs, case.y0, model.parameter_vector(), rounds, calls)}
        if case.hand_written_rhs is not None and "numbalsoda dop853" in runners:
            rhs_ns["numbalsoda dop853"] = rhs_nanoseconds(case.hand_written_rhs, case.y0,
                                                          case.data[:case.counter].copy(), rounds, calls)
    report(times, evaluations, rhs_ns)


def report(times: dict, evaluations: dict, rhs_ns: dict) -> None:
    """The two tables, ratios against numbalsoda's run (against lagcomp's driver when numbalsoda is missing)."""
    base = "numbalsoda dop853" if "numbalsoda dop853" in times else "lagcomp DOP853 driver, called directly"
    if base != "numbalsoda dop853":
        print(f"({NOT_INSTALLED}: ratios against lagcomp's driver)\n")
    baseline = times[base]
    print(f"| run | f evaluations | ms, median (min–max) | × {base} (median of per-round ratios) |")
    print("|---|---|---|---|")
    for name, samples in times.items():
        ratio = statistics.median(a / b for a, b in zip(samples, baseline, strict=True))
        print(f"| {name} | {evaluations[name]:,} | {statistics.median(samples):.2f} ({min(samples):.2f}–"
              f"{max(samples):.2f}) | {ratio:.2f}× |")
    print()
    print("| integrator | rhs alone, ns per call | rest, ns per f-evaluation "
          f"| f-evaluations × rhs, × {base}'s run |")
    print("|---|---|---|---|")
    base_ms = statistics.median(baseline)
    for run, ns in rhs_ns.items():
        per_eval = statistics.median(times[run]) * 1e6 / evaluations[run]
        bound = evaluations[run] * ns * 1e-6 / base_ms
        print(f"| {run} | {ns:.1f} | {per_eval - ns:.1f} | {bound:.2f}× |")


if __name__ == "__main__":
    main()
