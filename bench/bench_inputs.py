"""What a tabulated input costs the adaptive methods, and what its interpolant's error does to the result.

    python -m bench.bench_inputs [--t-end 10] [--repeats 5]

The pendulum on a support moved along x by x_s(t) = A sin ωt (A = 0.1, ω = 3, from θ = 0.3; ẍ_s enters
the forcing), compiled twice: with x_s a `lagcomp.Input` fed a cubic table of spacing Δ, and with the
expression written out.  For each method and tolerance: the accepted (and rejected) steps of both, the
ratio of their wall times (median of `--repeats` runs in this process), and the difference of
the final angle from the expression's run at rtol = atol = 1e-13 — the tolerance's error plus the
interpolant's.  The drivers do not restart at the table's breakpoints (lagcomp.kernel_support.inputs).
Then the cost of reading a table per evaluation: rk4 over the same steps, table against expression.
Last, a feedback torque given as a numba function u(t, y, p) (`lagcomp.integrate.function_inputs`) against
the same PD law compiled in: the ratio of their wall times over the same rk4 steps.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

AMPLITUDE, OMEGA = 0.1, 3.0


def _models(cache_dir):
    import sympy as sp

    import lagcomp as lc

    th, = lc.coordinates("theta")
    m, l, g, a, w = sp.symbols("m l g A omega", positive=True)  # noqa: E741

    def pendulum(support, name, **defaults):
        px, py = support + l * sp.sin(th), -l * sp.cos(th)
        return lc.System([th], T=m * (px.diff(lc.t) ** 2 + py.diff(lc.t) ** 2) / 2, V=m * g * py, name=name,
                         defaults={"m": 1.0, "l": 1.0, "g": 9.81, **defaults}, q0=(0.3,))
    tabulated = lc.compile(pendulum(lc.Input("x_s"), "bench_inputs_table"), cache_dir=cache_dir)
    written = lc.compile(pendulum(a * sp.sin(w * lc.t), "bench_inputs_expr", A=AMPLITUDE, omega=OMEGA),
                         cache_dir=cache_dir)
    return tabulated, written


def _timed(run, repeats: int) -> tuple[object, list[float]]:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        sol = run()
        times.append(time.perf_counter() - start)
    return sol, times


def measure(t_end: float = 10.0, repeats: int = 5, cache_dir=None) -> list[dict]:
    import lagcomp as lc

    tabulated, written = _models(cache_dir)
    reference = written.simulate((0.0, t_end), rtol=1e-13, atol=1e-13, progress=False).q[-1, 0]
    rows = []
    for method in ("dop853", "dopri5"):
        for rtol in (1e-6, 1e-9, 1e-12):
            options = dict(method=method, rtol=rtol, atol=rtol, progress=False)
            expr, expr_times = _timed(lambda o=options: written.simulate((0.0, t_end), **o), repeats)
            for spacing in (0.2, 0.1, 0.05, 0.025):
                times = np.linspace(0.0, t_end, round(t_end / spacing) + 1)
                table = lc.Tabulated(times, AMPLITUDE * np.sin(OMEGA * times))
                sol, table_times = _timed(lambda o=options, x_s=table: tabulated.simulate(
                    (0.0, t_end), inputs={"x_s": x_s}, **o), repeats)
                rows.append(dict(method=method, rtol=rtol, spacing=spacing, joints=times.size - 2,
                                 steps=sol.nsteps, rejected=sol.nrejected, expr_steps=expr.nsteps,
                                 expr_rejected=expr.nrejected,
                                 time_ratio=float(np.median(np.array(table_times) / np.array(expr_times))),
                                 error=abs(sol.q[-1, 0] - reference), expr_error=abs(expr.q[-1, 0] - reference)))
    return rows


def fixed_step_cost(t_end: float = 10.0, repeats: int = 5, cache_dir=None) -> list[dict]:
    """rk4 over the same 10⁵ steps with the table and with the expression: the ratio of their wall times is
    what reading the table (a binary search and a cubic per evaluation) costs against sin ωt."""
    import lagcomp as lc

    tabulated, written = _models(cache_dir)
    options = dict(method="rk4", dt=t_end / 100_000, save_every=100_000, progress=False)
    rows = []
    for spacing in (0.1, 0.001):
        times = np.linspace(0.0, t_end, round(t_end / spacing) + 1)
        table = lc.Tabulated(times, AMPLITUDE * np.sin(OMEGA * times))
        written.simulate((0.0, t_end), **options), tabulated.simulate((0.0, t_end), inputs={"x_s": table}, **options)
        ratios = []
        for _ in range(repeats):  # interleaved, so that a slow moment of the machine hits both
            _, expr_times = _timed(lambda: written.simulate((0.0, t_end), **options), 1)
            _, table_times = _timed(lambda x_s=table: tabulated.simulate((0.0, t_end), inputs={"x_s": x_s},
                                                                         **options), 1)
            ratios.append(table_times[0] / expr_times[0])
        rows.append(dict(spacing=spacing, pieces=times.size - 1, ratio=float(np.median(ratios)),
                         low=float(np.min(ratios)), high=float(np.max(ratios))))
    return rows


def function_cost(t_end: float = 10.0, repeats: int = 5, cache_dir=None) -> dict:
    """The inverted pendulum under τ = −Kp θ − Kd θ̇ as a law compiled in and as a numba function of (t, y, p):
    the ratio of wall times over the same 10⁶ rk4 steps is what the function input costs per kernel call (the
    wrapper's call of the user's function, its store into p, the kernel's load of it) against the law's
    arithmetic inlined in the kernel."""
    import sympy as sp
    from numba import njit

    import lagcomp as lc

    th, = lc.coordinates("theta")
    m, l, g, kp, kd = sp.symbols("m l g K_p K_d", positive=True)  # noqa: E741

    def pendulum(torque, name, **options):
        return lc.System([th], T=m * l**2 * th.diff(lc.t) ** 2 / 2, V=m * g * l * sp.cos(th), forces=[torque],
                         name=name, defaults={"m": 1.0, "l": 1.0, "g": 9.81, "K_p": 30.0, "K_d": 8.0}, q0=(0.3,),
                         **options)
    law = lc.compile(pendulum(lc.Input("tau", law=-kp * th - kd * th.diff(lc.t)), "bench_inputs_law"),
                     cache_dir=cache_dir)
    by_function = lc.compile(pendulum(lc.Input("tau"), "bench_inputs_function", parameters=(kd, kp, g, l, m)),
                             cache_dir=cache_dir)

    @njit
    def pd(t, y, p):
        return -p[1] * y[0] - p[0] * y[1]

    options = dict(method="rk4", dt=t_end / 1_000_000, save_every=1_000_000, progress=False)
    run_law = lambda: law.simulate((0.0, t_end), **options)  # noqa: E731
    run_function = lambda: by_function.simulate((0.0, t_end), inputs={"tau": pd}, **options)  # noqa: E731
    run_law(), run_function()  # (numba compiles the wrappers here)
    ratios, law_times = [], []
    for _ in range(repeats):  # interleaved, so that a slow moment of the machine hits both
        _, law_time = _timed(run_law, 1)
        _, function_time = _timed(run_function, 1)
        ratios.append(function_time[0] / law_time[0])
        law_times.append(law_time[0])
    return dict(ratio=float(np.median(ratios)), low=float(np.min(ratios)), high=float(np.max(ratios)),
                law_time=float(np.median(law_times)))


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=10.0)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    rows = measure(args.t_end, args.repeats)
    print(f"{'method':8} {'rtol':>7} {'Δ':>6} {'joints':>6} {'steps (rej)':>12} {'expr steps (rej)':>17} "
          f"{'time ×':>7} {'|Δθ| table':>11} {'|Δθ| expr':>10}")
    for r in rows:
        print(f"{r['method']:8} {r['rtol']:7.0e} {r['spacing']:6.3f} {r['joints']:6d} "
              f"{r['steps']:>6d} ({r['rejected']:>3d}) {r['expr_steps']:>10d} ({r['expr_rejected']:>3d}) "
              f"{r['time_ratio']:7.2f} {r['error']:11.2e} {r['expr_error']:10.2e}")
    print("\nrk4, 10⁵ steps: time with the table / with the expression (median, min–max)")
    for r in fixed_step_cost(args.t_end, args.repeats):
        print(f"  Δ = {r['spacing']:<6} ({r['pieces']} pieces): {r['ratio']:.2f} ({r['low']:.2f}–{r['high']:.2f})")
    print("\nPD torque as a numba function / as a law compiled in, rk4, the same 10⁶ steps (median, min–max)")
    r = function_cost(args.t_end, args.repeats)
    print(f"  {r['ratio']:.2f} ({r['low']:.2f}–{r['high']:.2f}); the law's run {r['law_time'] * 1e3:.0f} ms")


if __name__ == "__main__":
    main()
