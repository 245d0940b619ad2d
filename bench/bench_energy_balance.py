"""What `Solution.energy_balance` costs along a long run: its compiled loops over the rows against the kernels
called row by row from Python, and a sweep's balance against its plain energy drift, in one process.

    python -m bench.bench_energy_balance [--t-end 2000] [--rows 200001] [--repeats 3]

A damped pendulum (θ'' = −(g/l) sin θ − c θ', the balance's dissipation term busy throughout) is run over
[0, t_end] with `--rows` saved rows.  Printed, CPU time (`time.process_time`, median of `--repeats`):

* ``compiled``: `lagcomp.integrate.energy_balance.energy_balance` as it is (slopes and power in compiled loops over
  the rows, `lagcomp.integrate.balance_kernels`);
* ``row by row``: the same two steps with one Python call of the kernel per row and per difference (what they
  were before: ``rhs`` three times and ``power`` four times per row), and their ratio;
* the largest difference between the two balances' residuals (same arithmetic: 0 expected);
* a sweep of 64 trajectories over c with ``output="energy"`` (the balance, folded row by row in the sweep loop)
  against the same sweep of the undamped twin (the drift of T + V): the cost of the balance in a sweep.
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def _model(name: str, damped: bool):
    import sympy as sp

    import lagcomp as lc
    from lagcomp.model import t

    (th,) = lc.coordinates("th")
    m, g, l, c = sp.symbols("m g l c", positive=True)
    system = lc.System([th], T=m * l**2 * th.diff(t) ** 2 / 2, V=-m * g * l * sp.cos(th),
                       dissipation=c * th.diff(t) ** 2 / 2 if damped else sp.S.Zero, name=name,
                       defaults={"m": 1.0, "g": 9.81, "l": 1.0, **({"c": 0.01} if damped else {})})
    return lc.compile(system)


def _row_by_row(source, ts: np.ndarray, ys: np.ndarray, local: np.ndarray, nodes_t, nodes_y):
    """Slopes and power with a Python call per row (the former `_slopes` and `_power`)."""
    f, g, ahead, behind = np.empty_like(ys), np.empty_like(ys), np.empty(ys.shape[1]), np.empty(ys.shape[1])
    for i in range(ts.size):
        source.kernels.rhs(float(ts[i]), ys[i], source.p, f[i])
        eps = 1e-4 * local[i]
        source.kernels.rhs(float(ts[i]) + eps, ys[i] + eps * f[i], source.p, ahead)
        source.kernels.rhs(float(ts[i]) - eps, ys[i] - eps * f[i], source.p, behind)
        g[i] = (ahead - behind) / (2 * eps)
    out, lam = np.empty((nodes_t.size, 4)), np.zeros(0)
    for i in range(nodes_t.size):
        source.kernels.power(float(nodes_t[i]), nodes_y[i], source.p, lam, out[i])
    return f, g, out


def _median(run, repeats: int):
    times, result = [], None
    for _ in range(repeats):
        start = time.process_time()
        result = run()
        times.append(time.process_time() - start)
    return result, float(np.median(times))


def main(argv=None) -> None:
    from lagcomp.integrate import energy_balance as eb

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=2000.0)
    parser.add_argument("--rows", type=int, default=200_001)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)

    damped, free = _model("bench_balance_damped", True), _model("bench_balance_free", False)
    sol = damped.simulate((0.0, args.t_end), [2.0], [0.0], rtol=1e-10, atol=1e-12,
                          t_eval=np.linspace(0.0, args.t_end, args.rows))
    balance, compiled = _median(sol.energy_balance, args.repeats)
    source, ts, ys = sol.power_source, sol.t, np.hstack([sol.q, sol.qd])
    steps = np.diff(ts)
    local = np.maximum(np.concatenate([steps, [0.0]]), np.concatenate([[0.0], steps]))
    f, g = eb._slopes(source, ts, ys)
    nodes_t = (ts[:-1, None] + steps[:, None] * eb._NODES[None, :]).ravel()
    nodes_y = np.stack([eb._hermite(s, ys, (f, g), steps) for s in eb._NODES], axis=1).reshape(-1, ys.shape[1])
    (f_py, g_py, power_py), by_row = _median(lambda: _row_by_row(source, ts, ys, local, nodes_t, nodes_y),
                                             args.repeats)
    same = np.array_equal(f, f_py) and np.array_equal(g, g_py) and np.array_equal(eb._power(source, nodes_t, nodes_y),
                                                                                   power_py)
    print(f"damped pendulum, {ts.size:,} rows, CPU s (median of {args.repeats}):")
    print(f"  energy_balance (compiled loops)      {compiled:8.3f}   relative residual {balance.relative_residual:.2e}")
    print(f"  slopes + power, a Python call a row  {by_row:8.3f}   ({by_row / compiled:.1f}x the whole balance; "
          f"bitwise the same values: {same})")

    grid = {"th": np.linspace(0.5, 2.5, 64)}
    options = dict(q0=[0.0], qd0=[0.0], rtol=1e-10, atol=1e-12, output="energy", workers=1)
    damped.sweep((0.0, 1.0), grid, **options), free.sweep((0.0, 1.0), grid, **options)      # (compiles)
    with_balance, balanced = _median(lambda: damped.sweep((0.0, args.t_end / 10), grid, **options), args.repeats)
    plain, drift = _median(lambda: free.sweep((0.0, args.t_end / 10), grid, **options), args.repeats)
    print(f"sweep of 64 trajectories over [0, {args.t_end / 10:g}], one thread, CPU s:")
    print(f"  damped, energy balance  {balanced:8.3f}   largest residual {np.max(with_balance.energy_error):.2e}")
    print(f"  undamped, drift of T+V  {drift:8.3f}   largest drift {np.max(plain.energy_error):.2e}   "
          f"(ratio {balanced / drift:.2f}; steps {with_balance.nsteps.sum():,} against {plain.nsteps.sum():,})")


if __name__ == "__main__":
    main()
