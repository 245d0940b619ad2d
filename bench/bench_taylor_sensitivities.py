"""Taylor-method sensitivities: lagcomp's variational program against heyoka's ``var_ode_sys``, in one process.

    python -m bench.bench_taylor_sensitivities [--repeats 7]

The double pendulum (m = l = 1, g = 9.81) from a regular state (θ = (0.5, 0.3) at rest) and a chaotic one
(θ = (2, 1)), the 4 × 4 sensitivities ∂y(t)/∂y(0) with the state, to t_end = 10 and 100, and once with the
five parameters' columns too (k = 9; heyoka: ``var_args.vars | var_args.params``):

* lagcomp: ``simulate(method="taylor", sensitivities=("q0", "qd0"))`` (the kernel from the series of J's
  entries, `lagcomp.codegen.taylor_jacobian`, which `lagcomp.codegen.taylor_variational` picks for this model;
  the state's steps), ``save_every`` large so that only the end is kept;
* heyoka: ``taylor_adaptive(var_ode_sys(sys, var_args.vars, order=1))`` on the hand-reduced ODE (the form
  `bench.bench_taylor` uses), ``propagate_until``.

Both at the same tolerance (machine precision, each one's default, and 1e-10).  The reference is heyoka's
variational run in 80-bit long double at its default tolerance (ε = 1.1e-19), independent of both.  Errors are
max abs over the components, relative to the reference's largest (state and sensitivities apart).  Times are of
the integration only (both compiled before: heyoka's JIT and numba's kernels), the median of `--repeats`
interleaved rounds; the ratio (the median of the per-round ratios) is lagcomp / heyoka (below 1: lagcomp faster).

Measured (``--repeats 15``, × heyoka, load 0.3-0.6; "both" is heyoka's step rule, so the same steps and
errors): k = 4, machine precision: 0.77 / 0.72 / 0.74 ("both"; regular t = 10, 100, chaotic t = 10), 0.66 /
0.59 / 0.61 ("state"); tol 1e-10: 0.92 / 0.79 / 0.86 and 0.78 / 0.62 / 0.70.  k = 9 (regular, t = 100): 0.74
/ 0.63 at machine precision, 0.86 / 0.70 at 1e-10 ("both"/"state").  The closest row, k = 4 regular t = 10
at 1e-10 "both" (288 steps in 0.9 ms), moves by ±0.04 from run to run (0.92, 0.92, 0.99, 0.96 in four runs of
``--repeats 41``): a sixth of it is lagcomp's fixed cost of a run, 0.16 ms (heyoka's ``propagate_until``:
µs): Python around the driver, spread out (the options, the recorder, the Solution, numba's dispatch of the
kernels as function values), 0.11 ms of it a plain run's.  Before the parameters' convolutions were shared,
the operations' loops merged (`lagcomp.codegen.taylor_jacobian`) and the fixed cost cut (0.19 ms), k = 9 at
1e-10 took 1.08 / 0.87 and k = 4 at 1e-10 0.98 / 0.85 / 0.97 ("both").  Before (forward mode,
`lagcomp.codegen.taylor_variational`, in the same conditions, ``--repeats 7``): k = 4 machine precision 1.08 /
0.94 / 1.03 and 0.91 / 0.80 / 0.94, tol 1e-10 1.34 / 1.10 / 1.19 and 1.21 / 0.87 / 0.98; k = 9 1.62 / 0.94
and 1.92 / 1.64; the fixed cost 0.31 ms.  Before the k columns were written out (a loop over them inside each
operation) k = 4 "both" took 1.5x heyoka's.
"""

from __future__ import annotations

import argparse

import numpy as np

from bench.harness import interleaved_times, paired

P = [1.0, 1.0, 1.0, 1.0, 9.81]
STARTS = {"regular": np.array([0.5, 0.3, 0.0, 0.0]), "chaotic": np.array([2.0, 1.0, 0.0, 0.0])}
EPS = float(np.finfo(float).eps)
#: (start, t_end, parameter columns too): the chaotic start loses every digit of S by t = 100 (|S| ~ 1e8), so
#: it stops at 10.
CASES = (("regular", 10.0, False), ("regular", 100.0, False), ("chaotic", 10.0, False), ("regular", 100.0, True))
#: lagcomp's `sensitivity_control`s: "both", the default, is heyoka's (its step rule's norm covers the variational
#: components too: the same steps and errors); "state" takes a plain run's steps.
CONTROLS = ("both", "state")


def heyoka_system():
    """The double pendulum's ODE in heyoka's expressions (as `bench.bench_taylor.heyoka_pendulum`'s reduced one)."""
    import heyoka as hy

    th1, th2, w1, w2 = hy.make_vars("th1", "th2", "w1", "w2")
    m1, m2, l1, l2, g = (hy.par[i] for i in range(5))
    d = th1 - th2
    a11, a12, a22 = (m1 + m2) * l1**2, m2 * l1 * l2 * hy.cos(d), m2 * l2**2
    f1 = -m2 * l1 * l2 * w2**2 * hy.sin(d) - (m1 + m2) * g * l1 * hy.sin(th1)
    f2 = m2 * l1 * l2 * w1**2 * hy.sin(d) - m2 * g * l2 * hy.sin(th2)
    det = a11 * a22 - a12**2
    return [(th1, w1), (th2, w2), (w1, (a22 * f1 - a12 * f2) / det), (w2, (a11 * f2 - a12 * f1) / det)]


