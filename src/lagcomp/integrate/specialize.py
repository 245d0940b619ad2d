"""Drivers specialised for one model: a library driver compiled with the model's kernels as compile-time callees.

The library drivers (`lagcomp.integrate.drivers`) take a model's kernels as function values
(``numba.types.FunctionType``): numba compiles each driver once per installation, so a new model's
first result waits for its kernels only.  The price is paid at every kernel call of every step: a
call through an address, which the compiler cannot see through (it must assume the callee reads and
writes any array, so the driver reloads what it had in registers), and, at every driver call from
Python, numba's unboxing of each kernel (`kernel_types.AddressedKernel`).

The *specialised* driver of a model and a library driver is that driver's own Python function
(``py_func``) compiled once more (`compile_time.uncached_copy`), with the model's kernels for its kernel
arguments as values known at compile time (`compile_time.CompileTimeKernel`): numba calls each kernel
directly and links its machine code into the driver's, and the driver's arguments from Python are arrays
and numbers only.  It is the same source compiled with the same options (the library dispatcher's
``targetoptions``), so it does the same floating-point operations in the same order: the same steps,
rows and statuses as the library driver, bit for bit (`tests/test_specialize.py`; ``nfev`` counts one
more evaluation per driver call, and the two tiers' calls are sized from step rates learned per tier).
What it costs is one compile of the driver per model (the double pendulum's: RK4 1.3 s, DOP853's embedded
driver 12 s of CPU time; loading it later: 0.1 s), which is why a run compiles it only when asked
(``simulate(..., specialize=True)``, ``lagcomp precompile MODEL --specialize METHOD``), never on the path to a
model's first result.

The automatic tier (``specialize=None``, the default) uses it where that costs no compile: a run starts with it
when it is loaded in the process already (its calls are even cheaper than a library driver's, which unboxes each
kernel), and a run whose rest is estimated, between two driver calls, to take `AUTO_REMAINING_SECONDS` or more
moves to it when numba's cache holds it (`lagcomp.integrate.simulate._upgrade`).  It never compiles one in the
background: numba compiles under one process-wide lock, so a 12-s compile in a thread would hold up every other
compile of the process (a new model's kernels, a first ``Solution.energy``) for as long.

Each specialised driver is a small generated module (a header docstring, its imports, one function
``run`` taking the library driver's arguments after the kernels), built from a Python AST and
stored in the model's cache as a module of its own, under the model's input key plus the driver's name
and a digest of the library sources (`specialised_key`), so that a change of a driver or of what it
calls makes a new module.  numba caches ``run``'s machine code beside that module file: a later process
loads it (milliseconds) instead of compiling it.  The drivers of the embedded pairs are one library
function, so dop853, dopri5, tsit5 and bs3 share one specialised module per model.

A method's sweep loop (`Method.sweep`, which takes the driver's kernels and ``energy``) is specialised the same
way, in a module of its own (``sweep=True``; ``lagcomp precompile MODEL --specialize-sweep METHOD``), for the
automatic tier of large sweeps (`lagcomp.integrate.sweep.AUTO_TRAJECTORIES`).

Covered (`SPECIALISABLE`): the methods whose driver takes the model's kernels and nothing else of the
model (not Taylor's module data; Radau, whose constrained runs take other kernels, is not done yet), run
without sensitivities and without numba functions as inputs (their kernels are wrappers made per run).
"""

from __future__ import annotations

import ast
import functools
import inspect
import warnings
import weakref

from numba.core.errors import NumbaExperimentalFeatureWarning

from lagcomp.errors import OptionError
from lagcomp.integrate.methods import METHODS, Method, _kernel, library_function

#: The library drivers a model can have specialised (those taking kernels only, before their other arguments).
SPECIALISABLE_DRIVERS = ("lagcomp.integrate.drivers.fixed_step:runge_kutta_run",
                         "lagcomp.integrate.drivers.embedded:embedded_run",
                         "lagcomp.integrate.drivers.fixed_step:composition_run")
#: The methods whose driver is one of them.
SPECIALISABLE = tuple(name for name, m in METHODS.items() if m.driver in SPECIALISABLE_DRIVERS)
#: What the cache key of a specialised module adds to the model's input key (then the driver and the digest).
SUFFIX = "-specialised-"
#: The automatic tier (``specialize=None``): a run moves to the specialised driver, if numba's cache holds it, once
#: the rest of the run is estimated to take this long (loading it takes ~0.1 s: a tenth of that at most).
AUTO_REMAINING_SECONDS = 1.0
#: The specialised drivers loaded in this process: {model's kernels: {driver reference: ``run``}}.
_LOADED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def covers(method: Method, model, given, sensitivities) -> bool:
    """Whether a run of `method` on `model` can use its specialised driver: the refusals of `check` (and of
    ``sensitivities``, not None for a sensitivity run) as a test, for the automatic tier (``specialize=None``)."""
    return (method.name in SPECIALISABLE and model is given and sensitivities is None
            and getattr(model, "cache_key", None) is not None and getattr(model, "source_path", None) is not None)


