"""The kinds of kernels a model has: which `lagcomp.compile` builds, which are built the first time a feature asks.

A model's cache entry holds its eager module and, once built, a companion module per on-demand kind
(`lagcomp.cache`, `lagcomp.companion`):

* the **eager module**, written by `lagcomp.compile`: what a plain run with the default method
  (``simulate``, ``sweep``, ``lagcomp run``: dop853, the fixed-step explicit methods, rattle) calls:
  ``rhs`` (with ``reactions``, ``rhs_and_reactions``, the constraint residuals and matrix of a
  constrained model, the contact kernels of a model with contacts), ``mass_matrix``, ``forcing``,
  the energies and momenta with ``observables``, the events (``event_values``, ``event_gradients``,
  ``event_reset``), the constraint hooks (``project``, ``constraint_residual``, ``reactions_along``);
* a **companion module** for each kind of `ON_DEMAND` below, lowered (that kind alone), emitted, stored and
  numba-compiled the first time a feature asks for one of its names, from the equations the entry keeps
  (`lagcomp.codegen.companion_module`).  It imports the eager kernels its kernels call (among `CALLED`) from
  the eager module by name; it copies nothing.

Every name that is not in an on-demand kind is eager: a new kernel kind is eager unless it is added here.
To add an on-demand kind: build its kernels in `lagcomp.codegen.lower` under the kind's name (its
`_builders`), and list here, in a `KernelKind`, the names its module defines (kernels and module constants)
and the feature that asks for it (the message when it cannot be built).  Nothing else: its companion module,
cache key (``<key>-on-demand-<kind>``), file in `generated/` and loading follow from the registry.  Its kernels
may call ``rhs`` or ``rhs_and_reactions`` (through a `lagcomp.ir.JacobianSolve` or
`lagcomp.ir.AugmentedJacobianSolve` frame, `lagcomp.codegen.emit.eager_calls`), not a kernel of another
on-demand kind.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class KernelKind:
    """Kernels built together on demand: the names they define in their companion module, and what asks for them."""

    name: str
    names: tuple[str, ...]
    feature: str


#: The on-demand kinds, in the order their kernels are lowered (`lagcomp.codegen.lower`).
ON_DEMAND = (
    KernelKind("lanes", ("rhs_lanes",), "batched sweeps (sweep(..., batched=True))"),
    KernelKind("jacobians", ("rhs_with_jacobian", "rhs_jacobian", "rhs_parameter_jacobian", "rhs_with_full_jacobian",
                             "reaction_jacobian", "RHS_JACOBIAN_REFUSED", "RHS_PARAMETER_JACOBIAN_REFUSED"),
               "the exact Jacobians (method='radau', sensitivities, fits, Model.jacobian)"),
    KernelKind("directional", ("rhs_directional", "rhs_tangent", "rhs_tangent_parameters", "rhs_tangents",
                               "rhs_tangents_parameters"), "forward sensitivities (simulate(..., sensitivities=...))"),
    KernelKind("dae", ("dae_residual", "dae_jacobian"), "method='radau' on a constrained model"),
    KernelKind("canonical", ("momentum_rate", "velocities", "canonical_partials"),
               "the Hamiltonian form (gauss1/2/3, Lyapunov exponents, Model.hamiltonian)"),
    KernelKind("analysis", ("rest_partials",), "equilibria and small oscillations (lagcomp.analysis)"),
    KernelKind("geometry", ("geometry", "GEOMETRY", "GEOMETRY_SIZE", "GEOMETRY_PARENTS"), "the bodies' positions (animation, plots)"),
    KernelKind("taylor", ("taylor_coefficients", "TAYLOR_WORK", "TAYLOR_PERIODIC", "TAYLOR_REFUSED",
                          "TAYLOR_MODE_PROGRAMS"), "method='taylor'"),
    KernelKind("equations", ("EQUATIONS",), "Model.equations()"),
    KernelKind("power", ("power",), "the energy balance (Solution.energy_balance)"),
    KernelKind("input_jacobian", ("rhs_input_jacobian", "RHS_INPUT_JACOBIAN_REFUSED"),
               "state-space models (lagcomp.analysis.linearize(..., inputs=...), Model.rhs_input_jacobian)"),
    KernelKind("energy_lanes", ("energy_lanes", "energy_function_lanes"),
               "a run's summary (simulate(..., record='summary'))"),
)

#: The on-demand kinds only a kinematic tree (`lagcomp.Tree`) has: kernels a System's eager module holds, which no
#: run of a tree calls (its ``rhs`` is the articulated-body algorithm, which forms no M), built on first use.
TREE_ON_DEMAND = (
    KernelKind("dynamics", ("mass_matrix", "forcing"),
               "M(q) and F(q, q̇, t) of a kinematic tree (Model.mass_matrix, Model.forcing, lagcomp.analysis)"),
)

#: The on-demand kinds a model compiled from a kinematic tree (`lagcomp.Tree`) has, built from its recursions
#: (``dynamics``: the composite-rigid-body algorithm and recursive Newton–Euler), those differentiated in forward
#: mode (`lagcomp.codegen.tree_companion`; "dae" only has kernels for a tree with loops,
#: `lagcomp.codegen.tree_loop_companion`), the links' frames ("geometry", `lagcomp.codegen.tree_geometry`, whose
#: ``GEOMETRY_PARENTS`` a System's module does not define) and the energy balance's "power"
#: (`lagcomp.codegen.tree_power`), the Taylor series program of "taylor" (`lagcomp.codegen.tree_taylor`) and the
#: Hamiltonian form of "canonical" (`lagcomp.codegen.tree_canonical`), the recursion as LaTeX and text of
#: "equations" (`lagcomp.codegen.tree_latex`) and the lanes of batched sweeps, ``rhs`` per lane ("lanes",
#: `lagcomp.codegen.tree_lanes`); its other kinds are refused.
TREE_KINDS = ("lanes", "jacobians", "directional", "analysis", "dae", "geometry", "dynamics", "power", "canonical",
              "taylor", "equations")

#: Every name a companion module may define, and the kind that defines it.
KIND_OF = {name: kind for kind in ON_DEMAND for name in kind.names}

#: `KIND_OF` of a tree model: a System's on-demand names (its refused kinds included: asking for one says why) and
#: the names of `TREE_ON_DEMAND`.
TREE_KIND_OF = {**KIND_OF, **{name: kind for kind in TREE_ON_DEMAND for name in kind.names}}

#: The eager kernels that on-demand kernels call (the Jacobians start from ``rhs``, a constrained model's from
#: ``rhs_and_reactions``): a companion module imports them from the eager module.
CALLED = ("rhs", "rhs_and_reactions")


def on_demand(name: str) -> bool:
    """Whether the kernel or module constant `name` lives in the companion module (else in the eager one)."""
    return name in KIND_OF


def feature(name: str) -> str:
    """What asks for the on-demand `name` (for messages)."""
    return KIND_OF[name].feature
