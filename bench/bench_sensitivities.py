"""What forward sensitivities cost: a run with k columns against a plain run, in one process.

    python -m bench.bench_sensitivities [--t-end 1000] [--rtol 1e-10] [--repeats 7]

For each model (the double pendulum, n = 2; a 5-link pendulum, n = 5, both from a regular state; the free
axle, n = 5 with 3 constraints (Lagrange multipliers: its kernels solve the augmented system), from its launch)
and k = 1 (∂y/∂θ₁(0); the free axle's ∂y/∂g) and k = 2n (every initial-state component), and each
`sensitivity_control` ("state": the plain run's steps; "both": the norm covers the sensitivities too, more
steps): DOP853 at rtol = atol, the median over `--repeats` interleaved pairs of (time with k columns) / (time
of the plain run), and the same per accepted step.
Issue #22's target is a ratio ≤ 1.2 (1 + k).  Each evaluation of the augmented rhs
(`lagcomp.integrate.sensitivities.augmented_rhs`) calls the module's ``rhs_with_jacobian`` (f and J in
one call, J written straight into its work space, M's LDLᵀ written out for n ≤ 6), then forms J S.

Measured (``--t-end 300 --repeats 5``, the "state" rows; the "both" rows take 1.3-1.5× the steps):
double pendulum 3.2× (k = 1), 3.7× (k = 4); 5-link 3.0× (k = 1), 6.1× (k = 10).  Before
``rhs_with_jacobian`` (``rhs``, then ``rhs_jacobian`` calling ``rhs`` again, copying J from a work
array and solving by M in loops): 5.2×, 5.7×, 6.0×, 9.2×; with it but the loops: 4.2×, 4.8×, 4.8×, 7.8×.
With the defaults (t in [0, 1000], 7 repeats): 3.02×, 3.64×, 3.02×, 6.18× (before: 5.65×, 5.85×, 6.03×, 9.29×).
The free axle (``--t-end 300 --repeats 5``, "state"): 6.5× (k = 1, ∂y/∂g: ``rhs_with_jacobian`` and
``rhs_parameter_jacobian`` each solve the augmented system for (q̈, λ) and factor it again for their columns),
5.05× (k = 10, within 1.2 (1 + k) = 13.2); 8.1× and 5.8× when those kernels called ``rhs`` and ``reactions``
apart instead of ``rhs_and_reactions``.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def _timed(run) -> tuple[object, float]:
    start = time.perf_counter()
    sol = run()
    return sol, time.perf_counter() - start


def _runs(model, q0, t_end: float, rtol: float, columns, control):
    """The plain run and the run with sensitivity `columns` under `control`, as functions of no argument."""
    options = dict(rtol=rtol, atol=rtol, save_every=1_000_000, progress=False)

    def plain():
        return model.simulate((0.0, t_end), q0, **options)

    def with_columns():
        return model.simulate((0.0, t_end), q0, sensitivities=columns, sensitivity_control=control, **options)
    return plain, with_columns


def measure(t_end: float = 1000.0, rtol: float = 1e-10, repeats: int = 7, cache_dir=None) -> list[dict]:
    import lagcomp as lc
    from lagcomp import examples

    rows = []
    for name, kwargs in (("double_pendulum", {}), ("n_link_pendulum", {"n": 5}), ("free_axle", {})):
        model = lc.compile(examples.get(name, **kwargs), cache_dir=cache_dir)
        # the constrained free axle from its own (consistent) launch, k = 1 a parameter (the launch stays consistent)
        q0 = None if model.k else np.linspace(0.5, 0.2, model.n)
        first = "g" if model.k else model.coordinates[0]
        for columns, control in ((first, "state"), (("q0", "qd0"), "state"), (first, "both"), (("q0", "qd0"), "both")):
            plain, with_columns = _runs(model, q0, t_end, rtol, columns, control)
            plain(), with_columns()  # numba compiles (or loads) the kernels and the augmented rhs here
            ratios, step_ratios = [], []
            for _ in range(repeats):  # interleaved, so that a slow moment of the machine hits both
                base, base_time = _timed(plain)
                sol, sol_time = _timed(with_columns)
                ratios.append(sol_time / base_time)
                step_ratios.append((sol_time / sol.nsteps) / (base_time / base.nsteps))
            k = sol.sensitivities.shape[2]
            rows.append(dict(model=model.name, n=model.n, k=k, control=control, steps=sol.nsteps,
                             plain_steps=base.nsteps, ratio=float(np.median(ratios)),
                             per_step=float(np.median(step_ratios)), target=1.2 * (1 + k), plain_ms=1e3 * base_time))
    return rows


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=1000.0)
    parser.add_argument("--rtol", type=float, default=1e-10)
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args(argv)
    print(f"DOP853, rtol = atol = {args.rtol:g}, t in [0, {args.t_end:g}]; time with k columns / plain run "
          f"(median of {args.repeats})")
    print(f"{'model':18} {'k':>3} {'control':>7} {'steps':>7} {'plain':>7} {'plain ms':>9} {'time ×':>7} "
          f"{'per step ×':>11} {'target':>7}")
    for r in measure(args.t_end, args.rtol, args.repeats):
        print(f"{r['model']:18} {r['k']:3d} {r['control']:>7} {r['steps']:7d} {r['plain_steps']:7d} "
              f"{r['plain_ms']:9.1f} {r['ratio']:7.2f} {r['per_step']:11.2f} {r['target']:7.1f}")


if __name__ == "__main__":
    main()
