"""Kernel cost: ns per right-hand-side call, inside a compiled loop and from Python, and op counts.

Baseline: the hand-written numba RHS of the same system (`bench.systems`),
called in the same compiled loop.  All rows of a case are timed round-robin
and each ratio is the median of per-round ratios (`harness.interleaved`).  "In a loop" is what an integrator sees:
an `@njit` loop calls the kernel n times, nudging y[0] each time so nothing
can be hoisted.  "From Python" is one call of the jitted function per
Python-level call, as scipy's solve_ivp makes it.  GFLOP/s is the op count
after CSE (sympy's count_ops over the mass matrix and forcing, the numeric
solve not counted) over the in-loop time.
"""

from __future__ import annotations

import numpy as np

from lagcomp.benchmark import looped

from bench import systems
from bench.harness import Table, fmt, fmt_stat, interleaved, peer


def in_loop(rhs, y0, p, calls: int = 200_000):
    """(run, calls): a compiled loop of `calls` calls of `rhs`, compiled here."""
    out = np.empty(y0.size)
    loop = systems.chain_fast_loop if rhs is systems.chain_rhs_fast_ws else looped(rhs)
    loop(y0.copy(), p, out, 10)  # compile
    return (lambda: loop(y0.copy(), p, out, calls)), calls


def from_python(call, calls: int = 2_000):
    """(run, calls): `calls` calls of `call` from a Python loop."""
    def run():
        for _ in range(calls):
            call()
    return run, calls


def lambdify_rhs(eom):
    """sympy.lambdify of lagcomp's derived M and F (cse=True), q̈ by numpy.linalg.solve: the naive Python RHS."""
    import sympy as sp

    n = len(eom.q)
    f = sp.lambdify((eom.q, eom.qd, eom.parameters), (eom.M, eom.F), modules="numpy", cse=True)

    def rhs(t, y, p):
        M, F = f(y[:n], y[n:], p)
        return np.concatenate([y[n:], np.linalg.solve(np.asarray(M, float), np.asarray(F, float).ravel())])

    return rhs


def pydy_functions(n: int):
    """PyDy's cython and lambdify ODE functions of the N-link chain, and its op count after CSE."""
    import sympy as sp
    from pydy.codegen.c_code import CMatrixGenerator
    from pydy.codegen.ode_function_generators import generate_ode_function

    km, q, u, constants = systems.kane_chain(n)
    M, F = km.mass_matrix_full, km.forcing_full
    funcs = {}
    for generator in ("cython", "lambdify"):
        if generator == "cython" and peer("Cython") is None:
            continue
        funcs[generator] = generate_ode_function(F, q, u, constants, mass_matrix=M, generator=generator)
    gen = CMatrixGenerator([q, u, constants], [km.mass_matrix, km.forcing])  # runs its CSE
    ops = sum(sp.count_ops(e) for _, e in gen.subexprs) + sum(sp.count_ops(e) for m in gen.simplified_matrices for e in m)
    return funcs, int(ops)


def jitcode_f():
    """JiTCODE's compiled f of the double pendulum (the reduced ODE), default parameters inlined."""
    import symengine
    from jitcode import jitcode, y

    acc = systems.double_pendulum_reduced(symengine.sin, symengine.cos, y(0), y(1), y(2), y(3), 1.0, 1.0, 1.0, 1.0, 9.81)
    ode = jitcode([y(2), y(3), *acc], verbose=False)
    ode.compile_C(verbose=False)
    ode.set_integrator("dopri5")
    ode.set_initial_value(np.array([2.0, 1.0, 0.0, 0.0]), 0.0)
    return ode


def hand_written(case: str):
    """The hand-written numba RHS of a case, or None when there is none (constrained examples)."""
    if case == "double_pendulum":
        return systems.double_pendulum_rhs
    if case == "simple_pendulum" or case.startswith("n_link_pendulum_"):
        return systems.chain_rhs_fast_ws
    return None


def hand_call(hand, y0, p, out):
    """One call of the hand-written RHS from Python (the chain with its scratch allocated once)."""
    if hand is systems.chain_rhs_fast_ws:
        n = y0.size // 2
        s, c, mu, a, f = np.empty(n), np.empty(n), np.empty(n), np.empty((n, n)), np.empty(n)
        return lambda: systems.chain_rhs_fast_ws(0.0, y0, p, out, s, c, mu, a, f)
    return lambda: hand(0.0, y0, p, out)


