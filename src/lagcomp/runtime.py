"""`compile` a System into a `Model`: derive, lower, emit, cache, load.

This is the one module that sees both halves of the pipeline: on a cache miss
it runs the symbolic stages (mechanics → ir → codegen) and stores the
module; on a hit it loads the module straight from disk, with no sympy work
and, thanks to numba's own cache beside it, no numba compilation.  `load`
goes further for a later process: it finds a model by name and never imports
sympy, so a cached model is ready in well under a second.
"""

from __future__ import annotations

import functools
import math
import operator
import os
import warnings
from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

from lagcomp.cache import Cache, Entry, input_key, load_module
from lagcomp.companion import Companion, ModelKernels
from lagcomp.errors import CacheWarning, InitialConditionError, ModelError, ParameterError, SingularMassMatrixError
from lagcomp.integrate.contacts import contacts_of, frictions_of, mode_slot_count
from lagcomp.names import by_name


def compile(system, *, cache_dir: str | os.PathLike | None = None, eom=None, progress=None,  # noqa: A001
            **system_kwargs) -> "Model":
    """Compile `system` into a `Model` of numba kernels, using the on-disk cache.

    Parameters
    ----------
    system : System, Tree, or sympy.physics.mechanics LagrangesMethod / KanesMethod
        What to compile.  A `lagcomp.Tree` (rigid links and joints) is compiled
        from recursive multibody algorithms into a `lagcomp.tree_model.TreeModel`
        (`lagcomp.multibody`).  A LagrangesMethod is converted first
        (`lagcomp.from_lagranges_method`), with `system_kwargs` (name,
        parameters, defaults, q0, qd0, ...) passed on.  A KanesMethod is
        compiled as Kane's equations over the state (q, u) into a
        `lagcomp.kane_model.KaneModel` (options name, parameters, defaults,
        q0, u0, t_end, description, events).
    cache_dir : path, optional
        Cache root; defaults to $LAGCOMP_CACHE_DIR, else the user cache directory.
    eom : lagcomp.mechanics.lagrange.EOM, optional
        The equations of `system` if the caller has derived them already
        (used on a cache miss instead of deriving them again).
    progress : bool, optional
        On a cache miss, show which stage is running (deriving, CSE, the
        Taylor program, emitting): None (default) once the build has lasted
        two seconds, True always, False never.

    Returns
    -------
    Model
        ``model.from_cache`` tells whether the derivation was skipped.
    """
    from sympy.physics.mechanics import KanesMethod

    if isinstance(system, KanesMethod):
        from lagcomp.kane_model import compile_kane

        return compile_kane(system, cache_dir, **system_kwargs)
    from lagcomp.multibody.tree import Tree

    if isinstance(system, Tree):
        if system_kwargs or eom is not None:
            raise ModelError(f"compile() of a lagcomp.Tree takes no options ({sorted(system_kwargs)}"
                             f"{' and eom' if eom is not None else ''}): set them on the Tree itself.")
        from lagcomp.tree_model import compile_tree

        return compile_tree(system, cache_dir, progress)
    system = _as_system(system, system_kwargs)
    cache = Cache(cache_dir)
    key = input_key(system.fingerprint(), options={})
    model = _compiled(system, cache, key, eom, progress)
    cache.remember(system.name, key, run_defaults(system))
    return model


def _compiled(system, cache: Cache, key: str, eom, progress=None) -> "Model":
    """The Model of `system` from the cache entry under `key`, built first on a miss."""
    entry = cache.lookup(key)
    damaged = False
    if entry is not None:
        try:
            return Model(system, load_module(entry), entry, from_cache=True)
        except Exception as err:  # a damaged module that still hashed right, or a stale numba cache
            warnings.warn(f"lagcomp could not load {entry.path.name} ({err}); rebuilding it.", CacheWarning, stacklevel=3)
            cache.discard(entry)
            damaged = True
    with cache.lock(key):  # processes compiling the same system derive it once, one after the other
        entry = None if damaged else cache.lookup(key)  # stored by another process while this one waited?
        if entry is not None:
            return Model(system, load_module(entry), entry, from_cache=True)
        entry, eom = build(system, cache, key, eom, progress)
    return Model(system, load_module(entry), entry, from_cache=False, eom=eom)


def load(name: str, *, cache_dir: str | os.PathLike | None = None) -> "Model":
    """The model last compiled under `name`, from the cache, without sympy.

    `compile` records, per System name, which cache entry it used and the
    System's run defaults (parameter values, q0, qd0, t_end, events).  `load`
    reads that record, so a later process can simulate a compiled system with
    no sympy import, no derivation and no numba compilation.  The returned
    Model has ``system=None``: what needs the symbolic System (the
    `lagcomp.analysis` functions) needs `compile` instead.

    Raises ModelError when nothing named `name` was compiled into this cache
    (or its entry no longer matches this lagcomp, numba or Python version).
    """
    if not isinstance(name, str) or not name:
        raise ModelError(f"`lagcomp.load` takes the name a System was compiled under (a string), got {name!r}.")
    cache = Cache(cache_dir)
    found = cache.recall(name)
    if found is None:
        raise ModelError(f"No compiled model named {name!r} in the cache at {cache.root}: compile it first "
                         "(lagcomp.compile(system)), with the same cache directory and lagcomp version.")
    entry, defaults = found
    try:
        kernels = load_module(entry)
    except Exception as err:  # a damaged module that still hashed right
        warnings.warn(f"lagcomp could not load {entry.path.name} ({err}); discarding it.", CacheWarning, stacklevel=2)
        cache.discard(entry)
        raise ModelError(f"The compiled model {name!r} in {cache.root} is damaged and was discarded: "
                         "compile it again (lagcomp.compile(system)).") from err
    if entry.metadata.get("kane"):
        from lagcomp.kane_model import KaneModel

        return KaneModel(None, kernels, entry, from_cache=True, recorded=defaults)
    if entry.metadata.get("tree"):
        from lagcomp.tree_model import TreeModel

        return TreeModel(None, kernels, entry, from_cache=True, recorded=defaults)
    return Model(None, kernels, entry, from_cache=True, recorded=defaults)


class EventSpec(NamedTuple):
    """What a run needs of a declared event (its expression lives in the ``event_values`` kernel, its reset in
    ``event_reset``)."""

    name: str
    direction: int
    terminal: bool
    resets: bool = False


