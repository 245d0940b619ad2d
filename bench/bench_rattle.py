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

from bench.harness import Table, fmt_stat, interleaved_times, paired, stat_of


def driver_call(model, method: str, dt: float, steps: int):
    """One driver call over `steps` steps from the model's start, keeping only the last row."""
    from lagcomp.integrate.drivers.run_state import COUNTER_SLOTS
    from lagcomp.integrate.methods import METHODS

    m = METHODS[method]
    driver, coefficients = m.bound_driver(model.kernels), m.driver_arguments()
    y0, p = model.initial_state(), model.parameter_vector()

    def run():
        y, clock, counters = y0.copy(), np.zeros(2), np.zeros(COUNTER_SLOTS, dtype=np.int64)
        driver(y, clock, counters, p, 1, np.zeros(1), 0.0, dt, steps, steps + 1, steps * dt, steps,
               np.empty(1), np.empty((1, y.size)), *coefficients)
        return y
    return run


def measure(steps: int = 1_000_000, repeats: int = 7, dt: float = 0.01, cache_dir: str | None = None) -> Table:
    """The comparison as a markdown `Table`."""
    import lagcomp as lc
    from lagcomp.examples import get

    model = lc.compile(get("spherical_pendulum_cartesian"), cache_dir=cache_dir)
    methods = ("rattle", "rk4")
    runs = [driver_call(model, m, dt, steps) for m in methods]
    times = interleaved_times(runs, repeats)
    table = Table(f"Constrained symplectic: rattle on spherical_pendulum_cartesian, {steps:,} steps of dt = {dt:g} "
                  "(issue 20)", ["method", "steps/s", "time / rattle's", "energy error", "largest constraint residual"],
                  note=f"{__doc__.split(chr(10) + chr(10), 2)[2].strip()}  {repeats} rounds; "
                       "`python -m bench.bench_rattle` runs this table alone.")
    for method, t in zip(methods, times, strict=True):
        s = model.simulate((0.0, steps * dt), method=method, dt=dt, save_every=100, progress=False)
        energy_error = np.abs(s.energy - s.energy[0]).max() / abs(s.energy[0])
        rate = stat_of([steps / x for x in t])
        table.add(method, fmt_stat(rate), fmt_stat(paired(t, times[0]), "×"), f"{energy_error:.2e}",
                  f"{s.constraint_residual:.1e}")
    return table


def section(ctx) -> Table:
    """`python -m bench` section ``stiff`` (with `bench.bench_stiff`): rattle against rk4 with projection."""
    return measure(steps=100_000 if ctx.quick else 1_000_000, repeats=ctx.repeats, cache_dir=ctx.cache_dir)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--dt", type=float, default=0.01)
    args = parser.parse_args(argv)
    print(measure(args.steps, args.repeats, args.dt).markdown())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
