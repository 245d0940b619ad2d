"""Issue 39's scale table: lagcomp's kinematic trees against Pinocchio and MuJoCo on the same systems.

Systems (names as ``--systems`` takes them): planar n-link chains ``planar_N``, 3D chains on universal joints
``universal_N`` and on ball joints ``spherical_N`` (`lagcomp.examples.trees`' builders, their parameters drawn in
[1, 1.5], g = 9.81), the Panda and UR5 arms (``panda``, ``ur5``) and, on a floating base, the Solo12 quadruped and
the Talos humanoid (``solo12``, ``talos``: ``lc.from_urdf(path, floating_base=True)``, the root on an ``lc.Free``
joint), all from example-robot-data's URDFs.  For each, a fresh process with an empty lagcomp cache measures:

* the cold ``lc.compile(tree)`` plus the first ``rhs`` call, in CPU seconds (numba's compile of ``rhs`` included;
  importing lagcomp and building the tree are not), the operations of ``rhs`` (compiled: a step the links repeat
  counts once, `lagcomp.codegen.outline`; and evaluated by one call) and the process's peak memory;
* q̈ against Pinocchio's ABA at 5 random states first (Pinocchio's own URDF reader for the robots, with
  ``JointModelFreeFlyer`` for the floating bases; the chains built in Pinocchio by
  `lagcomp.multibody.pinocchio_peer.pinocchio_model`, a ball joint as ``JointModelSpherical``; the states converted
  by that module: quaternions and body-frame rates from the modified Rodrigues parameters): the largest relative
  difference (`relative`: max |Δq̈| / max |q̈|, normwise); the same against Pinocchio's M⁻¹ (τ − h) (CRBA and RNEA,
  an LU solve: backward stable, `pinocchio_solved`), with the largest cond(M) of the 5 states (Pinocchio's
  coordinates) — where the two Pinocchio answers part, the solve is the one within cond(M) ε of the exact q̈;
* ns per call: lagcomp's ``rhs`` in a compiled loop (`lagcomp.benchmark.looped`); Pinocchio's ``aba`` called from
  Python; Pinocchio's ABA in a C++ loop (`bench.pinocchio_loop`: its q̈ equal to Python's); MuJoCo's
  ``mj_forward`` from Python with contacts and all constraints disabled (the model written as MJCF from the same
  tree, `bench.mujoco_model`, ball and free joints included; its q̈ compared with lagcomp's, every coordinate).

Each figure is the best of 5 rounds, in one process per system right after the others: ratios are what to read,
this machine being shared.  The ratio against Pinocchio's C++ loop is set against issue 39's targets (≤ 0.5× for
the Panda and the 3D chains up to 30 bodies, ≤ 1.0× for a floating base).  A second table fits the growth
exponents k of cost ~ n^k over each chain family.  A peer that is not installed, or a C++ build that fails, is
reported as skipped.

    python -m bench.bench_scale [--smoke] [--systems planar_8 spherical_10 panda solo12 ...] [--no-cpp]
    python -m bench --only scale
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from bench.harness import Table, fmt
from bench.pinocchio_loop import cpp_loop, run_loop, save_case

ROOT = Path(__file__).resolve().parents[1]
FULL = ["planar_8", "planar_32", "planar_100", "universal_3", "universal_10", "universal_30", "spherical_3",
        "spherical_10", "spherical_30", "ur5", "panda", "solo12", "talos"]
QUICK = ["planar_8", "universal_3", "spherical_3", "ur5", "panda", "solo12"]
SMOKE = ["planar_4", "spherical_2", "ur5"]
#: robot -> (its URDF in example-robot-data, on a floating base).
ROBOTS = {"panda": ("panda_description/urdf/panda.urdf", False), "ur5": ("ur_description/urdf/ur5_robot.urdf", False),
          "solo12": ("solo_description/robots/solo12.urdf", True),
          "talos": ("talos_data/robots/talos_reduced.urdf", True)}
CHAINS = ("planar", "universal", "spherical")
#: issue 39's targets for the ratio of lagcomp's rhs to Pinocchio's ABA in C++, by system family.
TARGETS = {"universal": 0.5, "spherical": 0.5, "panda": 0.5, "solo12": 1.0, "talos": 1.0}

CHILD = r'''
import json, sys
import numpy as np
from bench import bench_scale as bs
system, out_dir = sys.argv[1], sys.argv[2]
tree, values = bs.build(system)
model, y, result = bs.cold_compile(tree, values)
result["system"] = system
p, out, n = model.parameter_vector(values), np.empty(2 * model.n), model.n
from lagcomp.benchmark import looped
loop = looped(model.kernels.rhs)
calls = max(2000, 400_000 // n)
result["lagcomp_ns"] = bs.best(lambda: loop(y.copy(), p, out, calls), calls)
result.update(bs.pinocchio_side(system, tree, values, model, y, out_dir))
result.update(bs.mujoco_side(tree, values, model, y))
print(json.dumps(result))
'''


def cold_compile(tree, values: dict, cache_dir=None) -> tuple:
    """(model, y, figures): ``lc.compile(tree)`` and its first ``rhs`` call at a random state y, timed in CPU
    seconds (numba's compile of ``rhs`` included, nothing built on demand: the operations are the eager kernels'
    count, read without building the Jacobians' companions as ``Model.operations`` would), with the process's peak
    memory and the operations of ``rhs`` compiled and evaluated."""
    import resource
    import time

    import numpy as np

    import lagcomp as lc

    start = time.process_time()
    model = lc.compile(tree, progress=False, cache_dir=cache_dir)
    p, n = model.parameter_vector(values), model.n
    y = states(n)[0]
    model.kernels.rhs(0.0, y, p, np.empty(2 * n))
    cpu = time.process_time() - start
    figures = {"n": n, "compile_cpu_s": cpu, "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
               "ops": model._operations["rhs"], "evaluated": evaluated(tree)}
    return model, y, figures


def states(n: int) -> list:
    """The 5 states y = (q, q̇) of an n-coordinate system where q̈ is compared: the timed one, uniform in [−1, 1],
    then 4 in [−2, 2] (MRPs past the shadow switch |σ| = 1 included)."""
    import numpy as np

    rng = np.random.default_rng(1)
    return [np.random.default_rng(39).uniform(-1.0, 1.0, size=2 * n)] + [rng.uniform(-2.0, 2.0, 2 * n)
                                                                          for _ in range(4)]


def build(system: str):
    """(lc.Tree, parameter values by name) of a system name: planar_N, universal_N, spherical_N, or a robot of
    `ROBOTS`."""
    import numpy as np

    import lagcomp as lc
    from lagcomp.examples import trees

    if system in ROBOTS:
        return lc.from_urdf(robot_file(system), floating_base=ROBOTS[system][1]), {}
    kind, _, size = system.rpartition("_")
    tree = getattr(trees, f"{kind}_chain")(int(size))
    rng = np.random.default_rng(int(size))
    return tree, {name: (9.81 if name == "g" else float(rng.uniform(1.0, 1.5))) for name in tree.parameter_names}


def robot_file(system: str) -> Path:
    """The URDF of a robot of example-robot-data (installed under its cmeel prefix)."""
    import importlib.metadata

    relative = ROBOTS[system][0]
    for file in importlib.metadata.files("example-robot-data") or []:
        if str(file).endswith(relative):
            return Path(file.locate())
    raise FileNotFoundError(f"example-robot-data ships no {relative}")


def evaluated(tree) -> int:
    """The operations one ``rhs`` call evaluates (each outlined step counted at every call)."""
    from lagcomp.codegen.outline import evaluated_operations
    from lagcomp.codegen.tree_lower import lower_tree

    return evaluated_operations(next(k for k in lower_tree(tree).kernels if k.name == "rhs"))


def best(run, calls: int, rounds: int = 5) -> float:
    """ns per call of `run()` (which makes `calls` calls): the best of `rounds` after a warm-up."""
    import time

    run()
    times = []
    for _ in range(rounds):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return min(times) / calls * 1e9


def pinocchio_peer(system: str, tree, values: dict):
    """(Pinocchio's model of the system, state(y) -> (q, v, τ, back)): `lagcomp.multibody.pinocchio_peer`'s
    conversion of lagcomp's state y, back turning Pinocchio's v̇ into lagcomp's q̈."""
    import pinocchio as pin

    from lagcomp.multibody import pinocchio_peer as peer

    names, n = tree.coordinate_names, tree.n
    if system not in ROBOTS:
        reference = peer.pinocchio_model(tree, values)
        return reference, lambda y: peer.tree_state(reference, tree, values, y)
    if ROBOTS[system][1]:
        reference = pin.buildModelFromUrdf(str(robot_file(system)), pin.JointModelFreeFlyer())
        return reference, lambda y: peer.free_flyer_state(pin, reference, names, y[:n], y[n:])
    reference = pin.buildModelFromUrdf(str(robot_file(system)))
    return reference, lambda y: peer.fixed_base_state(reference, names, y[:n], y[n:])


def pinocchio_side(system: str, tree, values: dict, model, y, out_dir: str) -> dict:
    """Pinocchio's model of the system, q̈ compared at y and 4 more random states with its ABA and with its
    M⁻¹ (τ − h) (`pinocchio_solved`), the largest cond(M); ns per ``aba`` from Python; the model and the state y
    saved in `out_dir` for the C++ loop."""
    import numpy as np

    try:
        import pinocchio as pin
    except ImportError:
        return {}
    reference, state = pinocchio_peer(system, tree, values)
    data = reference.createData()
    n, p, out = model.n, model.parameter_vector(values), np.empty(2 * model.n)
    worst, worst_solved, condition = 0.0, 0.0, 0.0
    for y_k in [y, *states(n)[1:]]:
        q, v, tau, back = state(y_k)
        model.kernels.rhs(0.0, y_k, p, out)
        solved, cond_k = pinocchio_solved(pin, reference, data, q, v, tau)
        worst = max(worst, relative(out[n:], back(pin.aba(reference, data, q, v, tau))))
        worst_solved, condition = max(worst_solved, relative(out[n:], back(solved))), max(condition, cond_k)
    q, v, tau, _ = state(y)
    reps = 20000
    result = {"pin_rel_diff": worst, "pin_solved_rel_diff": worst_solved, "cond_m": condition,
              "pin_python_ns": best(lambda: [pin.aba(reference, data, q, v, tau) for _ in range(reps)], reps)}
    save_case(reference, q, v, tau, out_dir)
    result["pin_ddq"] = pin.aba(reference, data, q, v, tau).tolist()
    return result


def pinocchio_solved(pin, reference, data, q, v, tau) -> tuple:
    """(v̇, cond(M)): Pinocchio's accelerations as M⁻¹ (τ − h), M its ``crba`` (upper triangle, mirrored) and h its
    ``rnea`` at v̇ = 0 (gravity, Coriolis and centrifugal forces), solved by LU with partial pivoting; cond(M) in the
    2-norm, in Pinocchio's coordinates.  A second Pinocchio answer, by another algorithm: the solve is backward
    stable, so within about cond(M) ε of the exact q̈, where an ABA's rounding may wander further (the 30-body
    ball chain, docs/benchmarks.md)."""
    import numpy as np

    M = np.triu(pin.crba(reference, data, q))
    M = M + np.triu(M, 1).T
    h = pin.rnea(reference, data, q, v, np.zeros(reference.nv))
    return np.linalg.solve(M, tau - h), float(np.linalg.cond(M))


def relative(value, expected) -> float:
    """max |value − expected| / max |expected|: the difference relative to the vector's scale (normwise, the
    ∞-norm; not coordinate by coordinate, where a q̈ component near zero would make any rounding look large)."""
    import numpy as np

    return float(np.max(np.abs(np.asarray(value) - expected)) / np.max(np.abs(expected)))


def mujoco_side(tree, values: dict, model, y) -> dict:
    """MuJoCo's q̈ (``mj_forward``, from Python; every coordinate, ball and free joints converted back to MRPs)
    against lagcomp's at y, and ns per ``mj_forward`` call."""
    import numpy as np

    try:
        import mujoco
    except ImportError:
        return {}
    from bench import mujoco_model

    m = mujoco.MjModel.from_xml_string(mujoco_model.mjcf(tree, values))
    d = mujoco.MjData(m)
    mujoco_model.set_state(m, d, tree, values, y)
    mujoco.mj_forward(m, d)
    n, out = tree.n, np.empty(2 * tree.n)
    model.kernels.rhs(0.0, y, model.parameter_vector(values), out)
    qdd = mujoco_model.accelerations(m, d, tree, values, y)
    reps = 20000
    return {"mujoco_rel_diff": relative(qdd, out[n:]),
            "mujoco_ns": best(lambda: [mujoco.mj_forward(m, d) for _ in range(reps)], reps)}


def measure(system: str, binary) -> dict:
    """One system in a fresh process and cache, then Pinocchio's C++ loop on the model that process saved."""
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, LAGCOMP_CACHE_DIR=str(Path(tmp, "cache")),
                   PYTHONPATH=os.pathsep.join([str(ROOT / "src"), str(ROOT), os.environ.get("PYTHONPATH", "")]))
        done = subprocess.run([sys.executable, "-c", CHILD, system, tmp], env=env, capture_output=True, text=True,
                              check=False, cwd=ROOT)
        if done.returncode != 0:
            return {"system": system, "error": (done.stderr.strip().splitlines() or ["failed"])[-1][:200]}
        result = json.loads(done.stdout.strip().splitlines()[-1])
        if isinstance(binary, Path) and Path(tmp, "model.bin").exists():
            ddq, result["pin_cpp_ns"] = run_loop(binary, Path(tmp, "model.bin"), Path(tmp, "state.txt"),
                                                 max(2000, 400_000 // result["n"]))
            scale = max(abs(x) for x in result["pin_ddq"])
            result["cpp_rel_diff"] = max(abs(a - b) for a, b in zip(ddq, result["pin_ddq"])) / scale
            # (the same model: the loop's q̈ within 1e-12 of Python's, or no farther from it than Python's is from
            # lagcomp's — at an ill-conditioned state g++ -march=native's FMAs round differently, `table`'s note)
            if result["cpp_rel_diff"] > max(1e-12, result.get("pin_rel_diff", 0.0)):
                result["pin_cpp_ns"] = float("nan")   # (another model: no ratio)
    return result


COLUMNS = ["system", "DOF", "ops of rhs (compiled / evaluated)", "cold compile + first rhs, CPU s", "peak MB",
           "q̈ vs Pinocchio (max rel.)", "q̈ vs Pinocchio's M⁻¹(τ − h)", "cond(M)", "lagcomp rhs ns (loop)", "Pinocchio ABA C++ loop ns", "lagcomp / Pinocchio C++",
           "issue 39 target", "Pinocchio aba from Python ns", "MuJoCo mj_forward from Python ns", "MuJoCo q̈ vs lagcomp"]


def target(system: str) -> float | None:
    """Issue 39's bound on lagcomp / Pinocchio C++ for `system` (None where the issue sets none)."""
    return TARGETS.get(system, TARGETS.get(system.rpartition("_")[0]))


def verdict(system: str, ratio: float) -> str:
    bound = target(system)
    if bound is None:
        return "–"
    if not math.isfinite(ratio):
        return f"≤ {bound:g}×: not measured"
    return f"≤ {bound:g}×: {'met' if ratio <= bound else 'missed'}"


def table(systems, cpp: bool) -> list[Table]:
    """The scale table and the growth table of `systems`, each measured cold in its own process."""
    binary = cpp_loop() if cpp else "skipped: --no-cpp"
    note = (f"Load average {os.getloadavg()[0]:.1f} at start on {os.cpu_count()} logical CPUs. "
            "Cold: a fresh process and lagcomp cache per system. ns are the best of 5 rounds in that process, one "
            "after the other (the C++ loop right after it): read the ratios. Pinocchio's C++ loop: "
            + (f"{binary}" if isinstance(binary, str) else "g++ -O3 -march=native, the ABA instantiated in the loop's "
               "program, its q̈ equal to Python's pin.aba") + ". MuJoCo: contacts and constraints disabled.")
    out = Table("Multibody at scale: lagcomp trees against Pinocchio and MuJoCo (issue 39)", COLUMNS, note=note)
    results = []
    for system in systems:   # (each result on stderr as it comes: a long run's figures survive an interruption)
        results.append(measure(system, binary))
        print(f"<!-- {json.dumps(results[-1])} -->", file=sys.stderr, flush=True)
    for r in results:
        system = r["system"]
        if "error" in r:
            out.add(system, *["–"] * (len(COLUMNS) - 2), r["error"])
            continue
        cpp_ns = r.get("pin_cpp_ns", float("nan"))
        ratio = r["lagcomp_ns"] / cpp_ns
        difference = f"{r['pin_rel_diff']:.1e}" if "pin_rel_diff" in r else "skipped: pin not installed"
        if r.get("cpp_rel_diff", 0.0) > 1e-12:
            difference += f" (C++ loop vs Python: {r['cpp_rel_diff']:.1e})"
        out.add(system, r["n"], f"{r['ops']:,} / {r['evaluated']:,}", fmt(r["compile_cpu_s"]), fmt(r["peak_mb"]),
                difference, f"{r['pin_solved_rel_diff']:.1e}" if "pin_solved_rel_diff" in r else "–",
                f"{r['cond_m']:.1e}" if "cond_m" in r else "–",
                fmt(r["lagcomp_ns"]), fmt(cpp_ns), fmt(ratio, "×"), verdict(system, ratio),
                fmt(r.get("pin_python_ns", float("nan"))), fmt(r.get("mujoco_ns", float("nan"))),
                f"{r['mujoco_rel_diff']:.1e}" if "mujoco_rel_diff" in r else "skipped: mujoco not installed")
    return [out, growth([r for r in results if "error" not in r])]


def exponent(sizes, values) -> float:
    """k of values ~ sizes^k, by least squares on the logarithms."""
    import numpy as np

    return float(np.polyfit(np.log(sizes), np.log(values), 1)[0])


GROWTH = {"ops compiled": "ops", "ops evaluated": "evaluated", "cold compile + first rhs": "compile_cpu_s",
          "peak MB": "peak_mb", "rhs ns": "lagcomp_ns", "Pinocchio C++ ns": "pin_cpp_ns"}


def growth(results) -> Table:
    """The exponents k of cost ~ n^k (n the DOF) within each chain family, fitted by least squares on the
    logarithms of its members (issue 39's target: ops of rhs ~ n and compile ~ n; a family needs two sizes)."""
    out = Table("Growth with the chain's size: k of cost ~ n^k (n = DOF), least squares over the sizes measured",
                ["family", "DOF"] + list(GROWTH),
                note="Issue 39's target: ops of rhs ~ n (the articulated-body algorithm) and cold compile ~ n. "
                     "The ops compiled count a step the links repeat once (it is emitted once, as a helper); the "
                     "ops evaluated count it at each call.")
    for family in CHAINS:
        members = sorted((r for r in results if r["system"].startswith(family + "_")), key=lambda r: r["n"])
        sizes = [r["n"] for r in members]
        if len(set(sizes)) < 2:
            continue
        cells = []
        for key in GROWTH.values():
            values = [r.get(key, float("nan")) for r in members]
            cells.append(f"n^{exponent(sizes, values):.2f}" if all(v > 0 for v in values) else "–")
        out.add(family, ", ".join(map(str, sizes)), *cells)
    return out


def available(systems) -> list:
    """`systems` less the robots whose URDF is not installed (example-robot-data)."""
    kept = []
    for system in systems:
        try:
            if system in ROBOTS:
                robot_file(system)
            kept.append(system)
        except Exception:  # noqa: BLE001  (not installed, or without that robot)
            print(f"<!-- {system}: skipped, example-robot-data is not installed -->", file=sys.stderr)
    return kept


def section(ctx):
    """`python -m bench --only scale`: the scale table and the growth table."""
    return table(available(QUICK if ctx.quick else FULL), cpp=ctx.use_peers)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--smoke", action="store_true", help=f"only {SMOKE}, no C++ build")
    parser.add_argument("--systems", nargs="+", help=f"systems (default {FULL})")
    parser.add_argument("--no-cpp", action="store_true", help="do not build Pinocchio's C++ loop")
    args = parser.parse_args(argv)
    systems = args.systems or (SMOKE if args.smoke else FULL)
    for out in table(available(systems), cpp=not (args.no_cpp or args.smoke)):
        print(out.markdown(), flush=True)


if __name__ == "__main__":
    main()
