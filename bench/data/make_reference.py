"""Tight reference for the chaotic double pendulum at t = 10, in high precision (mpmath).

    python bench/data/make_reference.py [--dps 30] [--out bench/data/double_pendulum_reference.json]

The double pendulum of the lagcomp example ``double_pendulum`` with its
defaults (m1 = m2 = l1 = l2 = 1, g = 9.81, θ = (2, 1), θ̇ = 0) is integrated
with mpmath's `odefun` (a Taylor-series method at the working precision) to
t = 1, 2, ..., 10.  Nearby trajectories separate fast (the state at t = 10 moves ~1e7 times
any perturbation at t = 0), so a double-precision run cannot give t = 10
to better than ~1e-9; at 30 digits the reference is good to far below
anything the benchmark measures.  g is the double nearest 9.81, exactly
(not the decimal 9.81): that is the system every benchmarked integrator
solves, and the difference shows at t = 10.  The
script writes the states as decimal strings; `--check FILE` compares a
second run (e.g. at another precision) with a stored one and prints the
largest difference, which is how the stored file was validated: the stored
30-digit run (about 10 minutes) and a 24-digit one agree to 1.3e-23 at
every t = 1, ..., 10.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import mpmath as mp

HERE = Path(__file__).resolve().parent


def rhs(t, y, m1=1, m2=1, l1=1, l2=1, g=9.81):
    g = mp.mpf(g)  # the double nearest 9.81, exactly: what every integrator in the benchmark is given
    th1, th2, w1, w2 = y
    d = th1 - th2
    c, s = mp.cos(d), mp.sin(d)
    a11, a12, a22 = (m1 + m2) * l1**2, m2 * l1 * l2 * c, m2 * l2**2
    f1 = -m2 * l1 * l2 * w2**2 * s - (m1 + m2) * g * l1 * mp.sin(th1)
    f2 = m2 * l1 * l2 * w1**2 * s - m2 * g * l2 * mp.sin(th2)
    det = a11 * a22 - a12 * a12
    return [w1, w2, (a22 * f1 - a12 * f2) / det, (a11 * f2 - a12 * f1) / det]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dps", type=int, default=30)
    parser.add_argument("--t-end", type=int, default=10)
    parser.add_argument("--out", default=str(HERE / "double_pendulum_reference.json"))
    parser.add_argument("--check", help="a stored reference to compare this run with (nothing is written)")
    args = parser.parse_args()
    mp.mp.dps = args.dps
    start = time.perf_counter()
    solution = mp.odefun(rhs, 0, [mp.mpf(2), mp.mpf(1), mp.mpf(0), mp.mpf(0)])
    states = {}
    for t in range(1, args.t_end + 1):
        states[str(t)] = [mp.nstr(v, args.dps, min_fixed=-1, max_fixed=1) for v in solution(t)]
        print(t, states[str(t)], f"{time.perf_counter() - start:.0f} s", flush=True)
    record = {
        "system": "double_pendulum", "params": {"m1": 1, "m2": 1, "l1": 1, "l2": 1, "g": "9.81 as a double"},
        "q0": [2, 1], "qd0": [0, 0], "state": "theta1 theta2 theta1_dot theta2_dot",
        "method": f"mpmath {mp.__version__} odefun (Taylor series), {args.dps} digits", "states": states,
    }
    if args.check:
        stored = json.loads(Path(args.check).read_text())["states"]
        worst = max(abs(mp.mpf(a) - mp.mpf(b)) for t in states for a, b in zip(states[t], stored[t]))
        print(f"largest difference from {args.check}: {mp.nstr(worst, 3)}")
        return
    Path(args.out).write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
