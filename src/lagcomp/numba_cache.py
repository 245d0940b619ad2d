"""numba's own cache files, of a generated module or of lagcomp's library code: unreadable ones removed, recompiled.

numba keeps the machine code of each ``cache=True`` function in an index
(``<module>.<function>-<line>.pyXY.nbi``) and data files (``….N.nbc``) under
``__pycache__`` beside the module.  It reads them lazily, at a function's
first call, and a damaged file (truncated, overwritten) then raises an
unpickling error on every run; it is never rebuilt.  `heal` reads them when a
module is loaded instead (each file is a pickle of a few kilobytes: about a
millisecond for a model's twenty functions) and removes every file of a
function whose files do not read back, so that numba compiles that function
again, once, and writes fresh files.

The library drivers (`lagcomp.integrate.drivers`) have explicit signatures,
so numba reads their files while their module is imported, and a damaged file
makes that import fail in every process.  `import_library_module` imports a
driver module and, only if that fails, removes the unreadable files of the
drivers and of `lagcomp.kernel_support` (found from the source files, as
numba finds them: `heal_source`) and imports it again, so the cost is paid
only by the process that finds the damage.

numba keys a function's cache files on its own source file only (its
modification time and size), but a function's machine code holds what it
calls and reads from other files: a driver holds the event helpers,
`kernel_support`, the status codes, the tableaux, the run-state slots; a
`kernel_support` function holds the others it calls (`resting` calls
`impacts`).  Editing one of those alone (a developer's checkout, an upgrade
that keeps modification times) would leave the callers' cached code stale.
`refresh_stale` keeps a digest of the sources a package's functions are
compiled from in a stamp file beside their cache files and removes the files
when the digest differs, so that numba compiles them again, once: the drivers'
package runs it for `LIBRARY_SOURCES` (`refresh_stale_drivers`), the
`kernel_support` package for its own files (`refresh_stale_kernel_support`),
each before any of its modules is imported.  A generated module needs no stamp:
its file is named after a key that holds the digest of `kernel_support`
(`lagcomp.cache.source_key`), so a change there compiles a new file.

This uses numba's cache internals (``Dispatcher._cache._cache_file``, the
locators and ``IndexDataCacheFile`` of ``numba.core.caching``, numba
0.5x–0.6x); where they are absent nothing is checked and numba behaves as
it always does.
"""

from __future__ import annotations

import importlib
import os
import warnings
from pathlib import Path
from types import ModuleType, SimpleNamespace

from lagcomp.source_digest import code_digest


def _cache_files(module: ModuleType):
    """(dispatcher, numba's IndexDataCacheFile) of every cached numba function defined in `module`."""
    for value in vars(module).values():
        cache_file = getattr(getattr(value, "_cache", None), "_cache_file", None)
        if cache_file is not None and getattr(value, "__module__", None) == module.__name__:
            yield value, cache_file


def _readable(cache_file) -> bool:
    """Whether the index and every data file it lists unpickle (what numba does before using them)."""
    try:
        index = cache_file._load_index()
        for data_name in index.values():
            cache_file._load_data(data_name)
    except FileNotFoundError:
        return True  # a data file gone is a miss numba already handles
    except Exception:  # noqa: BLE001 — pickle raises anything (UnpicklingError, ValueError, EOFError, ...)
        return False
    return True


def _remove(cache_file) -> list[str]:
    """Delete the index and data files of one function; the names removed."""
    index = Path(cache_file._index_path)
    base = index.name[: -len(".nbi")]
    removed = []
    for path in [index, *index.parent.glob(f"{base}.*.nbc")]:
        try:
            path.unlink()
            removed.append(path.name)
        except FileNotFoundError:
            pass
    return removed


def heal(module: ModuleType) -> list[str]:
    """Remove the numba cache files of `module`'s functions, and of the `lagcomp.kernel_support` functions
    its kernels call, that do not read back; the file names removed.

    Where a module function's files cannot be removed (a read-only cache),
    its disk cache is switched off for this process: numba compiles it in memory.
    """
    from numba.core.caching import NullCache

    removed = []
    for dispatcher, cache_file in _cache_files(module):
        if _readable(cache_file):
            continue
        try:
            removed += _remove(cache_file)
        except OSError:
            dispatcher._cache = NullCache()
            removed.append(f"{Path(cache_file._index_path).name} (read-only: compiled in memory instead)")
    support = Path(__file__).parent / "kernel_support"
    return removed + [file for source in sorted(support.glob("*.py")) for file in heal_source(source)]


def _locator(source: Path):
    """numba's cache locator for the module file `source` (its first that accepts it), or None."""
    from numba.core import caching

    implementation = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None)  # renamed in 0.60
    if implementation is None:
        return None
    stand_in = SimpleNamespace(__code__=SimpleNamespace(co_firstlineno=0))  # locators read only the line number
    for locator_class in implementation._locator_classes:
        locator = locator_class.from_function(stand_in, str(source))
        if locator is not None:
            return locator
    return None


def cache_directory(source: Path) -> Path | None:
    """Where numba keeps the cache files of the functions of the module file `source`: ``__pycache__``
    beside it, or under ``$NUMBA_CACHE_DIR``; None if numba would not cache them."""
    locator = _locator(source)
    return None if locator is None else Path(locator.get_cache_path())


