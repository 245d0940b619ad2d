"""What a call into the library drivers costs besides the steps: the figures behind `simulate`'s first-call binding.

    python -m bench.bench_call_cost [--rounds 7]

On the double pendulum with DOP853 (rtol = atol = 1e-10), in one process, timed round-robin:

* a driver call that takes no step (t_end = t0), its kernels bound as numba dispatchers or as
  `lagcomp.integrate.drivers.kernel_types.AddressedKernel`: numba's unboxing of the kernels;
* one call running t ∈ [0, 1000] with each binding: the per-step price of calling the kernels
  through their cfunc wrappers (AddressedKernel) instead of their native entries;
* `Model.simulate` over t ∈ [0, 0.1] (a few dozen steps), and its fixed cost per call: its time less that
  of the same run's driver call alone (bound as simulate's first call binds it, the same steps), paired
  round by round: what simulate adds (options, initial state, recording, the Solution, ...).

Ratios are medians of per-round ratios (`bench.harness.paired`).
"""

from __future__ import annotations

import argparse

import numpy as np

import lagcomp as lc
from bench.harness import fmt_stat, interleaved_times, no_events, paired, stat_of
from lagcomp.examples import get
from lagcomp.integrate.drivers.run_state import CLOCK_SLOTS, COUNTER_SLOTS
from lagcomp.integrate.drivers.sweep_rows import NO_PAUSE
from lagcomp.integrate.methods import METHODS


def driver_call(model, addressed: bool, t_end: float):
    """One DOP853 driver call from the model's default start to `t_end` (fresh state, no events)."""
    method = METHODS["dop853"]
    driver = method.bound_driver(model.kernels, addressed=addressed)
    y0, p = model.initial_state(None, None), model.parameter_vector(None)
    events = no_events(method, y0.size)
    coefficients = method.driver_arguments()
    ts, ys = np.empty(16), np.empty((16, y0.size))
    atol = np.full(y0.size, 1e-10)      # (one per component, as simulate passes it)

    def call():
        y, clock, counters = y0.copy(), np.zeros(CLOCK_SLOTS), np.zeros(COUNTER_SLOTS, dtype=np.int64)
        status, _ = driver(y, clock, counters, p, 0, np.zeros(1), t_end, 1e-10, atol, np.inf, 10**9, NO_PAUSE,
                           10**9, np.empty(0), ts, ys, *events, *coefficients)
        if status not in (0, 10):
            raise RuntimeError(f"DOP853 driver returned status {status}")
    return call


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    args = parser.parse_args()
    model = lc.compile(get("double_pendulum"))
    print("| what | dispatchers | AddressedKernel | AddressedKernel / dispatchers |")
    print("|---|---|---|---|")
    for label, t_end, per_call in (("driver call, no step (µs)", 0.0, 200), ("driver call, t to 1000 (ms)", 1000.0, 1)):
        runs = []
        for addressed in (False, True):
            call = driver_call(model, addressed, t_end)
            runs.append(lambda call=call: [call() for _ in range(per_call)])
        plain, addressed = interleaved_times(runs, repeats=args.rounds, per_call=[per_call, per_call])
        scale = 1e6 if t_end == 0.0 else 1e3
        print(f"| {label} | {fmt_stat(stat_of([v * scale for v in plain]))} | "
              f"{fmt_stat(stat_of([v * scale for v in addressed]))} | {fmt_stat(paired(addressed, plain), '×')} |")
    run = lambda: [model.simulate((0.0, 0.1), rtol=1e-10, atol=1e-10, progress=False) for _ in range(200)]  # noqa: E731
    call = driver_call(model, True, 0.1)
    alone = lambda: [call() for _ in range(200)]  # noqa: E731
    times, driver = interleaved_times([run, alone], repeats=args.rounds, per_call=[200, 200])
    print(f"\n`Model.simulate` over t ∈ [0, 0.1]: {fmt_stat(stat_of([v * 1e6 for v in times]))} µs per call; "
          f"its driver call alone {fmt_stat(stat_of([v * 1e6 for v in driver]))} µs; "
          f"simulate's fixed cost {fmt_stat(stat_of([(v - d) * 1e6 for v, d in zip(times, driver, strict=True)]))} µs per call")


if __name__ == "__main__":
    main()
