"""Compile a kinematic tree (`lagcomp.Tree`) into a `lagcomp.Model` through the recursive multibody path.

``lagcomp.compile(tree)`` comes here.  The kernels come from the recursions over the tree
(`lagcomp.codegen.tree_lower`), not from expanding T and V; the module is emitted, cached, loaded and run as any
model's: same cache (keyed by the tree's fingerprint), same drivers, same `Model` (a `TreeModel`, whose ``system``
is the Tree).  Its on-demand kernels of the kinds `lagcomp.codegen.kinds.TREE_KINDS` (the Jacobians, the tangent
kernels, ``rest_partials``: radau, sensitivities, linearization) are the recursions differentiated in forward mode
(`lagcomp.codegen.tree_companion`), ``mass_matrix`` and ``forcing``, which no run of a tree calls, their recursions,
and ``geometry`` (animation) the links' frames (`lagcomp.codegen.tree_geometry`), built on first use into companion
modules as a System's are, and so are ``power`` (the energy balance, `lagcomp.codegen.tree_power`) and
``taylor_coefficients`` (method="taylor", `lagcomp.codegen.tree_taylor`).  The Hamiltonian form of gauss1/2/3 is the
kind "canonical" (`lagcomp.codegen.tree_canonical`), the lanes of batched sweeps the kind "lanes" (``rhs`` per lane,
`lagcomp.codegen.tree_lanes`).

``Model.equations()`` is the kind "equations": the recursion in Featherstone's notation over a table of the tree's
nodes (placement, motion subspace, inertia, joint force of each), the loops' closure, T and V
(`lagcomp.codegen.tree_latex` says why the recursion and not the emitted program), rendered by sympy on first use
into a companion module, so that `lagcomp.load` shows them without sympy once they are built, as a System's.

What issue 39 does not provide yet is refused with a `ModelError` naming it: the other on-demand kernels (the lanes
of a tree with loops, contacts or friction elements; a System's kinds a tree has no use for) and the analyses that
read a System's T and V.
"""

from __future__ import annotations

import warnings

from lagcomp.cache import Cache, input_key, load_module
from lagcomp.codegen.kinds import ON_DEMAND, TREE_KINDS, TREE_ON_DEMAND
from lagcomp.companion import keep_equations
from lagcomp.errors import CacheWarning, ModelError
from lagcomp.runtime import Model, run_defaults


def compile_tree(tree, cache_dir=None, progress=None) -> TreeModel:
    """The `TreeModel` of `tree`, from the cache or built (derivation-free: the recursions are emitted)."""
    cache = Cache(cache_dir)
    key = input_key(tree.fingerprint(), options={"multibody": 1})
    entry = cache.lookup(key)
    if entry is not None:
        try:
            model = TreeModel(tree, load_module(entry), entry, from_cache=True)
            cache.remember(tree.name, key, run_defaults(tree))
            return model
        except Exception as err:  # noqa: BLE001  (a damaged module that still hashed right)
            warnings.warn(f"lagcomp could not load {entry.path.name} ({err}); rebuilding it.", CacheWarning,
                          stacklevel=3)
            cache.discard(entry)
    with cache.lock(key):
        entry = cache.lookup(key) or _build(tree, cache, key, progress)
    cache.remember(tree.name, key, run_defaults(tree))
    return TreeModel(tree, load_module(entry), entry, from_cache=False)


def _build(tree, cache: Cache, key: str, progress=None):
    from lagcomp.codegen.emit import emit_eager
    from lagcomp.codegen.tree_lower import lower_tree
    from lagcomp.stages import Stages

    stages_ = ("the recursions (articulated body, composite rigid body, Newton-Euler)", "emitting and storing")
    with Stages(f"compiling {tree.name}", stages_, progress) as stages:
        stages.start(stages_[0])
        ir = lower_tree(tree)
        stages.start(stages_[1])
        source = emit_eager(ir)
    metadata = {
        "tree": True, "coordinates": list(tree.coordinate_names), "parameters": list(tree.parameter_names),
        "cyclic": [],
        "constraints": list(tree.constraint_names), "holonomic": [True] * len(tree.constraint_names),   # loops
        "separable": False, "holonomic_separable": False,
        "operations": {k.name: k.operation_count for k in ir.kernels}, "on_demand": True,
    }
    keep_equations(cache, key, tree)   # (what the companions are built from: `lagcomp.codegen.tree_companion`)
    return cache.store(key, source, tree.name, metadata)


class TreeModel(Model):
    """A `lagcomp.Model` compiled from a `lagcomp.Tree` (module docstring).  ``system`` is the Tree."""

    @property
    def on_demand_entries(self) -> dict:
        """The cache entries of the companion modules of the on-demand kinds a tree has
        (`lagcomp.codegen.kinds.TREE_KINDS`), by kind, each built first if needed: what ``operations`` counts and
        ``lagcomp precompile --all`` builds."""
        return {kind: self.kernels.companion.entry(kind) for kind in TREE_KINDS}

    def on_demand_entry(self, kind: str):
        """The cache entry of the companion module of the on-demand `kind`, built first if needed; a ModelError
        naming the kind for one a tree does not have yet (issue 39)."""
        if kind not in TREE_KINDS:
            feature = next((k.feature for k in (*ON_DEMAND, *TREE_ON_DEMAND) if k.name == kind), "an unknown kind")
            raise ModelError(f"the {kind} kernels ({feature}) are not available for the kinematic tree "
                             f"{self.name!r} yet: a tree model has the on-demand kinds {list(TREE_KINDS)} "
                             "(issue 39).")
        return self.kernels.companion.entry(kind)
