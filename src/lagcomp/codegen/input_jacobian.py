"""The ``rhs_input_jacobian`` kernel: ∂f/∂u of y' = f(t, y, p, u), the input matrix B of a state-space model.

For the inputs u supplied at run time (`lagcomp.Input` without a law, in the model's order `input_names`)
of an unconstrained system without contacts: as ``rhs_parameter_jacobian`` along the parameters,
M ∂a/∂u = ∂F/∂u − ∂(M ā)/∂u |ā = a (`lagcomp.codegen.jacobian_blocks.acceleration_block`), q̇ free of u.
An input whose derivative the equations read (a support motion in T brings u̇ and ü into F) has no such B:
the response is to u̇ and ü as well, so the kernel refuses (a stub with the reason in
``RHS_INPUT_JACOBIAN_REFUSED``).  A constrained system's B comes from `lagcomp.analysis.linearize_steady`.
"""

from __future__ import annotations

from dataclasses import replace

import sympy as sp

from lagcomp.codegen.cse import cse_kernel
from lagcomp.codegen.jacobian_blocks import (
    acceleration_block,
    fresh_symbols,
    jacobian_entry,
)
from lagcomp.ir import NO_JACOBIAN, JacobianSolve, Kernel, Unavailable
from lagcomp.mechanics.lagrange import EOM
from lagcomp.model.system import t

DOC = ("Exact input Jacobian out[i, j] = ∂f_i/∂u_j, (N, U), of y' = f(t, y, p, u) as `rhs` computes it (symbolic, no\n"
       "differences): U = the inputs supplied at run time, in the model's order (`Model.inputs`; the matrix B of a\n"
       "state-space model).\n")


def input_jacobian_kernel(eom: EOM, mapping, loads) -> Kernel:
    """``rhs_input_jacobian(t, y, p, out) -> int`` of `eom` (module docstring)."""
    inputs, n = eom.system.inputs, eom.n
    width = len(inputs)
    read = [u.func.__name__ for u in inputs
            if any(d.expr == u for e in (*eom.M, *eom.F) for d in e.atoms(sp.Derivative))]
    if read:
        reason = (f"the derivatives of the input(s) {read} (in T or a constraint): the motion responds to u̇ and ü "
                  "as well, so ∂f/∂u is no input matrix")
        return Kernel(name="rhs_input_jacobian",
                      doc=DOC + f"Not available for this system: {reason}.\nWrites nothing and returns NO_JACOBIAN = "
                                f"{NO_JACOBIAN} (RHS_INPUT_JACOBIAN_REFUSED says why).",
                      args=("t", "y", "p", "out"), loads=(), temps=(), stores=(),
                      solve=Unavailable(status=NO_JACOBIAN, constant="RHS_INPUT_JACOBIAN_REFUSED", reason=reason))
    taken = {s.name for s in (*eom.q, *eom.qd, *eom.parameters, t)}
    taken |= {s.name for e in (*eom.M, *eom.F) for s in e.free_symbols}
    symbols = fresh_symbols("_u", width, taken)
    plain = dict(zip(inputs, symbols, strict=True))
    eom = replace(eom, M=eom.M.xreplace(plain), F=eom.F.xreplace(plain))
    mapping = {**mapping, **{s: mapping[u] for u, s in plain.items()}}
    block, m, mapping, loads = acceleration_block(eom, symbols, mapping, loads)
    stores = [(m[i][j], eom.M[i, j]) for i in range(n) for j in range(i + 1)]
    stores += [(jacobian_entry(n + i, j, width), block[i][j])
               for i in range(n) for j in range(width) if block[i][j] != 0]
    return cse_kernel(
        "rhs_input_jacobian",
        DOC + "Rows 0 (q̇ does not depend on u), then ∂a/∂u = M⁻¹ (∂F/∂u − ∂(M ā)/∂u |ā=a) (a = q̈ from `rhs`).\n"
        "Returns 0, or k > 0 as `rhs` does; `out` is then invalid.",
        ("t", "y", "p", "out"), stores, mapping, loads, solve=JacobianSolve(n=n, size=2 * n, m=m, columns=width),
    )
