"""On-disk cache of generated modules (filesystem only: no sympy, no numba).

Layout under the cache root::

    modules/<system>_<source key>.py     the emitted module; numba's machine
    modules/__pycache__/...              code is cached beside it (cache=True)
    index/<input key>.json               input key -> module file, its sha256,
                                         and the metadata a Model needs

Two keys, so that a second process does neither sympy nor numba work:

* the *source key* hashes the emitted source together with the numba and
  Python versions; the source already names the lagcomp version.  A module
  file is written once, atomically (temporary file, then `os.replace`), and
  never rewritten while it is intact: numba stamps its cache on the source
  file's mtime and size, so a rewrite would throw the machine code away.
* the *input key* hashes the system's canonical description, the compile
  options, the lagcomp, sympy, numba and Python versions and the source of
  lagcomp's compiler itself (so a development change to the derivation or
  the emitter never serves a module written by the old code).  An index
  entry under it lets `compile` skip the derivation entirely.

An entry whose file is missing, truncated or altered (sha256 mismatch) is a
miss: it is reported with a `CacheWarning` and rebuilt, never trusted.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import json
import os
import sys
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numba
import platformdirs
import sympy

from lagcomp import __version__
from lagcomp.errors import CacheWarning

ENV_VAR = "LAGCOMP_CACHE_DIR"
LAYOUT_VERSION = "1"


def cache_root(cache_dir: str | os.PathLike | None = None) -> Path:
    """The cache directory: `cache_dir`, else $LAGCOMP_CACHE_DIR, else the user cache dir."""
    if cache_dir is not None:
        return Path(cache_dir)
    if os.environ.get(ENV_VAR):
        return Path(os.environ[ENV_VAR])
    return Path(platformdirs.user_cache_dir("lagcomp")) / f"v{LAYOUT_VERSION}"


def _sha256(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


#: The parts of lagcomp whose code decides what a module contains.
_COMPILER_PARTS = ("model", "mechanics", "codegen", "ir.py")


@functools.lru_cache(maxsize=1)
def _compiler_digest() -> str:
    package = Path(__file__).parent
    digest = hashlib.sha256()
    for part in _COMPILER_PARTS:
        root = package / part
        for path in sorted(root.rglob("*.py")) if root.is_dir() else [root]:
            digest.update(path.relative_to(package).as_posix().encode())
            digest.update(path.read_bytes())
    return digest.hexdigest()


def _versions() -> str:
    return (f"lagcomp={__version__};compiler={_compiler_digest()};sympy={sympy.__version__};"
            f"numba={numba.__version__};python={sys.version_info[:3]}")


def input_key(fingerprint: str, options: dict) -> str:
    """Key of a system description plus compile options (skips derivation on a hit)."""
    return _sha256("\n".join([fingerprint, json.dumps(options, sort_keys=True), _versions()]))[:32]


def source_key(source: str) -> str:
    """Key of an emitted module (names the module file)."""
    return _sha256(f"{source}\nnumba={numba.__version__};python={sys.version_info[:3]}")[:16]


@dataclass(frozen=True)
class Entry:
    """A usable cache entry: the module file and the metadata stored with it."""

    path: Path
    module_name: str
    metadata: dict


def _atomic_write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


class Cache:
    """The cache under one root directory."""

    def __init__(self, cache_dir: str | os.PathLike | None = None):
        self.root = cache_root(cache_dir)

    def _index_file(self, key: str) -> Path:
        return self.root / "index" / f"{key}.json"

    def lookup(self, key: str) -> Entry | None:
        """The entry stored under input `key`, or None (with a warning if it was damaged)."""
        index = self._index_file(key)
        if not index.exists():
            return None
        try:
            record = json.loads(index.read_text(encoding="utf-8"))
            path = self.root / "modules" / record["module"]
            text = path.read_text(encoding="utf-8")
            if _sha256(text) != record["sha256"]:
                raise ValueError(f"{path} does not match its recorded sha256 (truncated or edited)")
        except (OSError, ValueError, KeyError, TypeError) as err:
            warnings.warn(f"lagcomp cache entry {index.name} is unusable ({err}); rebuilding it.", CacheWarning, stacklevel=3)
            index.unlink(missing_ok=True)
            return None
        return Entry(path=path, module_name=_module_name(path), metadata=record["metadata"])

    def store(self, key: str, source: str, system_name: str, metadata: dict) -> Entry:
        """Write `source` (unless an intact copy exists) and index it under input `key`."""
        path = self.root / "modules" / f"{system_name}_{source_key(source)}.py"
        digest = _sha256(source)
        intact = path.exists() and _sha256(path.read_text(encoding="utf-8", errors="replace")) == digest
        if not intact:
            _atomic_write(path, source)
        record = {"module": path.name, "sha256": digest, "metadata": metadata}
        _atomic_write(self._index_file(key), json.dumps(record, indent=1, sort_keys=True))
        return Entry(path=path, module_name=_module_name(path), metadata=metadata)

    def discard(self, entry: Entry) -> None:
        """Remove a module file that failed to load, so the rebuild writes a fresh one."""
        entry.path.unlink(missing_ok=True)


def _module_name(path: Path) -> str:
    return f"lagcomp_generated_{path.stem}"


def load_module(entry: Entry) -> ModuleType:
    """Import the module file of `entry` under its stable, unique name.

    The module is registered in `sys.modules` before it runs: numba's cache
    records the module by name and imports it again on later loads.
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
    return module
