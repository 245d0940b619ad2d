"""Pinocchio's ABA in a compiled C++ loop, as Pinocchio's own benchmarks time it: the baseline issue 39's ratios
are against (`bench.bench_scale`).

A small program is built once per pin version with g++ -O3 -march=native against the headers of the ``pin`` wheel
and Eigen, the ABA instantiated in it; it reads a model in Pinocchio's binary serialization and one state (q, v,
τ), prints q̈ once (checked against Python's ``pin.aba`` by the caller) and ns per call of each round.  Any joint
Pinocchio has runs through it: revolute and prismatic joints, ``JointModelSpherical``, ``JointModelFreeFlyer``.
"""

from __future__ import annotations

import hashlib
import shutil
import subprocess
import tempfile
from pathlib import Path

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


def save_case(reference, q, v, tau, directory) -> tuple[Path, Path]:
    """Write Pinocchio's model `reference` and the state (q, v, τ) where the loop times its ABA into `directory`:
    (model file, state file)."""
    model_file, state_file = Path(directory, "model.bin"), Path(directory, "state.txt")
    reference.saveToBinary(str(model_file))
    state_file.write_text(" ".join(repr(float(x)) for x in [*q, *v, *tau]))
    return model_file, state_file


def run_loop(binary: Path, model_file: Path, state_file: Path, calls: int, rounds: int = 5) -> tuple[list, float]:
    """(q̈ of the loop's first ABA call, ns per call: the best of `rounds` rounds of `calls` calls)."""
    done = subprocess.run([str(binary), str(model_file), str(state_file), str(calls), str(rounds)],
                          capture_output=True, text=True, check=True)
    ddq, times = ([float(x) for x in line.split()] for line in done.stdout.strip().splitlines())
    return ddq, min(times)
