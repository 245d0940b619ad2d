"""Start-up in fresh processes: the drivers' one-time compile, a new model's cold start, a cached model's warm start.

Drivers: `lagcomp precompile` in a fresh process with an empty numba cache
(a temporary NUMBA_CACHE_DIR): what a fresh installation pays once, in total
and per driver module.  Then `lagcomp precompile` once more in this run's own
environment, so that the cold starts find the drivers compiled (the state of
an installation after that first use).  Cold start (new model, empty lagcomp
cache, drivers in numba's cache): `lagcomp.compile` split into derivation,
lowering (CSE), emission and the rest (cache write, module load), then
numba's compilation of `rhs` (its first call), then the first short dop853
run split into numba's compilation of the other kernels it needs (read from
numba's compile events: `lagcomp.benchmark.numba_compiles`) and the rest (the
driver loaded from numba's cache, the run, writing numba's cache); the
pieces are timed by wrapping lagcomp's own stage functions, so they follow
the pipeline as it is.  Warm start: a later fresh process that loads the
model by name (`lagcomp.load`, no sympy) and runs it, timed from interpreter
start (`bench/bench_compile.py` has the three-process version), beside the
floors under it: a process that imports numpy and numba only, and one that
loads a trivial function from numba's cache (no lagcomp); and numba's
fixed cost of a cold start: its first compile in a fresh process.  Each case
runs under a time limit; a case that exceeds it is reported, not waited for.
Ratios: against lagcomp's cold start of the same case.
"""

from __future__ import annotations

import json
import os
import re
import resource
import subprocess
import sys
import tempfile
import time

from bench.bench_compile import LOAD_PROBE
from bench.harness import Table, fmt, stat_of

#: The issue 19 targets of the cold start (s, new model → first dop853 result, drivers compiled) and before it.
COLD_TARGETS = {"double_pendulum": ("cold_dp", 1.0, 4.2), "n_link_pendulum_10": ("cold10", 4.0, 10.2),
                "n_link_pendulum_24": ("cold24", 15.0, 31.6)}
WARM_TARGET = 0.6  # s, a cached double pendulum in a fresh process (0.8–1.0 s before issue 19)
NEW_OVER_WARM_TARGET = 1.5  # issue 35: a new double pendulum's first dop853 result over a cached one's, CPU

PRECOMPILE = "import sys; from lagcomp.cli import main; sys.exit(main(['precompile']))"
#: A line of `lagcomp precompile`: ``[3/13] lagcomp.integrate.drivers.embedded (embedded_run, ...): compiled in 4.2 s``.
PRECOMPILE_LINE = re.compile(r"^\[\d+/\d+\] (\S+) \((.*)\): (.+) in ([0-9.]+) s$")

COLD_PROBE = r"""
import json, sys, time
import lagcomp as lc
from bench.run import build_system
stages = {}
def timed(module, name):
    import importlib
    mod = importlib.import_module(module)
    original = getattr(mod, name, None)
    if original is None:
        return
    def wrapper(*args, **kwargs):
        start = time.perf_counter()
        try:
            return original(*args, **kwargs)
        finally:
            stages[name] = stages.get(name, 0.0) + time.perf_counter() - start
    setattr(mod, name, wrapper)
timed("lagcomp.mechanics.lagrange", "derive")
timed("lagcomp.codegen.lower", "lower")
timed("lagcomp.codegen.emit", "emit")
timed("lagcomp.codegen.emit", "emit_eager")   # (kernels on demand: compile emits the eager module)
system = build_system(sys.argv[1])
t0 = time.perf_counter()
model = lc.compile(system, cache_dir=sys.argv[2])
t1 = time.perf_counter()
import numpy as np
y, p = model.initial_state(), model.parameter_vector()
model.kernels.rhs(0.0, y, p, np.empty(y.size))
t2 = time.perf_counter()
from lagcomp.benchmark import numba_compiles
_, kernels = numba_compiles(lambda: model.simulate((0, 1e-3), method="dop853", progress=False))
t3 = time.perf_counter()
stages["emit"] = stages.get("emit", 0.0) + stages.pop("emit_eager", 0.0)
operations = getattr(model, "_operations", None) or model.operations    # (not building the on-demand kernels)
print(json.dumps(dict(stages, compile=t1 - t0, rhs=t2 - t1, kernels=kernels, run=t3 - t2 - sum(kernels.values()),
                      total=t3 - t0, from_cache=model.from_cache, ops=operations.get("rhs"))))
"""

#: A fresh process that imports numpy and numba only: the floor under any warm start, and a gauge of the load.
FLOOR_PROBE = "import json, numpy, numba; print(json.dumps({}))"