def section(ctx) -> Table:
    table = Table(
        "Kernel cost: ns per RHS call",
        ["case", "implementation", "ns/call, median (min–max)", "× hand-written numba in a loop", "ops after CSE", "GFLOP/s"],
        note="Baseline (1.00×): a hand-written numba RHS of the same system in the same compiled loop, "
             "compiled as a careful user compiles it (error_model=\"numpy\", libm's sin and cos): Cramer's rule "
             "for the double pendulum; for N links the fastest closed form (sin and cos once per link, the "
             "angle-difference identities, M's lower triangle, LDLᵀ with a reciprocal per pivot, scratch "
             "allocated once: `bench.systems.chain_rhs_fast_ws`); "
             "for the constrained examples, which have none, lagcomp's own rhs in the loop. "
             "ops: sympy count_ops after CSE, of lagcomp's rhs (M and F; its emitted LDLᵀ solve not counted) "
             "and of PyDy's mass matrix and forcing (its numeric solve not counted either).",
    )
    for case in ctx.kernel_cases():
        model = ctx.model(case)
        if model is None:
            table.add(case, "lagcomp", ctx.unavailable(case), "", "", "")
            continue
        y0, p = model.initial_state(), model.parameter_vector()
        n = model.n
        ops = model.operations.get("rhs", 0)
        out = np.empty(2 * n)
        ours = in_loop(model.kernels.rhs, y0, p)
        ours_py = from_python(lambda: model.kernels.rhs(0.0, y0, p, out))
        hand = hand_written(case)
        if hand is None:  # no closed form here: lagcomp's own in-loop call is the baseline
            rows = [("lagcomp rhs, in a loop (baseline: no hand-written RHS)", ours, ops),
                    ("lagcomp rhs, from Python", ours_py, ops)]
        else:
            label = "hand-written numba" if case == "double_pendulum" else "closed-form numba (loops)"
            rows = [(label + ", in a loop", in_loop(hand, y0, p), ""), ("lagcomp rhs, in a loop", ours, ops)]
            if case == "double_pendulum":  # the share of lagcomp's sin/cos polynomials in the difference
                rows.append(("hand-written numba with lagcomp's sin/cos, in a loop",
                             in_loop(systems.double_pendulum_rhs_polynomial_trig, y0, p), ""))
            rows += [
                     (label + ", from Python", from_python(hand_call(hand, y0, p, out)), ""),
                     ("lagcomp rhs, from Python", ours_py, ops)]
        if hand is not None and (case == "double_pendulum" or n <= ctx.peer_max_links):
            eom = ctx.eom(case)
            if eom is not None:
                g = lambdify_rhs(eom)
                rows.append(("sympy lambdify (M, F) + numpy solve", from_python(lambda: g(0.0, y0, p), 200), ""))
            if ctx.peer("pydy") is None:
                rows.append(("PyDy cython / lambdify", ctx.skipped, ""))
            else:
                funcs, pydy_ops = ctx.cached(("pydy", n), lambda: pydy_functions(n))
                x = y0.copy()
                for gen, f in funcs.items():
                    rows.append((f"PyDy {gen} ODE function, from Python",
                                 from_python(lambda f=f: f(x, 0.0, p), 500), pydy_ops))
                if "cython" not in funcs:
                    rows.append(("PyDy cython", ctx.skipped + " (Cython)", ""))
        if case == "double_pendulum":
            if ctx.peer("jitcode") is None:
                rows.append(("JiTCODE compiled f", ctx.skipped, ""))
            else:
                jf = ctx.cached("jitcode", jitcode_f).f
                rows.append(("JiTCODE compiled f, from Python", from_python(lambda: jf(0.0, y0)), ""))
        timed = [r for r in rows if not isinstance(r[1], str)]
        stats, ratios = interleaved([r[1][0] for r in timed], ctx.repeats, per_call=[r[1][1] for r in timed])
        results = {r[0]: (s.scaled(1e9), q) for r, s, q in zip(timed, stats, ratios)}
        if hand is not None:
            ctx.kernel_results[case] = (results[timed[0][0]][0], results["lagcomp rhs, in a loop"][0],
                                        results["lagcomp rhs, in a loop"][1])
        for name, stat, count in rows:
            if isinstance(stat, str):
                table.add(case, name, stat, "", "", "")
                continue
            stat, ratio = results[name]
            gflops = fmt(count / stat.median) if count and "loop" in name else ""
            table.add(case, name, fmt_stat(stat), fmt_stat(ratio, "×"), count or "", gflops)
    return table
