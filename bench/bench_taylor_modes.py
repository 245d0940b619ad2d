"""What the Taylor programs of the modes cost at build time: codegen and numba's compile of ``taylor_coefficients``.

    python -m bench.bench_taylor_modes [--base SRC]

For the ball on a floor (one contact: 2 programs), the particle on a sphere (one contact, a gap √(x² + y²) − R:
2 programs) and the belt oscillator (one friction element: 2 programs): the time of
`lagcomp.codegen.taylor.taylor_decomposition` (sympy-free series arithmetic over the lowered kernels; the median
of 5) and of numba's first compile of the emitted ``taylor_coefficients`` (an empty numba cache, in a fresh
process each).  With ``--base SRC`` (the ``src`` of an older lagcomp, whose Taylor program is the motion with every
contact open) the same for it, in the same run; the ratios are this tree's over the base's.

Measured (``--base`` the src of f953d75; two cores shared with other jobs, so compile times ±30%): codegen
1.3 / 11.1 / 5.4 ms (base 0.2 / 0.8 / 0.7 ms), numba's compile 2.10 / 14.43 / 1.38 s (base 1.40 / 1.58 / 1.40 s) for
the ball / sphere / belt: the sphere's held program has 46 series operations (the gap's second derivative, with
its √ and power −3/2) against its free fall's 2, and numba's compile grows with them.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

SYSTEMS = ("ball", "sphere", "belt")

_CHILD = r'''
import json, statistics, sys, time
import numpy as np, sympy as sp
import lagcomp as lc
from lagcomp.codegen.lower import lower
from lagcomp.codegen.taylor import taylor_decomposition
from lagcomp.mechanics.lagrange import derive

t = lc.t
which = sys.argv[1]
if which == "ball":
    x, = lc.coordinates("x")
    system = lc.System([x], T=x.diff(t) ** 2 / 2, V=9.81 * x, events=[lc.Contact("floor", x, restitution=0.5)],
                       name="bench_modes_ball")
elif which == "sphere":
    x, y = lc.coordinates("x y")
    system = lc.System([x, y], T=(x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=9.81 * y,
                       events=[lc.Contact("sphere", sp.sqrt(x**2 + y**2) - 2, restitution=0.5)],
                       name="bench_modes_sphere")
else:
    x, = lc.coordinates("x")
    system = lc.System([x], T=x.diff(t) ** 2 / 2, V=2 * x**2,
                       events=[lc.Friction("belt", x.diff(t) - 0.5, normal=9.81, static=0.6, kinetic=0.4)],
                       name="bench_modes_belt")
ir = lower(derive(system))
times = []
for _ in range(5):
    start = time.perf_counter()
    taylor_decomposition(ir)
    times.append(time.perf_counter() - start)
model = lc.compile(system, cache_dir=sys.argv[2])
kernels = model.kernels
p = np.zeros(64)
y = np.zeros(model.state_size)
start = time.perf_counter()
kernels.taylor_coefficients(0.0, y, p, np.zeros((y.size, 21)), np.zeros((kernels.TAYLOR_WORK, 21)))
compile_time = time.perf_counter() - start
print(json.dumps({"codegen": statistics.median(times), "compile": compile_time}))
'''


def measure(src: str, which: str) -> dict:
    """Codegen and compile seconds for `which` with the lagcomp in `src`, in a fresh process and caches."""
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as numba_cache:
        env = dict(os.environ, PYTHONPATH=src, NUMBA_CACHE_DIR=numba_cache, LAGCOMP_CACHE_DIR=cache)
        out = subprocess.run([sys.executable, "-c", _CHILD, which, cache], env=env, capture_output=True, text=True,
                             check=True)
        return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", help="the src directory of a lagcomp to compare with")
    args = parser.parse_args()
    here = str(Path(__file__).resolve().parent.parent / "src")
    for which in SYSTEMS:
        now = measure(here, which)
        line = f"{which:7s} codegen {now['codegen'] * 1e3:7.1f} ms   compile {now['compile']:6.2f} s"
        if args.base:
            base = measure(args.base, which)
            line += (f"   base: codegen {base['codegen'] * 1e3:7.1f} ms, compile {base['compile']:6.2f} s   "
                     f"ratios {now['codegen'] / base['codegen']:.2f}, {now['compile'] / base['compile']:.2f}")
        print(line, flush=True)


if __name__ == "__main__":
    main()
