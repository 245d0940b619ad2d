"""`lagcomp bench NAME`: how fast one compiled model is, without peers.

Reports, for a bundled example or a model compiled earlier under NAME:

- kernel cost of `rhs` in ns per call, inside a compiled loop (what the
  integrators see) and called from Python;
- the operation count after CSE of each kernel;
- steps per second of every method that applies (fixed-step methods at
  `dt` for `steps` steps, adaptive ones over the model's run length at
  rtol = atol = 1e-10), with each driver's first-call (numba) time;
- compile times: this process's compile or load; for a bundled example, a
  cold start in a fresh process with an empty cache, up to the first dop853
  result (derivation, then lowering + emission + cache write, numba's compile
  of `rhs`, of the other kernels that run needs, and the run itself); each
  driver's numba time (a compile on first use, else a load from numba's cache)
  shows in its method's first call.

Times are medians of `repeats` runs with (min–max); this machine's load
moves them, so compare models within one report rather than across runs.
`python -m bench` in the repository runs the comparisons against peers.
"""

from __future__ import annotations

import statistics
import tempfile
import time

import numpy as np


def looped(rhs):
    """An @njit loop making `n` calls of `rhs(t, y, p, out)`, nudging y[0] so no call can be hoisted."""
    import numba

    @numba.njit
    def loop(y, p, out, n):
        acc = 0.0
        for _ in range(n):
            y[0] += 1e-12
            rhs(0.0, y, p, out)
            acc += out[out.shape[0] - 1]
        return acc

    return loop


def _median(run, repeats: int, per_call: int = 1) -> tuple[float, float, float]:
    times = []
    for _ in range(max(repeats, 1)):
        start = time.perf_counter()
        run()
        times.append((time.perf_counter() - start) / per_call)
    return statistics.median(times), min(times), max(times)


