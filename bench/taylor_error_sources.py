"""Where method="taylor"'s energy error on long runs comes from: taylor_run's loop with one thing changed at a time.

    PYTHONPATH=src python -m bench.taylor_error_sources [--t-end 1e4] [--members 16] [--variants ...]

The double pendulum (θ = (2, 1) at rest, the default tolerance, order 20)
integrated by a copy of ``taylor_run``'s step loop (the module's own
``taylor_coefficients`` and ``lagcomp.kernel_support.angles.reduced_angle``) with one variant each:

* ``taylor_run``: as the driver does it: the series at the periodic
  coordinates reduced to [−π, π] with the carry folded in, compensated sums;
* ``unreduced``: the series at the stored y (the driver before issue 18);
* ``uncompensated``: reduced, but y + increment rounded plainly;
* ``norm reduced``: the step rule's ‖y‖ over the reduced state too;
* ``half step``, ``1.2 step``: the step of the rule times 0.5 or 1.2
  (truncation error falls or rises by 2²⁰ or 1.2²¹; round-off per unit time
  rises or falls with the number of steps);
* ``order 19``, ``order 22``: another order at the same rule.

For each, over starts θ1 = 2 + j ulp: the rms and mean of the relative
energy error E(y)/E(y0) − 1 at t = 10, 100, 10³, 10⁴ (hand-written energy,
angles reduced and carry included, so that the reading is the integration's
error and not the rounding of a wound-up stored angle), and steps per run.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
from numba import njit

import lagcomp as lc
from lagcomp import examples
from lagcomp.kernel_support.angles import reduced_angle

VARIANTS = {
    "taylor_run": dict(),
    "unreduced": dict(reduce=False),
    "uncompensated": dict(compensate=False),
    "norm reduced": dict(norm_reduced=True),
    "half step": dict(step_scale=0.5),
    "1.2 step": dict(step_scale=1.2),
    "order 19": dict(order=19),
    "order 22": dict(order=22),
}


@njit(cache=False)
def _energy(th1, th2, w1, w2):
    """E of the double pendulum with m = l = 1, g = 9.81 (bench_taylor.P)."""
    return w1 * w1 + 0.5 * w2 * w2 + w1 * w2 * math.cos(th1 - th2) - 2 * 9.81 * math.cos(th1) - 9.81 * math.cos(th2)


def make_loop(kernels):
    """``taylor_run``'s step loop over the module's kernels, with the variants' switches."""
    coefficients, reduced, work = kernels.taylor_coefficients, reduced_angle, kernels.TAYLOR_WORK

    @njit(cache=False)
    def loop(y0, p, t_end, checks, order, reduce, compensate, norm_reduced, step_scale, out):
        n = y0.shape[0]
        y, carry, z = y0.copy(), np.zeros(n), np.empty(n)
        X, W = np.empty((n, order + 1)), np.empty((work, order + 1))
        factor = math.exp(-0.7 / (order - 1)) / (math.e * math.e) * step_scale
        e0 = _energy(y[0], y[1], y[2], y[3])
        t, steps, c = 0.0, 0, 0
        while t < t_end:
            for i in range(n):
                z[i] = reduced(y[i], carry[i]) if reduce and i < 2 else y[i]
            coefficients(t, z, p, X, W)
            norm_y, norm_last, norm_before = 0.0, 0.0, 0.0
            for i in range(n):
                norm_y = max(norm_y, abs(z[i] if norm_reduced else y[i]))
                norm_last = max(norm_last, abs(X[i, order]))
                norm_before = max(norm_before, abs(X[i, order - 1]))
            scale = max(norm_y, 1.0)    # rtol = atol: relative control above 1
            h = min((scale / norm_last) ** (1.0 / order), (scale / norm_before) ** (1.0 / (order - 1))) * factor
            h = min(h, t_end - t)
            for i in range(n):
                acc = 0.0
                for j in range(order, 0, -1):
                    acc = (acc + X[i, j]) * h
                if compensate:
                    increment = acc - carry[i]
                    y_new = y[i] + increment
                    carry[i] = (y_new - y[i]) - increment
                    y[i] = y_new
                else:
                    y[i] += acc
            t += h
            steps += 1
            while c < checks.shape[0] and t >= checks[c]:
                out[c] = _energy(reduced(y[0], carry[0]), reduced(y[1], carry[1]), y[2] - carry[2],
                                 y[3] - carry[3]) / e0 - 1.0
                c += 1
        return steps
    return loop


def run(t_end: float, members: int, names: list[str]) -> None:
    model = lc.compile(examples.get("double_pendulum"))
    loop = make_loop(model.kernels)
    p = model.parameter_vector()
    checks = np.array([t for t in (10.0, 100.0, 1000.0, 1e4) if t <= t_end])
    print(f"double pendulum to t = {t_end:g}, {members} starts 1 ulp apart in θ1; relative energy error at "
          f"t = {', '.join(f'{t:g}' for t in checks)}\n")
    loop(np.array([2.0, 1.0, 0.0, 0.0]), p, 1.0, checks, 20, True, True, False, 1.0, np.empty(checks.size))  # compile
    print("| variant | steps per run | rms | mean | s per run |")
    print("|---|---|---|---|---|")
    for name in names:
        options = dict(order=20, reduce=True, compensate=True, norm_reduced=False, step_scale=1.0)
        options.update(VARIANTS[name])
        errors, steps = np.empty((members, checks.size)), 0
        start = time.perf_counter()
        for j in range(members):
            y0 = np.array([2.0 + j * np.spacing(2.0), 1.0, 0.0, 0.0])
            steps += loop(y0, p, t_end, checks, options["order"], options["reduce"], options["compensate"],
                          options["norm_reduced"], options["step_scale"], errors[j])
        wall = (time.perf_counter() - start) / members
        rms, mean = np.sqrt(np.mean(errors**2, axis=0)), np.mean(errors, axis=0)
        print(f"| {name} | {steps / members:.0f} | {' / '.join(f'{v:.1e}' for v in rms)} | "
              f"{' / '.join(f'{v:+.1e}' for v in mean)} | {wall:.2f} |", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=1e4)
    parser.add_argument("--members", type=int, default=16)
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    args = parser.parse_args()
    run(args.t_end, args.members, args.variants)


if __name__ == "__main__":
    main()
