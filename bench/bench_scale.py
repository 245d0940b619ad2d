"""Issue 39's scale table: lagcomp's kinematic trees against Pinocchio and MuJoCo on the same systems.

Systems: planar n-link chains and 3D chains on universal joints (the builders of tests/multibody_models.py, their
parameters drawn in [1, 1.5], g = 9.81), and the Panda and UR5 arms read by ``lc.from_urdf`` from
example-robot-data's URDFs.  For each, a fresh process with an empty lagcomp cache measures:

* the cold ``lc.compile(tree)`` plus the first ``rhs`` call, in CPU seconds (numba's compile of ``rhs`` included;
  importing lagcomp and building the tree are not), the op count of ``rhs`` and the process's peak memory;
* q̈ against Pinocchio's ABA at random states first (its own URDF reader for the arms; the chains built in
  Pinocchio by ``multibody_models.pinocchio_model``): the largest relative difference;
* ns per call: lagcomp's ``rhs`` in a compiled loop (`lagcomp.benchmark.looped`); Pinocchio's ``aba`` called from
  Python; Pinocchio's ABA in a C++ loop (a small program built here with g++ -O3 -march=native against the
  headers of the ``pin`` wheel and Eigen, the ABA instantiated in it as Pinocchio's own benchmarks do; the model
  passed by Pinocchio's binary serialization); MuJoCo's ``mj_forward`` from Python with contacts and all
  constraints disabled (the model written as MJCF from the same tree, its q̈ checked against Pinocchio's too).

Each figure is the best of 5 rounds, in one process per system right after the others: ratios are what to read,
this machine being shared.  A peer that is not installed, or a C++ build that fails, is reported as skipped.

    python -m bench.bench_scale [--smoke] [--systems planar_8 universal_10 panda ...] [--no-cpp]
    python -m bench --only scale
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from bench.harness import Table, fmt

ROOT = Path(__file__).resolve().parents[1]
FULL = ["planar_8", "planar_32", "planar_100", "universal_3", "universal_10", "universal_30", "ur5", "panda"]
QUICK = ["planar_8", "universal_3", "ur5", "panda"]
SMOKE = ["planar_4", "ur5"]
ROBOTS = {"panda": "panda_description/urdf/panda.urdf", "ur5": "ur_description/urdf/ur5_robot.urdf"}

CHILD = r'''
import json, resource, sys, time
import numpy as np
sys.path.insert(0, "tests")
import lagcomp as lc
from bench import bench_scale as bs
system, out_dir = sys.argv[1], sys.argv[2]
tree, values = bs.build(system)
start = time.process_time()
model = lc.compile(tree, progress=False)
rng = np.random.default_rng(39)
p = model.parameter_vector(values)
n = model.n
y = rng.uniform(-1.0, 1.0, size=2 * n)
out = np.empty(2 * n)
model.kernels.rhs(0.0, y, p, out)
result = {"system": system, "n": n, "ops": model.operations["rhs"], "compile_cpu_s": time.process_time() - start,
          "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}
from lagcomp.benchmark import looped
loop = looped(model.kernels.rhs)
calls = max(2000, 400_000 // n)
result["lagcomp_ns"] = bs.best(lambda: loop(y.copy(), p, out, calls), calls)
result.update(bs.pinocchio_side(system, tree, values, model, y, out_dir))
result.update(bs.mujoco_side(tree, values, model, y))
print(json.dumps(result))
'''


def build(system: str):
    """(lc.Tree, parameter values by name) of a system name: planar_N, universal_N, or a robot of `ROBOTS`."""
    import numpy as np

    import lagcomp as lc

    kind, _, size = system.rpartition("_")
    if system in ROBOTS:
        return lc.from_urdf(robot_file(system)), {}
    import multibody_models as mm

    tree = mm.planar_chain(int(size)) if kind == "planar" else mm.universal_chain(int(size))
    rng = np.random.default_rng(int(size))
    return tree, {name: (9.81 if name == "g" else float(rng.uniform(1.0, 1.5))) for name in tree.parameter_names}


def robot_file(system: str) -> Path:
    """The URDF of a robot of example-robot-data (installed under its cmeel prefix)."""
    import importlib.metadata

    for file in importlib.metadata.files("example-robot-data") or []:
        if str(file).endswith(ROBOTS[system]):
            return Path(file.locate())
    raise FileNotFoundError(f"example-robot-data ships no {ROBOTS[system]}")


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


def _numeric(expr, values: dict) -> float:
    import sympy as sp

    expr = sp.sympify(expr)
    return float(expr.subs({s: values[s.name] for s in expr.free_symbols}))


def pinocchio_side(system: str, tree, values: dict, model, y, out_dir: str) -> dict:
    """Pinocchio's model of the system, q̈ compared at 5 random states, ns per ``aba`` from Python; the model and
    one state saved in `out_dir` for the C++ loop."""
    import numpy as np

    try:
        import pinocchio as pin
    except ImportError:
        return {}
    if system in ROBOTS:
        reference = pin.buildModelFromUrdf(str(robot_file(system)))
    else:
        import multibody_models as mm

        reference = mm.pinocchio_model(tree, values)
    data = reference.createData()
    damping = np.array([_numeric(node.joint.damping, values) for node in tree.nodes])
    n, p, out = model.n, model.parameter_vector(values), np.empty(2 * model.n)
    rng, worst = np.random.default_rng(1), 0.0
    for state in [y] + [rng.uniform(-2.0, 2.0, 2 * n) for _ in range(4)]:
        q, v, order = pinocchio_state(reference, tree, state)
        expected = pin.aba(reference, data, q, v, -damping[order] * v)   # (no continuous joints in these systems)
        model.kernels.rhs(0.0, state, p, out)
        worst = max(worst, float(np.max(np.abs(out[n:][order] - expected)) / np.max(np.abs(expected))))
    q, v, order = pinocchio_state(reference, tree, y)
    tau = -damping[order] * v
    reps = 20000
    result = {"pin_rel_diff": worst,
              "pin_python_ns": best(lambda: [pin.aba(reference, data, q, v, tau) for _ in range(reps)], reps)}
    reference.saveToBinary(os.path.join(out_dir, "model.bin"))
    Path(out_dir, "state.txt").write_text(" ".join(repr(float(x)) for x in [*q, *v, *tau]))
    result["pin_ddq"] = pin.aba(reference, data, q, v, tau).tolist()
    return result


def pinocchio_state(reference, tree, y):
    """(q, v, order) in Pinocchio's joint order from lagcomp's state y: order[i] is lagcomp's index of Pinocchio's
    i-th velocity (one coordinate per joint, matched by name where Pinocchio's joints carry the URDF names, else
    in node order)."""
    import numpy as np

    n, names = tree.n, list(tree.coordinate_names)
    q, v, order = np.empty(n), np.empty(n), np.empty(n, dtype=int)
    for j in range(1, reference.njoints):
        name = reference.names[j]
        k = names.index(name) if name in names else j - 1
        q[reference.joints[j].idx_q], v[reference.joints[j].idx_v] = y[k], y[n + k]
        order[reference.joints[j].idx_v] = k
    return q, v, order


def mjcf(tree, values: dict) -> str:
    """The tree as a MuJoCo model: a body per link (placed by its joint's origin and rotation), its joints' hinges
    and slides in order (MuJoCo composes the joints of one body as the tree's massless frames do), inertial
    properties about the centre of mass; gravity; contacts and every constraint disabled."""
    import mujoco
    import numpy as np

    children = {}
    for link in tree.links:
        children.setdefault(link.parent, []).append(link)
    nodes = {}
    for node in tree.nodes:
        nodes.setdefault(node.link, []).append(node)

    def body(link) -> str:
        steps = nodes[link.name]
        first = steps[0].joint
        quat = np.empty(4)
        mujoco.mju_mat2Quat(quat, np.array([[_numeric(e, values) for e in row] for row in first.rotation]).ravel())
        text = (f'<body name="{link.name}" pos="{_floats(first.origin, values)}" '
                f'quat="{" ".join(repr(float(x)) for x in quat)}">')
        for node in steps:
            j = node.joint
            text += (f'<joint name="{j.coordinate.func.__name__}" type="{"hinge" if j.kind == "revolute" else "slide"}" '
                     f'axis="{_floats(j.axis, values)}" damping="{_numeric(j.damping, values)!r}" '
                     f'stiffness="{_numeric(j.stiffness, values)!r}" springref="{_numeric(j.rest, values)!r}"/>')
        last = steps[-1]
        I = last.inertia
        full = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]
        text += (f'<inertial pos="{_floats(last.com, values)}" mass="{_numeric(last.mass, values)!r}" '
                 f'fullinertia="{_floats(full, values)}"/>')
        return text + "".join(body(child) for child in children.get(link.name, [])) + "</body>"

    return (f'<mujoco model="{tree.name}"><compiler angle="radian" inertiafromgeom="false"/>'
            f'<option gravity="{_floats(tree.gravity, values)}"><flag contact="disable" constraint="disable"/></option>'
            f'<worldbody>{"".join(body(link) for link in children[None])}</worldbody></mujoco>')


def _floats(entries, values) -> str:
    return " ".join(repr(_numeric(e, values)) for e in entries)


def mujoco_side(tree, values: dict, model, y) -> dict:
    """MuJoCo's q̈ (``mj_forward``, from Python) against lagcomp's at y, and ns per ``mj_forward`` call."""
    import numpy as np

    try:
        import mujoco
    except ImportError:
        return {}
    m = mujoco.MjModel.from_xml_string(mjcf(tree, values))
    d = mujoco.MjData(m)
    n = tree.n
    for k, name in enumerate(tree.coordinate_names):
        d.qpos[m.joint(name).qposadr[0]], d.qvel[m.joint(name).dofadr[0]] = y[k], y[n + k]
    mujoco.mj_forward(m, d)
    out = np.empty(2 * n)
    model.kernels.rhs(0.0, y, model.parameter_vector(values), out)
    qacc = np.array([d.qacc[m.joint(name).dofadr[0]] for name in tree.coordinate_names])
    reps = 20000
    return {"mujoco_rel_diff": float(np.max(np.abs(qacc - out[n:])) / np.max(np.abs(out[n:]))),
            "mujoco_ns": best(lambda: [mujoco.mj_forward(m, d) for _ in range(reps)], reps)}


CPP = r"""
#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/serialization.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>

// argv: model.bin state.txt calls rounds. Prints q̈ once, then ns per aba call of each round.
int main(int argc, char **argv) {
  pinocchio::Model model;
  model.loadFromBinary(argv[1]);
  pinocchio::Data data(model);
  Eigen::VectorXd q(model.nq), v(model.nv), tau(model.nv);
  std::ifstream in(argv[2]);
  for (int i = 0; i < model.nq; ++i) in >> q[i];
  for (int i = 0; i < model.nv; ++i) in >> v[i];
  for (int i = 0; i < model.nv; ++i) in >> tau[i];
  long calls = std::atol(argv[3]);
  int rounds = std::atoi(argv[4]);
  pinocchio::aba(model, data, q, v, tau);
  for (int i = 0; i < model.nv; ++i) std::printf("%.17g ", data.ddq[i]);
  std::printf("\n");
  for (int r = 0; r < rounds; ++r) {
    auto start = std::chrono::steady_clock::now();
    for (long k = 0; k < calls; ++k) pinocchio::aba(model, data, q, v, tau);
    auto stop = std::chrono::steady_clock::now();
    std::printf("%.6f ", std::chrono::duration<double, std::nano>(stop - start).count() / calls);
  }
  std::printf("\n");
  return 0;
}
"""

#: What Pinocchio's CMake config asks of code compiled against its headers.
DEFINES = ["-DBOOST_MPL_LIMIT_LIST_SIZE=30", "-DBOOST_MPL_LIMIT_VECTOR_SIZE=30", "-DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS",
           "-DBOOST_FUSION_INVOKE_MAX_ARITY=12"]


def cpp_loop() -> Path | str:
    """The C++ ABA loop's executable (built once per pin version, kept in ~/.cache/lagcomp-bench), or why not."""
    import importlib.metadata

    try:
        version = importlib.metadata.version("pin")
        files = [f for dist in ("libpinocchio", "pin") for f in importlib.metadata.files(dist) or []]
    except importlib.metadata.PackageNotFoundError:
        return "skipped: pin not installed"
    header = "include/pinocchio/algorithm/aba.hpp"   # under the cmeel prefix of the wheels
    prefix = next((Path(f.locate()).parents[3] for f in files if str(f).endswith(header)), None)
    compiler = shutil.which("g++")
    eigen = next((Path(d) for d in ("/usr/include/eigen3", str(prefix) + "/include/eigen3")
                  if prefix and Path(d, "Eigen", "Dense").exists()), None)
    if prefix is None or compiler is None or eigen is None:
        missing = "Pinocchio's headers in the pin wheel" if prefix is None else "g++" if compiler is None else "Eigen"
        return f"skipped: {missing} not found (apt-get install g++ libeigen3-dev)"
    key = hashlib.sha256(f"{version} {CPP} {DEFINES}".encode()).hexdigest()[:12]
    binary = Path.home() / ".cache" / "lagcomp-bench" / f"pinocchio-aba-{key}"
    if binary.exists():
        return binary
    binary.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        source = Path(tmp, "aba_loop.cpp")
        source.write_text(CPP)
        built = subprocess.run([compiler, "-O3", "-DNDEBUG", "-march=native", "-std=c++17", *DEFINES,
                                f"-I{prefix}/include", f"-I{eigen}", str(source), "-o", str(Path(tmp, "aba")),
                                f"-L{prefix}/lib", "-lboost_serialization", f"-Wl,-rpath,{prefix}/lib"],
                               capture_output=True, text=True, check=False)
        if built.returncode != 0:
            return f"skipped: the C++ build failed ({built.stderr.strip().splitlines()[-1:]})"
        shutil.move(str(Path(tmp, "aba")), binary)
    return binary


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
            calls = max(2000, 400_000 // result["n"])
            run = subprocess.run([str(binary), str(Path(tmp, "model.bin")), str(Path(tmp, "state.txt")), str(calls),
                                  "5"], capture_output=True, text=True, check=True)
            ddq, times = ([float(x) for x in line.split()] for line in run.stdout.strip().splitlines())
            scale = max(abs(x) for x in result["pin_ddq"])
            result["cpp_matches_python"] = max(abs(a - b) for a, b in zip(ddq, result["pin_ddq"])) <= 1e-12 * scale
            result["pin_cpp_ns"] = min(times)
    return result


COLUMNS = ["system", "DOF", "ops of rhs", "cold compile + first rhs, CPU s", "peak MB", "q̈ vs Pinocchio (max rel.)",
           "lagcomp rhs ns (loop)", "Pinocchio ABA C++ loop ns", "lagcomp / Pinocchio C++", "Pinocchio aba from Python ns",
           "MuJoCo mj_forward from Python ns", "MuJoCo q̈ vs lagcomp"]


def table(systems, cpp: bool) -> Table:
    binary = cpp_loop() if cpp else "skipped: --no-cpp"
    note = (f"Load average {os.getloadavg()[0]:.1f} at start on {os.cpu_count()} logical CPUs. "
            "Cold: a fresh process and lagcomp cache per system. ns are the best of 5 rounds in that process, one "
            "after the other (the C++ loop right after it): read the ratios. Pinocchio's C++ loop: "
            + (f"{binary}" if isinstance(binary, str) else "g++ -O3 -march=native, the ABA instantiated in the loop's "
               "program, its q̈ equal to Python's pin.aba") + ". MuJoCo: contacts and constraints disabled.")
    out = Table("Multibody at scale: lagcomp trees against Pinocchio and MuJoCo (issue 39)", COLUMNS, note=note)
    results = [measure(system, binary) for system in systems]
    out.note += growth([r for r in results if "error" not in r])
    for r in results:
        system = r["system"]
        if "error" in r:
            out.add(system, *["–"] * 10, r["error"])
            continue
        cpp_ns = r.get("pin_cpp_ns", float("nan"))
        if r.get("cpp_matches_python") is False:
            cpp_ns = float("nan")
        out.add(system, r["n"], r["ops"], fmt(r["compile_cpu_s"]), fmt(r["peak_mb"]),
                f"{r['pin_rel_diff']:.1e}" if "pin_rel_diff" in r else "skipped: pin not installed",
                fmt(r["lagcomp_ns"]), fmt(cpp_ns), fmt(r["lagcomp_ns"] / cpp_ns, "×"),
                fmt(r.get("pin_python_ns", float("nan"))), fmt(r.get("mujoco_ns", float("nan"))),
                f"{r['mujoco_rel_diff']:.1e}" if "mujoco_rel_diff" in r else "skipped: mujoco not installed")
    return out


def growth(results) -> str:
    """The log-log slopes of rhs ops, cold compile CPU and rhs ns against DOF within each chain family (from its
    smallest to its largest member), as a sentence for the note."""
    import math

    parts = []
    for family in ("planar", "universal"):
        members = sorted((r for r in results if r["system"].startswith(family + "_")), key=lambda r: r["n"])
        if len(members) < 2 or members[0]["n"] == members[-1]["n"]:
            continue
        a, b = members[0], members[-1]
        span = math.log(b["n"] / a["n"])
        slopes = {key: math.log(b[key] / a[key]) / span for key in ("ops", "compile_cpu_s", "lagcomp_ns")}
        parts.append(f"{family} chains, {a['n']} to {b['n']} DOF: ops ~ n^{slopes['ops']:.2f}, cold compile ~ "
                     f"n^{slopes['compile_cpu_s']:.2f}, rhs ns ~ n^{slopes['lagcomp_ns']:.2f}")
    return (" Growth: " + "; ".join(parts) + ".") if parts else ""


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
    """`python -m bench --only scale`."""
    return table(available(QUICK if ctx.quick else FULL), cpp=ctx.use_peers)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--smoke", action="store_true", help=f"only {SMOKE}, no C++ build")
    parser.add_argument("--systems", nargs="+", help=f"systems (default {FULL})")
    parser.add_argument("--no-cpp", action="store_true", help="do not build Pinocchio's C++ loop")
    args = parser.parse_args(argv)
    systems = args.systems or (SMOKE if args.smoke else FULL)
    print(table(available(systems), cpp=not (args.no_cpp or args.smoke)).markdown(), flush=True)


if __name__ == "__main__":
    main()