def kernel_cost(model, repeats: int = 5, calls: int = 200_000, inputs: dict | None = None) -> dict:
    """ns per `rhs` call in a compiled loop and from Python: {"loop": (median, min, max), "python": ...}.

    A model with inputs (`Model.inputs`) needs their signals in `inputs` (as `simulate` takes them), over
    (0, t_end)."""
    y0 = model.initial_state()
    p = model.parameter_vector(inputs=inputs, span=(0.0, model.t_end)) if inputs else model.parameter_vector()
    out = np.empty(y0.size)
    loop = looped(model.kernels.rhs)
    loop(y0.copy(), p, out, 10)
    in_loop = _median(lambda: loop(y0.copy(), p, out, calls), repeats, calls)
    rhs, few = model.kernels.rhs, max(calls // 100, 100)

    def python():
        for _ in range(few):
            rhs(0.0, y0, p, out)
    python()
    from_python = _median(python, repeats, few)
    return {"loop": tuple(1e9 * v for v in in_loop), "python": tuple(1e9 * v for v in from_python)}


def applicable_methods(model) -> list:
    """The registry's methods that `model` accepts: those `lagcomp.integrate.options.check_method` does not refuse
    (separable-only, holonomic-separable-only, unconstrained-only, a Taylor kernel, and a Kane model's state (q, u)),
    nor a kinematic tree's model (`lagcomp.Tree`) for a kernel it does not have (a ModelError: the Taylor kernel)."""
    from lagcomp.errors import ModelError, OptionError
    from lagcomp.integrate.methods import METHODS
    from lagcomp.integrate.options import check_method

    accepted = []
    for m in METHODS.values():
        try:
            check_method(model, m)
        except (OptionError, ModelError):
            continue
        accepted.append(m)
    return accepted


def method_speed(model, method, repeats: int = 5, dt: float = 1e-3, steps: int = 100_000, rtol: float = 1e-10,
                 inputs: dict | None = None) -> dict:
    """Steps/s of one method; the first call's extra time (numba compiling or loading the driver).  `inputs`:
    the model's input signals (`simulate`'s ``inputs``), covering the run's span."""
    if method.adaptive:
        options = dict(rtol=max(rtol, method.rtol_min), atol=max(rtol, method.rtol_min))
        span = (0.0, model.t_end)
    else:
        options = dict(dt=dt, save_every=max(steps // 100, 1))
        span = (0.0, steps * dt)
    result = {}

    def run():
        result["sol"] = model.simulate(span, method=method.name, progress=False, **options,
                                       **({"inputs": inputs} if inputs else {}))
    start = time.perf_counter()
    run()
    first = time.perf_counter() - start
    median, low, high = _median(run, repeats)
    sol = result["sol"]
    nsteps = max(int(sol.nsteps), 1)
    return {"method": method.name, "setting": ", ".join(f"{k} {v:g}" for k, v in options.items() if k != "save_every"),
            "steps": nsteps, "status": int(sol.status), "steps_per_s": (nsteps / median, nsteps / high, nsteps / low),
            "first_call": first, "numba": max(first - median, 0.0)}


def numba_compiles(run) -> tuple[object, dict[str, float]]:
    """``run()``, and the seconds numba spent compiling during it per function compiled at the top level: {name: s}.

    A function compiled because another one calls it counts in its caller's time; a function loaded
    from numba's cache is no compile and does not appear (nor does writing the cache files).  Read
    from numba's event API (``numba:compile``).
    """
    from numba.core import event

    with event.install_recorder("numba:compile") as recorder:
        result = run()
    seconds, depth, started = {}, 0, 0.0
    for timestamp, happened in recorder.buffer:
        if happened.is_start:
            started = timestamp if depth == 0 else started
            depth += 1
            continue
        depth -= 1
        if depth == 0:
            name = happened.data["dispatcher"].py_func.__name__
            seconds[name] = seconds.get(name, 0.0) + timestamp - started
    return result, seconds


COLD_PROBE = r"""
import json, sys, time
import numpy as np
from lagcomp import examples
from lagcomp.benchmark import numba_compiles
from lagcomp.mechanics.lagrange import derive
from lagcomp.runtime import compile
system = examples.get(sys.argv[1], **json.loads(sys.argv[2]))
t0 = time.perf_counter()
eom = derive(system)
t1 = time.perf_counter()
model = compile(system, cache_dir=sys.argv[3], eom=eom)
t2 = time.perf_counter()
y, p = model.initial_state(), model.parameter_vector()
model.kernels.rhs(0.0, y, p, np.empty(y.size))
t3 = time.perf_counter()
_, kernels = numba_compiles(lambda: model.simulate((0.0, 1e-3), method="dop853", progress=False))
t4 = time.perf_counter()
print(json.dumps({"derive": t1 - t0, "lower + emit + cache": t2 - t1, "numba rhs": t3 - t2,
                  "numba, other kernels of the first dop853 run": sum(kernels.values()),
                  "first dop853 run, without those": t4 - t3 - sum(kernels.values()), "total": t4 - t0}))
"""


def cold_compile(example: str, arguments: dict | None = None, timeout: float = 600) -> dict:
    """Seconds of each stage of a cold start of a bundled example: new model → first dop853 result.

    In a fresh process with an empty model cache, because in this one the
    example's module (and its numba code) may be loaded already.  The
    drivers come from numba's cache (`lagcomp precompile`; on a fresh
    installation the first run compiles its driver once, and it shows in the
    last stage).
    """
    import json
    import subprocess
    import sys

    with tempfile.TemporaryDirectory(prefix="lagcomp-bench-") as cache_dir:
        out = subprocess.run([sys.executable, "-c", COLD_PROBE, example, json.dumps(arguments or {}), cache_dir],
                             capture_output=True, text=True, timeout=timeout, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _stat(values, unit: str = "", digits: int = 3) -> str:
    median, low, high = values
    return f"{median:.{digits}g}{unit} ({low:.{digits}g}–{high:.{digits}g})"


def report(model, *, example: tuple[str, dict] | None = None, load_seconds: float | None = None, repeats: int = 5,
           dt: float = 1e-3, steps: int = 100_000, methods=None, cold: bool = True, inputs: dict | None = None) -> str:
    """The markdown report of `lagcomp bench` for `model`.

    `example` = (name, factory arguments) of a bundled example, for the cold
    compile; `methods` restricts the methods timed (default: every applicable one);
    `inputs` the model's input signals (`simulate`'s ``inputs``).
    """
    lines = [f"# {model.name}: n = {model.n}, {model.k} constraint(s), {len(model.parameters)} parameter(s)", ""]
    cost = kernel_cost(model, repeats, inputs=inputs)
    rhs_ops = model.operations.get("rhs", 0)
    lines += ["| kernel cost | ns/call, median (min–max) |", "|---|---|",
              f"| rhs in a compiled loop | {_stat(cost['loop'])} |",
              f"| rhs from Python | {_stat(cost['python'])} |", "",
              f"rhs: {rhs_ops} operations after CSE, {rhs_ops / cost['loop'][0]:.2f} GFLOP/s in the loop.", "",
              "| kernel | operations after CSE |", "|---|---|"]
    lines += [f"| {name} | {count} |" for name, count in model.operations.items()]
    lines += ["", "| method | setting | steps | steps/s, median (min–max) | first call s (numba) | status |",
              "|---|---|---|---|---|---|"]
    for method in applicable_methods(model):
        if methods and method.name not in methods:
            continue
        try:
            r = method_speed(model, method, repeats, dt, steps, inputs=inputs)
        except Exception as err:  # a method that cannot run this model is reported, not fatal
            lines.append(f"| {method.name} | | | failed: {type(err).__name__}: {str(err)[:100]} | | |")
            continue
        lines.append(f"| {r['method']} | {r['setting']} | {r['steps']} | {_stat(r['steps_per_s'])} | "
                     f"{r['first_call']:.2f} ({r['numba']:.2f}) | {r['status']} |")
    lines += ["", "| compile | s |", "|---|---|"]
    if load_seconds is not None:
        lines.append(f"| this process: compile/load ({'from cache' if model.from_cache else 'built'}) | {load_seconds:.3f} |")
    if cold and example is not None:
        for stage, seconds in cold_compile(*example).items():
            lines.append(f"| cold (fresh process, empty cache), {stage} | {seconds:.2f} |")
    elif example is None:
        lines.append("| cold | not measured: not a bundled example |")
    lines += ["", f"Medians of {repeats} runs; driver compile times are in the methods' first calls."]
    return "\n".join(lines) + "\n"
