"""A sweep of 10⁴ bouncing balls (restitution e × drop height h₀ grid): throughput, and no missed impact.

    python -m bench.bench_reset_sweep [--e-min 0.8] [--h-min 1.0] [--side 100] [--repeats 3]

The ball: ẍ = −g on a floor at x = 0, written two ways: an event x = 0 downwards whose reset is ẋ → −e ẋ
(`lagcomp.Event(..., reset=...)`), and a contact (`lagcomp.Contact("floor", x, restitution=e)`, whose impact
the kernels derive from M and the gap's gradient).  Each trajectory runs to 0.9 times the earliest
accumulation point of the grid (t∞ = t₁ + 2 v₁ e/(g (1 − e))), with dop853 (rtol = atol = 1e-10) and taylor;
printed: trajectories per second (the best of `--repeats`, after a warm-up sweep that compiles), the impacts in
all, the trajectories whose impact count differs from the closed form (t₁ = √(2 h₀/g), then intervals
2 eᵏ v₁/g), and the worst relative error of their times.  `python -m bench` runs the contact's rows as its
"impacts" section, each against the same sweep without the floor (free fall: the cost of the impacts).

Measured again after the tunnelling fix (drivers/events.py `return_before`) and with the sweep keeping the
states after each impact and the contact's impulses (`Sweep.events[...]["y_after"]`, ``["impulses"]``), the
defaults (e in [0.8, 0.9], h₀ in [1, 2], to t = 3.66): 49 896 impacts for either floor, no trajectory with a
wrong count, impact times to 3.9e-14 (reset, dop853), 7.8e-16 (reset, taylor), 4.1e-14 (contact, dop853),
1.1e-15 (contact, taylor); the reset rows' counts and errors are those measured before the fix.
Throughput, 1 thread, load average 1.7 on the 2 shared cores: reset dop853 47 400/s, taylor 72 000/s;
contact dop853 27 200/s, taylor 34 700/s (the second thread gained nothing; with the load at 3, repeated
runs ranged 31 000–48 000/s (reset, dop853) and 18 500–34 000/s (contact, dop853), this commit and the one
before it alike).  In one process, of a 0.43 s contact sweep (dop853) the impulses of its 49 896 kept
impacts took 0.09 s (`drivers/sweep_impulses`; timed around `lagcomp.integrate.sweep._event_outputs`).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
import sympy as sp

import lagcomp as lc
from bench.harness import Table

G = 9.81


def ball(floor: str = "reset") -> lc.System:
    """The ball with its floor as a reset event ("reset"), a contact ("contact") or none ("none")."""
    (x,) = lc.coordinates("x")
    g, e = sp.symbols("g e", positive=True)
    events = {"reset": [lc.Event("impact", x, direction=-1, reset={x.diff(lc.t): -e * x.diff(lc.t)})],
              "contact": [lc.Contact("impact", x, restitution=e)], "none": []}[floor]
    return lc.System(coordinates=(x,), T=x.diff(lc.t) ** 2 / 2, V=g * x, name=f"bench_ball_{floor}",
                     parameters=(g, e), defaults={"g": G, "e": 0.8}, q0=(1.0,), qd0=(0.0,), events=events)


def impact_times(e: float, h0: float, t_end: float) -> np.ndarray:
    """The closed form: t₁ = √(2 h₀/g), then t_{k+1} = t_k + 2 eᵏ v₁/g, those before t_end."""
    v1 = math.sqrt(2 * G * h0)
    times = [math.sqrt(2 * h0 / G)]
    while times[-1] + 2 * e ** len(times) * v1 / G < t_end:
        times.append(times[-1] + 2 * e ** len(times) * v1 / G)
    return np.array(times)


def accumulation(e: float, h0: float) -> float:
    return math.sqrt(2 * h0 / G) + 2 * math.sqrt(2 * G * h0) * e / (G * (1 - e))


METHODS = (("dop853", dict(rtol=1e-10, atol=1e-10)), ("taylor", {}))


def grid(side: int, e_min: float = 0.8, h_min: float = 1.0) -> tuple[np.ndarray, np.ndarray, float]:
    """The restitutions, the drop heights, and the common end time: 0.9 × the grid's earliest t∞."""
    es, hs = np.linspace(e_min, 0.9, side), np.linspace(h_min, 2.0, side)
    return es, hs, 0.9 * min(accumulation(e, h) for e in es for h in hs)


