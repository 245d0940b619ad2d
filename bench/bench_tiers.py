"""The two tiers of drivers, and what recording costs: library against specialised drivers and their baselines.

    python -m bench.bench_tiers [--rounds 7] [--steps 1000000]

Four tables, every row timed round-robin with its baseline in this process, CPU time
(``time.process_time``); a ratio is the median (min–max) of the per-round ratios.

1. RK4 on the double pendulum (lagcomp example, y0 = (2, 1, 0, 0), dt = 1e-3, state at the end only):
   the library driver (`lagcomp.integrate.drivers.fixed_step`, the kernels as function values), the
   model's specialised driver (`lagcomp.integrate.specialize`: the same function compiled with the
   model's kernels as compile-time callees), each called once, and a hand-written numba loop as a careful
   user writes it: ``@njit(error_model="numpy")``, the textbook RK4 step around the hand-written
   closed-form rhs of bench/systems.py (Cramer's rule), compiled with the same error model.  Ratios are
   steps/s over the hand-written loop's (issue 38: ≥ 1.0 for the specialised tier, the library within 1.3×).
2. DOP853 on the double pendulum over [0, 100], rtol = atol = 1e-10, the state at t = 100 only: the library
   and the specialised driver called once, and numbalsoda's dop853 on the same hand-written rhs (a cfunc) if
   it is installed (it needs gfortran to build); ratios are times over numbalsoda's, else over the library's.
3. Recording, the same DOP853 run through ``Model.simulate``: every step saved (the default), ``t_eval``
   of 1001 points, ``save_every=10``, ``record="summary"``, each with the library and the specialised
   driver, against the library driver called once recording nothing (its state at t = 100 only).  The
   ratios are what each way of recording costs on top of the integration itself (issue 38: a summary,
   which keeps two rows, must cost less than a trajectory).  A summary evaluates the energy at every row
   during the run, which a trajectory defers until `Solution.energy` or `.summary` is read: the last row
   is a trajectory whose summary is read, the like-for-like comparison.
4. sin and cos: the double pendulum's generated ``rhs`` with lagcomp's own polynomials (`lagcomp.kernel_support.trig`,
   what the kernels call) against the same kernel with numba's libm ``math.sin``/``math.cos`` (the kernel's Python
   function compiled again with those in its globals), and the hand-written closed-form rhs (libm): in the textbook
   RK4 loop of table 1 (each call waits for the one before: latency), over 1024 independent states (throughput), and
   the batched ``rhs_lanes`` over the same 1024 states per lane (lagcomp's inlined ``vsin``/``vcos`` against libm).
   Each variant is checked for lanes bitwise equal to its scalar kernel on the 1024 states.

The specialised drivers are compiled (or loaded from numba's cache) before anything is timed: that is
their one-time cost per model, `lagcomp precompile MODEL --specialize METHOD`, and no part of a run here.
"""

from __future__ import annotations

import argparse
import math
import time
import types

import numba
import numpy as np

from bench import systems
from bench.harness import Stat, Table, fmt_stat, peer, stat_of

#: The double pendulum's start and parameters (m1, m2, l1, l2, g: the example's defaults).
Y0 = np.array([2.0, 1.0, 0.0, 0.0])
PARAMS = np.array([1.0, 1.0, 1.0, 1.0, 9.81])
#: RK4's step; DOP853's interval and tolerance.
DT, T_END, TOL = 1e-3, 100.0, 1e-10


def cpu_times(runs: list, rounds: int) -> list[list[float]]:
    """Per-round CPU times of `runs`, round-robin, after one untimed call of each."""
    for run in runs:
        run()
    times = [[] for _ in runs]
    for _ in range(max(rounds, 1)):
        for i, run in enumerate(runs):
            start = time.process_time()
            run()
            times[i].append(time.process_time() - start)
    return times


def ratio(times: list[float], base: list[float]) -> Stat:
    return stat_of([a / b for a, b in zip(times, base, strict=True)])


