"""On-disk cache of generated modules (filesystem work; no sympy, and numba only for its version and,
through `lagcomp.numba_cache`, the health of its own cache files beside a loaded module).

Layout under the cache root::

    modules/<system>_<source key>.py     the emitted module; numba's machine
    modules/__pycache__/...              code is cached beside it (cache=True)
    index/<input key>.json               input key -> module file, its sha256,
                                         and the metadata a Model needs
    index/<input key>-on-demand-<kind>.json   the same for a companion module: the
                                         kernels of one on-demand kind, built on
                                         first use (`lagcomp.codegen.kinds`,
                                         `lagcomp.companion`)
    equations/<input key>.pickle         the derived equations, from which a
                                         later process lowers the companion
    names/<system name>.json             the input key last compiled under that
                                         name and the System's run defaults
                                         (what `lagcomp.load` reads)

Two keys, so that a second process does neither sympy nor numba work:

* the *source key* hashes the emitted source together with the numba and
  Python versions and the code of `lagcomp.kernel_support` (sin, cos and the
  linear solvers the kernels call, which numba compiles into each kernel's
  machine code: a change there must not serve the old machine code); the
  source already names the lagcomp version.  A module file is written once,
  atomically (temporary file, then `os.replace`), and never rewritten while
  it is intact: numba stamps its cache on the source file's mtime and size,
  so a rewrite would throw the machine code away.
* the *input key* hashes the system's canonical description, the compile
  options, the lagcomp, sympy, numba and Python versions and the source of
  what produces the kernels (`KERNEL_PRODUCERS`: the derivation, the IR, the
  emitter and kernel_support), so that a development change there never
  serves a module written by the old code.  An index entry under it lets
  `compile` skip the derivation entirely.

Neither key covers the integration drivers (`lagcomp.integrate`): they are
library code that takes the kernels as function values, cached by numba
beside their own files, so a driver change recompiles the driver once and
keeps every model in the cache.

An entry whose file is missing, truncated or altered (sha256 mismatch), or
whose record names other lagcomp/numba/Python versions, is a miss: it is
reported with a `CacheWarning` and rebuilt, never trusted.  numba's own files
beside a module (``__pycache__/*.nbi``, ``*.nbc``) are read back when the
module is loaded, and unreadable ones are removed (numba recompiles, once),
with a `CacheWarning`; a ``names/`` record that does not parse is removed and
reported (`CorruptCacheRecordError`).  Module files are named after the System
up to `STEM_MAX` ASCII characters, else after a prefix and a hash.

Faults and concurrency
----------------------
* Every file is written to a temporary name and renamed into place, so a
  reader never sees a torn file; a writer killed mid-write leaves only a
  ``.*.tmp`` file, which nobody reads and the next `store` in that directory
  removes once it is an hour old.
* Processes that compile the same system at the same time serialize on a
  lock file per input key (``locks/<key>.lock``, `fcntl.flock`): the first
  derives and stores, the others wait and then find its entry, so one entry
  results and the system is derived once.  Writing a module file holds a
  lock per module file as well, so workers that store the same source under
  different keys never rewrite each other's file.  (Without `fcntl`, on
  Windows, only the atomic rename protects the files.)
* A cache root that cannot be written (read-only, full, a path under a
  regular file) never breaks a compile: lagcomp warns with a `CacheWarning`
  and uses a private temporary directory for the rest of the process,
  removed when the process exits.
"""

from __future__ import annotations

import atexit
import functools
import hashlib
import importlib.metadata
import importlib.util
import json
import os
import re
import shutil
import sys
import tempfile
import time
import warnings
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numba
import platformdirs

from lagcomp import __version__, numba_cache
from lagcomp.errors import CacheWarning, CorruptCacheRecordError, OptionError
from lagcomp.source_digest import code_digest

try:
    import fcntl
except ImportError:  # Windows: the atomic rename alone keeps files whole
    fcntl = None

ENV_VAR = "LAGCOMP_CACHE_DIR"
LAYOUT_VERSION = "1"