def check(method: Method, model, given) -> None:
    """Refuse ``specialize=True`` for a run the specialised drivers do not cover, before any work.

    `model` is the run's model after its function inputs were bound (`function_inputs.driven`), `given` the
    user's: they differ when an input is a numba function, whose wrapped kernels are made per run.
    """
    if method.name not in SPECIALISABLE:
        raise OptionError(f"`specialize=True` with method {method.name!r}: the specialised drivers cover "
                          f"{', '.join(SPECIALISABLE)}. Leave `specialize` unset for {method.name}, or pick one of "
                          "those methods.")
    if model is not given:
        raise OptionError(f"`specialize=True` with input(s) {list(model.function_inputs)} given as numba functions: "
                          "their kernels are wrapped per run, so no driver can be specialised for them. Leave "
                          "`specialize` unset, or give the inputs as tables.")


@functools.cache
def library_digest() -> str:
    """sha256 of the library sources the drivers are compiled from (`numba_cache.LIBRARY_SOURCES`) and of this
    module, which writes the specialised ones; once per process."""
    from lagcomp.cache import code_digest
    from lagcomp.numba_cache import LIBRARY_SOURCES

    return code_digest((*LIBRARY_SOURCES, "integrate/specialize.py", "integrate/compile_time.py"))


def target(method: Method, sweep: bool = False) -> tuple[str, tuple[str, ...]]:
    """(library function, the names of the kernels it takes first) of `method`'s driver, or with `sweep` of its sweep
    loop (`Method.sweep`, which takes the driver's kernels and ``energy``)."""
    kernels = method.driver_kernels
    return (method.sweep, (*kernels, "energy")) if sweep else (method.driver, kernels)


def specialised_key(model, method: Method, sweep: bool = False) -> str:
    """The cache key of `model`'s specialised module for `method`'s driver (or sweep loop)."""
    return f"{model.cache_key}{SUFFIX}{target(method, sweep)[0].partition(':')[2]}-{library_digest()[:16]}"


def driver(model, method: Method, sweep: bool = False):
    """The specialised ``run`` of `model` for `method`'s driver (or sweep loop), once per process: its module loaded
    (generated and stored first if missing), which compiles ``run`` from its explicit signature or loads it from
    numba's cache."""
    loaded = _LOADED.setdefault(model.kernels, {})
    reference = target(method, sweep)[0]
    if reference not in loaded:
        loaded[reference] = _module(model, method, sweep).run
    return loaded[reference]


def loaded(model, method: Method, sweep: bool = False) -> bool:
    """Whether `model`'s specialised driver (or sweep loop) for `method` is loaded in this process."""
    return loaded_for(model.kernels, target(method, sweep)[0]) is not None


def loaded_for(kernels, reference: str):
    """The specialised ``run`` of the library function `reference` loaded in this process for a model's `kernels`
    (its generated module), or None (also for kernels that cannot be weakly referenced: a stand-in's)."""
    try:
        return _LOADED.get(kernels, {}).get(reference)
    except TypeError:
        return None


def prepare(model, method: Method, sweep: bool = False) -> bool:
    """`driver`, for ``lagcomp precompile MODEL --specialize METHOD``; returns whether numba compiled it."""
    return sum(driver(model, method, sweep).stats.cache_misses.values()) > 0


def cached(model, method: Method, sweep: bool = False) -> bool:
    """Whether `model`'s specialised driver (or sweep loop) for `method` is ready without a compile: loaded in this
    process, or its module in the model cache with numba's cache files of ``run`` beside it."""
    from lagcomp.cache import Cache
    from lagcomp.numba_cache import cache_directory

    if method.name not in SPECIALISABLE:
        return False
    if loaded(model, method, sweep):
        return True
    entry = Cache(model.source_path.parent.parent).lookup(specialised_key(model, method, sweep))
    directory = None if entry is None else cache_directory(entry.path)
    return directory is not None and any(directory.glob(f"{entry.path.stem}.run-*.nbi"))


