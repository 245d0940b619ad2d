"""`python -m bench [--quick] [--out FILE]`: every section, one markdown document on stdout.

Order: cold compiles first (each case in a fresh process under a time limit,
which also fills this run's cache), then everything that runs the compiled
models in this process, then the targets of issue 8 with what this run
measured.  Sections can be picked with --only.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time

from bench.harness import SKIPPED, Table, Target, peer

FULL_CASES = ["double_pendulum", "kepler", "n_link_pendulum_2", "n_link_pendulum_4", "n_link_pendulum_8",
              "n_link_pendulum_10", "rolling_disc", "free_axle", "n_link_pendulum_16", "n_link_pendulum_24"]
QUICK_CASES = ["double_pendulum", "kepler", "n_link_pendulum_4"]
SECTIONS = ["compile", "kernels", "accuracy", "adaptive", "fixed", "sweeps", "ensembles", "long", "memory",
            "stiff", "impacts", "tiers", "scale"]

TARGETS = {
    "rhs_dp": ("double-pendulum RHS in a loop", "≤ 1.2× hand-written numba"),
    "rhs10": ("10-link RHS in a loop", "≤ 400 ns"),
    "dop853": ("DOP853 double pendulum [0, 100], tol 1e-10", "≤ 0.8× numbalsoda dop853, equal or better error"),
    "heyoka_raw": ("equal accuracy vs heyoka, raw Lagrangian", "faster than heyoka"),
    "heyoka_reduced": ("equal accuracy vs heyoka, reduced ODE", "say how far"),
    "rk4": ("RK4 double pendulum", "≥ 4 M steps/s"),
    "sweep": ("sweep, double pendulum, 10³ RK4 steps", "≥ 8,000 traj/s on 2 cores, ≥ 1.85× scaling"),
    "drivers": ("one-time compile of the library drivers (`lagcomp precompile`, empty numba cache)",
                "reported in its own row (issue 19)"),
    "cold_dp": ("cold start, double pendulum: new model → first dop853 result, drivers compiled",
                "≤ 1.0 s (4.2 s before issue 19)"),
    "cold10": ("cold start, 10-link chain: new model → first dop853 result, drivers compiled",
               "≤ 4 s (10.2 s before issue 19)"),
    "cold24": ("cold start, 24-link chain: new model → first dop853 result, drivers compiled",
               "≤ 15 s (31.6 s before issue 19)"),
    "warm": ("warm start of a cached model in a fresh process (double pendulum)",
             "≤ 0.6 s, no sympy import (0.8–1.0 s before issue 19)"),
    "radau_scipy": ("radau, stiff spring pendulum (issue 20)", "≥ 20× faster than scipy Radau at equal error"),
    "radau_lsoda": ("radau, stiff spring pendulum (issue 20)", "faster than numbalsoda's LSODA at equal error"),
    "radau_loop": ("radau, four-bar linkage DAE (issue 20)", "30 s with residual ≤ 1e-10 without projection"),
}


def build_system(case: str):
    """The lagcomp System of a benchmark case."""
    if case == "kepler":
        from bench.systems import kepler

        return kepler()
    from lagcomp import examples

    if case.startswith("n_link_pendulum_"):
        return examples.n_link_pendulum(int(case.rsplit("_", 1)[1]))
    return examples.get(case)


def system_name(case: str) -> str:
    return "bench_kepler" if case == "kepler" else case


class Context:
    """What the sections share: options, this run's cache, compiled models, cold-compile results, targets."""

    def __init__(self, args, cache_dir: str):
        self.quick = args.quick
        self.repeats = args.repeats
        self.cache_dir = cache_dir
        self.case_timeout = args.case_timeout
        self.cases = args.cases or (QUICK_CASES if args.quick else FULL_CASES)
        self.peer_max_links = 2 if args.quick else 4
        self.use_peers = not args.no_peers
        self.skipped = SKIPPED if self.use_peers else "skipped: --no-peers"
        self.cold: dict[str, dict | str] = {}
        self.driver_compile: dict | str = "not measured"  # `lagcomp precompile` with an empty numba cache
        self.drivers_ready: dict | str = "not measured"  # `lagcomp precompile` in this run's environment
        self.kernel_results: dict = {}
        self.targets = {k: Target(*v) for k, v in TARGETS.items()}
        self._models: dict = {}
        self._cache: dict = {}

    def peer(self, module: str):
        """The peer's module; None when it is not installed or --no-peers was given."""
        return peer(module) if self.use_peers else None

    def target(self, key: str) -> Target:
        return self.targets[key]

    def kernel_cases(self) -> list[str]:
        return [c for c in self.cases if c != "kepler"]

    def warm_cases(self) -> list[str]:
        return ["double_pendulum"] if self.quick else ["double_pendulum", "n_link_pendulum_10"]

    def peer_compile_cases(self) -> list[str]:
        return [] if self.quick else ["double_pendulum", "n_link_pendulum_4"]

    def unavailable(self, case: str) -> str:
        result = self.cold.get(case)
        return f"not compiled: {result}" if isinstance(result, str) else "not compiled"

    def model(self, case: str):
        """The compiled model (None when its cold compile failed or ran out of time)."""
        if case not in self._models:
            import lagcomp as lc

            if isinstance(self.cold.get(case), str):
                self._models[case] = None
            else:
                self._models[case] = lc.compile(build_system(case), cache_dir=self.cache_dir)
        return self._models[case]

    def eom(self, case: str):
        def derive():
            from lagcomp.mechanics.lagrange import derive

            return derive(build_system(case))
        return self.cached(("eom", case), derive)

    def cached(self, key, make):
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]


