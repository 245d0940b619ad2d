"""Every bench script in a smoke mode: does it still run against today's lagcomp (no timing judged).

    PYTHONPATH=src python -m bench.smoke [SCRIPT ...] [--timeout SECONDS]

Each script of `SCRIPTS` runs as ``python -m bench.SCRIPT ARGS`` in its own process with the arguments that
make it smallest (one round, short runs, few trajectories); `python -m bench` itself has its own test
(tests/test_bench.py).  A script whose arguments or library calls went stale (``bench_dop853`` calling the
DOP853 driver with the arguments of an older signature) fails here instead of when someone next measures.
tests/test_bench_scripts.py runs this list (marked slow: most scripts compile their models cold, 10–60 s
each) and checks that every script of the package is in it.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: script module -> the arguments of its smoke run.
SCRIPTS = {
    "bench_animation": ["--seconds", "0.2", "--fps", "10", "--dpi", "40", "--examples", "simple_pendulum"],
    "bench_call_cost": ["--rounds", "1"],
    "bench_collocation": ["simple_pendulum", "gauss2"],
    "bench_compile": ["simple_pendulum"],
    "bench_dop853": ["--smoke"],
    "bench_energy_balance": ["--t-end", "20", "--rows", "2001", "--repeats", "1"],
    "bench_floating_robots": ["--smoke"],
    "bench_equations_size": [],
    "bench_fixed_step": ["--steps", "1000", "--repeats", "1"],
    "bench_geometry": ["--rounds", "1"],
    "bench_inputs": ["--t-end", "0.5", "--repeats", "1"],
    "bench_large": ["--n", "3", "--repeats", "1"],
    "bench_jacobian_compile": ["planar_2", "--calls", "100"],
    "bench_kernel_compile": ["double_pendulum", "--kernels", "rhs_jacobian", "variational"],
    "bench_loop": ["--rounds", "1"],
    "bench_lyapunov": ["--repeats", "1"],
    "bench_mass_matrix_compile": ["planar_4"],
    "bench_multibody": ["4"],
    "bench_radau": ["--rounds", "1"],
    "bench_recording": ["--rounds", "1", "--t-end", "2"],
    "bench_rattle": ["--steps", "1000", "--repeats", "1"],
    "bench_reset_sweep": ["--side", "4", "--repeats", "1"],
    "bench_run": ["simple_pendulum"],
    "bench_scale": ["--smoke"],
    "bench_sensitivities": ["--t-end", "1", "--repeats", "1"],
    "bench_stiff": ["--rounds", "1", "--t-end", "0.5"],
    "bench_sweep": ["--side", "4", "--repeats", "1", "--scipy-samples", "1", "--dop853-tolerances", "1e-8",
                    "--taylor-tolerances", "1e-10", "--heyoka-tolerances", "1e-10"],
    "bench_taylor": ["--quick", "--sections", "1"],
    "bench_taylor_modes": [],
    "bench_taylor_sensitivities": ["--repeats", "1"],
    "bench_tiers": ["--rounds", "1", "--steps", "1000"],
    "pinocchio_rounding": ["--systems", "spherical_2"],
    "taylor_error_sources": ["--t-end", "10", "--members", "2"],
}

#: Scripts that cannot run without a peer (their reference is the peer's result), and the peer's module.
REQUIRES = {"bench_taylor_sensitivities": "heyoka", "pinocchio_rounding": "pinocchio"}

#: Scripts of the package that are not run here, and why.
NOT_RUN = {
    "taylor_library_vs_template": "compares with an older lagcomp checkout whose path it takes (no smoke form)",
}

#: Modules of the package that are not scripts (`python -m bench`'s sections and shared code).
LIBRARY = {"__init__", "__main__", "accuracy", "adaptive", "compile_time", "harness", "kernels", "mujoco_model",
           "pinocchio_loop", "run", "smoke", "systems", "throughput"}


def command(script: str) -> list[str]:
    """The command line of `script`'s smoke run."""
    return [sys.executable, "-m", f"bench.{script}", *SCRIPTS[script]]


def missing_peer(script: str) -> str | None:
    """The module `script` cannot run without when it is not installed, else None."""
    module = REQUIRES.get(script)
    return module if module is not None and importlib.util.find_spec(module) is None else None


def run(script: str, timeout: float) -> subprocess.CompletedProcess:
    """`script`'s smoke run from the repository root, with this checkout's lagcomp first on the path."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), str(ROOT), os.environ.get("PYTHONPATH", "")]),
               MPLBACKEND="Agg")
    return subprocess.run(command(script), cwd=ROOT, env=env, capture_output=True, text=True, timeout=timeout,
                          check=False)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scripts", nargs="*", metavar="SCRIPT", help="scripts to run (default: all of SCRIPTS)")
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds per script (default 600)")
    args = parser.parse_args(argv)
    unknown = [s for s in args.scripts if s not in SCRIPTS]
    if unknown:
        parser.error(f"not a bench script with a smoke run: {', '.join(unknown)} (known: {', '.join(SCRIPTS)})")
    failed = []
    for script in args.scripts or list(SCRIPTS):
        if missing_peer(script):
            print(f"skip {script}: {missing_peer(script)} is not installed", flush=True)
            continue
        start = time.perf_counter()
        try:
            result = run(script, args.timeout)
            ok, tail = result.returncode == 0, (result.stderr or result.stdout).strip().splitlines()[-1:]
        except subprocess.TimeoutExpired:
            ok, tail = False, [f"timed out after {args.timeout:.0f} s"]
        print(f"{'ok  ' if ok else 'FAIL'} {script} ({time.perf_counter() - start:.0f} s)"
              + ("" if ok else f": {' '.join(tail)[:300]}"), flush=True)
        if not ok:
            failed.append(script)
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