def measure(model, es, hs, t_end: float, method: str, options: dict, workers: int, repeats: int) -> dict:
    """The best time of `repeats` sweeps (after one that compiles), the impacts found, the trajectories whose
    count differs from the closed form, and the worst relative error of the impact times (no floor: only the
    time)."""
    events = ("events",) if model.event_names else ()
    model.sweep((0.0, t_end), {"e": es[:2], "x": hs[:2]}, output=events, method=method, progress=False, **options)
    best = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        result = model.sweep((0.0, t_end), {"e": es, "x": hs}, output=events, method=method, workers=workers,
                             event_cap=64, progress=False, **options)
        best = min(best, time.perf_counter() - start)
    found = {"seconds": best, "rate": result.status.size / best, "statuses": np.unique(result.status).tolist()}
    if events:
        record = result.events["impact"]
        wrong, worst = 0, 0.0
        for i, e in enumerate(es):
            for j, h in enumerate(hs):
                times, count = impact_times(e, h, t_end), int(record["count"][i, j])
                if count != times.size:
                    wrong += 1
                else:
                    worst = max(worst, float(np.max(np.abs(record["t"][i, j, :count] / times - 1))))
        found.update(impacts=int(record["count"].sum()), wrong=wrong, worst=worst)
    return found


def section(ctx) -> Table:
    """`python -m bench`'s "impacts" section: 10⁴ balls on a `lagcomp.Contact` floor (20² with --quick), each
    method against the same sweep without the floor."""
    side = 20 if ctx.quick else 100
    es, hs, t_end = grid(side)
    contact = lc.compile(ball("contact"), cache_dir=ctx.cache_dir)
    free = lc.compile(ball("none"), cache_dir=ctx.cache_dir)
    table = Table(f"Impacts: {side * side} bouncing balls on a contact (issue 21)",
                  ["method", "trajectories/s", "impacts", "wrong counts", "worst time error", "time / no floor"],
                  note=f"e in [0.8, 0.9] × h₀ in [1, 2], to t = {t_end:.3g} (0.9 × the earliest t∞); 1 thread; "
                       "the best of the repeats; counts and times against the closed form.")
    for method, options in METHODS:
        repeats = min(ctx.repeats, 3)
        hit = measure(contact, es, hs, t_end, method, options, 1, repeats)
        plain = measure(free, es, hs, t_end, method, options, 1, repeats)
        table.add(method, f"{hit['rate']:,.0f}", hit["impacts"], hit["wrong"], f"{hit['worst']:.1e}",
                  f"{hit['seconds'] / plain['seconds']:.1f}×")
    return table


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--e-min", type=float, default=0.8)
    parser.add_argument("--h-min", type=float, default=1.0)
    parser.add_argument("--side", type=int, default=100, help="grid points per axis (side² trajectories)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    es, hs, t_end = grid(args.side, args.e_min, args.h_min)
    for floor in ("reset", "contact"):
        model = lc.compile(ball(floor))
        for method, options in METHODS:
            for workers in (1, 2):
                found = measure(model, es, hs, t_end, method, options, workers, args.repeats)
                print(f"{floor:7s} {method:7s} {workers} thread(s): {found['rate']:9.0f} trajectories/s  "
                      f"({es.size * hs.size} to t = {t_end:.3g}, {found['impacts']} impacts; wrong counts "
                      f"{found['wrong']}; worst relative time error {found['worst']:.2g}; statuses "
                      f"{found['statuses']})")


if __name__ == "__main__":
    main()
