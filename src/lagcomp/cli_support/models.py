"""Which model a command names, and where it comes from.

The rule, the same for every command (``run``, ``sweep``, ``show``, ``bench``, ``stability``,
``animate``):

* ``path/to/model.py`` or ``path/to/model.py:NAME``: the file is run as a module (its folder first on
  ``sys.path`` while it is imported, as ``python model.py`` would have it) and NAME is a System in it,
  or a function returning one (called with the ``--arg K=V`` values); without ``:NAME`` the file must
  define exactly one System at module level.
* ``package.module`` or ``package.module:NAME``: the same for an importable module.
* a bare NAME: the bundled example of that name (``lagcomp list``) when there is one, else the model
  compiled earlier under NAME into the cache (what ``lagcomp.load(NAME)`` returns).  A model of your own
  named like a bundled example is run with ``--cached`` (the cache's model of that name), or from its
  file.  A command that runs a bundled example while the cache holds another model of that name says so.

Every command prints which model it ran (`ModelSource.label`).
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import inspect
import re
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from lagcomp.errors import CorruptCacheRecordError, LagcompError, ModelError


@dataclass(frozen=True)
class ModelSource:
    """A model named on the command line.

    Attributes
    ----------
    kind : {"example", "cache", "python"}
        A bundled example, a model compiled earlier (`lagcomp.load`), or one from a file or module.
    label : str
        Where it comes from, for the command's ``model`` line.
    system : callable or None
        Builds its System (sympy); None for a model from the cache, which has no System.
    model : callable
        Its compiled `lagcomp.Model` (loaded from the cache when it is there).
    note : callable
        ``note(model)``: something the user should know about the choice (a model of theirs named like the
        bundled example that ran), or None.
    """

    kind: str
    label: str
    system: Callable | None
    model: Callable
    note: Callable = lambda model: None


def key_values(pairs: list[str] | None, what: str) -> dict:
    """``name=value`` flags as {name: int or float}; anything else is a message naming the flag."""
    values = {}
    for pair in pairs or []:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise LagcompError(f"{what} {pair!r} must look like name=value.")
        try:
            values[key] = int(value) if value.lstrip("-").isdigit() else float(value)
        except ValueError as err:
            raise LagcompError(f"{what} {pair!r}: {value!r} is not a number.") from err
    return values


def resolve(args) -> ModelSource:
    """The model `args.name` names (see the module docstring for the rule)."""
    spec = args.name
    if _is_python_spec(spec):
        return _python_source(spec, args)
    if getattr(args, "cached", False):
        return _cached_source(spec, args.cache_dir)
    if is_example(spec):
        return _example_source(args)
    return _cached_source(spec, args.cache_dir, unknown_example=True)


def is_example(name: str) -> bool:
    """Whether `name` is a bundled example (``n_link_pendulum_<n>`` included)."""
    from lagcomp import examples

    return name in examples.EXAMPLES or re.fullmatch(r"n_link_pendulum_\d+", name) is not None


def _is_python_spec(spec: str) -> bool:
    """A file (a path, ``.py``) or a module (dotted, or ``module:NAME``) rather than a bare name: bundled examples
    and System names are identifiers."""
    return any(mark in spec for mark in "/\\.:")


# -- bundled examples ------------------------------------------------------------------


def example_system(name: str, arg: list[str] | None):
    """The bundled example `name` built with the ``--arg`` values; a wrong argument is a message."""
    from lagcomp import examples

    arguments = key_values(arg, "--arg")
    factory = examples.EXAMPLES.get(name)
    if factory is None and re.fullmatch(r"n_link_pendulum_\d+", name):
        factory = examples.EXAMPLES["n_link_pendulum"]
    if factory is not None and arguments:
        accepted = list(inspect.signature(factory).parameters)
        unknown = sorted(set(arguments) - set(accepted))
        if unknown:
            raise LagcompError(f"--arg {', '.join(unknown)}: the example {name!r} takes "
                               f"{', '.join(f'{a}=...' for a in accepted) or 'no arguments'}.")
    try:
        return examples.get(name, **arguments)
    except LagcompError:
        raise
    except (TypeError, ValueError, ArithmeticError) as err:
        raise LagcompError(f"The example {name!r} refused --arg {arguments}: {err}.") from err


def _example_alias(name: str, arg: list[str] | None) -> str:
    """The cache name under which the command line remembers a bundled example built with `arg`.

    It hashes the examples' and the compiler's source, so an edited example
    (or derivation) is compiled afresh instead of loaded.
    """
    from lagcomp.cache import KERNEL_PRODUCERS, code_digest

    digest = hashlib.sha256(code_digest(KERNEL_PRODUCERS).encode())
    for path in sorted((Path(__file__).parents[1] / "examples").glob("*.py")):
        digest.update(path.read_bytes())
    arguments = "".join(f".{k}={v}" for k, v in sorted(key_values(arg, "--arg").items()))
    return f"example.{name}{arguments}.{digest.hexdigest()[:16]}"


def _example_model(name: str, arg: list[str] | None, cache_dir):
    """The bundled example's model: loaded by its alias when this lagcomp compiled it before (no sympy),
    else compiled.  The cache's record of a user's model of the same name (`lagcomp.load`) is left as it was."""
    from lagcomp.cache import Cache
    from lagcomp.runtime import compile, load, run_defaults

    alias = _example_alias(name, arg)
    try:
        return load(alias, cache_dir=cache_dir)
    except ModelError:
        pass
    system = example_system(name, arg)
    cache = Cache(cache_dir)
    before = _recorded(cache, system.name)
    model = compile(system, cache_dir=cache_dir)
    cache.remember(alias, model.cache_key, run_defaults(system))
    if before is not None and before[0].key != model.cache_key:
        cache.remember(system.name, before[0].key, before[1])  # the user's model keeps its name
    return model


def _recorded(cache, name: str):
    try:
        return cache.recall(name)
    except CorruptCacheRecordError:
        return None


def _example_source(args) -> ModelSource:
    name, arg, cache_dir = args.name, args.arg, args.cache_dir
    return ModelSource(kind="example", label=f"{name}: the bundled example (lagcomp list)",
                       system=lambda: example_system(name, arg), model=lambda: _example_model(name, arg, cache_dir),
                       note=lambda model: _namesake_note(model, cache_dir))


def _namesake_note(model, cache_dir) -> str | None:
    """What to say when the cache records another model than the bundled example `model` under its name."""
    from lagcomp.cache import Cache

    name = model.name
    found = _recorded(Cache(cache_dir), name)
    if found is None or found[0].key == model.cache_key:
        return None
    return (f"the cache also holds a model of yours named {name!r} (lagcomp.load({name!r})); this command ran "
            "the bundled example: add --cached to run yours, or give its file (path/to/model.py:NAME).")


# -- models compiled earlier -------------------------------------------------------------


def _cached_source(name: str, cache_dir, unknown_example: bool = False) -> ModelSource:
    from lagcomp.cache import Cache

    def model():
        from lagcomp.runtime import load

        try:
            return load(name, cache_dir=cache_dir)
        except CorruptCacheRecordError:
            raise
        except ModelError:
            if not unknown_example:
                raise
        from lagcomp import examples

        raise LagcompError(f"{name!r} is neither a bundled example ({', '.join(sorted(examples.EXAMPLES))}) nor the "
                           f"name of a model compiled with lagcomp.compile() into the cache {Cache(cache_dir).root}; "
                           "a model in a file runs as path/to/model.py[:NAME].") from None

    root = Cache(cache_dir).root
    return ModelSource(kind="cache", label=f"{name}: compiled earlier under this name (lagcomp.load, cache {root})",
                       system=None, model=model)


# -- a System in a file or module ------------------------------------------------------------


def _python_source(spec: str, args) -> ModelSource:
    where, attribute = _split_spec(spec)
    module = _import(where)
    name, value = _pick(module, where, attribute)
    system = _built(value, name, where, key_values(args.arg, "--arg"))
    origin = f"{name}{'' if system is value else '()'} in {where}"

    def model():
        from lagcomp.runtime import Model, compile

        return system if isinstance(system, Model) else compile(system, cache_dir=args.cache_dir)

    from lagcomp.runtime import Model

    return ModelSource(kind="python", label=f"{getattr(system, 'name', name)}: {origin}",
                       system=None if isinstance(system, Model) else (lambda: system), model=model)


def _split_spec(spec: str) -> tuple[str, str | None]:
    """``where[:NAME]`` as (where, NAME or None); a Windows drive letter is no NAME."""
    match = re.fullmatch(r"(.+):([A-Za-z_]\w*)", spec)
    return (match.group(1), match.group(2)) if match else (spec, None)


def _import(where: str):
    """The module of a file path or a dotted module name; its own errors as a message naming it."""
    if where.endswith(".py") or "/" in where or "\\" in where:
        return import_file(Path(where).expanduser(), where)
    try:
        return importlib.import_module(where)
    except ModuleNotFoundError as err:
        if err.name and where.startswith(err.name):
            raise LagcompError(f"No module named {err.name!r} for the model {where!r}: give a file "
                               "(path/to/model.py[:NAME]) or a module on the Python path.") from err
        raise LagcompError(f"Importing the model module {where} raised ModuleNotFoundError: {err}") from err
    except Exception as err:
        raise LagcompError(f"Importing the model module {where} raised {type(err).__name__}: {err}") from err


def import_file(path: Path, where: str):
    """Run the Python file `path` as a module (its folder first on ``sys.path`` meanwhile, as ``python file.py``
    would have it, so its neighbours import); its errors as a message naming `where`."""
    if not path.is_file():
        raise LagcompError(f"The model file {where} does not exist (a model is named as path/to/model.py[:NAME], "
                           "a module as package.module[:NAME], or by a bundled example's name).")
    digest = hashlib.sha256(str(path.resolve()).encode() + path.read_bytes()).hexdigest()[:12]  # an edit: anew
    stem = re.sub(r"\W", "_", path.stem)
    module_name = f"lagcomp_user_model_{stem}_{digest}"
    if module_name in sys.modules:  # imported once per process (a model and an input function in one file)
        return sys.modules[module_name]
    spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(spec)
    folder = str(path.resolve().parent)
    sys.path.insert(0, folder)
    sys.modules[module_name] = module
    try:
        spec.loader.exec_module(module)
    except Exception as err:
        del sys.modules[module_name]
        raise LagcompError(f"Running the model file {where} raised {type(err).__name__}: {err}") from err
    finally:
        sys.path.remove(folder)
    return module


def _compilable() -> tuple[type, ...]:
    """What a file or module may define for the command line: a System, a kinematic tree (`lagcomp.Tree`), a
    compiled Model."""
    from lagcomp.model import System
    from lagcomp.multibody.tree import Tree
    from lagcomp.runtime import Model

    return System, Tree, Model


def _pick(module, where: str, attribute: str | None) -> tuple[str, object]:
    """The attribute `attribute` of `module`, or its one System (or Tree) when no attribute is named."""
    if attribute is not None:
        if not hasattr(module, attribute):
            found = _systems(module, _compilable())
            raise LagcompError(f"{where} has no {attribute!r}; its Systems: {', '.join(found) or 'none'}.")
        return attribute, getattr(module, attribute)
    found = _systems(module, _compilable())
    if len(found) == 1:
        return found[0], getattr(module, found[0])
    if not found:
        raise LagcompError(f"{where} defines no System at module level: name the System, or the function "
                           f"that returns one, as {where}:NAME.")
    raise LagcompError(f"{where} defines several Systems ({', '.join(found)}): choose one as {where}:NAME.")


def _systems(module, kinds) -> list[str]:
    return sorted(name for name, value in vars(module).items() if isinstance(value, kinds) and not name.startswith("_"))


def _built(value, name: str, where: str, arguments: dict):
    """`value` itself (a System, Tree or Model), or what the function `value` returns when called with
    `arguments`."""
    if isinstance(value, _compilable()):
        if arguments:
            raise LagcompError(f"--arg {', '.join(arguments)}: {name} in {where} is a System, not a function "
                               "that takes arguments.")
        return value
    if not callable(value):
        raise LagcompError(f"{name} in {where} is a {type(value).__name__}, not a System or a function returning one.")
    try:
        built = value(**arguments)
    except LagcompError:
        raise
    except Exception as err:
        raise LagcompError(f"{name}({', '.join(f'{k}={v}' for k, v in arguments.items())}) in {where} raised "
                           f"{type(err).__name__}: {err}") from err
    if not isinstance(built, _compilable()):
        raise LagcompError(f"{name}() in {where} returned a {type(built).__name__}, not a System or a Tree.")
    return built