#: A fresh process that loads one trivial function from numba's cache (no lagcomp): the floor under any warm
#: start that runs numba-compiled code.  numba's first load from its cache sets up its target context (every
#: implementation registry, which imports scipy.linalg for BLAS), whatever the function.
CACHED_FLOOR_SOURCE = "import numba\n\n\n@numba.njit(cache=True)\ndef first(x):\n    return x + 1.0\n"
CACHED_FLOOR_PROBE = ("import json, sys; sys.path.insert(0, sys.argv[1]); import cached_floor; "
                      "cached_floor.first(1.0); "
                      "print(json.dumps({}))")

#: numba's fixed cost in a fresh process: its first compile (of a trivial function) sets up LLVM and the typing
#: context, which a cold start's first kernel pays whatever the model.
FIRST_COMPILE_PROBE = r"""
import json, time
import numba, numpy as np
first = numba.njit(lambda y: y[0])
y = np.ones(1)
t0 = time.perf_counter()
first(y)
print(json.dumps({"compile": time.perf_counter() - t0}))
"""

PYDY_PROBE = r"""
import json, sys, time
t0 = time.perf_counter()
from bench.systems import kane_chain
from pydy.codegen.ode_function_generators import generate_ode_function
km, q, u, constants = kane_chain(int(sys.argv[1]))
t1 = time.perf_counter()
generate_ode_function(km.forcing_full, q, u, constants, mass_matrix=km.mass_matrix_full, generator="cython")
t2 = time.perf_counter()
print(json.dumps({"derive": t1 - t0, "generate": t2 - t1, "total": t2 - t0}))
"""

JITCODE_PROBE = r"""
import json, time
t0 = time.perf_counter()
from bench.kernels import jitcode_f
jitcode_f()
print(json.dumps({"total": time.perf_counter() - t0}))
"""


def run_probe(args: list[str], timeout: float, env: dict | None = None) -> dict | str:
    """The JSON of the last stdout line of ``python -c *args`` with its wall time as "process" and its CPU time
    (user + system, the child's own: less sensitive to other jobs on a shared machine) as "process_cpu"; an error
    as text."""
    started, cpu_started = time.perf_counter(), _children_cpu()
    try:
        out = subprocess.run([sys.executable, "-c", *args], capture_output=True, text=True, timeout=timeout,
                             cwd=_root(), env=env)
    except subprocess.TimeoutExpired:
        return f"over the {timeout:.0f} s limit"
    if out.returncode:
        return f"failed: {out.stderr.strip().splitlines()[-1][:150] if out.stderr.strip() else out.returncode}"
    result = json.loads(out.stdout.strip().splitlines()[-1])
    result["process"] = time.perf_counter() - started
    result["process_cpu"] = _children_cpu() - cpu_started
    return result


