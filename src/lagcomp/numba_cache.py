"""numba's own cache files of a generated module: found unreadable at load, removed, recompiled.

numba keeps the machine code of each ``cache=True`` function in an index
(``<module>.<function>-<line>.pyXY.nbi``) and data files (``….N.nbc``) under
``__pycache__`` beside the module.  It reads them lazily, at a function's
first call, and a damaged file (truncated, overwritten) then raises an
unpickling error on every run; it is never rebuilt.  `heal` reads them when a
module is loaded instead (each file is a pickle of a few kilobytes: about a
millisecond for a model's twenty functions) and removes every file of a
function whose files do not read back, so that numba compiles that function
again, once, and writes fresh files.

This uses numba's cache internals (``Dispatcher._cache._cache_file``, numba
0.5x–0.6x); where they are absent nothing is checked and numba behaves as
it always does.
"""

from __future__ import annotations

from pathlib import Path
from types import ModuleType


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
    """Remove the numba cache files of `module`'s functions that do not read back; the file names removed.

    Where they cannot be removed (a read-only cache), that function's disk
    cache is switched off for this process: numba compiles it in memory.
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
    return removed

