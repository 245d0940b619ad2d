"""Cold compile time of large systems, end to end and by stage (issue 8).

    python bench/bench_large.py                 # N = 10 and 24, 3 runs each
    python bench/bench_large.py --n 10 --repeats 5
    python bench/bench_large.py --src /path/to/old/src src   # before/after, runs interleaved

lagcomp before da1781f refused the 24-link chain (its singularity test,
det M / Π|rows of M|, underflows); LAGCOMP_BENCH_SKIP_MASS_CHECK=1 skips that
test so that the old code can be timed.

Each run is a fresh process with an empty cache directory, doing what a user
does: ``lagcomp.compile(n_link_pendulum(N))`` and a first
``model.simulate(method="dop853")``.  Stages are timed inside that one run:
import and system construction; derivation, lowering (CSE) and emission
(wrapped, as `runtime.build` calls them); the rest of `compile` (cache store,
module load); and numba's compilation during the first simulate, split into
the functions numba compiled (top level: the driver, `observables`, `rhs`
when called from Python), from numba's compile events.  "end to end" is from
the start of the process's work (before ``import lagcomp``) to the first
simulate returning.  Medians over the runs, with min–max.

Targets (issue 8): N = 10 ≤ 6 s, N = 24 ≤ 60 s end to end.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

CHILD = r"""
import json, os, sys, time
start = time.perf_counter()
import lagcomp as lc
from lagcomp import examples
from lagcomp.codegen import emit as emit_module, lower as lower_module
from lagcomp.mechanics import lagrange
n, cache_dir = int(sys.argv[1]), sys.argv[2]
system = examples.n_link_pendulum(n)
times = {"import + system": time.perf_counter() - start}

def timed(module, name, stage):
    function = getattr(module, name)
    def wrapper(*args, **kwargs):
        t0 = time.perf_counter()
        try:
            return function(*args, **kwargs)
        finally:
            times[stage] = times.get(stage, 0.0) + time.perf_counter() - t0
    setattr(module, name, wrapper)

if os.environ.get("LAGCOMP_BENCH_SKIP_MASS_CHECK"):  # lagcomp before da1781f refused a 24-link chain
    lagrange._check_mass_matrix = lambda *args: None
timed(lagrange, "derive", "derive")
timed(lower_module, "lower", "lower (CSE)")
timed(emit_module, "emit", "emit")
if hasattr(emit_module, "emit_eager"):   # (lagcomp with kernels on demand: compile emits the eager module)
    timed(emit_module, "emit_eager", "emit")
t0 = time.perf_counter()
model = lc.compile(system, cache_dir=cache_dir)
compile_total = time.perf_counter() - t0
times["store + load"] = compile_total - sum(times.get(k, 0.0) for k in ("derive", "lower (CSE)", "emit"))

from numba.core import event
class Compiles(event.Listener):
    def __init__(self):
        self.depth, self.started, self.top = 0, [], {}
    def on_start(self, e):
        self.depth += 1
        self.started.append(time.perf_counter())
    def on_end(self, e):
        self.depth -= 1
        elapsed = time.perf_counter() - self.started.pop()
        if self.depth == 0:
            name = "numba: " + e.data["dispatcher"].py_func.__name__
            self.top[name] = self.top.get(name, 0.0) + elapsed
listener = Compiles()
t0 = time.perf_counter()
with event.install_listener("numba:compile", listener):
    model.simulate((0.0, 0.1), method="dop853", progress=False)
first_run = time.perf_counter() - t0
times.update(listener.top)
times["numba: total first simulate"] = first_run
times["end to end"] = time.perf_counter() - start
# the kernels compile built (an older lagcomp: all of them); `operations` would build the on-demand ones too
print(json.dumps({"times": times, "operations": getattr(model, "_operations", None) or model.operations}))
"""


def run_once(n: int, src: str | None = None) -> dict:
    """One cold run in a fresh process with an empty cache directory (lagcomp from `src` if given)."""
    with tempfile.TemporaryDirectory() as cache_dir:
        env = dict(os.environ, LAGCOMP_CACHE_DIR=cache_dir)
        if src is not None:
            env["PYTHONPATH"] = os.path.abspath(src)
        out = subprocess.run([sys.executable, "-c", CHILD, str(n), cache_dir], env=env,
                             capture_output=True, text=True)
    if out.returncode:
        raise RuntimeError(f"n = {n}, src = {src}: {out.stderr.strip().splitlines()[-1]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, nargs="+", default=[10, 24])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--src", nargs="+", default=[None],
                        help="lagcomp source trees to compare (runs interleaved, so load hits them alike)")
    args = parser.parse_args(argv)
    for n in args.n:
        runs = {src: [] for src in args.src}
        for _ in range(args.repeats):
            for src in args.src:
                runs[src].append(run_once(n, src))
        stages = list(dict.fromkeys(k for rs in runs.values() for r in rs for k in r["times"]))
        print(f"\n### n_link_pendulum({n}), {args.repeats} cold run(s) each, median (min–max) in s\n")
        labels = [src or "installed" for src in args.src]
        ratio = len(args.src) == 2
        print("| stage | " + " | ".join(labels) + (" | ratio |" if ratio else " |"))
        print("|---|" + "---:|" * (len(labels) + ratio))
        for stage in stages:
            cells, medians = [], []
            for src in args.src:
                values = [r["times"].get(stage, 0.0) for r in runs[src]]
                medians.append(statistics.median(values))
                cells.append(f"{medians[-1]:.2f} ({min(values):.2f}–{max(values):.2f})")
            if ratio:
                cells.append(f"{medians[1] / medians[0]:.2f}" if medians[0] > 0 else "–")
            print(f"| {stage} | " + " | ".join(cells) + " |")
        for src in args.src:
            ops = runs[src][0]["operations"]
            print(f"\noperations after CSE ({src or 'installed'}): {', '.join(f'{k} {v}' for k, v in ops.items())}")


if __name__ == "__main__":
    main()
