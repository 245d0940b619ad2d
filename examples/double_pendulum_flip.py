"""Chaos map of the double pendulum: how long until a rod flips over, across the plane of release angles.

    python examples/double_pendulum_flip.py [--side 200] [--t-end 10] [--plot flip.png]

Both rods start at rest at angles (θ1, θ2) ∈ [−3, 3]²; a rod "flips" when its
angle reaches ±π (over the top).  Two terminal events, θk² − π² crossing
zero upwards, stop each trajectory at its first flip, so the sweep's
``t_final`` is the flip time (``status`` 1) or the end of the run (status 0:
no flip in time).  Energy forbids some flips outright: from rest,
E = −g l m [2 cos θ1 + cos θ2] (unit masses and lengths), and reaching θ2 = π
needs E ≥ −g (the least potential energy with θ2 = π, at θ1 = 0), so no rod
can flip where 2 cos θ1 + cos θ2 > 1.  The map shows that smooth region and
the fractal structure outside it.
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np
import sympy as sp

import lagcomp as lc
from lagcomp import examples


def flipping_double_pendulum() -> lc.System:
    """The bundled double pendulum with two terminal events: either rod passing over the top."""
    base = examples.double_pendulum()
    th1, th2 = base.coordinates
    return dataclasses.replace(
        base, name="double_pendulum_flip", description="Double pendulum stopped when a rod flips over the top.",
        events=(lc.Event("rod1_flips", th1**2 - sp.pi**2, direction=1, terminal=True),
                lc.Event("rod2_flips", th2**2 - sp.pi**2, direction=1, terminal=True)),
    )


def flip_map(side: int = 200, t_end: float = 10.0, rtol: float = 1e-9, cache_dir=None, workers=None):
    """(sweep, flip time per grid point (inf: none before t_end), the energetically forbidden region mask)."""
    model = lc.compile(flipping_double_pendulum(), cache_dir=cache_dir)
    angles = np.linspace(-3, 3, side)
    sweep = model.sweep((0, t_end), {"theta1": angles, "theta2": angles}, qd0=[0, 0], rtol=rtol, atol=rtol,
                        workers=workers)
    flip_time = np.where(sweep.status == 1, sweep.t_final, np.inf)
    th1, th2 = np.meshgrid(angles, angles, indexing="ij")
    forbidden = 2 * np.cos(th1) + np.cos(th2) > 1
    return sweep, flip_time, forbidden


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--side", type=int, default=200, help="grid points per axis")
    parser.add_argument("--t-end", type=float, default=10.0)
    parser.add_argument("--plot", metavar="PNG", help="draw the map (needs matplotlib)")
    args = parser.parse_args()
    started = time.perf_counter()
    sweep, flip_time, forbidden = flip_map(args.side, args.t_end)
    elapsed = time.perf_counter() - started
    flipped = np.isfinite(flip_time)
    print(f"{flip_time.size} trajectories in {elapsed:.1f} s (first run includes compilation)")
    print(f"flipped before t = {args.t_end:g}: {flipped.mean():.1%}; in the energetically forbidden region: "
          f"{np.count_nonzero(flipped & forbidden)} of {np.count_nonzero(forbidden)}")
    if args.plot:
        from lagcomp import plots

        fig = plots.plot_sweep(sweep, np.log10(np.where(flipped, flip_time, args.t_end)), label="log10 flip time",
                               cmap="magma", title=f"double pendulum from rest: time to the first flip (≤ {args.t_end:g})")
        fig.savefig(args.plot, dpi=120)
        print(f"plotted {args.plot}")


if __name__ == "__main__":
    main()