def heyoka_runner(y0: np.ndarray, t_end: float, tol: float | None, long_double: bool = False, params=False):
    """run() -> (state (4,), sensitivities (4, k)) at t_end by heyoka's variational Taylor integrator: k = 4
    columns ∂/∂y(0), then with `params` the 5 ∂/∂p."""
    import heyoka as hy

    wrt = hy.var_args.vars | hy.var_args.params if params else hy.var_args.vars
    system = hy.var_ode_sys(heyoka_system(), wrt, order=1)
    kind = np.longdouble if long_double else float
    options = dict(fp_type=np.longdouble) if long_double else {}
    if tol is not None:
        options["tol"] = kind(tol)
    ta = hy.taylor_adaptive(system, [kind(v) for v in y0], pars=[kind(v) for v in P], **options)
    start = np.array(ta.state, copy=True)     # y0 and the identity, as heyoka sets them

    def run():
        ta.time = kind(0.0)
        ta.state[:] = start
        ta.propagate_until(kind(t_end))
        state = np.array(ta.state, dtype=float)
        return state[:4], state[4:].reshape(4, -1)     # row i: ∂y_i/∂y_j(0) (then ∂y_i/∂p_j) along the row
    return run


def lagcomp_runner(model, y0: np.ndarray, t_end: float, tol: float, control: str = "both", params=False):
    columns = ("q0", "qd0", "params") if params else ("q0", "qd0")

    def run():
        sol = model.simulate((0.0, t_end), y0[:2], y0[2:], method="taylor", rtol=tol, atol=tol,
                             sensitivities=columns, sensitivity_control=control, save_every=1_000_000,
                             progress=False)
        return sol.y[-1], sol.sensitivities[-1]
    return run


def _errors(result, reference) -> tuple[float, float]:
    (y, S), (y_ref, S_ref) = result, reference
    return (float(np.abs(y - y_ref).max() / np.abs(y_ref).max()),
            float(np.abs(S - S_ref).max() / np.abs(S_ref).max()))


def fixed_cost(model, repeats: int) -> float:
    """Milliseconds of a lagcomp sensitivity run of one short step: what `simulate` costs besides the steps
    (options, the recorder, the Solution), which a short run pays in full (heyoka's ``propagate_until``: µs)."""
    run = lagcomp_runner(model, STARTS["regular"], 1e-9, EPS)
    (times,) = interleaved_times([run], repeats=repeats)
    return 1e3 * float(np.median(times))


def measure(repeats: int = 7, cache_dir=None) -> tuple[list[dict], float]:
    """The rows of the table, and lagcomp's fixed cost (`fixed_cost`)."""
    import lagcomp as lc
    from lagcomp import examples

    model = lc.compile(examples.get("double_pendulum"), cache_dir=cache_dir)
    rows = []
    for start, t_end, params in CASES:
        y0 = STARTS[start]
        reference = heyoka_runner(y0, t_end, None, long_double=True, params=params)()
        for tol in (EPS, 1e-10):
            runs = [heyoka_runner(y0, t_end, tol, params=params)]
            runs += [lagcomp_runner(model, y0, t_end, tol, c, params) for c in CONTROLS]
            times = interleaved_times(runs, repeats=repeats)
            for name, run, own in zip(("heyoka", *(f"lagcomp {c}" for c in CONTROLS)), runs, times, strict=True):
                rows.append(dict(start=start, t_end=t_end, k=9 if params else 4, tol=tol, run=name,
                                 errors=_errors(run(), reference),
                                 ms=1e3 * float(np.median(own)), ratio=paired(own, times[0]).median))
    return rows, fixed_cost(model, repeats)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args(argv)
    print("double pendulum, ∂y(t)/∂y(0) (k = 4), and ∂y(t)/∂p (k = 9); errors vs heyoka in long double "
          f"(relative max abs); time: median of {args.repeats} interleaved rounds, × heyoka: median of the "
          "per-round ratios")
    print(f"{'start':8} {'t_end':>6} {'k':>2} {'tol':>8} {'run':16} {'err y':>8} {'err S':>8} {'ms':>8} "
          f"{'× heyoka':>9}")
    rows, fixed = measure(args.repeats)
    for r in rows:
        print(f"{r['start']:8} {r['t_end']:6g} {r['k']:2d} {r['tol']:8.2g} {r['run']:16} {r['errors'][0]:8.1e} "
              f"{r['errors'][1]:8.1e} {r['ms']:8.2f} {r['ratio']:9.2f}")
    print(f"lagcomp's fixed cost of a run (one short step, included above): {fixed:.2f} ms")


if __name__ == "__main__":
    main()
