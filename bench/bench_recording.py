"""What `Model.simulate` costs on top of its driver, and what each way of recording costs on top of the integration.

    python -m bench.bench_recording [--rounds 21] [--t-end 100]

DOP853 on the double pendulum (lagcomp example, y0 = (2, 1, 0, 0)) over [0, t_end] at rtol = atol = 1e-10,
the model's specialised driver (`lagcomp.integrate.specialize`, compiled or loaded before anything is timed).
Every run is timed round-robin in this process, CPU time (``time.process_time``); a number is the median
(min–max) over the rounds of the per-round values.

1. simulate's fixed cost (issue 38, item 3 and the DOP853 target): for each way of recording, one
   ``Model.simulate(..., specialize=True)`` against its floor, the specialised driver called once directly with
   the arrays that simulate gives it (output buffers of `simulate.FIRST_CHUNK` rows, the ``t_eval`` times,
   ``save_every``), so the difference is the Python around the driver: checking the options, building the
   state, the `Solution`.  A summary's floor is the driver saving every step (the rows the summary folds): its
   difference also holds the fold.  Target: ≤ 0.1 ms for the plain run (every step saved).  The last row is a
   short run (``--short``, 1 by default): on a loaded machine the Python around a long run is slowed by whatever
   ran on the core meanwhile (caches refilled), some 5× its cost after a short run or at rest (measured: 0.1 ms
   after a 1 s run, 0.5 ms after a 100 s run or a 4 ms sleep, load 13 on 2 cores).
2. Recording against a driver that records nothing (issue 38, item 3): each way of recording through
   ``Model.simulate`` and by the driver alone, as a ratio over the driver called once keeping only the state at
   t_end (the integration itself).  A summary keeps two rows and running reductions: it must cost less than a
   trajectory.  A summary evaluates the energy at every row during the run, which a trajectory defers until
   ``Solution.energy`` or ``.summary`` is read: the last row is a trajectory whose summary is read.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from bench.harness import Table, fmt_stat, stat_of

#: The double pendulum's start (q, q̇) and parameters (m1, m2, l1, l2, g: the example's defaults).
Y0 = np.array([2.0, 1.0, 0.0, 0.0])
PARAMS = np.array([1.0, 1.0, 1.0, 1.0, 9.81])
TOL = 1e-10
#: The ways of recording: (label, simulate's options, what the driver saves: (save_every, t_eval points or 0)).
WAYS = [("every step (the default)", {}, (1, 0)),
        ("`t_eval`, 1001 points", {"t_eval": 1001}, (1, 1001)),
        ("`save_every=10`", {"save_every": 10}, (10, 0)),
        ("`record=\"summary\"`", {"record": "summary"}, (1, 0))]


def cpu_times(runs: list, rounds: int) -> list[list[float]]:
    """Per-round CPU times of `runs`, round-robin, after two untimed calls of each."""
    for run in runs:
        run()
        run()
    times = [[] for _ in runs]
    for _ in range(max(rounds, 1)):
        for i, run in enumerate(runs):
            start = time.process_time()
            run()
            times[i].append(time.process_time() - start)
    return times


def driver_call(driver, tableau, t_end: float, save_every: int | None, t_eval: int):
    """One call of the specialised embedded driver over [0, t_end], no pause, saving every `save_every`-th step into
    buffers of `simulate.FIRST_CHUNK` rows (None: nothing but the end state), or at `t_eval` equally spaced times;
    the event arguments of a run without events, as `lagcomp.integrate.simulate` passes them.  Returns the rows."""
    from lagcomp.integrate.simulate import FIRST_CHUNK, NO_PAUSE_AT

    none = np.zeros(0, dtype=np.int64)
    atol = np.full(Y0.size, TOL)        # (one per component, as simulate passes it)
    events = np.linspace(0.0, t_end, t_eval)[1:] if t_eval else np.empty(0)
    rows = 1 if save_every is None else (events.size + 1 if t_eval else FIRST_CHUNK)
    every = NO_PAUSE_AT if save_every is None else save_every
    ts, ys = np.empty(rows), np.empty((rows, Y0.size))

    def run():
        y, clock, counters = Y0.copy(), np.zeros(3), np.zeros(11, dtype=np.int64)
        status, saved = driver(y, clock, counters, PARAMS, 0, np.array([0.0, np.inf]), t_end, TOL, atol, np.inf,
                               10**9, NO_PAUSE_AT, every, events, ts, ys, none, none, np.empty(16),
                               np.empty((16, 4)), np.zeros(16, dtype=np.int64), np.full((16, 4), np.nan), none,
                               *tableau)
        assert status == 0, status
        return ts[:saved].copy(), ys[:saved].copy()
    return run


def simulate_call(model, t_end: float, read_summary: bool = False, **options):
    """One ``Model.simulate`` of the bench's run with the specialised driver (`options`: how it records)."""
    if "t_eval" in options:
        options["t_eval"] = np.linspace(0.0, t_end, options["t_eval"])

    def run():
        solution = model.simulate((0.0, t_end), Y0[:2], Y0[2:], progress=False, specialize=True, rtol=TOL, atol=TOL,
                                  **options)
        return solution.summary if read_summary else solution
    return run