def heal_source(source: Path) -> list[str]:
    """Remove numba's unreadable cache files of the functions of the module file `source`, without importing it.

    The cache directory is the one numba would use for `source` (`cache_directory`); the names removed.
    """
    from numba.core import caching

    locator = _locator(source)
    if locator is None or not hasattr(caching, "IndexDataCacheFile"):
        return []
    removed = []
    for index in sorted(Path(locator.get_cache_path()).glob(f"{source.stem}.*.nbi")):
        cache_file = caching.IndexDataCacheFile(str(index.parent), index.name[: -len(".nbi")], locator.get_source_stamp())
        if not _readable(cache_file):
            try:
                removed += _remove(cache_file)
            except OSError:
                pass  # read-only: numba reports the damage itself
    return removed


#: The library code whose numba cache files `import_library_module` heals: the drivers and what they call.
LIBRARY_PACKAGES = ("integrate/drivers", "kernel_support")


def import_library_module(name: str) -> ModuleType:
    """Import the library module `name`; if that fails on numba's damaged cache files, remove them and retry.

    A failure that no removal explains is raised as it is.
    """
    try:
        return importlib.import_module(name)
    except Exception:  # numba's unpickling raises anything (UnpicklingError, EOFError, ...)
        root = Path(__file__).parent
        removed = [file for package in LIBRARY_PACKAGES for source in sorted((root / package).glob("*.py"))
                   for file in heal_source(source)]
        if not removed:
            raise
    from lagcomp.errors import CacheWarning

    warnings.warn(f"lagcomp found numba's cache files of its drivers unreadable and removed them ({len(removed)} "
                  f"files, {removed[0]}, ...); numba compiles those drivers again, once.", CacheWarning, stacklevel=3)
    return importlib.import_module(name)



#: What numba compiles into the library drivers, as parts of the package (`lagcomp.source_digest.hashed_files`): the
#: drivers' own modules, the `kernel_support` functions they call, and the modules whose constants they read
#: when compiled (status codes, the tableaux and the Dormand–Prince coefficients these take).
#: `tests/test_driver_staleness.py` checks that every lagcomp module a driver imports is in one of them.
LIBRARY_SOURCES = ("integrate/drivers", "kernel_support", "integrate/status.py", "integrate/tableaux.py",
                   "integrate/dormand_prince.py")
#: What numba compiles into the `kernel_support` functions: their own package (`resting` calls `impacts`, which
#: calls `linear_solvers`; `trig` and `angles` are inlined).  `tests/test_driver_staleness.py` checks it is closed.
KERNEL_SUPPORT_SOURCES = ("kernel_support",)
#: The stamp file beside a library package's numba cache files: the digest of the sources they were compiled from.
STAMP_NAME = "lagcomp-library-sources.sha256"


def refresh_stale_drivers() -> list[str]:
    """`refresh_stale` for the drivers (`lagcomp.integrate.drivers`) and `LIBRARY_SOURCES`; run by their package
    before any driver module is imported: numba loads a driver with an explicit signature at its import."""
    return refresh_stale("integrate/drivers", LIBRARY_SOURCES)


def refresh_stale_kernel_support() -> list[str]:
    """`refresh_stale` for `lagcomp.kernel_support` and `KERNEL_SUPPORT_SOURCES`; run by that package before any
    of its modules is imported (numba loads their cached code at a function's first compilation, from a generated
    module, a driver or a test: all import the package first)."""
    return refresh_stale("kernel_support", KERNEL_SUPPORT_SOURCES)


def refresh_stale(package: str, sources: tuple[str, ...]) -> list[str]:
    """Remove numba's cache files of the library `package` if they were compiled from other `sources`; the names
    removed.

    numba keys a function's cache files on its own source file only (its modification time and size), but its
    machine code holds what it calls and reads from other files: a change there alone (a developer's checkout, an
    upgrade that keeps modification times) would leave the cached code stale.  So the digest of `sources`
    (`lagcomp.source_digest.code_digest`, about a millisecond) is kept in a stamp file in the package's numba cache
    directory (`cache_directory`); on a difference, or with no stamp beside existing cache files, every index and
    data file of the package's modules there is removed, with one `lagcomp.errors.CacheWarning`, and the new stamp
    written: numba compiles those functions again, once.  Nothing is checked where numba would not cache them.
    """
    root = Path(__file__).parent / package
    directory = cache_directory(root / "__init__.py")
    if directory is None:
        return []
    stamp = directory / STAMP_NAME
    digest = code_digest(sources)
    try:
        if stamp.read_text() == digest:
            return []
    except OSError:
        pass  # no stamp yet: a new cache, or one written before stamps
    cached = [path for source in sorted(root.glob("*.py"))
              for path in sorted(directory.glob(f"{source.stem}.*.nb[ic]"))]
    removed = []
    try:
        for path in cached:
            path.unlink(missing_ok=True)
            removed.append(path.name)
        directory.mkdir(parents=True, exist_ok=True)
        fresh = directory / f"{STAMP_NAME}.{os.getpid()}"
        fresh.write_text(digest)
        os.replace(fresh, stamp)  # whole, never half-written, for a process reading it meanwhile
    except OSError as err:
        from lagcomp.errors import CacheWarning

        warnings.warn(f"lagcomp could not refresh numba's cache of lagcomp.{package.replace('/', '.')} in "
                      f"{directory} ({err}); code compiled from older library sources may run.", CacheWarning,
                      stacklevel=3)
        return removed
    if removed:
        from lagcomp.errors import CacheWarning

        warnings.warn(f"lagcomp's library sources changed since numba cached lagcomp.{package.replace('/', '.')}: "
                      f"removed {len(removed)} cache files in {directory}; numba compiles those functions again, "
                      "once.", CacheWarning, stacklevel=3)
    return removed