def cache_root(cache_dir: str | os.PathLike | None = None) -> Path:
    """The cache directory: `cache_dir`, else $LAGCOMP_CACHE_DIR, else the user cache dir.

    A leading ``~`` or ``~user`` of either is the user's home (`Path.expanduser`), as a shell would read it:
    ``cache_dir="~/lc-cache"`` is not a directory named ``~`` in the working directory.
    """
    if cache_dir is not None:
        if not isinstance(cache_dir, (str, os.PathLike)) or not os.fspath(cache_dir):
            raise OptionError(f"`cache_dir` must be a directory path (str or pathlib.Path), got {cache_dir!r}.")
        return Path(cache_dir).expanduser()
    if os.environ.get(ENV_VAR):
        return Path(os.environ[ENV_VAR]).expanduser()
    return Path(platformdirs.user_cache_dir("lagcomp")) / f"v{LAYOUT_VERSION}"


def _sha256(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


#: The parts of lagcomp whose code decides what a module's kernels compute: the derivation, the IR, the
#: emitter and what the kernels call (not the drivers, which take the kernels as values).
KERNEL_PRODUCERS = ("model", "mechanics", "multibody", "ir.py", "codegen", "kernel_support")
#: The part numba compiles into the kernels' machine code from outside their module file.
KERNEL_LIBRARY = ("kernel_support",)


@functools.lru_cache(maxsize=1)
def _sympy_version() -> str:
    """sympy's version from its package metadata: a warm start (`lagcomp.load`) never imports sympy."""
    return importlib.metadata.version("sympy")


def _versions() -> str:
    return (f"lagcomp={__version__};compiler={code_digest(KERNEL_PRODUCERS)};sympy={_sympy_version()};"
            f"numba={numba.__version__};python={sys.version_info[:3]}")


def input_key(fingerprint: str, options: dict) -> str:
    """Key of a system description plus compile options (skips derivation on a hit)."""
    return _sha256("\n".join([fingerprint, json.dumps(options, sort_keys=True), _versions()]))[:32]


def source_key(source: str) -> str:
    """Key of an emitted module (names the module file)."""
    return _sha256(f"{source}\nnumba={numba.__version__};python={sys.version_info[:3]};"
                   f"kernel_support={code_digest(KERNEL_LIBRARY)}")[:16]


@dataclass(frozen=True)
class Entry:
    """A usable cache entry: its input key, the module file and the metadata stored with it.

    `import_name` is the name other generated modules import this one by (`import_name`): a companion module
    imports the eager kernels it calls from its model's eager module under that name.
    """

    key: str
    path: Path
    module_name: str
    metadata: dict
    import_name: str = ""


def _atomic_write(path: Path, text: str | bytes) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb" if isinstance(text, bytes) else "w", **({} if isinstance(text, bytes) else
                                                                       {"encoding": "utf-8"})) as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


#: Temporary files older than this (seconds) were left by a writer that died; `store` removes them.
STALE_TEMPORARY_AGE = 3600.0


def _remove_stale_temporaries(directory: Path) -> None:
    now = time.time()
    for tmp in directory.glob(".*.tmp"):
        try:
            if now - tmp.stat().st_mtime > STALE_TEMPORARY_AGE:
                tmp.unlink()
        except OSError:
            pass  # another process removed it, or it is not ours to remove


