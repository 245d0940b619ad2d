"""Models that pickle: a model travels as its cache entry's key and directory, its run defaults and its System.

A `Model` holds its generated module, which pickle cannot carry (``cannot pickle 'module'``).  What makes the
model is smaller: the cache root and input key of its entry, the run defaults it has now (`defaults`, which a
user may have changed, q0, qd0, t_end, the events), and the System it was compiled from, when it has one
and it pickles.  `Model.__reduce__` returns (`restore_model`, (`model_state`(model),)), so
``pickle.loads`` in another process (multiprocessing, joblib, Dask) runs `restore_model`, which

* loads the entry from the cache (no sympy work, and numba's cache beside the module: no compilation), or,
* when the entry is gone (another cache directory on a worker machine, a cleared cache, another lagcomp or
  numba version), compiles the System again into that cache — only when the pickle holds a System: a model
  from `lagcomp.load` or a compiled KanesMethod has none, and its unpickling is then a `ModelError` saying so.

The unpickled model is a model of the same equations with the same run defaults; it is not the same object
(a Kane model's ``kanes_method`` and ``first_order_form`` are not carried: as for a model from `load`).
"""

from __future__ import annotations

import pickle
from pathlib import Path

from lagcomp.errors import ModelError


def model_state(model) -> dict:
    """What `restore_model` rebuilds `model` from: plain data, and the System pickled (None if it does not)."""
    system = None
    if model.system is not None:
        try:
            system = pickle.dumps(model.system)
        except Exception:  # noqa: BLE001 - a System holding something unpicklable: carried without it
            system = None
    return {
        "root": str(Path(model.source_path).parent.parent),
        "key": model.cache_key,
        "kane": hasattr(model, "speeds"),
        "recorded": {
            "name": model.name, "description": model.description, "defaults": dict(model.defaults),
            "q0": None if model.q0 is None else list(model.q0), "qd0": None if model.qd0 is None else list(model.qd0),
            "t_end": model.t_end, "events": [list(event) for event in model.events],
        },
        "system": system,
    }


def restore_model(state: dict):
    """The model `state` describes (`model_state`): from its cache entry, else compiled from its System."""
    from lagcomp.cache import Cache, load_module
    from lagcomp.runtime import Model, compile

    cache, recorded = Cache(state["root"]), state["recorded"]
    entry = cache.lookup(state["key"])
    system = None if state["system"] is None else pickle.loads(state["system"])
    if entry is None:
        if system is None:
            raise ModelError(f"Unpickling the model {recorded['name']!r}: its cache entry {state['key'][:12]} is not "
                             f"in the cache at {state['root']} (another machine, a cleared cache, or another lagcomp "
                             "or numba version), and the pickle holds no System to compile it again (a model from "
                             "lagcomp.load, or a KanesMethod's): compile it in this process (lagcomp.compile).")
        model = compile(system, cache_dir=state["root"])
    elif state["kane"]:
        from lagcomp.kane_model import KaneModel

        model = KaneModel(None, load_module(entry), entry, from_cache=True, recorded=recorded)
    elif entry.metadata.get("tree"):
        from lagcomp.tree_model import TreeModel

        model = TreeModel(None, load_module(entry), entry, from_cache=True, recorded=recorded)
    else:
        model = Model(None, load_module(entry), entry, from_cache=True, recorded=recorded)
    model.system = system
    model.defaults = dict(recorded["defaults"])
    model.q0 = None if recorded["q0"] is None else tuple(recorded["q0"])
    model.qd0 = None if recorded["qd0"] is None else tuple(recorded["qd0"])
    return model
