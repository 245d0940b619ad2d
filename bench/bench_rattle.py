"""RATTLE against RK4 with projection, the fixed-step alternative for a constrained system, in one run.

    python -m bench.bench_rattle [--steps 1000000] [--repeats 7] [--dt 0.01]

On the spherical pendulum in Cartesian coordinates (`examples.spherical_pendulum_cartesian`): the
library drivers of both methods (`drivers.rattle.rattle_run`, `drivers.fixed_step.runge_kutta_run`
projecting after every step, as `simulate` runs rk4 on a constrained model) over the same steps from
the same start, timed round-robin (`bench.harness.interleaved_times`); the ratio is the median
(min–max) of the per-round ratios.  For context, each method's energy error and largest constraint
residual over the run (from `simulate`, every 100th step saved): RATTLE's energy error stays bounded,
RK4's drifts (order 4, so smaller at this step), and projection holds RK4's residual only after each step.
"""

from __future__ import annotations

import argparse

import numpy as np

from bench.harness import fmt_stat, interleaved_times, paired, stat_of


def driver_call(model, method: str, dt: float, steps: int):
    """One driver call over `steps` steps from the model's start, keeping only the last row."""
    from lagcomp.integrate.methods import METHODS

    m = METHODS[method]
    driver, coefficients = m.bound_driver(model.kernels), m.driver_arguments()
    y0, p = model.initial_state(), model.parameter_vector()

    def run():
        y, clock, counters = y0.copy(), np.zeros(2), np.zeros(6, dtype=np.int64)
        driver(y, clock, counters, p, 1, np.zeros(1), 0.0, dt, steps, steps + 1, steps * dt, steps,
               np.empty(1), np.empty((1, y.size)), *coefficients)
        return y
    return run


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--dt", type=float, default=0.01)
    args = parser.parse_args(argv)

    import lagcomp as lc
    from lagcomp.examples import get

    model = lc.compile(get("spherical_pendulum_cartesian"))
    methods = ("rattle", "rk4")
    runs = [driver_call(model, m, args.dt, args.steps) for m in methods]
    times = interleaved_times(runs, args.repeats)
    print(f"spherical_pendulum_cartesian, {args.steps:,} steps of dt = {args.dt:g}, {args.repeats} rounds\n")
    print("| method | steps/s | time / rattle's | energy error | largest constraint residual |")
    print("|---|---|---|---|---|")
    for method, t in zip(methods, times, strict=True):
        s = model.simulate((0.0, args.steps * args.dt), method=method, dt=args.dt, save_every=100)
        energy_error = np.abs(s.energy - s.energy[0]).max() / abs(s.energy[0])
        rate = stat_of([args.steps / x for x in t])
        print(f"| {method} | {fmt_stat(rate)} | {fmt_stat(paired(t, times[0]), '×')} | {energy_error:.2e} | "
              f"{s.constraint_residual:.1e} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