def _children_cpu() -> float:
    """CPU seconds (user + system) of this process's finished children so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _root() -> str:
    from pathlib import Path

    return str(Path(__file__).resolve().parents[1])


def precompile(timeout: float, numba_cache_dir: str | None = None) -> dict | str:
    """`lagcomp precompile` in a fresh process (with NUMBA_CACHE_DIR = `numba_cache_dir` if given).

    {"modules": {module: (drivers, "compiled" or "loaded from numba's cache", s)}, "total": s of the
    modules, "process": s from interpreter start}; an error as text.
    """
    env = dict(os.environ, **({"NUMBA_CACHE_DIR": numba_cache_dir} if numba_cache_dir else {}))
    started = time.perf_counter()
    try:
        out = subprocess.run([sys.executable, "-c", PRECOMPILE], capture_output=True, text=True, timeout=timeout,
                             cwd=_root(), env=env)
    except subprocess.TimeoutExpired:
        return f"over the {timeout:.0f} s limit"
    if out.returncode:
        return f"failed: {out.stderr.strip().splitlines()[-1][:150] if out.stderr.strip() else out.returncode}"
    modules = {m[1]: (m[2], m[3], float(m[4])) for m in map(PRECOMPILE_LINE.match, out.stdout.splitlines()) if m}
    return {"modules": modules, "total": sum(v[2] for v in modules.values()),
            "process": time.perf_counter() - started}


def prepare(ctx) -> None:
    """What the compile section reports and the later sections use: the drivers' one-time compile, the
    drivers made ready in this run's environment, then each case's cold start (which fills this run's cache)."""
    print("<!-- one-time driver compile (fresh numba cache) ... -->", file=sys.stderr, flush=True)
    with tempfile.TemporaryDirectory(prefix="lagcomp-bench-numba-") as numba_cache_dir:
        ctx.driver_compile = precompile(10 * ctx.case_timeout, numba_cache_dir)
    ctx.drivers_ready = precompile(10 * ctx.case_timeout)
    for case in ctx.cases:
        print(f"<!-- cold start of {case} ... -->", file=sys.stderr, flush=True)
        ctx.cold[case] = cold(case, ctx.cache_dir, ctx.case_timeout)


def cold(case: str, cache_dir: str, timeout: float) -> dict | str:
    return run_probe([COLD_PROBE, case, cache_dir], timeout)


def warm(case: str, cache_dir: str, repeats: int) -> list[dict] | str:
    from bench.run import system_name

    runs = []
    for _ in range(repeats):
        r = run_probe([LOAD_PROBE, system_name(case), cache_dir, "dop853"], 120)
        if isinstance(r, str):
            return r
        runs.append(r)
    return runs


def cached_floor(repeats: int) -> list[float]:
    """Seconds of `repeats` fresh processes running `CACHED_FLOOR_PROBE`, after one that fills numba's cache."""
    with tempfile.TemporaryDirectory() as directory:
        with open(os.path.join(directory, "cached_floor.py"), "w") as f:
            f.write(CACHED_FLOOR_SOURCE)
        env = dict(os.environ, NUMBA_CACHE_DIR=os.path.join(directory, "numba"))
        runs = [run_probe([CACHED_FLOOR_PROBE, directory], 120, env) for _ in range(repeats + 1)][1:]
    return [r["process"] for r in runs if isinstance(r, dict)]


def _driver_rows(ctx, table: Table) -> None:
    """The one-time compile of the library drivers: total, then one row per module."""
    result = ctx.driver_compile
    target = ctx.target("drivers")
    if isinstance(result, str):
        table.add("library drivers", "one-time compile (`lagcomp precompile`, empty numba cache)", result, "", "")
        target.measured = result
        return
    compiled = sum(how == "compiled" for _, how, _ in result["modules"].values())
    table.add("library drivers", "one-time compile (`lagcomp precompile`, empty numba cache)", fmt(result["total"]), "",
              f"{compiled} of {len(result['modules'])} modules compiled; "
              f"whole process {result['process']:.1f} s; one run")
    for module, (names, how, seconds) in result["modules"].items():
        table.add("library drivers", f"`{module.rpartition('.')[2]}` ({names})", fmt(seconds), "", how)
    ready = ctx.drivers_ready
    if isinstance(ready, dict):
        again = sum(how == "compiled" for _, how, _ in ready["modules"].values())
        table.add("library drivers", "`lagcomp precompile` again, this run's numba cache (before the cold starts)",
                  fmt(ready["total"]), "", f"{again} of {len(ready['modules'])} modules compiled; "
                                           f"whole process {ready['process']:.2f} s")
    target.measured = f"{result['total']:.1f} s ({compiled} modules; whole process {result['process']:.1f} s)"
    target.met = None


def section(ctx) -> Table:
    table = Table(
        "Start-up: the drivers' one-time compile, cold and warm starts (fresh processes)",
        ["case", "what", "s", "× lagcomp cold start", "pieces"],
        note=__doc__.split("\n\n", 1)[1].strip().replace("\n", " "),
    )
    _driver_rows(ctx, table)
    for case, result in ctx.cold.items():
        key, limit, before = COLD_TARGETS.get(case, (None, None, None))
        if isinstance(result, str):
            table.add(case, "lagcomp cold start", result, "", "")
            if key:
                ctx.target(key).measured = result
                ctx.target(key).met = False if "limit" in result else None
            continue
        total = result["total"]
        pieces = ", ".join(f"{k} {result[k]:.2f}" for k in ("derive", "lower", "emit") if k in result)
        other = result["compile"] - sum(result.get(k, 0.0) for k in ("derive", "lower", "emit"))
        kernels = sorted(result["kernels"].items(), key=lambda item: -item[1])
        pieces += (f", cache+load {other:.2f}, numba rhs {result['rhs']:.2f}, numba other kernels of the run "
                   f"{sum(result['kernels'].values()):.2f} ({', '.join(f'{k} {v:.2f}' for k, v in kernels[:3])}"
                   f"{', ...' if len(kernels) > 3 else ''}), first dop853 run without them {result['run']:.2f} "
                   f"(ops {result.get('ops')}; whole process {result['process']:.1f} s; one run)")
        wanted = f"; target ≤ {limit:g} s ({before:g} s before issue 19)" if key else ""
        table.add(case, "lagcomp cold start: compile + first rhs + first dop853 run" + wanted, fmt(total), "1.00×",
                  pieces)
        if case == "double_pendulum":
            firsts = [run_probe([FIRST_COMPILE_PROBE], 120) for _ in range(3)]
            first = stat_of([r["compile"] for r in firsts if isinstance(r, dict)] or [float("nan")])
            table.add(case, "numba's fixed cost: its first compile in a fresh process (a trivial function)",
                      f"{fmt(first.median)} ({fmt(first.low)}–{fmt(first.high)})", f"{first.median / total:.3f}×",
                      f"paid by the first kernel of every cold start (here numba rhs); {len(firsts)} runs")
        if key:
            target = ctx.target(key)
            target.measured = f"{total:.2f} s ({pieces})"
            target.met = total <= limit
        runs = warm(case, ctx.cache_dir, ctx.repeats if case in ctx.warm_cases() else 0)
        if isinstance(runs, str):
            table.add(case, "lagcomp warm start (lagcomp.load in a fresh process)", runs, "", "")
        elif runs:
            process = stat_of([r["process"] for r in runs])
            load = stat_of([r["compile"] + r["first_run"] for r in runs])
            imported = stat_of([r["import"] for r in runs]).median
            outside = stat_of([r["process"] - r["import"] - r["compile"] - r["first_run"] for r in runs]).median
            sympy = any(r["sympy"] for r in runs)
            wanted = f"; target ≤ {WARM_TARGET:g} s" if case == "double_pendulum" else ""
            table.add(case, "lagcomp warm start: whole process (interpreter start, import, load, first run)" + wanted,
                      f"{fmt(process.median)} ({fmt(process.low)}–{fmt(process.high)})",
                      f"{process.median / total:.3f}×",
                      f"load + first run {load.median:.3f} s; import lagcomp {imported:.3f} s; interpreter start "
                      f"and exit {outside:.3f} s; "
                      f"sympy imported: {sympy}; {len(runs)} runs")
            if case == "double_pendulum":
                floors = [run_probe([FLOOR_PROBE], 120) for _ in runs]
                floor = stat_of([r["process"] for r in floors if isinstance(r, dict)] or [float("nan")])
                table.add(case, "floor: a fresh process importing numpy and numba only (no lagcomp)",
                          f"{fmt(floor.median)} ({fmt(floor.low)}–{fmt(floor.high)})", f"{floor.median / total:.3f}×",
                          f"the warm start is {process.median / floor.median:.2f}× this; {len(floors)} runs")
                cached = stat_of(cached_floor(len(runs)) or [float("nan")])
                table.add(case, "floor: a fresh process loading one trivial function from numba's cache (no lagcomp)",
                          f"{fmt(cached.median)} ({fmt(cached.low)}–{fmt(cached.high)})",
                          f"{cached.median / total:.3f}×",
                          f"the warm start is {process.median / cached.median:.2f}× this; {len(runs)} runs")
                cpu = stat_of([r["process_cpu"] for r in runs]).median
                table.add(case, "new model vs warm start: CPU of the whole cold process over the warm one's "
                                f"(issue 35: ≤ {NEW_OVER_WARM_TARGET:g}×)",
                          f"{result['process_cpu']:.2f} / {cpu:.2f}", f"{result['process_cpu'] / cpu:.2f}× warm",
                          "fresh processes from interpreter start; the cold one compiles the model into an empty "
                          "cache and runs dop853, the warm one loads it by name and runs dop853")
                target = ctx.target("warm")
                target.measured = (f"{process.median:.2f} s (min {process.low:.2f}; import lagcomp {imported:.2f} s; "
                                   f"importing numpy and numba alone {floor.median:.2f} s; loading one function from "
                                   f"numba's cache alone {cached.median:.2f} s), sympy imported: {sympy}")
                target.met = process.median <= WARM_TARGET and not sympy
        if case in ctx.peer_compile_cases():
            n = 2 if case == "double_pendulum" else int(case.rsplit("_", 1)[1])
            if ctx.peer("pydy") is None or ctx.peer("Cython") is None:
                table.add(case, "PyDy Kane + cython", ctx.skipped, "", "")
            else:
                r = run_probe([PYDY_PROBE, str(n)], ctx.case_timeout)
                if isinstance(r, str):
                    table.add(case, "PyDy Kane + cython", r, "", "")
                else:
                    table.add(case, "PyDy: KanesMethod derivation + cython ODE function", fmt(r["total"]),
                              f"{r['total'] / total:.2f}×",
                              f"derive {r['derive']:.2f}, generate+compile {r['generate']:.2f}; one run")
            if case == "double_pendulum":
                if ctx.peer("jitcode") is None:
                    table.add(case, "JiTCODE", ctx.skipped, "", "")
                else:
                    r = run_probe([JITCODE_PROBE], ctx.case_timeout)
                    if isinstance(r, str):
                        table.add(case, "JiTCODE", r, "", "")
                    else:
                        table.add(case, "JiTCODE: reduced ODE → C, compiled", fmt(r["total"]),
                                  f"{r['total'] / total:.2f}×", "hand-reduced ODE given; one run")
    return table