def hand_written_rk4(rhs=None):
    """The textbook RK4 loop over the hand-written double pendulum (or over `rhs`), as a user writes it with numba."""
    rhs = rhs or numba.njit(error_model="numpy")(systems.double_pendulum_rhs.py_func)

    @numba.njit(error_model="numpy")
    def loop(y0, p, dt, steps):
        n = y0.shape[0]
        y, k1, k2, k3, k4, tmp = y0.copy(), np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n)
        for step in range(steps):
            t = step * dt
            rhs(t, y, p, k1)
            for i in range(n):
                tmp[i] = y[i] + 0.5 * dt * k1[i]
            rhs(t + 0.5 * dt, tmp, p, k2)
            for i in range(n):
                tmp[i] = y[i] + 0.5 * dt * k2[i]
            rhs(t + 0.5 * dt, tmp, p, k3)
            for i in range(n):
                tmp[i] = y[i] + dt * k3[i]
            rhs(t + dt, tmp, p, k4)
            for i in range(n):
                y[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
        return y
    return loop


def rk4_call(driver, coefficients, steps: int):
    """One call of a fixed-step driver (kernels bound) over `steps` steps, keeping the last state only."""
    def run():
        y, clock, counters = Y0.copy(), np.zeros(3), np.zeros(11, dtype=np.int64)
        driver(y, clock, counters, PARAMS, 0, np.array([0.0, np.inf]), 0.0, DT, steps, steps + 1, steps * DT, steps,
               np.empty(1), np.empty((1, 4)), *coefficients)
        return y
    return run


def dop853_call(driver, tableau):
    """One call of the embedded driver (kernels bound) over [0, T_END] at TOL, recording nothing but the end."""
    none = np.zeros(0, dtype=np.int64)
    atol = np.full(Y0.size, TOL)        # (one per component, as simulate passes it)

    def run():
        y, clock, counters = Y0.copy(), np.zeros(3), np.zeros(11, dtype=np.int64)
        driver(y, clock, counters, PARAMS, 0, np.array([0.0, np.inf]), T_END, TOL, atol, np.inf, 10**9, 10**9, 10**9,
               np.empty(0), np.empty(1), np.empty((1, 4)), none, none, np.empty(16), np.empty((16, 4)),
               np.zeros(16, dtype=np.int64), np.empty((16, 4)), none, *tableau)
        return y
    return run


def numbalsoda_call():
    """numbalsoda's dop853 on the hand-written rhs over [0, T_END] at TOL, or None when it is not installed."""
    numbalsoda = peer("numbalsoda")
    if numbalsoda is None:
        return None
    rhs = numba.njit(error_model="numpy")(systems.double_pendulum_rhs.py_func)

    @numba.cfunc(numbalsoda.lsoda_sig)
    def f(t, u, du, data):
        rhs(t, numba.carray(u, (4,)), numba.carray(data, (5,)), numba.carray(du, (4,)))

    grid = np.array([0.0, T_END])
    return lambda: numbalsoda.dop853(f.address, Y0, grid, data=PARAMS.copy(), rtol=TOL, atol=TOL, mxstep=10**7)[0][-1]


def _drivers(model, name: str):
    """(library driver, specialised driver, coefficient arrays) of the method `name` for `model`."""
    from lagcomp.integrate import specialize
    from lagcomp.integrate.methods import get_method

    method = get_method(name)
    specialize.prepare(model, method)
    return method.bound_driver(model.kernels), specialize.driver(model, method), method.driver_arguments()


def rk4_table(model, steps: int, rounds: int) -> Table:
    library, special, coefficients = _drivers(model, "rk4")
    hand = hand_written_rk4()
    runs = [lambda: hand(Y0, PARAMS, DT, steps), rk4_call(library, coefficients, steps),
            rk4_call(special, coefficients, steps)]
    assert np.array_equal(runs[1](), runs[2]())     # the tiers agree bit for bit
    times = cpu_times(runs, rounds)
    table = Table(f"RK4, double pendulum, {steps:,} steps of {DT}, state at the end only", [
        "driver", "steps/s (M)", "× the hand-written loop's steps/s"],
        note="CPU time, round-robin in one process; ratios are medians (min–max) of per-round ratios.")
    for label, t in zip(("hand-written numba loop (`error_model=\"numpy\"`)", "lagcomp library driver",
                         "lagcomp specialised driver"), times, strict=True):
        rate = stat_of([steps / x / 1e6 for x in t])
        table.add(label, fmt_stat(rate), fmt_stat(ratio(times[0], t), "×"))
    return table


def dop853_table(model, rounds: int) -> Table:
    library, special, tableau = _drivers(model, "dop853")
    runs = [dop853_call(library, tableau), dop853_call(special, tableau)]
    assert np.array_equal(runs[0](), runs[1]())
    labels = ["lagcomp library driver", "lagcomp specialised driver"]
    baseline = numbalsoda_call()
    if baseline is not None:
        runs.insert(0, baseline)
        labels.insert(0, "numbalsoda dop853 (hand-written rhs)")
    times = cpu_times(runs, rounds)
    base = "numbalsoda's" if baseline is not None else "the library driver's"
    table = Table(f"DOP853, double pendulum, [0, {T_END:g}], tol {TOL:g}, state at the end only",
                  ["driver", "time (ms)", f"× {base} time"],
                  note="numbalsoda is not installed: the baseline is the library driver" if baseline is None else "")
    for label, t in zip(labels, times, strict=True):
        table.add(label, fmt_stat(stat_of([x * 1e3 for x in t])), fmt_stat(ratio(t, times[0]), "×"))
    return table


def recording_table(model, rounds: int) -> Table:
    library, _, tableau = _drivers(model, "dop853")
    model.kernels.companion.entry("energy_lanes")     # a summary's lane kernels, built ahead as `lagcomp precompile --all` builds them
    # (a run builds them itself once the model's summaries have folded `recording.LANES_AFTER_ROWS` rows)
    span, tol = (0.0, T_END), {"rtol": TOL, "atol": TOL}

    def simulate(specialize, read_summary=False, **options):
        def run():
            solution = model.simulate(span, Y0[:2], Y0[2:], progress=False, specialize=specialize, **tol, **options)
            return solution.summary if read_summary else solution
        return run

    ways = [("every step (the default)", {}), ("`t_eval`, 1001 points", {"t_eval": np.linspace(0.0, T_END, 1001)}),
            ("`save_every=10`", {"save_every": 10}), ("`record=\"summary\"`", {"record": "summary"}),
            ("every step, then `Solution.summary` read", {"read_summary": True})]
    runs = [dop853_call(library, tableau)]
    for _, options in ways:
        runs += [simulate(False, **options), simulate(True, **options)]
    times = cpu_times(runs, rounds)
    rows = model.simulate(span, Y0[:2], Y0[2:], progress=False, **tol).t.size
    table = Table(f"Recording, DOP853 double pendulum [0, {T_END:g}] tol {TOL:g} ({rows:,} rows when every step is "
                  "saved), through `Model.simulate`", ["recording", "library driver", "specialised driver"],
                  note="× the time of the library driver called once recording nothing (its state at the end); "
                       f"that call: {fmt_stat(stat_of([x * 1e3 for x in times[0]]))} ms.")
    for i, (label, _) in enumerate(ways):
        table.add(label, fmt_stat(ratio(times[1 + 2 * i], times[0]), "×"),
                  fmt_stat(ratio(times[2 + 2 * i], times[0]), "×"))
    return table


def _libm_copy(kernel, **swap):
    """`kernel`'s Python function compiled again (``error_model="numpy"``, as the kernels) with `swap` in its globals."""
    function = kernel.py_func
    names = {**function.__globals__, **swap}
    copy = types.FunctionType(function.__code__, names, function.__name__, function.__defaults__, function.__closure__)
    return numba.njit(error_model="numpy")(copy)


@numba.njit(inline="always")
def _libm_sin(x):
    return math.sin(x)


@numba.njit(inline="always")
def _libm_cos(x):
    return math.cos(x)


def _states_loop(rhs):
    """rhs over every row of Ys (B, 4), `reps` times: independent calls, which the processor overlaps."""
    @numba.njit(error_model="numpy")
    def loop(Ys, p, reps):
        out, total = np.empty(4), 0.0
        for _ in range(reps):
            for row in range(Ys.shape[0]):
                rhs(0.0, Ys[row], p, out)
                total += out[2]
        return total
    return loop


def trig_table(model, steps: int, rounds: int) -> Table:
    """Table 4 (module docstring)."""
    rng = np.random.default_rng(0)
    states = np.vstack([rng.uniform(-3.0, 3.0, (2, 1024)), rng.uniform(-2.0, 2.0, (2, 1024))])
    rows, params = np.ascontiguousarray(states.T), np.repeat(PARAMS[:, None], 1024, axis=1)
    times, out, bad = np.zeros(1024), np.empty((4, 1024)), np.zeros(1024, dtype=np.bool_)
    scalar = {"poly": _libm_copy(model.kernels.rhs), "libm": _libm_copy(model.kernels.rhs, sin=math.sin, cos=math.cos),
              "hand": numba.njit(error_model="numpy")(systems.double_pendulum_rhs.py_func)}
    lanes = {"poly": _libm_copy(model.kernels.rhs_lanes),
             "libm": _libm_copy(model.kernels.rhs_lanes, vsin=_libm_sin, vcos=_libm_cos)}
    for key, batched in lanes.items():      # lanes bitwise equal to the scalar kernel, state by state
        batched(times, states, params, out, bad)
        one = np.empty(4)
        for lane in range(1024):
            scalar[key](0.0, rows[lane].copy(), PARAMS, one)
            assert np.array_equal(one, out[:, lane]), (key, lane)
    labels = ["lagcomp's sin/cos polynomials", "numba's libm sin/cos", "hand-written rhs (libm)"]
    rk4 = [hand_written_rk4(scalar[k]) for k in scalar]
    loops = [_states_loop(scalar[k]) for k in scalar]
    reps = max(1, steps // 1000)
    runs = ([lambda f=f: f(Y0, PARAMS, DT, steps) for f in rk4] + [lambda f=f: f(rows, PARAMS, reps) for f in loops]
            + [lambda f=f: [f(times, states, params, out, bad) for _ in range(reps)] for f in lanes.values()])
    t = cpu_times(runs, rounds)
    table = Table("sin and cos in the double pendulum's rhs: lagcomp's polynomials against numba's libm",
                  ["rhs", "RK4 loop, ns per rhs", "× polynomials", "1024 states, ns per rhs", "× polynomials",
                   "rhs_lanes, ns per lane", "× polynomials"],
                  note="CPU time, round-robin; RK4: the loop of the RK4 table; lanes: 1024 lanes per call, "
                       "bitwise equal to the scalar kernel of the same sin/cos (checked).")
    for i, label in enumerate(labels):
        cells = [fmt_stat(stat_of([x / (4 * steps) * 1e9 for x in t[i]])), fmt_stat(ratio(t[i], t[0]), "×"),
                 fmt_stat(stat_of([x / (1024 * reps) * 1e9 for x in t[3 + i]])), fmt_stat(ratio(t[3 + i], t[3]), "×")]
        cells += ([fmt_stat(stat_of([x / (1024 * reps) * 1e9 for x in t[6 + i]])), fmt_stat(ratio(t[6 + i], t[6]), "×")]
                  if i < 2 else ["—", "—"])
        table.add(label, *cells)
    return table


def measure(rounds: int = 7, steps: int = 1_000_000, cache_dir=None) -> list[Table]:
    """The four tables (module docstring)."""
    import lagcomp as lc
    from lagcomp import examples

    model = lc.compile(examples.get("double_pendulum"), cache_dir=cache_dir)
    return [rk4_table(model, steps, rounds), dop853_table(model, rounds), recording_table(model, rounds),
            trig_table(model, steps, rounds)]


def section(ctx) -> list[Table]:
    """`python -m bench` section ``tiers``."""
    return measure(rounds=ctx.repeats, steps=200_000 if ctx.quick else 1_000_000, cache_dir=ctx.cache_dir)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--steps", type=int, default=1_000_000)
    args = parser.parse_args(argv)
    for table in measure(max(args.rounds, 1), max(args.steps, 1)):
        print(table.markdown(), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
