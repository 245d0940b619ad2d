"""The source of one companion module: the kernels of one on-demand kind (`lagcomp.codegen.kinds`), lowered from
the derived equations and emitted (used by `lagcomp.companion` on first use, and for `generated/`).

Each kind is lowered alone (`lagcomp.codegen.lower.lower` with the kind's name), so a feature pays the lowering,
CSE and numba compilation of its own kernels only; two kinds are built differently: "taylor" decomposes the
motion kernels (``rhs``, lowered again: its program starts from their IR) into the Taylor program and emits
``taylor_coefficients`` alone, and "equations" lowers nothing and emits ``EQUATIONS``.
"""

from __future__ import annotations

from lagcomp.codegen.emit import emit_companion
from lagcomp.codegen.kinds import KernelKind
from lagcomp.codegen.latex import lagrange_equations
from lagcomp.codegen.lower import lower
from lagcomp.codegen.power import TERMS, multiplier_symbols, power_terms
from lagcomp.codegen.taylor import taylor_decomposition, taylor_program
from lagcomp.codegen.tree_companion import tree_companion_source
from lagcomp.mechanics.lagrange import EOM
from lagcomp.multibody.tree import Tree


def companion_source(eom: EOM, kind: KernelKind, eager_module: str) -> tuple[str, dict]:
    """The source of the companion module of `kind` for `eom`, and the metadata stored with it: ``operations``
    (arithmetic operations after CSE, per kernel) and, for the kind "taylor", ``taylor_program``
    (`lagcomp.codegen.taylor.taylor_program`, None without one), for the kind "power", ``power_terms``
    (`active_power_terms`).  `eager_module` is the name the companion imports the eager kernels it calls from
    (`lagcomp.cache.import_name` of the model's eager module).  A kinematic tree's (`eom` a `lagcomp.Tree`) come
    from its recursions (`lagcomp.codegen.tree_companion`)."""
    if isinstance(eom, Tree):
        return tree_companion_source(eom, kind, eager_module)
    if kind.name == "taylor":
        ir = lower(eom, "motion")
        taylor = taylor_decomposition(ir)
        program = taylor_program(taylor)
        operations = {"taylor_coefficients": program["operations"]} if program else {}
        return emit_companion(ir, kind, eager_module, taylor=taylor), {"operations": operations,
                                                                       "taylor_program": program}
    if kind.name == "equations":
        return emit_companion(lower(eom, "equations"), kind, eager_module, equations=lagrange_equations(eom)), {
            "operations": {}}
    ir = lower(eom, kind.name)
    operations = {k.name: k.operation_count for k in ir.kernels if k.name in kind.names}
    metadata = {"operations": operations}
    if kind.name == "power":        # which terms of dh/dt the system has: none, and h is a first integral
        metadata["power_terms"] = active_power_terms(eom)
    return emit_companion(ir, kind, eager_module), metadata


def active_power_terms(eom: EOM) -> list[str]:
    """The names of the terms of dh/dt (`lagcomp.codegen.power.TERMS`) that are not identically zero for `eom`:
    an empty list when h is a first integral (no forces or inputs, no dissipation, no explicit time, no moving
    constraint); a sweep reports the energy balance instead of the drift of T + V otherwise."""
    return [name for name, term in zip(TERMS, power_terms(eom, multiplier_symbols(eom)), strict=True) if term != 0]
