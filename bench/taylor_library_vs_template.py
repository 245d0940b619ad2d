"""Taylor throughput of the library drivers against the template drivers they replaced (#19), in one process.

The scalar template drivers are in the generated modules of commit d18c60c (the last before the move):

    mkdir old && for m in double_pendulum pythagorean_three_body henon_heiles; do
        git show d18c60c:generated/$m.py > old/$m.py; done

The batched one is in the order-11 lanes module the code of commit efc66f1 writes (``git archive efc66f1 |
tar -x -C old-src``; with ``PYTHONPATH=old-src/src`` run one batched Taylor sweep of the double pendulum at
rtol = atol = 1e-8 and copy the lanes module from that cache's modules/ into old/; without it the batched row
is skipped).  Then:

    python bench/taylor_library_vs_template.py old

Times are CPU times of this thread (the machine may be shared).  Each scalar example gives three rows:

* ``call``: microseconds of one call that returns at once (t_end = t0): what a call costs apart from
  steps.  The library driver's is mostly numba turning its two kernel arguments (dispatchers) into
  first-class function values (`numba.experimental.function_type`: compile-result and address look-ups
  per kernel, per call): ~70 µs of CPU time against ~3 µs for the template driver.  ``bound`` is the
  driver as simulate calls it (`Method.bound_driver`), its kernels bound as
  `lagcomp.integrate.drivers.kernel_types.AddressedKernel`: their numba type and address looked up once.
* ``runs``: steps per second of 8 runs to the first t of `SCALAR` at machine precision (order 20), the
  runs of the earlier figures (Hénon-Heiles: 785 steps, 0.5 ms, per call, 0.07 ms of it the call cost).
* ``long``: steps per second of one run to the second t of `SCALAR` (10 ms or more): the cost per step.

with the ratio library/template of the best times (above 1: the library is faster) and the median of the
per-round ratios.
"""

from __future__ import annotations

import functools
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
from lagcomp.integrate.methods import get_method

ROUNDS = 11
EPS = 2.220446049250313e-16
cpu = time.thread_time


#: example -> (t_end of the short runs, t_end of the long run)
SCALAR = {"double_pendulum": (200.0, 1000.0), "pythagorean_three_body": (60.0, 60.0), "henon_heiles": (300.0, 6000.0)}


def old_modules(directory) -> dict[str, str]:
    """example -> its template-era module in `directory` (named after the example, or example_<key>.py);
    "lanes" -> the batched Taylor module."""
    found = {}
    for path in sorted(pathlib.Path(directory).glob("*.py")):
        text = path.read_text(encoding="utf-8")
        if "def sweep_taylor_lanes(" in text:
            found["lanes"] = str(path)
        elif "def taylor_run(" in text:
            found[path.stem if path.stem in SCALAR else path.stem.rsplit("_", 1)[0]] = str(path)
    return found


def load(path: str, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module          # numba's cache finds the module of its functions by name
    spec.loader.exec_module(module)
    return module


def compare(label: str, variants: dict, unit: str, per_call: bool = False) -> None:
    """Time the variants round-robin, the first the baseline; each returns (CPU seconds, work done)."""
    for run in variants.values():
        run()                           # compile or load first
    best, ratios = dict.fromkeys(variants, math.inf), {name: [] for name in variants}
    for _ in range(ROUNDS):
        times = {}
        for name, run in variants.items():
            times[name], work = run()
            best[name] = min(best[name], times[name])
        for name in variants:
            ratios[name].append(times[next(iter(variants))] / times[name])
    baseline = best[next(iter(variants))]
    parts = []
    for name in variants:
        figure = f"{best[name] / work * 1e6:.1f} µs/{unit}" if per_call else f"{work / best[name]:,.0f} {unit}/s"
        ratio = f" ({baseline / best[name]:.3f}, median {np.median(ratios[name]):.3f})" if parts else ""
        parts.append(f"{name} {figure}{ratio}")
    print(f"{label}: " + ", ".join(parts))


def scalar(example: str, path: str) -> None:
    """Per-call cost and steps per second at machine precision (order 20) of template and library drivers."""
    t_runs, t_long = SCALAR[example]
    model = lc.compile(get(example))
    kernels, old = model.kernels, load(path, f"template_{example}")
    p, y0 = model.parameter_vector(), model.initial_state(None, None)
    n = y0.size
    finals = {}

    def timed(label, driver, t_end, runs):
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
            finals[label] = y
            return total, (steps if t_end > 0 else runs)
        return run

    drivers = {"template": old.taylor_run,
               "library": functools.partial(taylor_run, kernels.taylor_coefficients, kernels.event_values,
                                            kernels.TAYLOR_PERIODIC, kernels.TAYLOR_WORK),
               "bound": get_method("taylor").bound_driver(kernels)}
    compare(f"scalar taylor, {example}, call",
            {name: timed(name, driver, 0.0, 1000) for name, driver in drivers.items()}, "call", per_call=True)
    compare(f"scalar taylor, {example}, runs to t = {t_runs:g}",
            {name: timed(name, driver, t_runs, 8) for name, driver in drivers.items()}, "steps")
    compare(f"scalar taylor, {example}, long, to t = {t_long:g}",
            {name: timed(name, driver, t_long, 1) for name, driver in drivers.items()}, "steps")
    assert all(np.array_equal(finals["template"], y) for y in finals.values()), "final states differ"


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
            {"template": timed("template", old.sweep_taylor_lanes),
             "library": timed("library", lambda *args: sweep_taylor_lanes(*lanes, *args))}, "trajectories")
    assert np.array_equal(finals["template"], finals["library"]), "final states differ"


if __name__ == "__main__":
    old = old_modules(sys.argv[1])
    for example in SCALAR:
        scalar(example, old[example])
    if "lanes" in old:
        batched(old["lanes"])
