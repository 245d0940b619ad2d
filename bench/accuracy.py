"""Kernel accuracy: ulps against a 40-digit evaluation, and what it does to a close-approach integration.

Table 1, every bundled example: `lagcomp.accuracy.kernel_accuracy` at 20
random states (times in [0, 1]); the gravitational examples also at close
approaches (pairs 1e-2..1e-8 apart).  "componentwise" is each component in
ulps of itself (near-zero ones in ulps of 2⁻²⁶ × the largest), "normwise" in
ulps of the largest (lagcomp.accuracy's docstring).  Where a hand-written
form exists (`bench.systems`' double pendulum and chain, a numpy N-body,
Hairer's restricted three-body) it is measured against the same reference.

Table 2, the Pythagorean three-body problem on [0, 20] (through the closest
approach, r23 = 4.1e-4 at t = 15.83): scipy's DOP853 at tol 1e-13 on a
hand-written rhs; the same steps replayed with lagcomp's compiled rhs; lagcomp's
own dop853 at the same tol, and its Taylor method at its default tolerance.
Errors of the end state against scipy's steps each cut in REFINE and replayed
in long double (64-bit mantissa) on the hand-written rhs: truncation 4⁸ times
and rounding 2¹¹ times below those of the runs measured.
"""

from __future__ import annotations

import numpy as np

from bench import systems
from bench.harness import Table, fmt

#: How finely the reference cuts each of scipy's steps.
REFINE = 4
T_END = 20.0
TOL = 1e-13


def nbody_qdd(y, p):
    """Hand-written planar N-body accelerations, p = (G, m1..mN), in y's dtype (float64 or long double)."""
    G, m = p[0], p[1:]
    n = len(m)
    x = y[: 2 * n].reshape(n, 2)
    a = np.zeros((n, 2), dtype=y.dtype)
    for i in range(n):
        for j in range(n):
            if i != j:
                d = x[j] - x[i]
                r2 = d[0] * d[0] + d[1] * d[1]
                a[i] += G * m[j] * d / (r2 * np.sqrt(r2))
    return a.ravel()


def arenstorf_qdd(y, p):
    """Hairer, Nørsett & Wanner's restricted three-body right-hand side (Solving ODEs I, II.0)."""
    mu = p[0]
    mu1 = 1.0 - mu
    d1 = ((y[0] + mu) ** 2 + y[1] ** 2) ** 1.5
    d2 = ((y[0] - mu1) ** 2 + y[1] ** 2) ** 1.5
    return np.array([y[0] + 2 * y[3] - mu1 * (y[0] + mu) / d1 - mu * (y[0] - mu1) / d2,
                     y[1] - 2 * y[2] - mu1 * y[1] / d1 - mu * y[1] / d2])


