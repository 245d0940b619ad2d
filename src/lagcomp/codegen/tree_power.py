r"""The ``power`` kernel of a kinematic tree (`lagcomp.Tree`): the rate of change of h = T + V, term by term.

The same kernel as a System's (`lagcomp.codegen.power`): ``power(t, y, p, lam, out)`` writes the four terms of
dh/dt (`lagcomp.codegen.power.TERMS`) into ``out``.  A tree's joint i acts on its joint variable with the
generalized force τ_i − k_i (q_i − rest_i) − c_i ṡ_i (`lagcomp.multibody.kinematics.local_nodes`), ṡ_i the node's
rate in the recursions: q̇_i, or for a spherical joint's part k the body rate ω_k = (J(σ) σ̇)_k.  The spring is in V;
the rest does work at the rate

* out[0] = Σ_i τ_i ṡ_i (the joints' torques and forces, ``torque=``: "forces");
* out[1] = −Σ_i c_i ṡ_i² (the joints' dampers, ``damping=``: "dissipation", −2D with D = ½ Σ c ṡ²);
* out[2] = −∂L/∂t = 0 and out[3] = −λ·b = 0: only a joint's torque (and an event) may read t
  (`lagcomp.multibody.tree`), so L has no explicit time and a loop's points do not move (b = 0).

The rates are those the recursions use, so on a spherical joint the power is ω·τ, the same number as q̇·Q in the
MRP coordinates (Q_σ = Jᵀ Q_ω, `lagcomp.multibody.charts`).
"""

from __future__ import annotations

import sympy as sp

from lagcomp.codegen.power import TERMS
from lagcomp.codegen.tree_lower import program_kernel
from lagcomp.ir import Kernel, ReturnZero
from lagcomp.multibody.joints import t
from lagcomp.multibody.kinematics import node_rate
from lagcomp.multibody.program import Program


def tree_power_terms(prog: Program, tree, local) -> list:
    """[Σ τ ṡ, −Σ c ṡ², 0, 0] of `tree` over its kernel locals `local` (`lagcomp.codegen.tree_companion.TreeLocals`),
    bound in `prog` (module docstring)."""
    signals = {c.diff(t): local.qd[i] for i, c in enumerate(tree.coordinates)}
    signals.update({c: local.q[i] for i, c in enumerate(tree.coordinates)})

    def localized(e):
        return sp.sympify(e).xreplace(signals).xreplace(local.mapping)

    forces, dissipation = [], []
    for node, local_node in zip(tree.nodes, local.nodes):
        torque, damping = localized(node.joint.torque), localized(node.joint.damping)
        if torque == 0 and damping == 0:
            continue
        rate = node_rate(prog, local_node)
        forces.append(torque * rate)
        dissipation.append(-damping * rate ** 2)
    return [prog.let(sp.Add(*forces)), prog.let(sp.Add(*dissipation)), sp.S.Zero, sp.S.Zero]


def tree_power_kernels(tree, local) -> tuple[Kernel, ...]:
    """The ``power`` kernel of `tree` (module docstring), its signature the System's."""
    prog = Program()
    terms = tree_power_terms(prog, tree, local)
    stores = [(f"out[{i}]", term) for i, term in enumerate(terms)]
    return (program_kernel(
        "power",
        "The rate of change of the energy function h = T + V, term by term, into `out` (4,): out[0] = Σ τ ṡ (the\n"
        "joints' torques), out[1] = −Σ c ṡ² (their dampers), out[2] = −∂L/∂t = 0 and out[3] = −λ·b = 0\n"
        "(only torques read t); ṡ the joint rates of the recursions (a ball joint's body rates). `lam` is not\n"
        "read. dh/dt is their sum along a motion (lagcomp.codegen.tree_power). Returns 0.",
        ("t", "y", "p", "lam", "out"), prog, stores, local.loads, ReturnZero()),)


def active_tree_power_terms(tree, local) -> list[str]:
    """The names of the terms of dh/dt (`TERMS`) not identically zero for `tree` (as
    `lagcomp.codegen.companion_module.active_power_terms` for a System's): empty when h is a first integral."""
    terms = tree_power_terms(Program(), tree, local)
    return [name for name, term in zip(TERMS, terms, strict=True) if sp.sympify(term) != 0]

