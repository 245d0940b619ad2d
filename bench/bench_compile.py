"""Cold vs warm process: what compiling a system costs the first time and every later time.

    python bench/bench_compile.py [example ...]

For each example, runs three fresh Python processes against one empty cache
directory: the first derives, emits and lets numba compile (cold); the second
must load everything from the cache (warm, through `lagcomp.compile`, which
builds the System with sympy to find its cache key); the third loads the model
by name with `lagcomp.load`, which never imports sympy (the warm start a later
process sees).  Prints, per example, the time to `compile`/`load` and to the
first `simulate` call (which includes numba's compilation or cache load of the
driver and kernels), the warm/cold ratio, and the whole `load` process's wall
time from interpreter start (the issue 8 target: ≤ 1.0 s, no sympy import).
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time

PROBE = """
import json, sys, time
t0 = time.perf_counter()
import lagcomp as lc
from lagcomp import examples
t1 = time.perf_counter()
model = lc.compile(examples.get(sys.argv[1]), cache_dir=sys.argv[2])
t2 = time.perf_counter()
model.simulate((0, 0.1), method=sys.argv[3], progress=False, **({"dt": 1e-3} if sys.argv[3] == "rk4" else {}))
t3 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "compile": t2 - t1, "first_run": t3 - t2, "from_cache": model.from_cache}))
"""


LOAD_PROBE = """
import json, sys, time
t0 = time.perf_counter()
import lagcomp as lc
t1 = time.perf_counter()
model = lc.load(sys.argv[1], cache_dir=sys.argv[2])
t2 = time.perf_counter()
model.simulate((0, 0.1), method=sys.argv[3], progress=False, **({"dt": 1e-3} if sys.argv[3] == "rk4" else {}))
t3 = time.perf_counter()
print(json.dumps({"import": t1 - t0, "compile": t2 - t1, "first_run": t3 - t2, "sympy": "sympy" in sys.modules}))
"""


def probe(name: str, cache_dir: str, method: str, script: str = PROBE) -> dict:
    started = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", script, name, cache_dir, method], capture_output=True, text=True, check=True)
    result = json.loads(out.stdout.strip().splitlines()[-1])
    result["process"] = time.perf_counter() - started
    return result


def main(names: list[str]) -> None:
    print("| example | method | cold compile s | cold first run s | warm compile s | warm first run s | warm/cold total "
          "| load s | load first run s | load process s | sympy imported |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in names:
        for method in ("rk4", "dop853"):
            with tempfile.TemporaryDirectory() as cache_dir:
                cold = probe(name, cache_dir, method)
                warm = probe(name, cache_dir, method)
                loaded = probe(name, cache_dir, method, LOAD_PROBE)
            assert warm["from_cache"] and not cold["from_cache"]
            ratio = (warm["compile"] + warm["first_run"]) / (cold["compile"] + cold["first_run"])
            print(f"| {name} | {method} | {cold['compile']:.2f} | {cold['first_run']:.2f} | "
                  f"{warm['compile']:.3f} | {warm['first_run']:.3f} | {ratio:.3f} | "
                  f"{loaded['compile']:.3f} | {loaded['first_run']:.3f} | {loaded['process']:.2f} | {loaded['sympy']} |")


if __name__ == "__main__":
    main(sys.argv[1:] or ["simple_pendulum", "double_pendulum"])