def _numba_qdd(rhs):
    def qdd(y, p):
        out = np.empty(y.size)
        rhs(0.0, y, p, out)
        return out[y.size // 2:]
    return qdd


HAND_WRITTEN = {
    "double_pendulum": _numba_qdd(systems.double_pendulum_rhs),
    "n_link_pendulum": _numba_qdd(systems.chain_rhs),
    "pythagorean_three_body": nbody_qdd,
    "restricted_three_body": arenstorf_qdd,
}


def _state_sets(model, name: str, quick: bool):
    from lagcomp.accuracy import close_approach_states, random_states

    n = 8 if quick else 20
    sets = [("random", random_states(model, n, seed=1), np.linspace(0.0, 1.0, n))]
    distances = (1e-2, 1e-4, 1e-6, 1e-8)
    if name == "pythagorean_three_body":
        points = [("x1", "y1"), ("x2", "y2"), ("x3", "y3")]
        sets.append(("close approaches", close_approach_states(model, points, n, distances=distances), 0.0))
    if name == "restricted_three_body":
        mu = model.defaults["mu"]
        sets.append(("near the primaries", close_approach_states(model, [("x", "y")], n, distances=distances,
                                                                 anchors=[(1 - mu, 0.0), (-mu, 0.0)]), 0.0))
    return sets


def _ulps_pair(error) -> str:
    return f"{fmt(error.max)} / {fmt(error.max_normwise)}"


def kernel_table(ctx) -> Table:
    import lagcomp as lc
    from lagcomp import examples
    from lagcomp.accuracy import kernel_accuracy, reference_values

    table = Table(
        "Kernel accuracy: ulps against a 40-digit evaluation (max componentwise / max normwise)",
        ["example", "states", "rhs q̈", "rhs median", "hand-written q̈", "reactions λ", "energy"],
        note="`lagcomp.accuracy.kernel_accuracy`; hand-written forms from bench/accuracy.py and bench/systems.py. "
             "A componentwise figure in the thousands with a normwise one of a few ulps is a component that "
             "cancels in any float64 form (the hand-written one shows it too).",
    )
    for name in sorted(examples.EXAMPLES):
        model = lc.compile(examples.get(name), cache_dir=ctx.cache_dir)
        for label, states, times in _state_sets(model, name, ctx.quick):
            acc = kernel_accuracy(model, states, t=times)
            hand = "–"
            if name in HAND_WRITTEN:
                ref = reference_values(model, acc.states, t=times)
                p = model.parameter_vector()
                qdd = [HAND_WRITTEN[name](y, p) for y in acc.states]
                hand = f"{fmt(ref.ulps('rhs', qdd).max())} / {fmt(ref.ulps('rhs', qdd, floor=1.0).max())}"
            reactions = _ulps_pair(acc["reactions"]) if "reactions" in acc.errors else "–"
            table.add(name, f"{len(acc.states)} {label}" + (f" ({acc.skipped} singular)" if acc.skipped else ""),
                      _ulps_pair(acc["rhs"]), fmt(acc["rhs"].median), hand, reactions, fmt(acc["energy"].max))
    return table


def dop853_replay(qdd, y0, p, steps, dtype=np.float64, refine: int = 1):
    """The end state of scipy's DOP853 formulas applied along the accepted step times `steps`, in `dtype`.

    Each step is cut into `refine` equal ones (refine = 1 takes scipy's steps exactly: h = t₁ − t₀).
    """
    from scipy.integrate._ivp.rk import DOP853

    A, B, C = (np.asarray(c, dtype=dtype) for c in (DOP853.A, DOP853.B, DOP853.C))
    y, p = np.asarray(y0, dtype=dtype), np.asarray(p, dtype=dtype)
    n = y.size // 2

    def f(state):
        return np.concatenate([state[n:], qdd(state, p)])

    K = np.empty((len(B), y.size), dtype=dtype)
    for t0, t1 in zip(steps[:-1], steps[1:]):
        span = np.asarray(t1, dtype=dtype) - np.asarray(t0, dtype=dtype)
        for _ in range(refine):
            h = span / refine
            K[0] = f(y)
            for s in range(1, len(B)):
                K[s] = f(y + h * (A[s, :s] @ K[:s]))
            y = y + h * (B @ K)
    return y


def _lagcomp_qdd(model):
    def qdd(y, p):
        out = np.empty(y.size)
        model.kernels.rhs(0.0, np.ascontiguousarray(y, dtype=float), p, out)
        return out[y.size // 2:]
    return qdd


def run_table(ctx) -> Table:
    import lagcomp as lc
    from lagcomp import examples
    from scipy.integrate import solve_ivp

    model = lc.compile(examples.get("pythagorean_three_body"), cache_dir=ctx.cache_dir)
    p, y0 = model.parameter_vector(), model.initial_state()
    scipy_run = solve_ivp(lambda t, y: np.concatenate([y[6:], nbody_qdd(y, p)]), (0.0, T_END), y0,
                          method="DOP853", rtol=TOL, atol=TOL)
    steps = scipy_run.t
    exact = dop853_replay(nbody_qdd, y0, p, steps, np.longdouble, REFINE)
    scale = float(np.max(np.abs(exact)))

    def error(y) -> str:
        return f"{float(np.max(np.abs(np.asarray(y, np.longdouble) - exact))) / scale:.2e}"

    def ratio(y, base) -> str:
        return f"{float(np.max(np.abs(np.asarray(y, np.longdouble) - exact))) / float(np.max(np.abs(base - exact))):.2f}×"

    hand = scipy_run.y[:, -1]
    table = Table(
        f"Pythagorean three-body problem to t = {T_END:g}: end-state error",
        ["run", "steps", "max |y − y_ref| / max |y_ref|", "× scipy + hand-written rhs"],
        note=f"Reference: scipy's steps each cut in {REFINE}, DOP853 in long double on the hand-written rhs "
             f"(its own truncation: the same in long double on scipy's steps, "
             f"{error(dop853_replay(nbody_qdd, y0, p, steps, np.longdouble, 1))}).",
    )
    table.add("scipy DOP853, hand-written numpy rhs, tol 1e-13", len(steps) - 1, error(hand), "1.00×")
    replayed = dop853_replay(_lagcomp_qdd(model), y0, p, steps)
    table.add("the same steps, lagcomp's compiled rhs", len(steps) - 1, error(replayed), ratio(replayed, hand))
    for label, options in (("lagcomp dop853, tol 1e-13", dict(method="dop853", rtol=TOL, atol=TOL)),
                           ("lagcomp taylor, default tol", dict(method="taylor"))):
        sol = model.simulate((0.0, T_END), progress=False, **options)
        y = np.concatenate([sol.q[-1], sol.qd[-1]])
        table.add(label, len(sol.t) - 1, error(y), ratio(y, hand))
    return table


def section(ctx) -> list[Table]:
    return [kernel_table(ctx), run_table(ctx)]
