"""Digests of lagcomp's own source files: what the cache keys (`lagcomp.cache`) and the stamps of numba's cache of
the library code (`lagcomp.numba_cache`) hash, so that a change to that code is never served stale."""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path


def hashed_files(parts: tuple[str, ...]) -> list[Path]:
    """The Python files of the package `parts` (directories or files of lagcomp), in a stable order."""
    package = Path(__file__).parent
    files = []
    for part in parts:
        root = package / part
        files += sorted(root.rglob("*.py")) if root.is_dir() else [root]
    return files


@functools.cache
def code_digest(parts: tuple[str, ...]) -> str:
    """sha256 over the paths and bytes of `hashed_files(parts)`."""
    package = Path(__file__).parent
    digest = hashlib.sha256()
    for path in hashed_files(parts):
        digest.update(path.relative_to(package).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()
