"""Taylor throughput of the library drivers against the template drivers they replaced (#19), in one process.

The template drivers live in modules emitted before the move (commit efc66f1): write them with that
commit's code (``git archive efc66f1 | tar -x -C old``; with ``PYTHONPATH=old/src`` compile the double
pendulum, the Pythagorean three-body problem and Hénon-Heiles, and run one batched Taylor sweep of the
double pendulum at rtol = atol = 1e-8, which writes its order-11 lanes module), then:

    python bench/taylor_library_vs_template.py DIR   # DIR: those modules (the old cache's modules/)

Times are CPU times of this thread (the machine may be shared).  Each row gives steps (or
trajectories) per second of both and the ratio library/template of the best times (above 1: the
library is faster), with the median of the per-round ratios.
"""

from __future__ import annotations

import importlib.util
import math
import pathlib
import sys
import time

import numpy as np

import lagcomp as lc
from lagcomp.examples import get
from lagcomp.integrate import sweep as sweep_module
from lagcomp.integrate.drivers.taylor import taylor_run
from lagcomp.integrate.drivers.taylor_lanes import sweep_taylor_lanes

ROUNDS = 11
EPS = 2.220446049250313e-16
cpu = time.thread_time


def old_modules(directory) -> dict[str, str]:
    """example -> its template-era module in `directory`; "lanes" -> the batched Taylor module."""
    found = {}
    for path in sorted(pathlib.Path(directory).glob("*.py")):
        text = path.read_text(encoding="utf-8")
        if "def sweep_taylor_lanes(" in text:
            found["lanes"] = str(path)
        elif "def taylor_run(" in text:
            found[path.stem.rsplit("_", 1)[0]] = str(path)
    return found


def load(path: str, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module          # numba's cache finds the module of its functions by name
    spec.loader.exec_module(module)
    return module


def compare(label: str, template, library, unit: str) -> None:
    """Time template() and library() round-robin; each returns (CPU seconds, work done)."""
    template(), library()               # compile or load both first
    best, ratios = {"template": math.inf, "library": math.inf}, []
    for _ in range(ROUNDS):
        (t_template, work), (t_library, _) = template(), library()
        best["template"], best["library"] = min(best["template"], t_template), min(best["library"], t_library)
        ratios.append(t_template / t_library)
    print(f"{label}: template {work / best['template']:,.0f} {unit}/s, library {work / best['library']:,.0f} {unit}/s,"
          f" library/template {best['template'] / best['library']:.3f} (median of rounds {np.median(ratios):.3f})")


def scalar(example: str, path: str, t_end: float, runs: int = 8) -> None:
    """Steps per second of one run to t_end at machine precision (order 20), repeated `runs` times."""
    model = lc.compile(get(example))
    kernels, old = model.kernels, load(path, f"template_{example}")
    p, y0 = model.parameter_vector(), model.initial_state(None, None)
    n = y0.size

    def timed(driver):
        def run():
            total, steps = 0.0, 0
            for _ in range(runs):
                y, clock, counters = y0.copy(), np.array([0.0, 0.0]), np.zeros(6, dtype=np.int64)
                no_events = (np.empty(0, dtype=np.int64), np.empty(0, dtype=np.int64), np.empty(16),
                             np.empty((16, n)), np.empty(16, dtype=np.int64))
                start = cpu()
                driver(y, clock, counters, p, 0, np.zeros(1), t_end, EPS, EPS, math.inf, 10**9, 2**62, 10**9,
                       np.empty(0), np.empty(4), np.empty((4, n)), *no_events, np.zeros(n))
                total += cpu() - start
                steps += counters[1]
            return total, steps
        return run

    parts = (kernels.taylor_coefficients, kernels.event_values, kernels.TAYLOR_PERIODIC, kernels.TAYLOR_WORK)
    compare(f"scalar taylor, {example} to t = {t_end:g}", timed(old.taylor_run),
            timed(lambda *args: taylor_run(*parts, *args)), "steps")


def batched(path: str, n_traj: int = 512) -> None:
    """Trajectories per second of a batched sweep of the double pendulum at rtol = atol = 1e-8 (order 11)."""
    model = lc.compile(get("double_pendulum"))
    old = load(path, "template_lanes")
    new = sweep_module._worker_kernels(sweep_module._taylor_lanes_spec(model, 1e-8, 1e-8))
    assert new.TAYLOR_ORDER == old._TAYLOR_ORDER
    Y0 = np.zeros((n_traj, 4))
    Y0[:, 0], Y0[:, 1] = np.linspace(-2, 2, n_traj), 0.5
    P = np.repeat(model.parameter_vector()[None, :], n_traj, axis=0)
    finals = {}

    def timed(label, loop):
        def run():
            out = (np.empty((n_traj, 4)), np.empty(n_traj), np.empty(n_traj, dtype=np.int64),
                   np.empty((n_traj, 3), dtype=np.int64), np.empty((n_traj, 0, 4)), np.empty((n_traj, 2)))
            start = cpu()
            loop(Y0, P, 0.0, 10.0, 1e-8, 1e-8, math.inf, 10**9, 1, *out)
            finals[label] = out[0]
            return cpu() - start, n_traj
        return run

    lanes = (new.taylor_lanes, new.taylor_lanes_advance, new.TAYLOR_ORDER, new.TAYLOR_LANES, new.energy)
    compare(f"batched taylor, double_pendulum, {n_traj} trajectories to t = 10",
            timed("template", old.sweep_taylor_lanes),
            timed("library", lambda *args: sweep_taylor_lanes(*lanes, *args)), "trajectories")
    assert np.array_equal(finals["template"], finals["library"]), "final states differ"


if __name__ == "__main__":
    old = old_modules(sys.argv[1])
    scalar("double_pendulum", old["double_pendulum"], 200.0)
    scalar("pythagorean_three_body", old["pythagorean_three_body"], 60.0)
    scalar("henon_heiles", old["henon_heiles"], 300.0)
    batched(old["lanes"])
