"""The library's fixed-step drivers against the template copies they replaced and against hand-written numba.

    python -m bench.bench_fixed_step [--steps 1000000] [--repeats 7]

Before #19 every generated module carried its own ``rk4_run`` and ``composition_run``, calling
the kernels as module globals; since, one library driver (`lagcomp.integrate.drivers.fixed_step`)
takes them as function values.  The baseline is the generated module as committed at
``BEFORE`` (template drivers included), written to a temporary directory and imported; the
library driver runs the same module's kernels, on the same start, in the same process.  For the
double pendulum, a hand-written numba RK4 loop over a hand-written RHS (bench/systems.py, as in
the fixed-step throughput table) is timed too.  All rows of a case are timed round-robin; ratios
are medians (min–max) of the per-round ratios; the trajectories are checked bitwise equal first.
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from bench import systems
from bench.harness import fmt_stat, interleaved_times, paired, stat_of

#: The commit whose generated modules hold the template drivers (the last one before they moved).
BEFORE = "d18c60c"
ROOT = Path(__file__).resolve().parent.parent


def template_module(case: str, directory: Path):
    """``generated/<case>.py`` as committed at `BEFORE`, imported from `directory`."""
    source = subprocess.run(["git", "show", f"{BEFORE}:generated/{case}.py"], cwd=ROOT, capture_output=True,
                            text=True, check=True).stdout
    name = f"before_19_{case}"
    path = directory / f"{name}.py"
    path.write_text(source, encoding="utf-8")
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # numba's cache locator needs the module registered
    spec.loader.exec_module(module)
    return module


def fixed_step_call(driver, y0, p, dt, steps, coefficients=()):
    """A call of a fixed-step driver over `steps` steps from y0, keeping only the last row."""
    def run():
        y, clock, counters = y0.copy(), np.zeros(2), np.zeros(6, dtype=np.int64)
        driver(y, clock, counters, p, 0, np.array([0.0, np.inf]), 0.0, dt, steps, steps + 1, steps * dt, steps,
               np.empty(1), np.empty((1, y.size)), *coefficients)
        return y
    return run


def sweep_call(loop, y0, p, dt, steps, trajectories, coefficients):
    """A call of a fixed-step sweep loop over `trajectories` starts near y0, keeping the final states and energies."""
    Y0 = np.repeat(y0[None, :], trajectories, axis=0)
    Y0[:, 0] += np.linspace(-0.1, 0.1, trajectories)
    P = np.repeat(p[None, :], trajectories, axis=0)

    def run():
        final, t_final = np.empty_like(Y0), np.empty(trajectories)
        status, counts = np.empty(trajectories, dtype=np.int64), np.empty((trajectories, 3), dtype=np.int64)
        dense, energy = np.empty((trajectories, 0, y0.size)), np.empty((trajectories, 2))
        loop(Y0, P, 0, 0.0, dt, steps, steps * dt, 1, final, t_final, status, counts, dense, energy, *coefficients)
        return final, energy
    return run


def case_rows(case: str, method: str, dt: float, steps: int, repeats: int, directory: Path) -> list[tuple]:
    from lagcomp.integrate.drivers import fixed_step, fixed_sweeps
    from lagcomp.integrate.methods import get_method

    module = template_module(case, directory)
    import lagcomp as lc
    from lagcomp.examples import get

    model = lc.compile(get(case))
    y0, p = model.initial_state(), model.parameter_vector()
    m = get_method(method)
    coefficients = m.driver_arguments()
    if method == "rk4":
        template = fixed_step_call(module.rk4_run, y0, p, dt, steps)
        library = fixed_step_call(
            lambda *a: fixed_step.runge_kutta_run(module.rhs, module.project, module.constraint_residual, *a),
            y0, p, dt, steps, coefficients)
    else:
        template = fixed_step_call(module.composition_run, y0, p, dt, steps, coefficients)
        library = fixed_step_call(lambda *a: fixed_step.composition_run(module.rhs, *a), y0, p, dt, steps,
                                  coefficients)
    # sweeps: 100 trajectories of steps / 100 steps each, every step's energy folded (save_every 1)
    short = steps // 100
    if method == "rk4":
        template_sweep = sweep_call(module.sweep_rk4_run, y0, p, dt, short, 100, ((),))
        library_sweep = sweep_call(
            lambda *a: fixed_sweeps.runge_kutta_sweep(module.rhs, module.project, module.constraint_residual,
                                                      module.energy, *a), y0, p, dt, short, 100, coefficients)
    else:
        template_sweep = sweep_call(module.sweep_composition_run, y0, p, dt, short, 100, (coefficients,))
        library_sweep = sweep_call(lambda *a: fixed_sweeps.composition_sweep(module.rhs, module.energy, *a),
                                   y0, p, dt, short, 100, coefficients)
    for a, b in zip(template_sweep(), library_sweep()):
        if not np.array_equal(a, b):
            raise AssertionError(f"{case} {method}: the library sweep's outputs differ from the template's")
    sweep_times = interleaved_times([template_sweep, library_sweep], repeats)
    check = (template(), library())
    if not np.array_equal(*check):
        raise AssertionError(f"{case} {method}: the library driver's state differs from the template's")
    runs, labels = [template, library], [f"template {method} (module globals, before #19)", f"library {method}"]
    simulate = lambda: model.simulate((0, steps * dt), method=method, dt=dt, save_every=10_000,  # noqa: E731
                                      progress=False)
    runs.append(simulate)
    labels.append(f"library {method} through Model.simulate")
    if case == "double_pendulum":
        hand = systems.rk4_driver(systems.double_pendulum_rhs)
        runs.insert(0, lambda: hand(y0.copy(), p, dt, steps))
        labels.insert(0, "hand-written numba rk4")
    times = interleaved_times(runs, repeats)
    base = times[labels.index(f"template {method} (module globals, before #19)")]
    hand_times = times[0] if case == "double_pendulum" else None
    rows = []
    for label, ts in zip(labels, times):
        rate = stat_of([steps / t for t in ts])
        rows.append((case, label, f"{rate.median:.3g}", fmt_stat(paired(base, ts), "×"),
                     fmt_stat(paired(hand_times, ts), "×") if hand_times else ""))
    for label, ts in zip((f"template {method} sweep (before #19)", f"library {method} sweep"), sweep_times):
        rate = stat_of([steps / t for t in ts])
        rows.append((case, label + " (100 trajectories, energy every step)", f"{rate.median:.3g}",
                     fmt_stat(paired(sweep_times[0], ts), "×"), ""))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    print("| case | driver | steps/s (median) | × template | × hand-written |")
    print("|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as directory:
        for case, method in (("double_pendulum", "rk4"), ("henon_heiles", "yoshida4")):
            for row in case_rows(case, method, 1e-3, args.steps, args.repeats, Path(directory)):
                print("| " + " | ".join(map(str, row)) + " |")


if __name__ == "__main__":
    main()
