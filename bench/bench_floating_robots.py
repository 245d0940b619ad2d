"""Floating-base robots from URDF (issue 39): cold compile, q̈ against Pinocchio's free flyer, rhs per call.

    PYTHONPATH=src:. python -m bench.bench_floating_robots [--robots solo12 talos] [--smoke]

Each robot of example-robot-data is read by ``lc.from_urdf(path, floating_base=True)`` (the root link on an
``lc.Free`` joint) and compiled in a fresh process with an empty cache: the CPU seconds from the import of lagcomp
to the first rhs, and the peak memory.  Then q̈ against Pinocchio's ABA of ``buildModelFromUrdf(path,
JointModelFreeFlyer())`` at 5 random states (`lagcomp.multibody.pinocchio_peer.free_flyer_accelerations`), and
ns per rhs call in a compiled loop beside ns per ``pin.aba`` called from Python, both at the robot's neutral
state at rest (which includes Python's call overhead: no ratio is printed).  The ratios against Pinocchio's ABA
in its C++ loop and MuJoCo's ``mj_forward`` are `python -m bench.bench_scale --systems solo12 talos`'s (the same
robots, the same conversions).  Issue 39's target: a floating-base robot with 30+ joints compiled in ≤ 60 s.
Needs pin and example-robot-data.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

from bench import bench_scale

#: The floating-base robots of `bench.bench_scale.ROBOTS`.
ROBOTS = [robot for robot, (_, floating) in bench_scale.ROBOTS.items() if floating]

PROBE = r"""
import json, resource, sys, time
start = time.process_time()
import numpy as np
import lagcomp as lc
tree = lc.from_urdf(sys.argv[1], floating_base=True)
model = lc.compile(tree, cache_dir=sys.argv[2], progress=False)
model.rhs(0.0, np.zeros(2 * model.n))
compile_cpu = time.process_time() - start
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
import pinocchio as pin
from lagcomp.benchmark import looped
from lagcomp.multibody.pinocchio_peer import free_flyer_accelerations
reference = pin.buildModelFromUrdf(sys.argv[1], pin.JointModelFreeFlyer())
data = reference.createData()
rng, worst = np.random.default_rng(0), 0.0
for _ in range(5):
    q, v = rng.uniform(-1, 1, model.n), rng.uniform(-1, 1, model.n)
    q[3:6] = rng.uniform(-0.5, 0.5, 3)
    got = model.rhs(0.0, np.concatenate([q, v]))[model.n:]
    expected = free_flyer_accelerations(pin, reference, data, model.coordinates, q, v)
    worst = max(worst, float(np.max(np.abs(got - expected)) / np.max(np.abs(expected))))
p, out, y = model.parameter_vector(), np.empty(2 * model.n), np.zeros(2 * model.n)   # Pinocchio's neutral state, at rest
loop, calls = looped(model.kernels.rhs), 20000
def best(run):
    run()
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        run()
        times.append(time.perf_counter() - t0)
    return min(times) / calls * 1e9
qp, vp, tau = pin.neutral(reference), np.zeros(reference.nv), np.zeros(reference.nv)
print(json.dumps({"n": model.n, "ops": model._operations["rhs"], "compile_cpu_s": compile_cpu, "peak_mb": peak,
                  "rel_diff": worst, "lagcomp_ns": best(lambda: loop(y.copy(), p, out, calls)),
                  "pin_python_ns": best(lambda: [pin.aba(reference, data, qp, vp, tau) for _ in range(calls)])}))
"""


def measure(robot: str) -> dict | str:
    """The probe's figures for `robot` in a fresh process and cache, or why not."""
    try:
        path = bench_scale.robot_file(robot)
    except Exception as err:  # noqa: BLE001  (not installed)
        return f"skipped: {err}"
    root = Path(__file__).resolve().parents[1]
    with tempfile.TemporaryDirectory(prefix="lagcomp-floating-") as cache:
        out = subprocess.run([sys.executable, "-c", PROBE, str(path), cache], capture_output=True, text=True,
                             cwd=root, check=False)
    if out.returncode:
        return f"failed: {(out.stderr.strip().splitlines() or ['?'])[-1][:200]}"
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", nargs="+", choices=ROBOTS, default=ROBOTS)
    parser.add_argument("--smoke", action="store_true", help="solo12 only")
    args = parser.parse_args(argv)
    print("| robot | DOF | rhs ops | cold compile + first rhs (CPU s) | peak MB | q̈ vs Pinocchio (rel.) "
          "| lagcomp rhs ns | pin.aba from Python ns (call overhead included: not a C++ baseline) |")
    print("|---|---|---|---|---|---|---|---|")
    for robot in ["solo12"] if args.smoke else args.robots:
        r = measure(robot)
        if isinstance(r, str):
            print(f"| {robot} | {r} |  |  |  |  |  |  |")
            continue
        print(f"| {robot} | {r['n']} | {r['ops']} | {r['compile_cpu_s']:.1f} | {r['peak_mb']:.0f} | "
              f"{r['rel_diff']:.1e} | {r['lagcomp_ns']:.0f} | {r['pin_python_ns']:.0f} |", flush=True)


if __name__ == "__main__":
    main()
