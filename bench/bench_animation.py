"""Frames per second of wall time that `lagcomp animate` renders, for the bundled examples it draws.

    python -m bench.bench_animation [--seconds 5] [--fps 30] [--dpi 100] [--examples NAME ...]

For each example (the bundled ones built from bodies, and the double pendulum drawn from points): a run
saved at the frames' times, as `lagcomp animate` makes it, then its clip rendered three ways, each timed
in this process (wall time and CPU time, `time.process_time`):

* ``blitted``: what `lagcomp.animation.save_animation` does now: the figure's static part drawn once, each
  frame only its moving artists over it (`MechanismAnimation.rgba_frames`), encoded as a GIF by Pillow;
* ``frames only``: the same blitted frames without the encoding (the renderer's own rate);
* ``matplotlib save``: ``anim.save(path, writer=PillowWriter)``, matplotlib's own loop, which draws the
  whole figure for every frame (what lagcomp did before).

frames/s = frames / wall seconds (and frames / CPU seconds of this process, which a loaded machine's
contention does not inflate); the speed-up is the ratio of the wall times of the first and last renderings
of the same clip in the same process.  The machine's load is printed with the figures (os.getloadavg).
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

import numpy as np

#: The examples `lagcomp animate` draws that this bench renders by default.
DEFAULT_EXAMPLES = ("double_pendulum", "turn_indicator", "compton_disc", "driven_pendulum_support", "symmetric_top",
                    "wheel_jack")


def _animation(name: str, seconds: float, fps: float, dpi: float, cache_dir):
    import lagcomp as lc
    from lagcomp import examples
    from lagcomp.animation import EXAMPLE_DRAWINGS, body_drawing, frame_times

    model = lc.compile(examples.get(name), cache_dir=cache_dir, progress=False)
    times = frame_times(np.array([0.0, seconds]), fps, 1.0)
    sol = model.simulate((0.0, seconds), t_eval=times, rtol=1e-10, atol=1e-10, progress=False)
    drawing = EXAMPLE_DRAWINGS[name](model.coordinates) if name in EXAMPLE_DRAWINGS else body_drawing(sol)
    return lc.animate(sol, **drawing, fps=fps, title=name, dpi=dpi, progress=False)


def _timed(work) -> tuple[float, float]:
    wall, cpu = time.perf_counter(), time.process_time()
    work()
    return time.perf_counter() - wall, time.process_time() - cpu


def measure(name: str, seconds: float, fps: float, dpi: float, cache_dir, folder: Path) -> dict:
    """Wall and CPU seconds of the three renderings of one example's clip."""
    from matplotlib.animation import PillowWriter

    from lagcomp.animation import save_animation

    anim = _animation(name, seconds, fps, dpi, cache_dir)
    frames = len(anim.frame_times)
    result = {"example": name, "frames": frames}
    result["blitted"] = _timed(lambda: save_animation(anim, folder / f"{name}.gif", progress=False))
    result["frames only"] = _timed(lambda: sum(1 for _ in anim.rgba_frames()))
    result["matplotlib save"] = _timed(lambda: anim.save(folder / f"{name}_mpl.gif", writer=PillowWriter(fps=fps)))
    return result


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=5.0, help="simulated seconds per clip (default 5)")
    parser.add_argument("--fps", type=float, default=30.0, help="frames per second of the clip (default 30)")
    parser.add_argument("--dpi", type=float, default=100.0, help="resolution of the 5 x 5 inch figure (default 100)")
    parser.add_argument("--examples", nargs="+", default=list(DEFAULT_EXAMPLES))
    args = parser.parse_args(argv)
    load = os.getloadavg()
    print(f"# lagcomp animate: frames/s of wall time ({args.seconds:g} s clips at {args.fps:g} fps, "
          f"{5 * args.dpi:.0f} x {5 * args.dpi:.0f} px; load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}, "
          f"{os.cpu_count()} CPUs)\n")
    print("| example | frames | blitted, GIF: frames/s of wall (of CPU) | blitted frames only: frames/s of wall "
          "(of CPU) | matplotlib save, GIF: frames/s of wall (of CPU) | speed-up |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory(prefix="lagcomp-bench-animation-") as folder:
        for name in args.examples:
            r = measure(name, args.seconds, args.fps, args.dpi, Path(folder) / "cache", Path(folder))
            n = r["frames"]
            (fast, fast_cpu), (raw, raw_cpu), (slow, slow_cpu) = r["blitted"], r["frames only"], r["matplotlib save"]
            print(f"| {name} | {n} | {n / fast:.1f} ({n / fast_cpu:.0f}) | {n / raw:.1f} ({n / raw_cpu:.0f}) | "
                  f"{n / slow:.1f} ({n / slow_cpu:.1f}) | {slow / fast:.1f}x |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
