"""DESIGN's two ways to call the kernels from cached drivers, measured on lagcomp's own RK4 driver.

    python -m bench.bench_shared_driver [--cases double_pendulum n_link_pendulum_10] [--steps 200000]

(a) is what lagcomp does: the drivers are appended to every generated module
and call ``rhs`` as a module global, so numba links the kernel into each
driver and optimizes it there again, once per model and driver.  (b) is one
driver for all models: the same text of ``rk4_run`` with ``rhs``,
``project`` and ``constraint_residual`` as arguments of type
``numba.types.FunctionType``, compiled eagerly from an explicit signature and
cached once per installation (a later process loads it even for another
model: the signature does not name the kernel), at the price of an indirect
call per evaluation.

Each case runs in a fresh process with an empty lagcomp cache and an empty
numba cache, in this order: import the shared driver (its compile: paid once
per installation), compile the model, the first call of ``rhs`` (its
numba compile, both ways), the first RK4 run through the module's
``rk4_run`` (a) and through the shared driver (b); then steps/s of both on
the same run.  Printed as a markdown table.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import textwrap

HEADER = textwrap.dedent('''
    """rk4_run of templates/drivers.py with its kernels as first-class function arguments (bench probe)."""
    from numba import types

    KERNEL = types.FunctionType(types.int64(types.float64, types.float64[::1], types.float64[::1],
                                            types.float64[::1]))
    PROJECT = types.FunctionType(types.int64(types.float64, types.float64[::1], types.float64[::1]))
    RESIDUAL = types.FunctionType(types.float64(types.float64, types.float64[::1], types.float64[::1]))
    VECTOR, MATRIX, INT, FLOAT = types.float64[::1], types.float64[:, ::1], types.int64, types.float64
    SIGNATURE = types.UniTuple(types.int64, 2)(KERNEL, PROJECT, RESIDUAL, VECTOR, VECTOR, types.int64[::1], VECTOR,
                                               INT, VECTOR, FLOAT, FLOAT, INT, INT, FLOAT, INT, VECTOR, MATRIX)
''')


def shared_source() -> str:
    """The shared driver's module: the drivers template, and rk4_run again with its kernels as arguments."""
    from lagcomp.codegen.templating import template

    text = template("drivers", events=False)
    start = text.rindex("@njit", 0, text.index("def rk4_run("))
    end = text.index("@njit", text.index("def rk4_run("))
    shared = text[start:end].replace("@njit(cache=True", "@njit(SIGNATURE, cache=True").replace(
        "def rk4_run(y,", "def rk4_run_shared(rhs, project, constraint_residual, y,")
    return HEADER + text + "\n\n" + shared


PROBE = textwrap.dedent('''
    import json, sys, time
    import numpy as np
    started = time.perf_counter()
    sys.path.insert(0, sys.argv[3])
    import shared_rk4
    shared_import = time.perf_counter() - started

    import lagcomp as lc
    from bench.run import build_system

    model = lc.compile(build_system(sys.argv[1]), cache_dir=sys.argv[2])
    k = model.kernels
    y0 = model.initial_state()
    y0[: model.n] = 0.5
    p = model.parameter_vector()
    steps = int(sys.argv[4])

    def module_run(n):
        y, clock, counters = y0.copy(), np.zeros(2), np.zeros(6, dtype=np.int64)
        k.rk4_run(y, clock, counters, p, 0, np.array([0.0, np.inf]), 0.0, 1e-3, n, n + 1, n * 1e-3, n,
                  np.empty(2), np.empty((2, y.size)))
        return y

    def shared_run(n):
        y, clock, counters = y0.copy(), np.zeros(2), np.zeros(6, dtype=np.int64)
        shared_rk4.rk4_run_shared(k.rhs, k.project, k.constraint_residual, y, clock, counters, p, 0,
                                  np.array([0.0, np.inf]), 0.0, 1e-3, n, n + 1, n * 1e-3, n, np.empty(2),
                                  np.empty((2, y.size)))
        return y

    out = {"shared_import": shared_import}
    t = time.perf_counter(); k.rhs(0.0, y0, p, np.empty(y0.size)); out["rhs"] = time.perf_counter() - t
    t = time.perf_counter(); module_run(10); out["module_driver"] = time.perf_counter() - t
    t = time.perf_counter(); shared_run(10); out["shared_driver"] = time.perf_counter() - t
    assert np.array_equal(module_run(1000), shared_run(1000)), "the two drivers differ"
    for name, run in (("module_rate", module_run), ("shared_rate", shared_run)):
        best = np.inf
        for _ in range(5):
            t = time.perf_counter(); run(steps); best = min(best, time.perf_counter() - t)
        out[name] = steps / best
    print(json.dumps(out))
''')


def probe(case: str, steps: int, shared_dir: str) -> dict:
    with tempfile.TemporaryDirectory() as cache_dir, tempfile.TemporaryDirectory() as numba_cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": numba_cache}
        env.pop("LAGCOMP_CACHE_DIR", None)
        out = subprocess.run([sys.executable, "-c", PROBE, case, cache_dir, shared_dir, str(steps)], env=env,
                             capture_output=True, text=True, check=True)
        return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", default=["double_pendulum", "n_link_pendulum_10"])
    parser.add_argument("--steps", type=int, default=200_000)
    args = parser.parse_args()
    print("| case | shared driver compile (once per installation) | rhs compile | (a) module rk4_run compile "
          "| (b) shared driver, first call | (a) steps/s | (b) steps/s | (b)/(a) |")
    print("|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as shared_dir:
        with open(os.path.join(shared_dir, "shared_rk4.py"), "w") as f:
            f.write(shared_source())
        for case in args.cases:
            r = probe(case, args.steps, shared_dir)
            print(f"| {case} | {r['shared_import']:.2f} s | {r['rhs']:.2f} s | {r['module_driver']:.2f} s | "
                  f"{r['shared_driver']:.3f} s | {r['module_rate']:.3g} | {r['shared_rate']:.3g} | "
                  f"{r['shared_rate'] / r['module_rate']:.2f} |")


if __name__ == "__main__":
    main()