def run_defaults(system) -> dict:
    """The parts of `system` a run uses that are not in its cache key, as JSON-ready data."""
    def floats(values):
        return None if values is None else [float(v) for v in values]

    return {
        "name": system.name,
        "description": system.description,
        "defaults": {k: float(v) for k, v in system.defaults.items()},
        "q0": floats(system.q0),
        "qd0": floats(system.qd0),
        "t_end": float(system.t_end),
        "events": [[e.name, int(e.direction), bool(e.terminal), e.changes_state] for e in system.events],
    }


def _as_system(system, system_kwargs: dict):
    """`system` itself, or the System of a sympy LagrangesMethod / KanesMethod."""
    from sympy.physics import mechanics as me

    from lagcomp.model.interop import from_kanes_method, from_lagranges_method
    from lagcomp.model.system import System

    if isinstance(system, me.LagrangesMethod):
        return from_lagranges_method(system, **system_kwargs)
    if isinstance(system, me.KanesMethod):
        return from_kanes_method(system, **system_kwargs)
    if system_kwargs:
        raise ModelError(f"compile() takes System options {sorted(system_kwargs)} only with a sympy method object; "
                         "set them on the System itself.")
    if not isinstance(system, System):
        raise ModelError(f"compile() needs a lagcomp System or a sympy LagrangesMethod/KanesMethod, "
                         f"got {type(system).__name__}.")
    return system


#: The stages of a build, as its progress bar names them (see `lagcomp.stages`).
BUILD_STAGES = ("deriving the equations of motion (sympy)", "lowering and CSE of the kernels a run calls",
                "emitting and storing the module")


def build(system, cache: Cache, key: str, eom=None, progress=None) -> tuple[Entry, object]:
    """Derive (unless `eom` is given), lower and emit the eager module of `system` (`lagcomp.codegen.kinds`),
    store it under `key` with the equations its companion module is lowered from later
    (`lagcomp.companion`); returns the entry and the equations."""
    from lagcomp.codegen.emit import emit_eager
    from lagcomp.codegen.lower import lower
    from lagcomp.companion import keep_equations
    from lagcomp.mechanics.lagrange import derive
    from lagcomp.stages import Stages

    derive_, lower_, emit_ = BUILD_STAGES
    with Stages(f"compiling {system.name}", BUILD_STAGES, progress) as stages:
        stages.start(derive_)
        eom = derive(system) if eom is None else eom
        stages.start(lower_)
        ir = lower(eom, "eager")
        stages.start(emit_)
        source = emit_eager(ir)
    metadata = {
        "coordinates": list(system.coordinate_names),
        "parameters": list(system.parameter_names),
        "cyclic": list(eom.cyclic),
        "constraints": list(eom.constraint_names),
        "holonomic": list(eom.holonomic),
        "separable": eom.separable,
        "holonomic_separable": eom.holonomic_separable,
        "operations": {k.name: k.operation_count for k in ir.kernels},
        "on_demand": True,
        **({"inputs": list(ir.input_names), "input_orders": list(ir.input_orders)} if ir.input_names else {}),
    }
    keep_equations(cache, key, eom)
    return cache.store(key, source, system.name, metadata), eom


#: The kernels' namespace of each eager module loaded in this process, by module name and cache root: the Models
#: of one cache entry share it (and the drivers bound to it, and its companion modules).
_NAMESPACES: dict = {}


@functools.cache
def _run_entry() -> tuple:
    """(`lagcomp.integrate.options.known_options`, `lagcomp.integrate.simulate.simulate`), imported at the first run
    (not with lagcomp: they import the drivers) and kept: an import statement costs ~1 µs at each `Model.simulate`."""
    from lagcomp.integrate.options import known_options
    from lagcomp.integrate.simulate import simulate

    return known_options, simulate


def _namespace(module, entry: Entry, name: str, system, eom):
    """``Model.kernels``: `module` itself for an entry without a companion module, else the `ModelKernels`
    of the eager `module` and its companion (`lagcomp.companion`), one per module and process."""
    if not entry.metadata.get("on_demand"):
        return module
    key = (entry.module_name, entry.path.parent.parent)   # (one module may serve two roots: each its companions)
    kernels = _NAMESPACES.get(key)
    if kernels is None or kernels.eager_module is not module:
        kernels = _NAMESPACES[key] = ModelKernels(module, Companion(entry, name, system, eom))
    companion = kernels.companion
    if companion.system is None and system is not None:   # (a later compile can build it: loaded models cannot)
        companion.system = system
    if companion.eom is None and eom is not None:
        companion.eom = eom
    return kernels


def _baumgarte_gains(baumgarte) -> tuple[float, float]:
    from lagcomp.errors import OptionError

    try:
        alpha, beta = (float(v) for v in baumgarte)
    except (TypeError, ValueError) as err:
        raise OptionError(f"`baumgarte` must be a pair (alpha, beta) of numbers, got {baumgarte!r}.") from err
    if not (alpha >= 0 and beta >= 0 and math.isfinite(alpha) and math.isfinite(beta)):
        raise OptionError(f"`baumgarte` gains must be finite and non-negative, got ({alpha}, {beta}).")
    return alpha, beta


def _snapshot(values: dict) -> tuple:
    """The keys and values of `values` (a model's defaults), to tell later whether it changed (`_unchanged`)."""
    return tuple(values), tuple(values.values())


def _unchanged(values: dict, snapshot: tuple) -> bool:
    """Whether `values` holds the very objects of `snapshot`: same keys and values, in the same order (the
    snapshot's values are floats, immutable, so identity tells that nothing was assigned since)."""
    keys, kept = snapshot
    return (len(values) == len(keys) and all(map(operator.is_, values, keys))
            and all(map(operator.is_, values.values(), kept)))


def _float_tuple(values) -> bool:
    """Whether `values` is None or a tuple of floats: immutable, so kept results derived from it stay valid."""
    return values is None or (type(values) is tuple and all(type(v) is float for v in values))