@contextmanager
def _locked(path: Path):
    """Hold an exclusive `flock` on the file `path` (created if needed) for the block."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a+b") as f:
        if fcntl is not None:
            fcntl.flock(f.fileno(), fcntl.LOCK_EX)
        try:
            yield
        finally:
            if fcntl is not None:
                fcntl.flock(f.fileno(), fcntl.LOCK_UN)


#: The private temporary root this process falls back to when its cache root cannot be written.
_fallback_root: Path | None = None
#: Roots already reported unwritable (one warning per root and process).
_reported_roots: set = set()


def fallback_root() -> Path:
    """A private temporary cache root for this process (created on first use, removed at exit)."""
    global _fallback_root
    if _fallback_root is None:
        _fallback_root = Path(tempfile.mkdtemp(prefix="lagcomp-cache-"))
        atexit.register(shutil.rmtree, _fallback_root, ignore_errors=True)
    return _fallback_root


class Cache:
    """The cache under one root directory (which moves to `fallback_root` if it cannot be written)."""

    def __init__(self, cache_dir: str | os.PathLike | None = None):
        self.root = cache_root(cache_dir)

    def _index_file(self, key: str) -> Path:
        return self.root / "index" / f"{key}.json"

    def _fall_back(self, err: OSError) -> bool:
        """Move to the temporary root after a failed write; False if already there."""
        if self.root == fallback_root():
            return False
        if self.root not in _reported_roots:
            _reported_roots.add(self.root)
            warnings.warn(f"lagcomp cannot write its cache under {self.root} ({err}); using {fallback_root()} for "
                          f"this process instead. Set {ENV_VAR} or cache_dir= to a writable directory to keep "
                          "compiled systems across runs.", CacheWarning, stacklevel=4)
        self.root = fallback_root()
        return True

    @contextmanager
    def lock(self, key: str):
        """Hold the lock of input `key` (one compile of a system at a time, across processes)."""
        try:
            lock = _locked(self.root / "locks" / f"{key}.lock")
            lock.__enter__()
        except OSError as err:
            if not self._fall_back(err):
                raise
            lock = _locked(self.root / "locks" / f"{key}.lock")
            lock.__enter__()
        try:
            yield
        finally:
            lock.__exit__(None, None, None)

    def lookup(self, key: str) -> Entry | None:
        """The entry stored under input `key`, or None (with a warning if it was damaged or stale)."""
        index = self._index_file(key)
        if not index.exists():
            return None
        try:
            record = json.loads(index.read_text(encoding="utf-8"))
            if record.get("versions", _versions()) != _versions():
                raise ValueError(f"it was written by another lagcomp or numba version ({record['versions']})")
            path = self.root / "modules" / record["module"]
            text = path.read_text(encoding="utf-8")
            if _sha256(text) != record["sha256"]:
                raise ValueError(f"{path} does not match its recorded sha256 (truncated or edited)")
        except (OSError, ValueError, KeyError, TypeError, AttributeError) as err:
            warnings.warn(f"lagcomp cache entry {index.name} is unusable ({err}); rebuilding it.", CacheWarning, stacklevel=3)
            try:
                index.unlink(missing_ok=True)
            except OSError:
                pass  # a read-only cache: the rebuilt entry goes to the fallback root
            return None
        return Entry(key=key, path=path, module_name=_module_name(path), metadata=record["metadata"],
                     import_name=_import_name(path, record["sha256"]))

    def store(self, key: str, source: str, system_name: str, metadata: dict) -> Entry:
        """Write `source` (unless an intact copy exists) and index it under input `key`.

        A root that cannot be written is replaced by the fallback root, with a `CacheWarning`.
        """
        try:
            return self._store(key, source, system_name, metadata)
        except OSError as err:
            if not self._fall_back(err):
                raise
            return self._store(key, source, system_name, metadata)

    def _store(self, key: str, source: str, system_name: str, metadata: dict) -> Entry:
        path = self.root / "modules" / f"{_file_stem(system_name)}_{source_key(source)}.py"
        digest = _sha256(source)
        with _locked(self.root / "locks" / f"{path.stem}.lock"):
            intact = path.exists() and _sha256(path.read_text(encoding="utf-8", errors="replace")) == digest
            if not intact:
                _atomic_write(path, source)
        _remove_stale_temporaries(path.parent)
        record = {"module": path.name, "sha256": digest, "metadata": metadata, "versions": _versions()}
        _atomic_write(self._index_file(key), json.dumps(record, indent=1, sort_keys=True))
        return Entry(key=key, path=path, module_name=_module_name(path), metadata=metadata,
                     import_name=_import_name(path, digest))

    def store_equations(self, key: str, data: bytes) -> None:
        """Keep `data` (the pickled equations of the system under input `key`) beside its entry, so that a later
        process lowers the on-demand kernels without deriving again (`lagcomp.companion`).  Best effort: a
        cache that cannot be written keeps none, and that process derives them (or says why it cannot)."""
        try:
            _atomic_write(self.root / "equations" / f"{key}.pickle", data)
        except OSError:
            pass

    def equations(self, key: str) -> bytes | None:
        """The data `store_equations` kept under `key`, or None (never stored, or unreadable)."""
        try:
            return (self.root / "equations" / f"{key}.pickle").read_bytes()
        except OSError:
            return None

    def _name_file(self, name: str) -> Path:
        safe = name if re.fullmatch(r"[A-Za-z0-9_.-]{1,100}", name) else f"_{_sha256(name)[:32]}"
        return self.root / "names" / f"{safe}.json"

    def remember(self, name: str, key: str, run_defaults: dict) -> None:
        """Record that `name` was last compiled under input `key`, with the System's `run_defaults`.

        Best effort: a cache that cannot be written keeps its older record (or
        none), and `recall` then finds that one (or nothing).
        """
        record = json.dumps({"name": name, "key": key, "run_defaults": run_defaults}, indent=1, sort_keys=True)
        path = self._name_file(name)
        try:
            if not path.exists() or path.read_text(encoding="utf-8") != record:
                _atomic_write(path, record)
        except OSError:
            pass

    def recall(self, name: str) -> tuple[Entry, dict] | None:
        """The entry last compiled under `name` and its run defaults, or None if there is none (or it is stale).

        A record that does not parse is removed and reported with `CorruptCacheRecordError`,
        so that the caller says so (and the next `compile` under that name writes a new one).
        """
        path = self._name_file(name)
        try:
            text = path.read_text(encoding="utf-8")
        except OSError:
            return None
        try:
            record = json.loads(text)
            key, run_defaults, recorded = record["key"], record["run_defaults"], record["name"]
            if not (isinstance(key, str) and isinstance(run_defaults, dict)):
                raise TypeError("its key or run defaults have the wrong type")
        except (ValueError, KeyError, TypeError) as err:
            try:
                path.unlink(missing_ok=True)
            except OSError:
                pass
            raise CorruptCacheRecordError(
                f"The cache's record of the model {name!r} ({path}) was corrupt ({type(err).__name__}: {err}) and "
                "has been removed: compile the model again (lagcomp.compile(system)) to record it afresh."
            ) from None
        if recorded != name:
            return None  # another name hashed to the same file name
        entry = self.lookup(key)
        return None if entry is None else (entry, run_defaults)

    def discard(self, entry: Entry) -> None:
        """Remove a module file that failed to load, so the rebuild writes a fresh one."""
        try:
            entry.path.unlink(missing_ok=True)
        except OSError:
            pass  # read-only: the rebuild falls back to a writable root


#: System names up to this long (ASCII letters, digits, _) name their module files as they are.
STEM_MAX = 64


def _file_stem(name: str) -> str:
    """`name` as the start of a module file name: itself when short and ASCII, else a prefix and a hash.

    File names are limited (255 bytes on most file systems, the lock file adds to the module's),
    while a System name is any Python identifier, of any length and alphabet.
    """
    if re.fullmatch(rf"[A-Za-z0-9_]{{1,{STEM_MAX}}}", name):
        return name
    prefix = re.sub(r"[^A-Za-z0-9_]", "", name)[:32]
    return f"{prefix}_{_sha256(name)[:16]}"


def _module_name(path: Path) -> str:
    return f"lagcomp_generated_{path.stem}"


def import_name(system_name: str, source: str) -> str:
    """The name under which the generated module of `source` (of the system `system_name`) is imported by other
    generated modules: ``from <import_name> import rhs`` in a companion module (`lagcomp.codegen.kinds`).

    It depends on the source text alone, not on the numba, Python or kernel_support versions that name the
    module's file (`source_key`), so that a companion module's text is the same in every cache and in
    `generated/`, and names the exact eager source it was emitted against.  `load_module` registers every
    module it loads under this name as well as its own (`Entry.module_name`, which numba's cache files are named
    after).
    """
    return f"lagcomp_kernels_{_file_stem(system_name)}_{_sha256(source)[:16]}"


def _import_name(path: Path, digest: str) -> str:
    """`import_name` of the module file `path` (``<file stem>_<source key>.py``) whose text has sha256 `digest`."""
    return f"lagcomp_kernels_{path.stem.rsplit('_', 1)[0]}_{digest[:16]}"


def load_module(entry: Entry) -> ModuleType:
    """Import the module file of `entry` under its stable, unique name.

    The module is registered in `sys.modules` before it runs: numba's cache
    records the module by name and imports it again on later loads.  It is
    registered under `Entry.import_name` too, the name companion modules
    import it by.
    """
    if entry.module_name in sys.modules:
        return sys.modules[entry.module_name]
    spec = importlib.util.spec_from_file_location(entry.module_name, entry.path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[entry.module_name] = module
    try:
        spec.loader.exec_module(module)
    except BaseException:
        del sys.modules[entry.module_name]
        raise
    if entry.import_name:
        sys.modules.setdefault(entry.import_name, module)
    removed = numba_cache.heal(module)
    if removed:
        warnings.warn(f"lagcomp found numba's cache files of {entry.path.name} (or of the kernel_support code its "
                      "kernels call) unreadable and removed them "
                      f"({len(removed)} files, {removed[0]}, ...); numba compiles those functions again, once.",
                      CacheWarning, stacklevel=3)
    return module
