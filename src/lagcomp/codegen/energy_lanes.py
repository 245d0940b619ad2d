"""The energy kernels over many rows of one run at once (``energy_lanes``, ``energy_function_lanes``): a summary's.

A run with ``record="summary"`` evaluates T + V, and h where it is not T + V, at every saved row
(`lagcomp.integrate.recording`).  Called row by row through a function value, the double pendulum's scalar
``energy`` (three cosines) costs 35 ns a row, 28 ns inlined into a loop: more than ten times a trajectory's copy of
the row (2 ns).  The same body in a loop over the rows that LLVM vectorizes (one row per SIMD lane, as ``rhs_lanes``
does for the trajectories of a batched sweep: `lagcomp.codegen.lower`) costs about 5 ns a row with the rows laid
out as columns (a strided loop over the rows as they come, one row per line, does not vectorize: 29 ns).

Each lane computes the scalar kernel's bits: the same temporaries and stores from the same CSE, printed with
``vsin``/``vcos`` (`lagcomp.kernel_support.trig`), which are the scalar kernels' ``sin``/``cos`` without their
branch to libm for |x| > ``_TRIG_POLY_MAX`` or a non-finite x; no fastmath on either.  So that the caller can keep
that branch, each lane also writes ``reach``, the sum of |x| over the arguments x of sin and cos in that row (0.0
without any): every argument is within the polynomials' range when ``reach <= _TRIG_POLY_MAX``, and the caller
evaluates the other rows (NaN included) again with the scalar kernel.
"""

from __future__ import annotations

from dataclasses import replace

import sympy as sp

from lagcomp.codegen.bindings import symbol_slots
from lagcomp.ir import Kernel

#: The arguments of the lane kernels: times T (B,), rows as columns Y (2n, B), the run's parameters p (n_p,),
#: the values out (B,) and the reach of the trigonometric arguments (B,).
ARGS = ("T", "Y", "p", "out", "reach")


def energy_lanes_kernels(energy: Kernel, energy_function: Kernel, eom) -> tuple[Kernel, Kernel]:
    """``energy_lanes`` from the scalar `energy` kernel, and ``energy_function_lanes`` from `energy_function` (the
    same function when h is T + V: an alias, as the scalar kernels are).  `eom` has no inputs (a scalar kernel's
    loads are then its state's and parameters')."""
    lanes = _lanes_kernel(energy, "energy_lanes", eom)
    if energy_function.alias == energy.name:
        h = Kernel(name="energy_function_lanes", doc=energy_function.doc.splitlines()[0] + " Here h = T + V.",
                   args=ARGS, loads=(), temps=(), stores=(), alias="energy_lanes")
    else:
        h = _lanes_kernel(energy_function, "energy_function_lanes", eom)
    return lanes, h


def _lanes_kernel(scalar: Kernel, name: str, eom) -> Kernel:
    """The scalar kernel `scalar` (``return`` of one value) over rows as lanes: a local bound to ``y[i]`` reads
    ``Y[i, _l]``, ``t`` reads ``T[_l]``, a parameter is read from the shared ``p``; the value goes to ``out[_l]``
    and the reach of its sin and cos arguments to ``reach[_l]`` (module docstring)."""
    columns = {local: f"Y[{index}, _l]" for _, local, array, index in symbol_slots(eom) if array == "y"}
    expressions = [e for _, e in scalar.temps + scalar.stores]
    uses_t = any(sp.Symbol("t", real=True) in e.free_symbols for e in expressions)
    arguments = sorted({f.args[0] for e in expressions for f in e.atoms(sp.sin, sp.cos)}, key=sp.default_sort_key)
    (target, value), = scalar.stores
    assert target == "return", scalar.stores
    return replace(
        scalar, name=name, args=ARGS, lanes=True,
        doc=f"{scalar.doc.splitlines()[0]}\nFor every row l: T (B,) times, Y (2n, B) rows as columns, p the run's "
            f"parameters; out[l] = `{scalar.name}`\nof row l, reach[l] = the sum of |x| over the arguments x of its "
            "sin and cos (0.0 without any):\nwhere it is not <= _TRIG_POLY_MAX, evaluate the row with "
            f"`{scalar.name}`.",
        loads=(("t", "T[_l]"),) * uses_t + tuple((local, columns.get(local, source)) for local, source in scalar.loads),
        stores=(("out[_l]", value), ("reach[_l]", sp.Add(*(sp.Abs(x) for x in arguments)))),
    )