def _module(model, method: Method, sweep: bool):
    """The specialised module of `model` for `method`'s driver (or sweep loop), from the model's cache (stored first
    if missing)."""
    from lagcomp.cache import Cache, load_module

    cache, key = Cache(model.source_path.parent.parent), specialised_key(model, method, sweep)
    reference = target(method, sweep)[0]
    entry = cache.lookup(key)
    if entry is None:
        with cache.lock(key):
            entry = cache.lookup(key) or cache.store(
                key, module_source(model, method, sweep), f"{model.name}_{reference.partition(':')[2]}",
                {"driver": reference, "library": library_digest()})
    with warnings.catch_warnings():
        # ``run`` passes more than 30 arguments, which Python packs into a tuple; numba warns that a tuple holding
        # dispatchers' types is an experimental first-class function feature, which the call does not use.
        warnings.simplefilter("ignore", NumbaExperimentalFeatureWarning)
        return load_module(entry)


def module_source(model, method: Method, sweep: bool = False) -> str:
    """The source of the specialised module of `model` for `method`'s driver, or with `sweep` its sweep loop (module
    docstring)."""
    from lagcomp import __version__

    reference, names = target(method, sweep)
    library = library_function(reference)
    parameters = list(inspect.signature(library.py_func).parameters)
    kernels = [_kernel(model.kernels, name) for name in names]
    rest = parameters[len(kernels):]
    options = {k: v for k, v in library.targetoptions.items() if k not in ("cache", "nopython") and v is not None}
    header = (f"The library driver {reference} specialised for the model {model.name!r}, generated by lagcomp "
              f"{__version__}. Do not edit.\n\n"
              "Its kernels are compile-time callees (lagcomp.integrate.compile_time): numba compiles the library\n"
              "driver's own Python function once more, with this model's kernels for its kernel arguments, and\n"
              "caches `run` beside this file. Same source, same options: bitwise the library driver's steps and\n"
              "results (lagcomp.integrate.specialize).\n\n"
              f"Library sources: sha256 {library_digest()}.\n")
    module_name, function = reference.split(":")
    body = [ast.Expr(ast.Constant(header)),
            ast.ImportFrom("numba", [ast.alias("njit")], 0),
            ast.ImportFrom("lagcomp.integrate.compile_time",
                           [ast.alias("compile_time"), ast.alias("run_signature"), ast.alias("uncached_copy")], 0),
            ast.ImportFrom(module_name, [ast.alias(function)], 0),
            *_kernel_imports(kernels, names),
            _assign("_driver", _call(ast.Name("uncached_copy"), [ast.Name(function)])),
            *(_assign(name, _call(ast.Name("compile_time"), [ast.Name(name)])) for name in names),
            _run(function, names, rest, options)]
    return ast.unparse(ast.fix_missing_locations(ast.Module(body, []))) + "\n"


def _kernel_imports(kernels, names) -> list[ast.ImportFrom]:
    """One import per module of the `kernels` (dispatchers), each under its driver argument's name in `names`."""
    modules: dict[str, list[ast.alias]] = {}
    for kernel, name in zip(kernels, names, strict=True):
        alias = ast.alias(kernel.__name__, None if kernel.__name__ == name else name)
        modules.setdefault(kernel.__module__, []).append(alias)
    return [ast.ImportFrom(module, aliases, 0) for module, aliases in modules.items()]


def _run(function, kernels, parameters, options) -> ast.FunctionDef:
    """``run(<parameters>)``: the library driver's call with `kernels` (module globals) before `parameters`, with
    the library `function`'s signature less its kernels (`compile_time.run_signature`)."""
    call = _call(ast.Name("_driver"), [ast.Name(name) for name in (*kernels, *parameters)])
    doc = ("The library driver's call with this model's kernels first: the driver protocol of\n"
           "    lagcomp.integrate.drivers, the arguments after the kernels; returns (status, n_saved).")
    return ast.FunctionDef(
        name="run", args=ast.arguments(posonlyargs=[], args=[ast.arg(name) for name in parameters], kwonlyargs=[],
                                       kw_defaults=[], defaults=[]),
        body=[ast.Expr(ast.Constant(doc)), ast.Return(call)],
        decorator_list=[_call(ast.Name("njit"), [_call(ast.Name("run_signature"), [ast.Name(function),
                                                                                   ast.Constant(len(kernels))])],
                              keywords={"cache": True, **options})])


def _call(function, args=(), keywords=None) -> ast.Call:
    return ast.Call(function, list(args), [ast.keyword(k, ast.Constant(v)) for k, v in (keywords or {}).items()])


def _assign(name: str, value) -> ast.Assign:
    return ast.Assign([ast.Name(name)], value, lineno=0)
