"""Kapitza's pendulum: where a vertically vibrated support holds the pendulum upside down.

    python examples/kapitza_map.py [--side 40] [--t-end 10] [--plot kapitza.png]

The support moves as A cos Ωt (example ``driven_pendulum``).  In the
high-frequency limit the averaged potential −g l cos θ + (AΩ)² sin²θ / 4 has
a minimum at θ = π exactly when A²Ω² > 2 g l, so the inverted position is
stable above the curve A = √(2gl) / Ω.  The sweep starts every (A, Ω) of
the grid 0.05 rad from upright, and a terminal event stops a run once the
pendulum strays more than 0.5 rad: what survives to ``t_end`` is stable.
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np
import sympy as sp

import lagcomp as lc
from lagcomp import examples

G, L = 9.81, 1.0


def watched_driven_pendulum() -> lc.System:
    """The bundled driven pendulum with a terminal event: |θ − π| reaching 0.5 rad."""
    base = examples.driven_pendulum()
    (theta,) = base.coordinates
    return dataclasses.replace(base, name="driven_pendulum_falls", description="Kapitza pendulum, stopped when it falls.",
                               events=(lc.Event("falls", (theta - sp.pi) ** 2 - sp.Rational(1, 4), direction=1,
                                                terminal=True),))


def stability_map(side: int = 40, t_end: float = 10.0, cache_dir=None, workers=None):
    """(sweep, stable mask over (A, Ω), the high-frequency prediction A Ω > √(2 g l))."""
    model = lc.compile(watched_driven_pendulum(), cache_dir=cache_dir)
    amplitudes, frequencies = np.linspace(0.005, 0.05, side), np.linspace(60.0, 250.0, side)
    sweep = model.sweep((0, t_end), {"A": amplitudes, "Omega": frequencies}, q0=[np.pi - 0.05], qd0=[0.0],
                        params={"g": G, "l": L}, rtol=1e-9, atol=1e-9, workers=workers)
    stable = sweep.status == 0
    A, W = np.meshgrid(amplitudes, frequencies, indexing="ij")
    return sweep, stable, A * W > np.sqrt(2 * G * L)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--side", type=int, default=40, help="grid points per axis")
    parser.add_argument("--t-end", type=float, default=10.0)
    parser.add_argument("--plot", metavar="PNG", help="draw the map (needs matplotlib)")
    args = parser.parse_args()
    started = time.perf_counter()
    sweep, stable, predicted = stability_map(args.side, args.t_end)
    print(f"{stable.size} runs in {time.perf_counter() - started:.1f} s (first run includes compilation)")
    print(f"stable: {stable.mean():.1%}; agreeing with A Ω > √(2gl): {np.mean(stable == predicted):.1%}")
    if args.plot:
        from lagcomp import plots

        fig = plots.plot_sweep(sweep, stable.astype(float), label="stays upright", cmap="cividis",
                               title="Kapitza pendulum: inverted position held (yellow); curve A Ω = √(2gl)")
        omega = np.linspace(60.0, 250.0, 200)
        fig.axes[0].plot(np.sqrt(2 * G * L) / omega, omega, "w--")
        fig.axes[0].set_xlim(sweep.axes["A"][0], sweep.axes["A"][-1])
        fig.savefig(args.plot, dpi=120)
        print(f"plotted {args.plot}")


if __name__ == "__main__":
    main()
