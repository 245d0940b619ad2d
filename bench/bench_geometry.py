"""What the ``geometry`` kernel costs: lowering it, and evaluating it for an animation's frames.

    python -m bench.bench_geometry [--rounds 5]

For each bundled example built from bodies, in one process:

* lowering: `lagcomp.codegen.geometry.geometry_kernel` against the whole `lagcomp.codegen.lower.lower` of
  the same derived equations (which includes it), sympy's cache cleared before each call so that every
  call works as a first compile does, timed round-robin (`bench.harness.interleaved`);
* frames: `BodyGeometry.frames` (one kernel call per frame, from Python) against drawing the same frames
  with matplotlib's Agg canvas (`MechanismAnimation.draw` and a canvas draw), the figure's own cost.

Ratios are medians of per-round ratios.
"""

from __future__ import annotations

import argparse

import numpy as np
from sympy.core.cache import clear_cache

import lagcomp as lc
from bench.harness import fmt_stat, interleaved
from lagcomp.animation import frame_times, interpolated_coordinates
from lagcomp.codegen import lower as lowering
from lagcomp.codegen.bindings import symbol_bindings
from lagcomp.codegen.cse import cse_kernel
from lagcomp.codegen.geometry import geometry_kernel
from lagcomp.examples import get
from lagcomp.examples.bodies import BODIES_EXAMPLES
from lagcomp.mechanics.lagrange import derive


def lowering_cost(name: str, rounds: int) -> str:
    eom = derive(get(name))
    mapping, loads = symbol_bindings(eom)

    def whole():
        clear_cache()
        lowering.lower(eom)

    def geometry():
        clear_cache()
        geometry_kernel(eom, lambda *spec: cse_kernel(*spec, mapping, loads))

    (whole_s, geometry_s), (_, ratio) = interleaved([whole, geometry], repeats=rounds)
    return (f"| {name} | lowering | {fmt_stat(geometry_s, 's')} | {fmt_stat(ratio)} of lower() "
            f"({fmt_stat(whole_s, 's')}) |")


def frame_cost(name: str, rounds: int) -> str:
    model = lc.compile(get(name))
    sol = model.simulate((0, 1), t_eval=np.linspace(0, 1, 101))
    times = frame_times(sol.t, 30, 1.0)
    q = interpolated_coordinates(sol, times)
    anim = lc.animate(sol, fps=30, dpi=40)

    def drawing():
        for k in range(len(times)):
            anim.draw(k)
            anim._fig.canvas.draw()

    (draw_s, geometry_s), (_, ratio) = interleaved([drawing, lambda: sol.geometry.frames(times, q)], repeats=rounds,
                                                   per_call=[len(times)] * 2)
    return (f"| {name} | per frame ({len(times)} frames) | {fmt_stat(geometry_s, 's')} | {fmt_stat(ratio)} of drawing "
            f"a frame ({fmt_stat(draw_s, 's')}) |")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    rounds = parser.parse_args(argv).rounds
    print("| example | what | geometry | ratio |\n|---|---|---|---|")
    for name in BODIES_EXAMPLES:
        print(lowering_cost(name, rounds))
        print(frame_cost(name, rounds))


if __name__ == "__main__":
    main()