class Model:
    """A compiled system: its kernels, parameter order and defaults.

    Attributes
    ----------
    system : System or None
        The description it was compiled from; None for a model from `load`.
    name, description : str
    defaults : dict
        Parameter values used where `params` leaves one out.
    q0, qd0 : tuple of float or None
        Default initial coordinates and velocities.
    t_end : float
        The System's suggested run length.
    events : tuple of EventSpec
        The declared events (name, direction, terminal, resets), in kernel order.
    kernels : lagcomp.companion.ModelKernels
        The generated kernels (``rhs``, ``mass_matrix``, ``forcing``, ``energy``,
        ``energy_function``, ``momenta``, ...), numba functions following the
        conventions of `lagcomp.ir`: those a plain run calls from the eager
        module, the others (`lagcomp.codegen.kinds`) from the companion module
        of their kind, built the first time one of them is read (`lagcomp.companion`).
    source_path : pathlib.Path
        The eager module's file (`on_demand_entry` has the companions').
    cache_key : str
        The cache's input key of the compiled description.
    from_cache : bool
        True when the module came from the cache without derivation.
    coordinates, parameters : tuple of str
        Coordinate names (order of q) and parameter names (order of p).
    cyclic : tuple of str
        Cyclic coordinates (their conjugate momenta are conserved).
    constraints : tuple of str
        Constraint names, the order of the multipliers λ (reactions).
    separable : bool
        Whether the explicit symplectic methods (verlet, yoshida4, yoshida6) apply.
    holonomic_separable : bool
        Whether RATTLE (method "rattle") applies: separable apart from constraints that are
        all holonomic and scleronomic, Φ(q) = 0 (`lagcomp.mechanics.lagrange.EOM`).
    operations : dict
        Arithmetic operations per kernel after CSE (reading it builds the on-demand kernels).
    inputs : tuple of str
        The inputs supplied at run time (`lagcomp.Input` without a law), by name: ``simulate`` and
        ``sweep`` take a signal for each in ``inputs={name: ...}`` (`lagcomp.integrate.inputs`).
    input_orders : tuple of int
        The highest derivative of each input the kernels read (2 for a support motion in T).
    """

    def __init__(self, system, kernels, entry: Entry, from_cache: bool, recorded: dict | None = None, eom=None):
        self.system = system
        recorded = run_defaults(system) if system is not None else recorded
        self.name = recorded["name"]
        self.description = recorded["description"]
        self.defaults = dict(recorded["defaults"])
        self.q0 = None if recorded["q0"] is None else tuple(recorded["q0"])
        self.qd0 = None if recorded["qd0"] is None else tuple(recorded["qd0"])
        self.t_end = recorded["t_end"]
        self.events = tuple(EventSpec(*spec) for spec in recorded["events"])
        self.kernels = _namespace(kernels, entry, recorded["name"], system, eom)
        self.source_path = entry.path
        self.cache_key = entry.key
        self.from_cache = from_cache
        self.coordinates = tuple(entry.metadata["coordinates"])
        self.parameters = tuple(entry.metadata["parameters"])
        self.cyclic = tuple(entry.metadata["cyclic"])
        self.constraints = tuple(entry.metadata["constraints"])
        self.holonomic = tuple(entry.metadata["holonomic"])
        self.separable = bool(entry.metadata["separable"])
        self.holonomic_separable = bool(entry.metadata["holonomic_separable"])
        self._operations = dict(entry.metadata["operations"])
        self._taylor_program_kept = entry.metadata.get("taylor_program")  # (an entry without a companion)
        self.inputs = tuple(entry.metadata.get("inputs", ()))
        self.input_orders = tuple(entry.metadata.get("input_orders", ()))
        self._default_parameters: tuple | None = None  # (defaults' snapshot, p): `parameter_vector`
        self._default_state: tuple | None = None  # (q0, qd0, y): `initial_state`

    @property
    def operations(self) -> dict:
        """Arithmetic operations per kernel after CSE, the on-demand kernels' (`lagcomp.codegen.kinds`) included:
        reading it builds them if they are not yet."""
        operations = dict(self._operations)
        for entry in self.on_demand_entries.values():
            operations.update(entry.metadata["operations"])
        return operations

    @property
    def on_demand_entries(self) -> dict[str, Entry]:
        """The cache entries of the companion modules (the on-demand kernels, `lagcomp.companion`), by kind, every
        one built first if needed; none for a model whose one module holds every kernel (a Kane model)."""
        return self.kernels.companion.entries() if isinstance(self.kernels, ModelKernels) else {}

    def on_demand_entry(self, kind: str) -> Entry | None:
        """The cache entry of the companion module of the on-demand `kind` (`lagcomp.codegen.kinds`), built first
        if needed; None for a model whose one module holds every kernel (a Kane model)."""
        return self.kernels.companion.entry(kind) if isinstance(self.kernels, ModelKernels) else None

    @property
    def _taylor_program(self) -> dict | None:
        """The Taylor program (`lagcomp.codegen.taylor.taylor_program`), from the entry of the companion module of
        the kind "taylor": for batched Taylor sweeps and Taylor sensitivities."""
        taylor = self.on_demand_entry("taylor")
        return self._taylor_program_kept if taylor is None else taylor.metadata["taylor_program"]

    @property
    def event_names(self) -> tuple[str, ...]:
        return tuple(e.name for e in self.events)

    @property
    def contacts(self) -> tuple[str, ...]:
        """The names of the contacts (`lagcomp.Contact`), in order: the columns of an impact's ``impulses``."""
        return tuple(name for name, _, _ in contacts_of(self))

    @property
    def frictions(self) -> tuple[str, ...]:
        """The names of the friction elements (`lagcomp.Friction`), in order: the columns of
        `Solution.friction_forces`."""
        return tuple(name for name, *_ in frictions_of(self))

    @property
    def n(self) -> int:
        return len(self.coordinates)

    @property
    def state_size(self) -> int:
        """Length of the state y the kernels and drivers take: 2n for (q, q̇)."""
        return 2 * self.n

    @property
    def state_names(self) -> tuple[str, ...]:
        """Labels of the state y the drivers advance: the coordinates, then ``<coordinate>_dot``."""
        return self.coordinates + tuple(f"{c}_dot" for c in self.coordinates)

    @property
    def k(self) -> int:
        """Number of constraints."""
        return len(self.constraints)

    def __reduce__(self):
        """Pickle as the cache entry, run defaults and System (`lagcomp.pickling`): the module itself cannot."""
        from lagcomp.pickling import model_state, restore_model

        return restore_model, (model_state(self),)

    def __repr__(self) -> str:
        origin = "cache" if self.from_cache else "fresh build"
        return f"Model({self.name!r}, n={self.n}, parameters={self.parameters}, from {origin}: {self.source_path})"

    def _repr_html_(self) -> str:
        """A compact HTML summary for Jupyter (`lagcomp.notebook.model_html`)."""
        from lagcomp.notebook import model_html

        return model_html(self)

    def equations(self):
        """The equations of motion, constraints and energy as LaTeX and text (`lagcomp.equations.Equations`).

        ``.latex`` is an ``align*`` environment, ``str()`` plain text, and Jupyter renders the
        result as math.  sympy rendered them when the model was compiled, into its module, so a
        model from `load` has them too, without sympy.
        """
        from lagcomp.equations import Equations

        return Equations(self.name, self.kernels.EQUATIONS)

    # -- inputs -------------------------------------------------------------------

    def parameter_vector(self, params: dict | None = None, baumgarte=(0.0, 0.0), inputs=None,
                         span=None) -> np.ndarray:
        """Parameter values by name (defaults filled in) as the kernel vector p.

        For constrained systems p continues with the Baumgarte gains (α, β), which
        add −2α (Λ q̇ + b) − β² Φ to the acceleration-level constraints; a model with contacts with
        their modes (0: open) and the flag that lets an impact close one (0; `lagcomp.integrate.contacts`
        sets both for a run).  A model with
        inputs needs a signal for each in `inputs` (`lagcomp.integrate.inputs`): their
        tables end p, and must cover the time `span` (t0, t1) when it is given.
        """
        p = self._parameter_values(params, baumgarte)
        modes = mode_slot_count(self.kernels)
        if modes:  # the contacts' modes, all open, and closing not allowed (`lagcomp.ir.ContactModes`)
            p = np.concatenate([p, np.zeros(modes)])
        if not self.inputs:
            if inputs:
                from lagcomp.errors import OptionError

                raise OptionError(f"`inputs` given, but {self.name!r} has no inputs (lagcomp.Input without a law).")
            return p
        from lagcomp.errors import OptionError
        from lagcomp.integrate.inputs import pack_inputs

        if inputs is None and span is None:  # a one-state evaluation (Model.rhs, lagcomp.analysis), which takes none
            raise OptionError(f"{self.name!r} reads the input(s) {list(self.inputs)}: evaluating it at one state "
                              f"needs their values there, `inputs={{{self.inputs[0]!r}: value, ...}}` (a number, or a "
                              "signal as `simulate` takes).")
        return np.concatenate([p, pack_inputs(self.inputs, self.input_orders, inputs, span, p.size)])

    def _parameter_values(self, params, baumgarte) -> np.ndarray:
        """p without the inputs' tables: the user parameters, then a constrained system's Baumgarte gains.

        With `params` None the values are the defaults', checked once and kept (`_default_parameters`)
        until `defaults` changes: a run of a short simulation saves the ~3 µs of checking them again.
        """
        if params is None:
            kept = self._default_parameters
            if kept is not None and _unchanged(self.defaults, kept[0]):
                p = np.empty(kept[1].size + (2 if self.k else 0))
                if self.k:
                    p[-2:] = _baumgarte_gains(baumgarte)
                p[:kept[1].size] = kept[1]
                return p
        values = dict(self.defaults)
        if params is not None and not isinstance(params, Mapping):
            raise ParameterError(f"`params` must be a mapping of parameter name to value, like "
                                 f"{dict.fromkeys(self.parameters[:2], 1.0)}, got {type(params).__name__}.")
        values.update(by_name(params or {}, "params", self.parameters))
        unknown = sorted(set(values) - set(self.parameters))
        if unknown:
            raise ParameterError(f"Unknown parameter(s) {unknown} for {self.name!r}; its parameters are {list(self.parameters)}.")
        missing = [k for k in self.parameters if k not in values]
        if missing:
            raise ParameterError(f"Missing value(s) for parameter(s) {missing} of {self.name!r}; pass them in `params`.")
        p = np.empty(len(self.parameters) + (2 if self.k else 0))
        if self.k:
            p[-2:] = _baumgarte_gains(baumgarte)
        for k, name in enumerate(self.parameters):
            try:
                p[k] = float(values[name])
            except (TypeError, ValueError) as err:
                raise ParameterError(f"Parameter `{name}` must be a number, got {values[name]!r}.") from err
            if not math.isfinite(p[k]):
                raise ParameterError(f"Parameter `{name}` is {p[k]}; it must be finite.")
        if params is None and all(type(value) is float for value in self.defaults.values()):
            self._default_parameters = (_snapshot(self.defaults), p[:len(self.parameters)].copy())
        return p

    def initial_state(self, q0=None, qd0=None) -> np.ndarray:
        """The state y = (q0, qd0), defaults from the System, checked for length and finiteness.

        The default state (q0 and qd0 None) is checked once and kept (`_default_state`) while `q0` and
        `qd0` are the same tuples of floats; each call returns a fresh copy.
        """
        from_defaults = q0 is None and qd0 is None
        if from_defaults and self._default_state is not None:
            kept_q0, kept_qd0, y = self._default_state
            if kept_q0 is self.q0 and kept_qd0 is self.qd0:
                return y.copy()
        parts = []
        for what, given, default in (("q0", q0, self.q0), ("qd0", qd0, self.qd0)):
            values = given if given is not None else default
            if values is None:
                values = [0.0] * self.n if what == "qd0" else None
            if values is None:
                raise InitialConditionError(f"`q0` is required: {self.name!r} has no default initial coordinates.")
            try:
                values = np.asarray(values, dtype=float)
            except (TypeError, ValueError) as err:
                raise InitialConditionError(f"`{what}` must be {self.n} number(s), one per coordinate "
                                            f"{list(self.coordinates)}, got {values!r}.") from err
            if values.ndim == 0:
                values = values.reshape(1)
            if values.shape != (self.n,):
                shape = f"shape {values.shape}" if values.ndim > 1 else f"{values.size} value(s)"
                raise InitialConditionError(
                    f"`{what}` has {shape}; {self.name!r} has {self.n} coordinates {list(self.coordinates)}."
                )
            if not np.isfinite(values).all():
                raise InitialConditionError(f"`{what}` = {values.tolist()} is not finite.")
            parts.append(values)
        y = np.concatenate(parts)
        if from_defaults and all(_float_tuple(v) for v in (self.q0, self.qd0)):  # immutable: identity tells a change
            self._default_state = (self.q0, self.qd0, y.copy())
        return y

    # -- kernels from Python --------------------------------------------------------

    def rhs(self, t: float, y, params: dict | None = None, inputs: dict | None = None) -> np.ndarray:
        """dy/dt at one state y = (q, q̇); raises SingularMassMatrixError where M is singular.

        A model with inputs (`lagcomp.Input`) takes their signals in `inputs` as `simulate` does (a number: a
        constant; a table is evaluated at `t`)."""
        y = self._vector(y, 2 * self.n, "y")
        out = np.empty(2 * self.n)
        status = self.kernels.rhs(float(t), y, self.parameter_vector(params, inputs=inputs), out)
        if status:
            raise self._singular_mass_matrix(t, y, status)
        return out

    def jacobian(self, t: float, y, params: dict | None = None, inputs: dict | None = None) -> np.ndarray:
        """∂f/∂y of y' = f(t, y) at one state, shape (N, N) with N = `state_size` (row i the component f_i):
        the exact Jacobian the model's ``rhs_jacobian`` kernel computes (the one ``method="radau"`` uses;
        scipy's ``solve_ivp(..., jac=...)`` takes it as it is).

        Raises SingularMassMatrixError where M is singular (the augmented matrix, for a constrained model),
        ModelError where the model has no Jacobian kernel (its ``RHS_JACOBIAN_REFUSED`` says why).
        """
        y = self._vector(y, self.state_size, "y")
        out = np.empty((self.state_size, self.state_size))
        status = self.kernels.rhs_jacobian(float(t), y, self.parameter_vector(params, inputs=inputs), out)
        refused = getattr(self.kernels, "RHS_JACOBIAN_REFUSED", None)   # the stub's reason (no sympy import here)
        if status and refused is not None:
            raise ModelError(f"{self.name!r} has no Jacobian kernel: its equations hold {refused}.")
        if status:
            raise self._singular_mass_matrix(t, y, status)
        return out

    def rhs_parameter_jacobian(self, t: float, y, params: dict | None = None) -> np.ndarray:
        """∂f/∂p of y' = f(t, y, p) at one state, shape (N, P) with N = `state_size` and P = len(`parameters`),
        column j the parameter ``parameters[j]``: the exact derivative the model's ``rhs_parameter_jacobian``
        kernel computes (the parameter counterpart of `jacobian`, the columns of the forward sensitivities).

        Raises SingularMassMatrixError where M is singular (the augmented matrix, for a constrained model),
        ModelError where the model has no such kernel (its ``RHS_PARAMETER_JACOBIAN_REFUSED`` says why).
        """
        y = self._vector(y, self.state_size, "y")
        out = np.empty((self.state_size, len(self.parameters)))
        status = self.kernels.rhs_parameter_jacobian(float(t), y, self.parameter_vector(params), out)
        refused = getattr(self.kernels, "RHS_PARAMETER_JACOBIAN_REFUSED", None)
        if status and refused is not None:
            raise ModelError(f"{self.name!r} has no parameter Jacobian kernel: its equations hold {refused}.")
        if status:
            raise self._singular_mass_matrix(t, y, status)
        return out

    def rhs_input_jacobian(self, t: float, y, params: dict | None = None, inputs: dict | None = None) -> np.ndarray:
        """∂f/∂u of y' = f(t, y, p, u) at one state, shape (N, U), column j the input ``inputs[j]`` of the model
        (`inputs` names its signals, as for `rhs`): the exact derivative the on-demand ``rhs_input_jacobian``
        kernel computes, the input matrix B of a state-space model (`lagcomp.analysis.linearize`).

        Raises ModelError for a model without inputs, a constrained one (`lagcomp.analysis.linearize_steady`
        gives its B) or one with contacts, and where the equations read an input's derivatives (its
        ``RHS_INPUT_JACOBIAN_REFUSED`` says which); SingularMassMatrixError where M is singular.
        """
        if not self.inputs:
            raise ModelError(f"{self.name!r} has no inputs (lagcomp.Input without a law): no input matrix.")
        if self.k or self.contacts or self.frictions or getattr(self, "speeds", None) is not None:
            raise ModelError(f"rhs_input_jacobian is built for unconstrained Lagrange models without contacts; "
                             f"{self.name!r} is not one: lagcomp.analysis.linearize_steady(..., inputs=...) gives "
                             "the input matrix B of a constrained system.")
        y = self._vector(y, self.state_size, "y")
        out = np.empty((self.state_size, len(self.inputs)))
        status = self.kernels.rhs_input_jacobian(float(t), y, self.parameter_vector(params, inputs=inputs), out)
        refused = getattr(self.kernels, "RHS_INPUT_JACOBIAN_REFUSED", None)
        if status and refused is not None:
            raise ModelError(f"{self.name!r} has no input matrix: its equations hold {refused}.")
        if status:
            raise self._singular_mass_matrix(t, y, status)
        return out

    def _singular_mass_matrix(self, t: float, state, status: int) -> SingularMassMatrixError:
        """The error for a kernel that found M singular (pivot `status`) at `state` = (q, ...)."""
        where = ", ".join(f"{c}={v:.6g}" for c, v in zip(self.coordinates, state[: self.n]))
        return SingularMassMatrixError(
            f"The mass matrix of {self.name!r} is singular at t={t:g}, {where} (pivot {status}): "
            "the kinetic energy is not positive definite in the velocities there."
        )

    def reactions(self, t: float, y, params: dict | None = None) -> dict[str, float]:
        """The multipliers λ at one state, by constraint name (generalized reaction forces)."""
        y = self._vector(y, 2 * self.n, "y")
        out = np.empty(self.k)
        status = self.kernels.reactions(float(t), y, self.parameter_vector(params), out)
        if status:
            raise SingularMassMatrixError(
                f"The augmented matrix [M Λᵀ; Λ 0] of {self.name!r} is singular at t={t:g} (pivot {status})."
            )
        return dict(zip(self.constraints, out.tolist()))

    @functools.cached_property
    def residual_labels(self) -> tuple[tuple[str, str], ...]:
        """(constraint, level) of each entry of the ``constraint_residuals`` kernel's output.

        Level "position" for Φ of the holonomic constraints, then "velocity"
        for Λ q̇ + b of all constraints.  Made once (every run reads it).
        """
        holonomic = tuple((c, "position") for c, h in zip(self.constraints, self.holonomic) if h)
        return holonomic + tuple((c, "velocity") for c in self.constraints)

    def constraint_residuals(self, t: float, y, params: dict | None = None) -> dict[str, float]:
        """Residuals at one state by name: ``"<name>"`` for Φ (holonomic) and ``"<name>_dot"`` for Λ q̇ + b."""
        y = self._vector(y, 2 * self.n, "y")
        out = np.empty(len(self.residual_labels))
        self.kernels.constraint_residuals(float(t), y, self.parameter_vector(params), out)
        names = [c if level == "position" else f"{c}_dot" for c, level in self.residual_labels]
        return dict(zip(names, out.tolist()))

    def _vector(self, values, size: int, what: str) -> np.ndarray:
        """`values` as a contiguous float vector of shape (size,): the kernels do not check bounds."""
        try:
            values = np.ascontiguousarray(values, dtype=float).ravel()
        except (TypeError, ValueError) as err:
            raise InitialConditionError(f"`{what}` must be {size} numbers for {self.name!r}, got {values!r}.") from err
        if values.shape != (size,):
            raise InitialConditionError(
                f"`{what}` must have shape ({size},) for {self.name!r} (coordinates {list(self.coordinates)}), "
                f"got shape {values.shape}."
            )
        return values

    def _state(self, q, qd):
        qd = np.zeros(self.n) if qd is None else qd
        return np.concatenate([self._vector(q, self.n, "q"), self._vector(qd, self.n, "qd")])

    def mass_matrix(self, q, t: float = 0.0, params: dict | None = None) -> np.ndarray:
        """M(q, t), shape (n, n)."""
        out = np.empty((self.n, self.n))
        self.kernels.mass_matrix(float(t), self._state(q, None), self.parameter_vector(params), out)
        return out

    def forcing(self, q, qd, t: float = 0.0, params: dict | None = None) -> np.ndarray:
        """F(q, q̇, t) of M q̈ = F, shape (n,)."""
        out = np.empty(self.n)
        self.kernels.forcing(float(t), self._state(q, qd), self.parameter_vector(params), out)
        return out

    def momenta(self, q, qd, t: float = 0.0, params: dict | None = None) -> np.ndarray:
        """Conjugate momenta ∂L/∂q̇, shape (n,)."""
        out = np.empty(self.n)
        self.kernels.momenta(float(t), self._state(q, qd), self.parameter_vector(params), out)
        return out

    def energy(self, q, qd, t: float = 0.0, params: dict | None = None) -> float:
        """Total mechanical energy T + V."""
        return float(self.kernels.energy(float(t), self._state(q, qd), self.parameter_vector(params)))

    def energy_function(self, q, qd, t: float = 0.0, params: dict | None = None) -> float:
        """Energy function (Jacobi integral) h."""
        return float(self.kernels.energy_function(float(t), self._state(q, qd), self.parameter_vector(params)))

    # -- Hamiltonian form (unconstrained systems) --------------------------------------

    def canonical_state(self, q, qd, t: float = 0.0, params: dict | None = None) -> np.ndarray:
        """x = (q, p), shape (2n,): coordinates and conjugate momenta p = ∂L/∂q̇ at (q, q̇, t)."""
        return np.concatenate([np.asarray(q, dtype=float).ravel(), self.momenta(q, qd, t, params)])

    def _canonical_input(self, x, kernel: str) -> np.ndarray:
        """`x` as a contiguous float vector of shape (2n,), for a kernel of unconstrained systems only."""
        if self.k:
            raise ModelError(
                f"`{kernel}` needs an unconstrained system: {self.name!r} has constraints {list(self.constraints)}, "
                "so its momenta do not determine its velocities."
            )
        x = np.ascontiguousarray(x, dtype=float)
        if x.shape != (2 * self.n,):
            raise InitialConditionError(
                f"`x` must be (q, p) with shape ({2 * self.n},) for {self.name!r}, got shape {x.shape}."
            )
        return x

    def hamiltonian(self, t: float, x, params: dict | None = None) -> float:
        """H(q, p, t) at the canonical state x = (q, p) (see `canonical_state`).

        The Legendre transform of L: the energy function at q̇ solved from
        p = M(q, t) q̇ + b(q, t).  Raises SingularMassMatrixError where M is singular.
        """
        from lagcomp.integrate.drivers import canonical

        x = self._canonical_input(x, "hamiltonian")
        p = self.parameter_vector(params)
        k = self.kernels
        status = k.velocities(float(t), x, p, np.empty(self.n))
        if status:
            raise self._singular_mass_matrix(t, x, status)
        return float(canonical.hamiltonian(k.velocities, k.energy_function, float(t), x, p))

    def canonical_jacobian(self, t: float, x, params: dict | None = None) -> np.ndarray:
        """∂f/∂x, shape (2n, 2n), of the canonical equations ẋ = f(t, x) = (q̇, ṗ) at x = (q, p).

        ṗ includes the non-conservative forces (∂L/∂q + Q − ∂D/∂q̇, at fixed q̇);
        rows are (q̇, ṗ), columns (q, p).  Raises SingularMassMatrixError where M is singular.
        """
        from lagcomp.integrate.drivers import canonical

        x = self._canonical_input(x, "canonical_jacobian")
        out = np.empty((2 * self.n, 2 * self.n))
        k = self.kernels
        status = canonical.canonical_jacobian(k.velocities, k.canonical_partials, float(t), x,
                                              self.parameter_vector(params), out)
        if status:
            raise self._singular_mass_matrix(t, x, status)
        return out

    # -- runs -----------------------------------------------------------------------

    def simulate(self, t_span, q0=None, qd0=None, params: dict | None = None, **options):
        """Integrate from `t_span[0]` to `t_span[1]` and return a `Solution`.

        Parameters
        ----------
        t_span : (float, float)
            Start and end time, t0 < t1.
        q0, qd0 : array_like, shape (n,), optional
            Initial coordinates and velocities; default to the System's.
        params : dict, optional
            Parameter values by name; missing ones come from the System's defaults.
        inputs : dict, optional
            A signal for each input of the model (`Model.inputs`), by name:
            ``lagcomp.Tabulated(times, values, kind="cubic" | "linear")``, a pair
            ``(times, values)`` (cubic), a scipy CubicSpline / PPoly of degree ≤ 3,
            a number (constant), or a numba function ``u(t, y, p) -> float`` of
            the time, the state (q, q̇) and p (`lagcomp.integrate.function_inputs`;
            values only, not with radau).  Tables must cover `t_span`; changing
            them, or the function, never recompiles the model (`lagcomp.integrate.inputs`).

        Other Parameters
        ----------------
        method : str
            Integration method (default "dop853"), a name of
            `lagcomp.integrate.methods.METHODS`: the adaptive embedded pairs dop853,
            dopri5, tsit5 and bs3, taylor, rk4, verlet, yoshida4/6, rattle, gauss1/2/3; verlet and yoshida4/6
            are explicit symplectic methods for separable systems (`Model.separable`),
            rattle their constrained counterpart of order 2 for separable systems with holonomic,
            time-independent constraints (`Model.holonomic_separable`; the constraints hold to round-off
            without projection),
            gauss1/2/3 implicit symplectic ones for any unconstrained system,
            taylor an adaptive Taylor-series method (unconstrained systems of
            smooth functions; machine precision by default).
        dt : float
            Step of fixed-step methods (required for all but the adaptive ones).
        implicit_solver : {"fixed_point", "newton"}, optional
            How gauss1/2/3 solve their stage equations: fixed-point iteration
            (the default: cheapest per step on ordinary problems), or
            simplified Newton with the Jacobian of the canonical equations,
            which converges at steps where fixed-point iteration does not
            (stiff or fast motions; status -5 says the step was too large).
        rtol, atol : float, or for atol array_like or dict
            Tolerances of adaptive methods (defaults 1e-8, 1e-10; for taylor machine
            epsilon, and atol = rtol unless given).  `atol` is one number, or one per
            state component in its units (2n, ordered as `state_names`: q, then q̇), or
            ``{coordinate: (atol of q, atol of q̇)}``: positions and velocities do not
            share a unit (`lagcomp.integrate.tolerances`).
        t_eval : array_like, optional
            Times at which to save, by dense output (adaptive methods only).
        save_every : int
            Save every k-th step (and the last); bounds memory on long runs.
        first_step, max_step : float
            Initial and largest step of adaptive methods.
        max_steps : int
            Accepted steps allowed before the run stops with a failed status.
        projection : bool, optional
            Constrained systems: project the state onto the constraints after
            every step (positions by Gauss-Newton on Φ = 0, then velocities on
            Λ q̇ + b = 0). Default: on for fixed-step methods, off for adaptive
            ones, whose error control keeps the drift at the tolerance.
        baumgarte : (float, float)
            Constrained systems: Baumgarte gains (α, β) ≥ 0, replacing Λ q̈ = γ
            by Λ q̈ = γ − 2α (Λ q̇ + b) − β² Φ; (0, 0) by default.
        project_initial : bool
            Constrained systems: project inconsistent q0/qd0 (a residual
            above 1e-9 of the size of its terms, in any units:
            `lagcomp.integrate.constraints.INITIAL_TOLERANCE`) onto the
            constraints (reported in `Solution.projected_initial_state`)
            instead of raising `InitialConditionError`.
        events : None, bool or list of str
            Which of the System's events to locate (adaptive methods only):
            None (default) all of them with dop853/dopri5 and none with the
            fixed-step methods; True all (an error for fixed-step methods);
            False none; or their names.  Occurrences are in `Solution.events`;
            a terminal one stops the run with status 1.
        record : {"trajectory", "summary"}
            Keep every saved row (default), or only the first and last rows
            and `Solution.summary` (largest energy errors, coordinate ranges,
            reduced over every saved row), so memory stays O(1) however long
            the run.  A kept trajectory evaluates `Solution.energy`,
            `energy_function`, `momenta` and `summary` when first read (numba
            compiles their kernel then, not before the run's first result);
            ``"summary"`` evaluates them during the run.  Same values either way.
        specialize : bool or None
            Run the method's driver specialised for this model: the library
            driver compiled once more with the model's kernels as compile-time
            callees, cached with the model (`lagcomp.integrate.specialize`),
            for long runs and repeated runs.  Bitwise the same steps and
            results as the library driver.  True: always (its first use
            compiles it, DOP853's in 12 s of CPU; `lagcomp precompile MODEL
            --specialize dop853` does it ahead); False: never; None (default):
            when it costs no compile, i.e. from the first call if it is loaded
            in this process, and for the rest of a run estimated to need a
            second more if numba's cache holds it.  rk4, the embedded pairs
            (dop853, dopri5, tsit5, bs3) and verlet/yoshida4/yoshida6 only.
        progress : bool, optional
            Show a progress bar: None (default) for runs lasting over two
            seconds, True always, False never.  Ctrl-C stops a run between
            driver calls (about every quarter second) and returns what was
            computed, with status 2 (also when it arrives in the call that
            ends the run, numba's first compilation included).
        throw : bool
            Raise `IntegrationError` (with the partial solution) on failure
            instead of returning a Solution whose `status` is negative.
        max_residual : float, optional
            Constrained systems (rk4, dop853, dopri5): stop with status -6
            once a step's constraint residual (|Φ| or |Λ q̇ + b|) exceeds
            this bound; that step is kept as the last row.  None: no bound.
        memory_limit : int
            Bytes the saved rows may take (default 2 GiB).  Where their number
            is known before the run (fixed-step methods, `t_eval`), a larger
            request is refused with `OptionError` before anything runs; an
            adaptive run without `t_eval` stops with status -7 once its rows
            reach the limit, keeping them.
        sensitivities : str or sequence of str, optional
            Integrate the first-order variational equations with the state
            (dop853, dopri5, tsit5, bs3): ∂y(t)/∂w for the columns w named by
            "q0" (every coordinate's initial value), "qd0" (every velocity's),
            "params" (every parameter), a state name (``theta1``,
            ``theta1_dot``), a parameter name, or ``"q0:theta1"``-style names
            as `Solution.sensitivity_names` gives them.  Results in
            `Solution.sensitivities`, shape (m, 2n, k).  The step-size control
            covers the state and the sensitivities (``sensitivity_control=
            "both"``, the default) or the state only (``"state"``: the plain
            run's steps, faster, but wrong where those steps do not resolve
            the sensitivities, as on a steady motion).  A model with
            constraints also gets dλ/dw in `Solution.reaction_sensitivities`
            (m, k, columns).  Refused for other methods, projection, located
            events that read inputs and function inputs; see
            `lagcomp.integrate.sensitivities`.
        """
        known_options, simulate = _run_entry()
        if options.pop("u0", None) is not None:  # (None: what `lagcomp run` passes when --u0 is not given)
            raise InitialConditionError(f"`u0` gives the initial speeds of a Kane model (state (q, u)); {self.name!r} "
                                        f"is a Lagrange model: give its initial velocities as `qd0` (--qd0 on the "
                                        f"command line), one per coordinate {list(self.coordinates)}.")
        known_options(simulate, options, "Model.simulate")
        return simulate(self, t_span, q0, qd0, params, **options)

    def fit(self, t=None, observations=None, params0: dict | None = None, **options):
        """Fit parameters to measured trajectories by least squares with the exact Jacobian; a `FitResult`.

        Parameters
        ----------
        t : array_like, shape (m,)
            Data times, increasing, at or after `t0` (the run's start, default 0).
        observations : array_like, shape (m, K)
            The measured components `observe` at the times `t`.
        params0 : dict
            The parameters to fit and their starting values; the others come from `fixed`, then from the
            System's defaults.

        Other Parameters
        ----------------
        observe : str or sequence of str
            The measured state components (``theta1``, ``theta1_dot``); default every coordinate.
        fixed : dict
            Values of parameters that are not fitted.
        bounds : dict
            ``{name: (low, high)}`` for some fitted parameters.
        q0, qd0 : array_like
            The experiment's initial state (default the System's).
        t0 : float
            The time of that initial state (default 0).
        sigma : float or array_like (K,)
            The noise's standard deviation (per observed component): residuals are divided by it and the
            covariance is (JᵀJ)⁻¹ of the weighted Jacobian.  Without it, the covariance is scaled by the
            reduced χ² (the noise level estimated from the residuals).
        experiments : list of (t, observations, q0, qd0)
            Several experiments fitted at once (their residuals stacked), instead of `t`, `observations`,
            `q0`, `qd0`.
        fit_initial : sequence of str
            State components whose initial values are fitted too (each experiment's own, starting from its
            `q0`, `qd0`), named ``q0:theta1``, ``qd0:theta1_dot`` in the result (``...[e]`` for experiment e
            of several).  `params0` may then be None.
        method, rtol, atol
            The runs' (an embedded pair; rtol 1e-10; atol by default rtol times the largest |component| of the
            initial states, `lagcomp.fitting.default_atol`, so the same accuracy in any units).
        max_nfev, and other keywords
            Passed to `scipy.optimize.least_squares`.

        Each residual and Jacobian evaluation is one run per experiment with the fitted parameters'
        sensitivities (`simulate(..., sensitivities=...)`); see `lagcomp.fitting`.  Refused (`OptionError`)
        for unknown names, data of the wrong shape or not finite, and runs that cannot carry
        sensitivities (a method without them); a run failing during the fit raises `IntegrationError`
        naming the trial parameters.
        """
        from lagcomp.fitting import fit

        return fit(self, t, observations, params0, **options)

    def sweep(self, t_span, grid, **options):
        """Integrate every point of a grid of initial values and parameters, on all cores; returns a `Sweep`.

        Parameters
        ----------
        t_span : (float, float)
            Start and end time, shared by all trajectories.
        grid : dict of str to array_like, or array_like of shape (N, k)
            Swept quantities by name: coordinate names (initial q), ``<coordinate>_dot``
            (initial q̇) and parameter names.  A dict is combined as a Cartesian
            product (``combine="product"``, outputs shaped like the grid) or
            element-wise (``combine="zip"``); an (N, k) array needs ``names``.

        Other Parameters
        ----------------
        q0, qd0, params, inputs
            Values of everything not swept (defaults: the System's); a swept
            parameter needs no value here, nor does ``q0`` when the grid sweeps
            every coordinate.  Every trajectory reads the same input tables, and
            calls the same input functions with its own p (a swept gain read
            from p is its own).
        method, dt, rtol, atol, t_eval, save_every, max_step, max_steps, implicit_solver, events
            As for `simulate`, checked by the same code with the same messages
            (`lagcomp.integrate.options.run_options`); each trajectory has its own
            step-size control.
        projection, baumgarte, project_initial
            Constrained systems, as for `simulate`: every initial state is
            checked against the constraints (an inconsistent one is refused,
            naming its trajectory, unless ``project_initial=True`` projects it).
        output : str or sequence of {"dense", "energy", "events"}
            What to keep besides the final state, time, status and counters:
            states at common times (``t_eval`` for adaptive methods, every
            ``save_every``-th step for fixed-step ones), the largest relative
            energy error, the first ``event_cap`` occurrences of each event.
        workers : int, optional
            Threads (default: one per CPU); the result does not depend on it.
        client : dask.distributed.Client, optional
            Run the chunks as Dask tasks; workers rebuild the kernels from
            the emitted source (once per worker process).
        batched : bool
            Advance blocks of trajectories together through SIMD kernels
            (final states and energy errors only).  rk4 and dop853: blocks
            of 128 and 64 through ``rhs_lanes``, each trajectory with its own
            steps for dop853,
            about 2x the throughput, with the arithmetic of the scalar path
            (sin and cos included, `lagcomp.kernel_support.trig`): the same results
            bitwise while the arguments of sin and cos stay below 1e5 in size
            (beyond, the scalar kernels call libm: within 2 ulp).  taylor:
            through the Taylor program unrolled at the order the tolerances
            need (`lagcomp.codegen.taylor_lanes`), written and compiled at the
            first such sweep of the model at that order (about 10 s for the
            double pendulum at order 13, then cached), about 6x the
            throughput; each trajectory takes the scalar method's steps, and
            its coefficients differ from the scalar kernel's by rounding only.
        memory_limit : int
            Bytes the outputs may take (default 2 GiB); a larger request is
            refused before the sweep starts.
        progress : bool, optional
            Progress bar (None: for sweeps over two seconds).  Ctrl-C stops
            between chunks; `Sweep.done` marks the trajectories that ran.
        """
        from lagcomp.integrate.options import known_options
        from lagcomp.integrate.sweep import sweep

        known_options(sweep, options, "Model.sweep")
        return sweep(self, t_span, grid, **options)
