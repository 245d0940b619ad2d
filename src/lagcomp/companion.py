"""A model's on-demand kernels: its companion modules, one per kind, each built the first time a feature asks
for one of its names.

`lagcomp.compile` writes the eager module of a model (what a plain run calls) and keeps the derived
equations beside its cache entry (``equations/<key>.pickle``).  The kernels of each on-demand kind
(`lagcomp.codegen.kinds`: Jacobians, tangent kernels, the DAE's, the Hamiltonian form, the Taylor program,
geometry, the LaTeX equations, ...) are lowered, emitted and stored as a companion module of that kind under the
key ``<key>-on-demand-<kind>`` the first time a feature reads one of their names from ``model.kernels``
(`ModelKernels`), with the cache's guarantees (atomic writes, a lock per key, stale = miss), and numba
compiles each of them at its first call, as any kernel: a feature pays for its own kinds only.  A companion
imports the eager kernels it calls from the eager module, by the name `lagcomp.cache.load_module` registers it
under (`lagcomp.cache.import_name`).  A second process finds the companion in the cache: no sympy, no lowering.

The equations a companion is lowered from are, in this order: those the compile of this process derived,
those the cache entry keeps (unpickled: sympy is imported then, nothing is derived), those derived again from
the System.  A model from `lagcomp.load` whose entry keeps none cannot build a companion it has not yet built:
the error names the feature that asked (`lagcomp precompile NAME --all` builds every kernel ahead).
"""

from __future__ import annotations

import pickle
import threading
import warnings

from lagcomp.cache import Cache, Entry, load_module
from lagcomp.codegen.kinds import (
    KIND_OF,
    ON_DEMAND,
    TREE_KIND_OF,
    TREE_ON_DEMAND,
    KernelKind,
)
from lagcomp.errors import CacheWarning, ModelError

#: What a companion's input key adds to the model's, before the kind's name.
SUFFIX = "-on-demand"

#: The on-demand kinds by name (a kinematic tree's own, `lagcomp.codegen.kinds.TREE_ON_DEMAND`, included).
_KINDS = {kind.name: kind for kind in (*ON_DEMAND, *TREE_ON_DEMAND)}


def companion_key(key: str, kind: str) -> str:
    """The input key of the companion module of `kind` of the model under input `key`."""
    return f"{key}{SUFFIX}-{kind}"


def keep_equations(cache: Cache, key: str, eom) -> None:
    """Store `eom` beside the entry under `key`, for the companions a later process may build (best effort: a
    System holding what pickle cannot write, a Python function say, keeps none; that process derives again)."""
    try:
        data = pickle.dumps(eom, protocol=pickle.HIGHEST_PROTOCOL)
    except Exception:  # noqa: BLE001  (whatever a user's System holds that pickle refuses)
        return
    cache.store_equations(key, data)


def build_companion(eom, cache: Cache, key: str, system_name: str, kind: KernelKind, eager_module: str) -> Entry:
    """Lower, emit and store the companion module of `kind` of `eom` (the model under input `key`, whose eager
    module companions import as `eager_module`)."""
    from lagcomp.codegen.companion_module import companion_source

    source, metadata = companion_source(eom, kind, eager_module)
    return cache.store(companion_key(key, kind.name), source, f"{system_name}_on_demand_{kind.name}", metadata)


