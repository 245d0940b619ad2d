"""Kinematic trees (issue 39, first step): cold compile and rhs cost of planar n-link chains built as lc.Tree.

For each n, a fresh process with an empty lagcomp cache (so numba compiles ``rhs`` too) measures the CPU time of
``lc.compile(tree)`` plus the first ``rhs`` call, its peak memory, the op count of ``rhs``, then ns per ``rhs`` call in
a compiled loop (`lagcomp.benchmark.looped`) and, when ``pin`` is installed, Pinocchio's ABA called from Python on
the same chain (a Python call per evaluation: not the C++ loop issue 39 compares against, a later step), with the
largest relative difference of q̈ between the two.

    python -m bench.bench_multibody [8 16 32 50 100]
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

CHILD = r'''
import json, resource, sys, time
import numpy as np
sys.path.insert(0, "tests")
start = time.process_time()
import lagcomp as lc
import multibody_models as mm
n = int(sys.argv[1])
tree = mm.planar_chain(n)
model = lc.compile(tree, progress=False)
built = time.process_time() - start
rng = np.random.default_rng(n)
values = {name: float(rng.uniform(0.5, 1.5)) for name in model.parameters} | {"g": 9.81}
p = model.parameter_vector(values)
y = rng.normal(size=2 * n) * 0.5
out = np.empty(2 * n)
model.kernels.rhs(0.0, y, p, out)
first = time.process_time() - start
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
from lagcomp.benchmark import looped
loop = looped(model.kernels.rhs)
loop(y.copy(), p, out, 10)
calls = max(2000, 2_000_000 // n)
times = []
for _ in range(5):
    s = time.perf_counter()
    loop(y.copy(), p, out, calls)
    times.append(time.perf_counter() - s)
best = min(times)
result = {"n": n, "ops": model._operations["rhs"],   # (eager only: `operations` would build the Jacobians)
          "build_s": built, "first_rhs_s": first, "peak_mb": peak,
          "rhs_ns": best / calls * 1e9}
try:
    import pinocchio as pin
except ImportError:
    pin = None
if pin is not None:
    ref = mm.pinocchio_model(tree, values)
    data = ref.createData()
    q, v = y[:n].copy(), y[n:].copy()
    model.kernels.rhs(0.0, y, p, out)
    a = pin.aba(ref, data, q, v, np.zeros(n))
    result["max_rel_diff"] = float(np.max(np.abs(out[n:] - a)) / np.max(np.abs(a)))
    tau = np.zeros(n)
    reps = 20000
    s = time.perf_counter()
    for _ in range(reps):
        pin.aba(ref, data, q, v, tau)
    result["pin_python_ns"] = (time.perf_counter() - s) / reps * 1e9
print(json.dumps(result))
'''


def measure(n: int) -> dict:
    """One cold measurement of the n-link chain in a fresh process and cache."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, LAGCOMP_CACHE_DIR=cache)
        done = subprocess.run([sys.executable, "-c", CHILD, str(n)], env=env, capture_output=True, text=True,
                              check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(sizes) -> None:
    print("| links | ops of rhs | compile (CPU s) | + first rhs (CPU s) | peak MB | rhs ns (loop) | "
          "Pinocchio ABA from Python, ns | max rel. diff of q̈ |")
    print("|---|---|---|---|---|---|---|---|")
    for n in sizes:
        r = measure(n)
        print(f"| {n} | {r['ops']} | {r['build_s']:.1f} | {r['first_rhs_s']:.1f} | {r['peak_mb']:.0f} | "
              f"{r['rhs_ns']:.0f} | {r.get('pin_python_ns', float('nan')):.0f} | {r.get('max_rel_diff', float('nan')):.1e} |",
              flush=True)


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [8, 16, 32, 50, 100])
