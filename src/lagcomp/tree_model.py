"""Compile a kinematic tree (`lagcomp.Tree`) into a `lagcomp.Model` through the recursive multibody path.

``lagcomp.compile(tree)`` comes here.  The kernels come from the recursions over the tree
(`lagcomp.codegen.tree_lower`), not from expanding T and V; the module is emitted, cached, loaded and run as any
model's: same cache (keyed by the tree's fingerprint), same drivers, same `Model` (a `TreeModel`, whose ``system``
is the Tree).  What this first step of issue 39 does not provide yet is refused with a `ModelError` naming it: the
on-demand kernels (Jacobians for radau and sensitivities, the Hamiltonian form, Taylor, geometry, the equations'
LaTeX) and the analyses that read a System's T and V.
"""

from __future__ import annotations

import warnings

from lagcomp.cache import Cache, input_key, load_module
from lagcomp.companion import keep_equations
from lagcomp.errors import CacheWarning
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
    keep_equations(cache, key, tree)   # (what the companion would be built from: the tree, which refuses it)
    return cache.store(key, source, tree.name, metadata)


class TreeModel(Model):
    """A `lagcomp.Model` compiled from a `lagcomp.Tree` (module docstring).  ``system`` is the Tree."""

    @property
    def on_demand_entries(self) -> dict:
        """None built: a tree model has no companion modules yet (its on-demand kernels are refused, issue 39), so
        `operations` counts the eager kernels and ``lagcomp precompile --all`` builds nothing more."""
        return {}

    def on_demand_entry(self, kind: str):
        """None: a tree model has no companion module yet (its on-demand kernels are refused, issue 39)."""
        return None