def prepared(cache_dir=None):
    """(model, specialised DOP853 driver, its tableau arrays): compiled or loaded, and the summary's lane kernels
    built, as ``lagcomp precompile double_pendulum --all --specialize dop853`` leaves them."""
    import lagcomp as lc
    from lagcomp import examples
    from lagcomp.integrate import specialize
    from lagcomp.integrate.methods import get_method

    model = lc.compile(examples.get("double_pendulum"), cache_dir=cache_dir)
    method = get_method("dop853")
    specialize.prepare(model, method)
    model.kernels.companion.entry("energy_lanes")
    return model, specialize.driver(model, method), method.driver_arguments()


def check_floors(model, driver, tableau, t_end: float) -> None:
    """The driver called directly saves the rows `simulate` returns, bit for bit (else the floor is not its floor)."""
    for _, options, (every, points) in WAYS[:3]:
        ts, ys = driver_call(driver, tableau, t_end, every, points)()
        solution = simulate_call(model, t_end, **options)()
        # (simulate adds the initial state itself)
        assert np.array_equal(solution.t[1:], ts) and np.array_equal(solution.y[1:], ys), options


def measure(rounds: int = 21, t_end: float = 100.0, short: float = 1.0, cache_dir=None) -> list[Table]:
    """The two tables (module docstring)."""
    model, driver, tableau = prepared(cache_dir)
    check_floors(model, driver, tableau, t_end)
    nothing = driver_call(driver, tableau, t_end, None, 0)
    runs = [nothing]
    for _, options, (every, points) in WAYS:
        runs += [driver_call(driver, tableau, t_end, every, points), simulate_call(model, t_end, **dict(options))]
    runs += [simulate_call(model, t_end, read_summary=True), driver_call(driver, tableau, short, 1, 0),
             simulate_call(model, short)]
    times = cpu_times(runs, rounds)
    rows = model.simulate((0.0, t_end), Y0[:2], Y0[2:], progress=False, rtol=TOL, atol=TOL).t.size
    what = f"DOP853, double pendulum, [0, {t_end:g}], tol {TOL:g}, {rows:,} rows when every step is saved"
    fixed = Table(f"`Model.simulate`'s fixed cost: {what}",
                  ["recording", "driver alone (ms)", "`simulate` (ms)", "difference (ms)", "× the driver alone"],
                  note="CPU time, round-robin in one process; the specialised driver; medians (min–max) over "
                       f"{max(rounds, 1)} rounds of per-round values. A summary's driver alone saves every step.")
    recording = Table(f"Recording against a driver that records nothing: {what}",
                      ["recording", "driver alone", "`Model.simulate`"],
                      note="× the time of the specialised driver called once keeping only the state at the end: "
                           f"{fmt_stat(stat_of([x * 1e3 for x in times[0]]))} ms.")
    for i, (label, _, _) in enumerate(WAYS):
        alone, whole = times[1 + 2 * i], times[2 + 2 * i]
        fixed.add(label, fmt_stat(stat_of([x * 1e3 for x in alone])), fmt_stat(stat_of([x * 1e3 for x in whole])),
                  fmt_stat(stat_of([(b - a) * 1e3 for a, b in zip(alone, whole, strict=True)])),
                  fmt_stat(stat_of([b / a for a, b in zip(alone, whole, strict=True)]), "×"))
        recording.add(label, fmt_stat(stat_of([a / z for a, z in zip(alone, times[0], strict=True)]), "×")
                      if i < 3 else "—", fmt_stat(stat_of([b / z for b, z in zip(whole, times[0], strict=True)]), "×"))
    alone, whole = times[-2], times[-1]
    fixed.add(f"every step, a short run: [0, {short:g}]", fmt_stat(stat_of([x * 1e3 for x in alone])),
              fmt_stat(stat_of([x * 1e3 for x in whole])),
              fmt_stat(stat_of([(b - a) * 1e3 for a, b in zip(alone, whole, strict=True)])),
              fmt_stat(stat_of([b / a for a, b in zip(alone, whole, strict=True)]), "×"))
    recording.add("every step, then `Solution.summary` read", "—",
                  fmt_stat(stat_of([b / z for b, z in zip(times[-3], times[0], strict=True)]), "×"))
    return [fixed, recording]


def section(ctx) -> list[Table]:
    """`python -m bench` section ``tiers``, after `bench.bench_tiers`' tables."""
    return measure(rounds=max(3 * ctx.repeats, 1), t_end=10.0 if ctx.quick else 100.0, cache_dir=ctx.cache_dir)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=21)
    parser.add_argument("--t-end", type=float, default=100.0)
    parser.add_argument("--short", type=float, default=1.0, help="the end time of the short run of table 1")
    args = parser.parse_args(argv)
    for table in measure(max(args.rounds, 1), args.t_end, args.short):
        print(table.markdown(), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
