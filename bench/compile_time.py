"""Compile time, cold and warm, each in a fresh process; PyDy and JiTCODE building the same system.

Cold (empty cache): `lagcomp.compile` split into derivation, lowering (CSE),
emission and the rest (cache write, module load), then numba's compilation
of `rhs` (first call) and of the dop853 driver (a first short run).  The
pieces are timed by wrapping lagcomp's own stage functions, so they follow
the pipeline as it is.  Warm: a later fresh process that loads the model by
name (`lagcomp.load`, no sympy) and runs it, from interpreter start: the warm
start a user sees (`bench/bench_compile.py` has the three-process version).
Each case runs under a time limit; a case that exceeds it is reported, not
waited for.  Ratios: against lagcomp's cold end-to-end time of the same case.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time

from bench.bench_compile import LOAD_PROBE
from bench.harness import Table, fmt, stat_of

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
system = build_system(sys.argv[1])
t0 = time.perf_counter()
model = lc.compile(system, cache_dir=sys.argv[2])
t1 = time.perf_counter()
import numpy as np
y, p = model.initial_state(), model.parameter_vector()
model.kernels.rhs(0.0, y, p, np.empty(y.size))
t2 = time.perf_counter()
model.simulate((0, 1e-3), method="dop853", progress=False)
t3 = time.perf_counter()
print(json.dumps(dict(stages, compile=t1 - t0, rhs=t2 - t1, driver=t3 - t2, total=t3 - t0,
                      from_cache=model.from_cache, ops=model.operations.get("rhs"))))
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


def run_probe(args: list[str], timeout: float) -> dict | str:
    started = time.perf_counter()
    try:
        out = subprocess.run([sys.executable, "-c", *args], capture_output=True, text=True, timeout=timeout,
                             cwd=_root())
    except subprocess.TimeoutExpired:
        return f"over the {timeout:.0f} s limit"
    if out.returncode:
        return f"failed: {out.stderr.strip().splitlines()[-1][:150] if out.stderr.strip() else out.returncode}"
    result = json.loads(out.stdout.strip().splitlines()[-1])
    result["process"] = time.perf_counter() - started
    return result


def _root() -> str:
    from pathlib import Path

    return str(Path(__file__).resolve().parents[1])


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


def section(ctx) -> Table:
    table = Table(
        "Compile time, cold and warm (fresh processes)",
        ["case", "what", "s", "× lagcomp cold end to end", "pieces"],
        note=__doc__.split("\n\n", 1)[1].strip().replace("\n", " "),
    )
    for case, result in ctx.cold.items():
        if isinstance(result, str):
            table.add(case, "lagcomp cold", result, "", "")
            continue
        total = result["total"]
        pieces = ", ".join(f"{k} {result[k]:.2f}" for k in ("derive", "lower", "emit") if k in result)
        other = result["compile"] - sum(result.get(k, 0.0) for k in ("derive", "lower", "emit"))
        pieces += f", cache+load {other:.2f}, numba rhs {result['rhs']:.2f}, numba dop853 driver {result['driver']:.2f}"
        table.add(case, "lagcomp cold: compile + first rhs + first dop853 run", fmt(total), "1.00×",
                  pieces + f" (ops {result.get('ops')}; one run)")
        runs = warm(case, ctx.cache_dir, ctx.repeats if case in ctx.warm_cases() else 0)
        if isinstance(runs, str):
            table.add(case, "lagcomp warm (lagcomp.load in a fresh process)", runs, "", "")
        elif runs:
            process = stat_of([r["process"] for r in runs])
            load = stat_of([r["compile"] + r["first_run"] for r in runs])
            sympy = any(r["sympy"] for r in runs)
            table.add(case, "lagcomp warm: whole process (interpreter start, import, load, first run)",
                      f"{fmt(process.median)} ({fmt(process.low)}–{fmt(process.high)})",
                      f"{process.median / total:.3f}×",
                      f"load + first run {load.median:.3f} s; import lagcomp {stat_of([r['import'] for r in runs]).median:.3f} s; "
                      f"sympy imported: {sympy}; {len(runs)} runs")
            if case == "double_pendulum":
                target = ctx.target("warm")
                target.measured = f"{process.median:.2f} s (min {process.low:.2f}), sympy imported: {sympy}"
                target.met = process.median <= 1.0 and not sympy
        for n_links, key in ((10, "cold10"), (24, "cold24")):
            if case == f"n_link_pendulum_{n_links}":
                target = ctx.target(key)
                limit = 6.0 if n_links == 10 else 60.0
                without_driver = total - result["driver"]
                target.measured = (f"{total:.1f} s with the first dop853 run, {without_driver:.1f} s to a callable "
                                   f"rhs ({pieces})")
                target.met = total <= limit
                if not target.met and without_driver <= limit:
                    target.verdict = "missed with the dop853 driver's numba compile; met without it"
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
                              f"{r['total'] / total:.2f}×", f"derive {r['derive']:.2f}, generate+compile {r['generate']:.2f}; one run")
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
    for key in ("cold10", "cold24"):
        target = ctx.target(key)
        if target.met is None:
            case = "n_link_pendulum_10" if key == "cold10" else "n_link_pendulum_24"
            result = ctx.cold.get(case)
            if isinstance(result, str):
                target.measured = f"{case}: {result}"
                target.met = False if "limit" in result else None
    return table
