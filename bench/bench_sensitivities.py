"""What forward sensitivities cost: a run with k columns against a plain run, in one process.

    python -m bench.bench_sensitivities [--t-end 1000] [--rtol 1e-10] [--repeats 7] [--calls]

For each model (the double pendulum, n = 2; a 5-link pendulum, n = 5, both from a regular state; the free
axle, n = 5 with 3 constraints (Lagrange multipliers: its kernels solve the augmented system), from its launch)
and k = 1 (∂y/∂θ₁(0); the free axle's ∂y/∂g), k = 2 (θ(0) of the double pendulum, θ₁(0), θ₂(0) of the 5-link,
the free axle's ∂y/∂(g, α)) and k = 2n (every initial-state component), and each `sensitivity_control`
("state": the plain run's steps; "both": the norm covers the sensitivities too, more steps): DOP853 at rtol =
atol, the median over `--repeats` interleaved triples of (time with k columns) / (time of the plain run), and
the same per accepted step, for both ways `lagcomp.integrate.sensitivities` evaluates J S: the full Jacobians
("jacobian": ``rhs_with_jacobian``, or with a parameter's column ``rhs_with_full_jacobian``, then J S) and the
module's tangent kernels ("directional": for one column ``rhs_tangent``, for more ``rhs_tangents``, the shared
part once and a loop over the columns).  It takes the second for every k (`DIRECTIONAL_MAX_COLUMNS`), from
``--calls``: ns per call of each path's augmented rhs at one state, k = 1 to 2n.
Issue #22's target is a ratio ≤ 1.2 (1 + k).

Measured (``--t-end 300 --repeats 5``, CPU time), jacobian × / directional × ("state"; "both"):
  k = 1   double pendulum 3.08 / 1.53; 4.02 / 2.04 (1.33× the steps, 1.53 per step)   target 2.4
          5-link          2.98 / 1.38; 4.14 / 1.92 (1.47× the steps)
          free axle       4.55 / 1.92; 4.44 / 1.87
  k = 2   double pendulum 3.28 / 1.93; 4.24 / 2.40                                     target 3.6
          5-link          3.39 / 1.64; 4.68 / 2.31
          free axle       4.73 / 2.36; 4.74 / 2.41 (two parameters' columns)
  k = 2n  double pendulum 3.76 / 2.16; 4.79 / 2.78 (k = 4, target 6.0); 5-link 5.98 / 3.29; 8.07 / 4.44
          (k = 10, target 13.2); free axle 4.84 / 3.68; 5.12 / 3.99 (k = 10)
Per call (``--calls --repeats 3``, ns, jacobian / directional): double pendulum (``rhs`` 37) k = 1 150 / 54,
2 156 / 66, 4 170 / 72, with a parameter's 190 / 65 (k = 1) to 216 / 88 (k = 5); 5-link (``rhs`` 112) 426 / 169,
461 / 178, 760 / 320 (k = 10), with a parameter's 584 / 228 to 974 / 380 (k = 11); free axle (``rhs`` 284) 1152 /
542, 1195 / 658, 1518 / 1095 (k = 10), with a parameter's 1583 / 581 to 2012 / 1177 (k = 11).  ``rhs_tangents`` at
k = 1 costs 64, 166, 591 ns against ``rhs_tangent``'s 54, 167, 531, hence one column keeps the latter.
Before ``rhs_tangents`` (at c68c8bd: k = 2 through a closure calling ``rhs_directional`` per column, with a
parameter's, else the full Jacobians): k = 2 "state" 3.34, 3.36, 3.70; "both" 4.31, 4.72, 3.74; per call two
columns 153 (full), 469 (full), 1170 (closure) ns.
One column's directional path is the module's tangent kernel (``rhs_tangent``, ``rhs_tangent_parameters``) as
the driver's rhs.  Before it, through a closure calling ``rhs_directional`` (at 8427c72, wall time): k = 1
"state" 2.36, 1.89, 1.99, "both" 2.99, 2.65, 1.98; both ways in one process by CPU time, 11 runs each (closure /
tangent kernel): "state" 2.46 / 1.59, 1.91 / 1.38, 2.02 / 1.87, "both" 3.13 / 2.05, 2.45 / 1.76, 1.95 / 1.82.
Per call through the drivers' function type (double pendulum): the closure 104 ns, ``rhs_tangent`` 54,
``rhs_tangent_parameters`` 65, ``rhs`` 37.  A plain DOP853 step costs ~1.0 µs, ~530 ns of it the driver's own
(with a trivial kernel of 4 components; 983 ns with 8): the k = 1 step is now mostly the driver's.  Under
"both" the extra steps are genuine: |S| grows to 420 (|y| ≤ 2.4), and against a run at rtol 1e-13 the
sensitivities' error at rtol 1e-10 is 2.2e-4 under "both", 1.9e-3 under "state" (6.7e-4 with "state" at rtol
3e-11, 8779 steps).  The free axle's ``rhs_tangent`` (534 ns, ``rhs`` 274) solves K twice; factoring it once
for both solves (tried: 529 ns, the same bits) does not pay, nor would sparing ``kkt_solve``'s allocations.
Before (at 6f5c921, the full Jacobians for every k, wall time): k = 1 3.28, 3.01, 6.56 ("state"), 4.23, 4.21,
6.15 ("both"); free axle k = 10 5.15, 5.19.
Earlier: ``rhs_with_jacobian`` (f and J in one call, J written straight into its work space, M's LDLᵀ written
out for n ≤ 6) took the "state" k = 1 rows from 5.2×, 6.0× (``rhs``, then ``rhs_jacobian`` calling ``rhs``
again, copying J and solving by M in loops) to 3.2×, 3.0×; the free axle's kernels calling
``rhs_and_reactions`` instead of ``rhs`` and ``reactions`` apart from 8.1× to 6.5×.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from numba import njit

#: The models: (example, its arguments, the k = 1 and k = 2 columns; the third row takes every initial-state
#: component).  The free axle's columns are parameters absent from its constraints: its launch stays consistent.
MODELS = (("double_pendulum", {}, "theta1", "q0"),
          ("n_link_pendulum", {"n": 5}, "theta1", ("theta1", "theta2")),
          ("free_axle", {}, "g", ("g", "alpha")))
#: The two ways `lagcomp.integrate.sensitivities` evaluates J S: the full Jacobians, or the module's tangent
#: kernels (the value of `DIRECTIONAL_MAX_COLUMNS` that forces each).
PATHS = (("jacobian", {False: 0, True: 0}), ("directional", {False: 1_000_000, True: 1_000_000}))


def _timed(run) -> tuple[object, float]:
    """`run`'s result and the CPU time it took (`time.process_time`): on a shared machine wall time also counts
    other processes' time slices, and the ratios moved by 30% between runs at a load of 2-3 on 2 cores, where CPU
    time agreed to a few % (the drivers run in the calling thread)."""
    start = time.process_time()
    sol = run()
    return sol, time.process_time() - start


def _runs(model, q0, t_end: float, rtol: float, columns, control):
    """The plain run and the run with sensitivity `columns` under `control`, as functions of no argument."""
    options = dict(rtol=rtol, atol=rtol, save_every=1_000_000, progress=False)

    def plain():
        return model.simulate((0.0, t_end), q0, **options)

    def with_columns():
        return model.simulate((0.0, t_end), q0, sensitivities=columns, sensitivity_control=control, **options)
    return plain, with_columns


def _with_path(limit, run):
    """`run` with `DIRECTIONAL_MAX_COLUMNS` = `limit` (each path's closure is kept apart, keyed by it)."""
    from lagcomp.integrate import sensitivities

    def run_on_path():
        kept, sensitivities.DIRECTIONAL_MAX_COLUMNS = sensitivities.DIRECTIONAL_MAX_COLUMNS, limit
        try:
            return run()
        finally:
            sensitivities.DIRECTIONAL_MAX_COLUMNS = kept
    return run_on_path


def _model(name, kwargs, cache_dir):
    import lagcomp as lc
    from lagcomp import examples

    model = lc.compile(examples.get(name, **kwargs), cache_dir=cache_dir)
    # the constrained free axle from its own (consistent) launch
    return model, (None if model.k else np.linspace(0.5, 0.2, model.n))


def measure(t_end: float = 1000.0, rtol: float = 1e-10, repeats: int = 7, cache_dir=None) -> list[dict]:
    """One row per model, k and control: the time of each path over the plain run's (median of `repeats`
    interleaved triples: a slow moment of the machine hits all three), and per accepted step."""
    rows = []
    for name, kwargs, one, two in MODELS:
        model, q0 = _model(name, kwargs, cache_dir)
        for columns in (one, two, ("q0", "qd0")):
            for control in ("state", "both"):
                plain, with_columns = _runs(model, q0, t_end, rtol, columns, control)
                paths = {path: _with_path(limit, with_columns) for path, limit in PATHS}
                plain()
                for run in paths.values():
                    run()  # numba compiles (or loads) the kernels and the augmented rhs here
                ratios = {path: [] for path in paths}
                per_step = {path: [] for path in paths}
                for _ in range(repeats):
                    base, base_time = _timed(plain)
                    for path, run in paths.items():
                        sol, sol_time = _timed(run)
                        ratios[path].append(sol_time / base_time)
                        per_step[path].append((sol_time / sol.nsteps) / (base_time / base.nsteps))
                k = sol.sensitivities.shape[2]
                rows.append(dict(model=model.name, n=model.n, k=k, control=control, steps=sol.nsteps,
                                 plain_steps=base.nsteps, plain_ms=1e3 * base_time, target=1.2 * (1 + k),
                                 **{path: float(np.median(ratios[path])) for path in paths},
                                 **{f"{path}_per_step": float(np.median(per_step[path])) for path in paths}))
    return rows


@njit(cache=True)
def _calls(rhs, y, p, out, times):
    """`times` calls of `rhs` (a kernel or an augmented rhs) at one state, for their cost per call."""
    status = 0
    for i in range(times):
        status += rhs(0.5 + 1e-9 * i, y, p, out)
    return status


def call_costs(times: int = 200_000, repeats: int = 5, cache_dir=None) -> list[dict]:
    """ns per call of ``rhs`` and of the augmented rhs of each path for k = 1 .. 2n initial-state columns (+ one
    parameter column), at one state (median of `repeats`): where the directional path stops paying."""
    from lagcomp.integrate import sensitivities as sens

    rows = []
    for name, kwargs, _, _ in MODELS:
        model, q0 = _model(name, kwargs, cache_dir)
        n, p = model.state_size, model.parameter_vector(None)
        y = (model.simulate((0.0, 0.1), q0, progress=False).y[-1]).copy()
        out = np.empty(n)

        def cost(rhs, state, parameters, output):
            _calls(rhs, state, parameters, output, 10)
            samples = []
            for _ in range(repeats):
                start = time.process_time()
                _calls(rhs, state, parameters, output, times)
                samples.append((time.process_time() - start) / times * 1e9)
            return float(np.median(samples))

        rhs_ns = cost(model.kernels.rhs, y, p, out)
        for with_parameter in (False, True):
            for k_state in range(1 if not with_parameter else 0, n + 1):
                requested = tuple(model.state_names[:k_state]) + ((model.parameters[-1],) if with_parameter else ())
                if not requested:
                    continue
                cols = sens.columns(model, requested)
                augmented = sens.initial_state(y, cols, 1.0)
                augmented[n:] += np.linspace(-0.3, 0.4, augmented.size - n)
                row = dict(model=model.name, k=cols.k, parameter=with_parameter, rhs=rhs_ns)
                for path, limit in PATHS:
                    kept, sens.DIRECTIONAL_MAX_COLUMNS = sens.DIRECTIONAL_MAX_COLUMNS, limit
                    try:  # (each path's work space at the end of p: the tangent kernel's direction, or J's floats)
                        kernels = sens.sensitivity_kernels(model.kernels, n, len(model.parameters), cols, 1.0)
                        p_run = sens.run_parameters(p, model, cols)
                    finally:
                        sens.DIRECTIONAL_MAX_COLUMNS = kept
                    row[path] = cost(kernels.rhs, augmented, p_run, np.empty(augmented.size))
                rows.append(row)
    return rows


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=1000.0)
    parser.add_argument("--rtol", type=float, default=1e-10)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--calls", action="store_true", help="the cost per call of each path, k = 1 .. 2n, instead")
    args = parser.parse_args(argv)
    if args.calls:
        print("ns per call at one state: rhs, and the augmented rhs of each path (k columns; +p: the last is a "
              "parameter's)")
        print(f"{'model':18} {'k':>3} {'+p':>3} {'rhs':>7} {'jacobian':>9} {'directional':>12} {'dir/jac':>8}")
        for r in call_costs(repeats=args.repeats):
            print(f"{r['model']:18} {r['k']:3d} {'+p' if r['parameter'] else '':>3} {r['rhs']:7.0f} "
                  f"{r['jacobian']:9.0f} {r['directional']:12.0f} {r['directional'] / r['jacobian']:8.2f}")
        return
    print(f"DOP853, rtol = atol = {args.rtol:g}, t in [0, {args.t_end:g}]; CPU time with k columns / plain run "
          f"(median of {args.repeats}), the full Jacobians' path and the directional one in the same run")
    print(f"{'model':18} {'k':>3} {'control':>7} {'steps':>7} {'plain':>7} {'plain ms':>9} {'jacobian ×':>11} "
          f"{'directional ×':>14} {'per step':>9} {'target':>7}")
    for r in measure(args.t_end, args.rtol, args.repeats):
        print(f"{r['model']:18} {r['k']:3d} {r['control']:>7} {r['steps']:7d} {r['plain_steps']:7d} "
              f"{r['plain_ms']:9.1f} {r['jacobian']:11.2f} {r['directional']:14.2f} "
              f"{r['directional_per_step']:9.2f} {r['target']:7.1f}")


if __name__ == "__main__":
    main()
