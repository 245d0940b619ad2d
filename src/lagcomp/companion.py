"""A model's on-demand kernels: its companion module, built the first time a feature asks for one of them.

`lagcomp.compile` writes the eager module of a model (what a plain run calls) and keeps the derived
equations beside its cache entry (``equations/<key>.pickle``).  The kernels of the on-demand kinds
(`lagcomp.codegen.kinds`: Jacobians, tangent kernels, the DAE's, the Hamiltonian form, the Taylor program,
geometry, the LaTeX equations, ...) are lowered, emitted and stored as one companion module under the key
``<key>-on-demand`` the first time a feature reads one of their names from ``model.kernels``
(`ModelKernels`), with the cache's guarantees (atomic writes, a lock per key, stale = miss), and numba
compiles each of them at its first call, as any kernel.  A second process finds the companion in the cache:
no sympy, no lowering.

The equations a companion is lowered from are, in this order: those the compile of this process derived,
those the cache entry keeps (unpickled: sympy is imported then, nothing is derived), those derived again from
the System.  A model from `lagcomp.load` whose entry keeps none cannot build its companion: the error names
the feature that asked (`lagcomp precompile NAME --all` builds every kernel ahead).
"""

from __future__ import annotations

import pickle
import threading
import warnings

from lagcomp.cache import Cache, Entry, load_module
from lagcomp.codegen.kinds import feature, on_demand
from lagcomp.errors import CacheWarning, ModelError

#: What the companion's input key adds to the model's.
SUFFIX = "-on-demand"


def companion_key(key: str) -> str:
    """The input key of the companion module of the model under input `key`."""
    return key + SUFFIX


def keep_equations(cache: Cache, key: str, eom) -> None:
    """Store `eom` beside the entry under `key`, for the companion a later process may build (best effort: a
    System holding what pickle cannot write, a Python function say, keeps none; that process derives again)."""
    try:
        data = pickle.dumps(eom, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception:  # noqa: BLE001  (whatever a user's System holds that pickle refuses)
        return
    cache.store_equations(key, data)


def build_companion(eom, cache: Cache, key: str, system_name: str) -> Entry:
    """Lower, emit and store the companion module of `eom` (the model under input `key`)."""
    from lagcomp.codegen.emit import emit_companion
    from lagcomp.codegen.latex import lagrange_equations
    from lagcomp.codegen.lower import lower
    from lagcomp.codegen.taylor import taylor_decomposition, taylor_program

    ir = lower(eom, "on_demand")
    taylor = taylor_decomposition(ir)
    program = taylor_program(taylor)
    source = emit_companion(ir, taylor, lagrange_equations(eom))
    operations = {k.name: k.operation_count for k in ir.kernels if on_demand(k.name)}
    if program:
        operations["taylor_coefficients"] = program["operations"]
    return cache.store(companion_key(key), source, f"{system_name}_on_demand",
                       {"operations": operations, "taylor_program": program})


class Companion:
    """The companion module of one cache entry, loaded (or built) once per process at its first use."""

    def __init__(self, entry: Entry, name: str, system=None, eom=None):
        self.root, self.key, self.name = entry.path.parent.parent, entry.key, name
        self.system, self.eom = system, eom
        self._entry: Entry | None = None
        self._module = None
        self._lock = threading.Lock()

    def entry(self, wanted: str = "the on-demand kernels") -> Entry:
        """The companion's cache entry, built first if there is none (`wanted`: the name that asked)."""
        with self._lock:
            if self._entry is None:
                cache = Cache(self.root)
                key = companion_key(self.key)
                entry = cache.lookup(key)
                if entry is None:
                    with cache.lock(key):   # processes that need it at once build it once
                        entry = cache.lookup(key) or build_companion(self._buildable(wanted, cache), cache,
                                                                     self.key, self.name)
                self._entry = entry
            return self._entry

    def module(self, wanted: str = "the on-demand kernels"):
        """The companion module, loaded (and built first if needed)."""
        entry = self.entry(wanted)
        if self._module is None:
            self._module = load_module(entry)
        return self._module

    def _buildable(self, wanted: str, cache: Cache):
        """`_equations`, unless what they describe refuses on-demand kernels (a kinematic tree, for now: its
        ``on_demand_refusal`` says why), which raises a ModelError naming `wanted` and its feature."""
        eom = self._equations(wanted, cache)
        refusal = getattr(eom, "on_demand_refusal", None)
        if refusal is not None:
            what = f"`{wanted}` ({feature(wanted)})" if on_demand(wanted) else wanted
            raise ModelError(refusal(what))
        return eom

    def _equations(self, wanted: str, cache: Cache):
        """The equations to lower the companion from (module docstring), or a ModelError naming the feature."""
        if self.eom is not None:
            return self.eom
        what = f"`{wanted}` ({feature(wanted)})" if on_demand(wanted) else wanted
        data = cache.equations(self.key)
        if data is not None:
            try:
                self.eom = pickle.loads(data)  # noqa: S301  (the cache's own file, written by `keep_equations`)
                return self.eom
            except ImportError as err:
                raise ModelError(f"{what} of {self.name!r} is built on first use from the model's equations, "
                                 f"which needs sympy ({err}): install it, or build every kernel ahead where it is "
                                 f"installed (lagcomp precompile {self.name} --all).") from err
            except Exception as err:  # noqa: BLE001  (a damaged file is a miss)
                warnings.warn(f"lagcomp could not read the equations kept for {self.name!r} ({err}); deriving "
                              "them again.", CacheWarning, stacklevel=4)
        if self.system is None:
            raise ModelError(f"{what} of {self.name!r} is built on first use from the model's equations, and the "
                             f"cache entry lagcomp.load found keeps none: compile the System instead "
                             f"(lagcomp.compile(system)), or build every kernel ahead (lagcomp precompile "
                             f"{self.name} --all).")
        from lagcomp.mechanics.lagrange import derive

        self.eom = derive(self.system)
        return self.eom


class ModelKernels:
    """A model's kernels as one namespace (``model.kernels``): the eager module's names, and the companion's
    (`lagcomp.codegen.kinds.ON_DEMAND`), which the first read of one of them loads or builds.

    A name of neither raises AttributeError without building anything, so ``getattr(kernels, name, default)``
    keeps its meaning for the eager names.
    """

    def __init__(self, module, companion: Companion):
        self._module, self._companion = module, companion

    def __getattr__(self, name: str):
        if name in ("_module", "_companion"):   # (while unpickling or copying, before __init__ set them)
            raise AttributeError(name)
        try:
            value = getattr(self._module, name)   # (the module's own names too: __name__, __file__, ...)
        except AttributeError:
            if not on_demand(name):
                raise
            value = getattr(self._companion.module(name), name)
        self.__dict__[name] = value     # (later reads find it without this call: the modules never change)
        return value

    @property
    def companion(self) -> Companion:
        """The companion module's loader (`Companion`)."""
        return self._companion

    @property
    def eager_module(self):
        """The eager module itself."""
        return self._module
