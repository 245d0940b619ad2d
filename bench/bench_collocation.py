"""Gauss-Legendre stage solvers: fixed-point iteration vs simplified Newton.

    python bench/bench_collocation.py [example] [method] [dt ...] [q0=v,v,...] [param=value ...]

Defaults: double_pendulum, gauss2, dt = 0.01 and 0.05, the example's default
initial state and parameters.  For each solver and step, integrates 1e5
steps (save_every = 1000) and prints the best of 3 warm runs: wall time,
steps per second, and the evaluations of the canonical equations f per step
(Newton also evaluates one Jacobian per step); a failed run (status -5)
counts the steps it took.  Then, in a fresh process with an empty model cache, the
first-call time of the gauss method for each solver: its library driver
(`lagcomp.integrate.drivers.collocation`) is imported then, from numba's cache once
compiled (the model's kernels are compiled beforehand and not counted).
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time

import lagcomp as lc
from lagcomp import examples
from lagcomp.integrate.methods import IMPLICIT_SOLVERS

STEPS = 100_000

PROBE = """
import sys, time
import numpy as np
import lagcomp as lc
from lagcomp import examples
name, method, solver, cache_dir = sys.argv[1:]
model = lc.compile(examples.get(name), cache_dir=cache_dir)
k, n = model.kernels, model.n
y, p = model.initial_state(), model.parameter_vector()
out = np.empty(n)
k.velocities(0.0, y, p, out), k.momenta(0.0, y, p, out), k.momentum_rate(0.0, y, p, out)
k.canonical_partials(0.0, y, p, np.empty((4, n, n)))
k.observables(np.zeros(1), y[None, :], p, np.empty(1), np.empty(1), np.empty((1, n)))
start = time.perf_counter()
model.simulate((0, 0.01), method=method, dt=0.01, implicit_solver=solver)
print(time.perf_counter() - start)
"""


def speed(model, method: str, solver: str, dt: float, settings: dict) -> tuple[float, lc.Solution]:
    """Best wall time of 3 runs of STEPS steps, and the last run's solution."""
    def run():
        return model.simulate((0, STEPS * dt), method=method, dt=dt, save_every=1000, implicit_solver=solver,
                              **settings)
    run()
    times = []
    for _ in range(3):
        start = time.perf_counter()
        sol = run()
        times.append(time.perf_counter() - start)
    return min(times), sol


def compile_time(name: str, method: str, solver: str) -> float:
    with tempfile.TemporaryDirectory() as cache_dir:
        out = subprocess.run([sys.executable, "-c", PROBE, name, method, solver, cache_dir],
                             capture_output=True, text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def main(name: str = "double_pendulum", method: str = "gauss2", *rest: str) -> None:
    dts = [float(a) for a in rest if "=" not in a] or [0.01, 0.05]
    given = dict(a.split("=", 1) for a in rest if "=" in a)
    settings = {"params": {k: float(v) for k, v in given.items() if k != "q0"}}
    if "q0" in given:
        settings["q0"] = [float(v) for v in given["q0"].split(",")]
    print(f"{name}, {method}, {STEPS} steps, {given or 'defaults'}")
    print("| solver | dt | status | wall s | steps/s | f evals/step |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as cache_dir:
        model = lc.compile(examples.get(name), cache_dir=cache_dir)
        for dt in dts:
            for solver in IMPLICIT_SOLVERS:
                wall, sol = speed(model, method, solver, dt, settings)
                steps = max(sol.nsteps, 1)
                print(f"| {solver} | {dt} | {sol.status} | {wall:.3f} | {steps / wall:,.0f} | {sol.nfev / steps:.2f} |")
    print("\n| solver | first gauss run s |\n|---|---|")
    for solver in IMPLICIT_SOLVERS:
        print(f"| {solver} | {compile_time(name, method, solver):.2f} |")


if __name__ == "__main__":
    main(*sys.argv[1:])