class Companion:
    """The companion modules of one cache entry, each loaded (or built) once per process at its first use."""

    def __init__(self, entry: Entry, name: str, system=None, eom=None):
        self.root, self.key, self.name = entry.path.parent.parent, entry.key, name
        self.eager_module = entry.import_name
        self.system, self.eom = system, eom
        #: The kind of each on-demand name of this model: a kinematic tree's holds M and F too
        #: (`lagcomp.codegen.kinds.TREE_KIND_OF`).
        self.kind_of = TREE_KIND_OF if entry.metadata.get("tree") else KIND_OF
        self._entries: dict[str, Entry] = {}
        self._modules: dict = {}
        self._lock = threading.RLock()

    def entry(self, kind: str, wanted: str | None = None) -> Entry:
        """The cache entry of the companion of `kind`, built first if there is none (`wanted`: the name that
        asked, for messages)."""
        with self._lock:
            if kind not in self._entries:
                cache = Cache(self.root)
                key = companion_key(self.key, kind)
                entry = cache.lookup(key)
                if entry is None:
                    with cache.lock(key):   # processes that need it at once build it once
                        entry = cache.lookup(key) or build_companion(self._buildable(kind, wanted, cache), cache,
                                                                     self.key, self.name, _KINDS[kind],
                                                                     self.eager_module)
                self._entries[kind] = entry
            return self._entries[kind]

    def built(self, kind: str, on_disk: bool = True) -> bool:
        """Whether the companion of `kind` is in the cache (loaded in this process or on disk), building nothing;
        with `on_disk` False, whether this process has it (no look-up in the cache on disk, whose index a busy
        machine may take milliseconds to read)."""
        with self._lock:
            if kind not in self._entries:
                if not on_disk:
                    return False
                entry = Cache(self.root).lookup(companion_key(self.key, kind))
                if entry is None:
                    return False
                self._entries[kind] = entry
            return True

    def entries(self) -> dict[str, Entry]:
        """The entry of every on-demand kind, by kind, built first where needed (``lagcomp precompile --all``)."""
        return {kind.name: self.entry(kind.name) for kind in ON_DEMAND}

    def module(self, kind: str, wanted: str | None = None):
        """The companion module of `kind`, loaded (and built first if needed)."""
        entry = self.entry(kind, wanted)
        with self._lock:
            if kind not in self._modules:
                self._modules[kind] = load_module(entry)
            return self._modules[kind]

    def _buildable(self, kind: str, wanted: str | None, cache: Cache):
        """`_equations`, unless what they describe refuses the on-demand `kind` (a kinematic tree's
        ``on_demand_refusal`` says why, for the kinds it has not), which raises a ModelError naming `wanted` and
        its feature."""
        eom = self._equations(kind, wanted, cache)
        refusal = getattr(eom, "on_demand_refusal", None)
        reason = None if refusal is None else refusal(self._what(kind, wanted), kind)
        if reason is not None:
            raise ModelError(reason)
        return eom

    @staticmethod
    def _what(kind: str, wanted: str | None) -> str:
        """How messages name what was asked: the kernel and its feature, else the kind and its feature."""
        if wanted in TREE_KIND_OF:
            return f"`{wanted}` ({TREE_KIND_OF[wanted].feature})"
        return f"the {kind} kernels ({_KINDS[kind].feature})"

    def _equations(self, kind: str, wanted: str | None, cache: Cache):
        """The equations to lower a companion from (module docstring), or a ModelError naming the feature."""
        if self.eom is not None:
            return self.eom
        what = self._what(kind, wanted)
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
                              "them again.", CacheWarning, stacklevel=5)
        if self.system is None:
            raise ModelError(f"{what} of {self.name!r} is built on first use from the model's equations, and the "
                             f"cache entry lagcomp.load found keeps none: compile the System instead "
                             f"(lagcomp.compile(system)), or build every kernel ahead (lagcomp precompile "
                             f"{self.name} --all).")
        from lagcomp.mechanics.lagrange import derive

        self.eom = derive(self.system)
        return self.eom


#: What `ModelKernels` finds for a name its eager module does not hold.
_ABSENT = object()


class ModelKernels:
    """A model's kernels as one namespace (``model.kernels``): the eager module's names, and the companions'
    (`lagcomp.codegen.kinds.ON_DEMAND`): the first read of a name of a kind loads or builds that kind's module.

    A name of neither raises AttributeError without building anything, so ``getattr(kernels, name, default)``
    keeps its meaning for the eager names.
    """

    def __init__(self, module, companion: Companion):
        self._module, self._companion = module, companion

    def __getattr__(self, name: str):
        if name in ("_module", "_companion"):   # (while unpickling or copying, before __init__ set them)
            raise AttributeError(name)
        # (the module's own names too: __name__, __file__, ...).  A name of neither is looked for at each read
        # (``getattr(kernels, "CONTACTS", ())`` on a model without contacts, a dozen per run): found absent in the
        # two dicts, not by the module's own AttributeError (~2 µs, its message formatted, then caught).
        value = vars(self._module).get(name, _ABSENT)
        if value is _ABSENT:
            kind = self._companion.kind_of.get(name)
            if kind is None:
                raise AttributeError(f"{self._module.__name__!r} has no kernel or attribute {name!r}")
            value = getattr(self._companion.module(kind.name, name), name)
        self.__dict__[name] = value     # (later reads find it without this call: the modules never change)
        return value

    @property
    def companion(self) -> Companion:
        """The companion modules' loader (`Companion`)."""
        return self._companion

    @property
    def eager_module(self):
        """The eager module itself."""
        return self._module