def machine() -> str:
    import numba
    import numpy

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    revision = "unknown revision"
    try:
        import subprocess
        from pathlib import Path

        out = subprocess.run(["git", "describe", "--always", "--dirty"], capture_output=True, text=True, timeout=10,
                             cwd=Path(__file__).resolve().parents[1])
        if out.returncode == 0:
            revision = f"lagcomp at {out.stdout.strip()}"
    except (OSError, subprocess.SubprocessError):
        pass
    return (f"{cpu}, {os.cpu_count()} logical CPUs, load average {load:.1f} at start; Python {platform.python_version()}, "
            f"numba {numba.__version__}, numpy {numpy.__version__}; {revision}")


def targets_table(ctx) -> Table:
    table = Table("Issue 8 targets (start-up: issue 19; stiff: issue 20)", ["target", "wanted", "this run", "verdict"])
    dp = ctx.kernel_results.get("double_pendulum")
    if dp:
        base, ours, ratio = dp
        t = ctx.target("rhs_dp")
        t.measured = f"{ratio.median:.2f}× ({ratio.low:.2f}–{ratio.high:.2f}; {ours.median:.0f} vs {base.median:.0f} ns)"
        t.met = ratio.median <= 1.2
    n10 = ctx.kernel_results.get("n_link_pendulum_10")
    t = ctx.target("rhs10")
    if n10:
        t.measured = f"{n10[1].median:.0f} ns ({n10[1].low:.0f}–{n10[1].high:.0f}; {n10[2].median:.2f}× the closed-form loop)"
        t.met = n10[1].median <= 400
    elif "n_link_pendulum_10" in ctx.cold:
        t.measured = ctx.unavailable("n_link_pendulum_10")
    for target in ctx.targets.values():
        table.add(*target.row())
    return table


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench", description="lagcomp against its peers, in one run.")
    parser.add_argument("--quick", action="store_true", help="small cases only (under 3 minutes)")
    parser.add_argument("--out", help="also write the markdown to this file")
    parser.add_argument("--repeats", type=int, default=5, help="timed repeats per figure (medians; default 5)")
    parser.add_argument("--case-timeout", type=float, default=None,
                        help="time limit of one cold compile, seconds (default 120, 60 with --quick)")
    parser.add_argument("--only", nargs="+", choices=SECTIONS, help="run only these sections")
    parser.add_argument("--cases", nargs="+", help="benchmark cases (default: all, or the quick set)")
    parser.add_argument("--no-peers", action="store_true", help="lagcomp and the hand-written baselines only")
    parser.add_argument("--cache-dir", help="reuse this cache directory instead of a fresh temporary one "
                                            "(cold compiles are then warm)")
    args = parser.parse_args(argv)
    args.repeats = max(args.repeats, 1)
    if args.case_timeout is None:
        args.case_timeout = 60.0 if args.quick else 120.0
    sections = args.only or SECTIONS
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="lagcomp-bench-") as tmp:
        ctx = Context(args, args.cache_dir or tmp)
        head = ["# lagcomp benchmarks" + (" (--quick)" if args.quick else ""), "",
                f"Machine: {machine()}.", "",
                "Every figure is a median of repeated runs with (min–max), and a ratio against a baseline measured "
                "in this same run: the machines are small and shared, so absolute times move between runs "
                "and ratios much less. Peers that are not installed are reported as skipped.", ""]
        print("\n".join(head), flush=True)
        chunks = ["\n".join(head)]

        def emit(table: Table) -> None:
            text = table.markdown()
            print(text, flush=True)
            chunks.append(text)

        from bench import compile_time

        if "compile" in sections:  # fills the cache; the compile section reports these
            compile_time.prepare(ctx)
        runners = {"compile": compile_time.section}
        from bench import (
            accuracy,
            adaptive,
            bench_loop,
            bench_rattle,
            bench_recording,
            bench_reset_sweep,
            bench_scale,
            bench_stiff,
            bench_sweep,
            bench_taylor,
            bench_tiers,
            kernels,
            throughput,
        )

        runners.update(kernels=kernels.section, accuracy=accuracy.section, adaptive=adaptive.section,
                       fixed=throughput.fixed_section,
                       sweeps=throughput.sweep_section, ensembles=bench_sweep.section,
                       long=lambda ctx: [throughput.long_run_section(ctx), bench_taylor.long_run_table(ctx)],
                       memory=throughput.memory_section,
                       stiff=lambda ctx: [bench_stiff.section(ctx), bench_rattle.section(ctx), bench_loop.section(ctx)],
                       impacts=bench_reset_sweep.section,
                       tiers=lambda ctx: [*bench_tiers.section(ctx), *bench_recording.section(ctx)],
                       scale=bench_scale.section)
        for name in SECTIONS:
            if name in sections:
                print(f"<!-- section {name} ... -->", file=sys.stderr, flush=True)
                try:
                    tables = runners[name](ctx)
                    for table in tables if isinstance(tables, list) else [tables]:  # a section may print several
                        emit(table)
                except Exception as err:  # one broken section must not hide the others
                    import traceback

                    traceback.print_exc()
                    emit(Table(f"Section {name}: failed", ["error"], rows=[[f"{type(err).__name__}: {err}"[:300]]]))
        emit(targets_table(ctx))
        tail = f"Total wall time {time.perf_counter() - started:.0f} s. Reproduce: `python -m bench{' --quick' if args.quick else ''}`."
        print(tail)
        chunks.append(tail + "\n")
    if args.out:
        with open(args.out, "w") as f:
            f.write("\n".join(chunks))
    return 0
