"""Kinematic trees (issue 39): cold compile and rhs cost of n-link chains built as lc.Tree, and how they grow.

For each n, a fresh process with an empty lagcomp cache (so numba compiles ``rhs`` too) measures the CPU time of
``lc.compile(tree)`` plus the first ``rhs`` call, its peak memory, the operations of ``rhs`` (those numba compiles:
a step the links repeat counts once, `lagcomp.codegen.outline`; and those one call evaluates), then ns per ``rhs``
call in a compiled loop (`lagcomp.benchmark.looped`) and, when ``pin`` is installed, Pinocchio's ABA called from
Python on the same chain (a Python call per evaluation: not the C++ loop issue 39 compares against) with the
largest relative difference of q̈ between the two.  Last, the exponents k of cost ~ n^k fitted over the sizes
(least squares on the logarithms).

    python -m bench.bench_multibody [planar|universal|spherical] [8 16 32 50 100]

The chains are `lagcomp.examples.trees`' ``planar_chain`` (links hinged about z), ``universal_chain`` (3D
links on universal joints: two DOF each) and ``spherical_chain`` (3D links on ball joints: three MRPs each; in
Pinocchio ``JointModelSpherical``, the states converted by `lagcomp.multibody.pinocchio_peer.tree_state`).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

import numpy as np

CHILD = r'''
import json, resource, sys, time
import numpy as np
start = time.process_time()
import lagcomp as lc
from lagcomp.examples import trees
kind, n = sys.argv[1], int(sys.argv[2])
tree = getattr(trees, f"{kind}_chain")(n)
model = lc.compile(tree, progress=False)
built = time.process_time() - start
rng = np.random.default_rng(n)
values = {name: float(rng.uniform(0.5, 1.5)) for name in model.parameters} | {"g": 9.81}
p = model.parameter_vector(values)
dof = tree.n
y = rng.normal(size=2 * dof) * 0.5
out = np.empty(2 * dof)
model.kernels.rhs(0.0, y, p, out)
first = time.process_time() - start
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
from lagcomp.codegen.outline import evaluated_operations
from lagcomp.codegen.tree_lower import lower_tree
rhs_ir = next(k for k in lower_tree(tree).kernels if k.name == "rhs")
from lagcomp.benchmark import looped
loop = looped(model.kernels.rhs)
loop(y.copy(), p, out, 10)
calls = max(2000, 2_000_000 // dof)
times = []
for _ in range(5):
    s = time.perf_counter()
    loop(y.copy(), p, out, calls)
    times.append(time.perf_counter() - s)
result = {"n": n, "dof": dof, "ops": model._operations["rhs"],   # (eager only: `operations` would build the Jacobians)
          "evaluated": evaluated_operations(rhs_ir),
          "build_s": built, "first_rhs_s": first, "peak_mb": peak, "rhs_ns": min(times) / calls * 1e9}
try:
    import pinocchio as pin
except ImportError:
    pin = None
if pin is not None:
    from lagcomp.multibody.pinocchio_peer import pinocchio_model, tree_state
    ref = pinocchio_model(tree, values)
    data = ref.createData()
    q, v, tau, back = tree_state(ref, tree, values, y)
    model.kernels.rhs(0.0, y, p, out)
    a = back(pin.aba(ref, data, q, v, tau))
    result["max_rel_diff"] = float(np.max(np.abs(out[dof:] - a)) / np.max(np.abs(a)))
    reps = 20000
    s = time.perf_counter()
    for _ in range(reps):
        pin.aba(ref, data, q, v, tau)
    result["pin_python_ns"] = (time.perf_counter() - s) / reps * 1e9
print(json.dumps(result))
'''


def measure(kind: str, n: int) -> dict:
    """One cold measurement of the n-link chain in a fresh process and cache."""
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, LAGCOMP_CACHE_DIR=cache)
        done = subprocess.run([sys.executable, "-c", CHILD, kind, str(n)], env=env, capture_output=True, text=True,
                              check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def exponent(sizes, values) -> float:
    """k of values ~ sizes^k, by least squares on the logarithms."""
    return float(np.polyfit(np.log(sizes), np.log(values), 1)[0])


def main(kind: str, sizes) -> None:
    print(f"{kind} chains: | links | DOF | ops of rhs (compiled) | ops of rhs (evaluated) | compile (CPU s) | "
          "+ first rhs (CPU s) | peak MB | rhs ns (loop) | Pinocchio ABA from Python, ns | max rel. diff of q̈ |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    rows = []
    for n in sizes:
        r = measure(kind, n)
        rows.append(r)
        print(f"| {n} | {r['dof']} | {r['ops']} | {r['evaluated']} | {r['build_s']:.1f} | {r['first_rhs_s']:.1f} | "
              f"{r['peak_mb']:.0f} | {r['rhs_ns']:.0f} | {r.get('pin_python_ns', float('nan')):.0f} | "
              f"{r.get('max_rel_diff', float('nan')):.1e} |", flush=True)
    if len(rows) > 1:
        n = [r["n"] for r in rows]
        fits = {"ops compiled": [r["ops"] for r in rows], "ops evaluated": [r["evaluated"] for r in rows],
                "compile + first rhs": [r["first_rhs_s"] for r in rows], "rhs ns": [r["rhs_ns"] for r in rows]}
        print("growth over n = " + ", ".join(map(str, n)) + ": "
              + ", ".join(f"{name} ~ n^{exponent(n, values):.2f}" for name, values in fits.items()))


if __name__ == "__main__":
    args = sys.argv[1:]
    chain = args.pop(0) if args and not args[0].isdigit() else "planar"
    main(chain, [int(a) for a in args] or [8, 16, 32, 50, 100])
