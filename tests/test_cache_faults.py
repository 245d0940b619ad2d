"""The cache under faults and concurrency: torn writes, stale entries, unwritable roots, many processes.

The multi-process tests start real processes (``spawn``, as a sweep on
several machines or a batch of jobs would) that meet at a barrier and then
compile the same new system at the same instant.
"""

from __future__ import annotations

import errno
import hashlib
import json
import multiprocessing
import os
import time
import warnings

import pytest
import sympy as sp

import lagcomp as lc
import lagcomp.cache as cache_module
from lagcomp.model import t

x, = lc.coordinates("x")
m, k = sp.symbols("m k", positive=True)


def spring(name: str = "faulty_spring", stiffness=k) -> lc.System:
    return lc.System([x], T=m * x.diff(t) ** 2 / 2, V=stiffness * x**4 / 4 + x**2 / 2, name=name,
                     defaults={"m": 1.0, "k": 0.5}, q0=(1.0,))


def _modules(root):
    return sorted((root / "modules").glob("*.py"))


def _indexes(root):
    return sorted((root / "index").glob("*.json"))


def _runs(model) -> bool:
    return model.simulate((0, 1), method="rk4", dt=0.01).success


# -- torn and interrupted writes -----------------------------------------------------


class _DiskFull:
    """A file object that writes half of what it is given, then fails as a full disk does."""

    def __init__(self, f):
        self.f = f

    def write(self, text):
        self.f.write(text[: len(text) // 2])
        raise OSError(errno.ENOSPC, "No space left on device")

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.f.close()


def test_write_interrupted_midway_leaves_no_torn_file(tmp_path, monkeypatch):
    real_fdopen = os.fdopen

    def fdopen(fd, *args, **kwargs):  # files under tmp_path fail half-way; the fallback root works
        f = real_fdopen(fd, *args, **kwargs)
        return _DiskFull(f) if os.readlink(f"/proc/self/fd/{fd}").startswith(str(tmp_path)) else f

    monkeypatch.setattr(cache_module.os, "fdopen", fdopen)
    with pytest.warns(lc.CacheWarning, match="cannot write its cache"):
        model = lc.compile(spring(), cache_dir=tmp_path)
    monkeypatch.undo()
    # nothing under the real root: no module, no index, no temporary file
    assert not [p for p in tmp_path.rglob("*") if p.is_file() and p.suffix != ".lock"]
    assert model.source_path.is_relative_to(cache_module.fallback_root()) and _runs(model)
    assert not lc.compile(spring(), cache_dir=tmp_path).from_cache  # the real root works again


def test_temporary_files_of_dead_writers_are_ignored_then_removed(tmp_path):
    system = spring()
    lc.compile(system, cache_dir=tmp_path)
    (module,) = _modules(tmp_path)
    text = module.read_text()
    old = module.parent / f".{module.name}.dead1.tmp"
    young = module.parent / f".{module.name}.dead2.tmp"
    for leftover in (old, young):
        leftover.write_text(text[: len(text) // 3])  # what a writer killed mid-write leaves
    os.utime(old, (time.time() - 2 * cache_module.STALE_TEMPORARY_AGE,) * 2)
    for index in _indexes(tmp_path):
        index.unlink()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        model = lc.compile(system, cache_dir=tmp_path)
    assert model.source_path == module and module.read_text() == text
    assert not old.exists() and young.exists()  # a young one may belong to a live writer


# -- stale entries ---------------------------------------------------------------------


def test_entry_recorded_by_another_version_is_rebuilt(tmp_path):
    system = spring()
    lc.compile(system, cache_dir=tmp_path)
    (index,) = _indexes(tmp_path)
    record = json.loads(index.read_text())
    record["versions"] = record["versions"].replace("numba=", "numba=0.0.1+")
    index.write_text(json.dumps(record))
    with pytest.warns(lc.CacheWarning, match="another lagcomp or numba version"):
        model = lc.compile(system, cache_dir=tmp_path)
    assert not model.from_cache and _runs(model)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert lc.compile(system, cache_dir=tmp_path).from_cache


def test_another_numba_version_gets_its_own_entry(tmp_path, monkeypatch):
    import numba

    system = spring()
    first = lc.compile(system, cache_dir=tmp_path)
    monkeypatch.setattr(numba, "__version__", "0.0.1")
    other = lc.compile(system, cache_dir=tmp_path)
    assert not other.from_cache and other.source_path != first.source_path
    assert len(_modules(tmp_path)) == 2 and len(_indexes(tmp_path)) == 2
    monkeypatch.undo()
    assert lc.compile(system, cache_dir=tmp_path).source_path == first.source_path


# -- unwritable roots ----------------------------------------------------------------


def test_root_under_a_regular_file_falls_back_to_a_temporary_directory(tmp_path):
    # a path under a regular file cannot be created, even by root (chmod does not stop root)
    blocker = tmp_path / "not_a_directory"
    blocker.write_text("")
    root = blocker / "cache"
    with pytest.warns(lc.CacheWarning, match="cannot write its cache under"):
        model = lc.compile(spring(), cache_dir=root)
    assert model.source_path.is_relative_to(cache_module.fallback_root())
    assert _runs(model)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # reported once per root and process
        again = lc.compile(spring(), cache_dir=root)
    assert again.from_cache and _runs(again)


@pytest.mark.parametrize("fault", [errno.ENOSPC, errno.EROFS, errno.EACCES])
def test_full_or_read_only_root_never_breaks_a_simulation(tmp_path, monkeypatch, fault):
    real_write = cache_module._atomic_write

    def failing_write(path, text):
        if path.is_relative_to(tmp_path):
            raise OSError(fault, os.strerror(fault), str(path))
        real_write(path, text)

    monkeypatch.setattr(cache_module, "_atomic_write", failing_write)
    with pytest.warns(lc.CacheWarning, match=os.strerror(fault)):
        model = lc.compile(spring(), cache_dir=tmp_path)
    assert model.source_path.is_relative_to(cache_module.fallback_root()) and _runs(model)


# -- many processes ------------------------------------------------------------------


def _compile_at_barrier(barrier, root: str, name: str, simulate: bool, queue) -> None:
    """Child process: wait for the others, compile the system and evaluate its kernels (or run it), report."""
    import lagcomp.mechanics.lagrange as lagrange

    derivations = []
    original = lagrange.derive
    lagrange.derive = lambda system: derivations.append(system.name) or original(system)
    barrier.wait()
    started = time.time()
    model = lc.compile(spring(name), cache_dir=root)
    if simulate:
        sol = model.simulate((0, 2), method="rk4", dt=0.01, progress=False)
        final, success = sol.y[-1].tolist(), sol.success
    else:  # the rhs kernel alone: numba compiles one small function instead of a driver
        final, success = model.rhs(0.0, [0.3, -0.2]).tolist(), True
    queue.put(dict(pid=os.getpid(), started=started, from_cache=model.from_cache, derivations=len(derivations),
                   path=str(model.source_path), final=final, success=success,
                   sha=hashlib.sha256(model.source_path.read_bytes()).hexdigest()))


def _start_together(root, names, simulate=False) -> list[dict]:
    context = multiprocessing.get_context("spawn")
    barrier, queue = context.Barrier(len(names)), context.Queue()
    processes = [context.Process(target=_compile_at_barrier, args=(barrier, str(root), name, simulate, queue))
                 for name in names]
    for process in processes:
        process.start()
    results = [queue.get(timeout=300) for _ in processes]
    for process in processes:
        process.join(timeout=60)
        assert process.exitcode == 0
    return results


def test_processes_compiling_the_same_new_system_at_once(tmp_path):
    n = 4
    results = _start_together(tmp_path, ["concurrent_spring"] * n)
    assert len({r["pid"] for r in results}) == n and all(r["success"] for r in results)
    assert max(r["started"] for r in results) - min(r["started"] for r in results) < 0.5  # at the same instant
    assert sum(r["derivations"] for r in results) == 1  # one derived, the others waited and loaded it
    assert sum(not r["from_cache"] for r in results) == 1
    assert len({r["path"] for r in results}) == 1 and len({r["sha"] for r in results}) == 1
    assert len({tuple(r["final"]) for r in results}) == 1  # the same kernels
    (module,) = _modules(tmp_path)
    (index,) = _indexes(tmp_path)
    assert json.loads(index.read_text())["sha256"] == hashlib.sha256(module.read_bytes()).hexdigest()
    assert not list(tmp_path.rglob("*.tmp"))


def test_cache_shared_by_many_workers(tmp_path):
    # four workers, two systems, all at once, each running a simulation as a sweep worker does:
    # two entries, one module each, equal results per system
    names = ["shared_a", "shared_b"] * 2
    results = _start_together(tmp_path, names, simulate=True)
    assert all(r["success"] for r in results)
    assert len(_modules(tmp_path)) == 2 and len(_indexes(tmp_path)) == 2
    for name in set(names):
        mine = [r for r in results if f"/{name}_" in r["path"]]
        assert len(mine) == 2 and sum(r["derivations"] for r in mine) == 1
        assert len({tuple(r["final"]) for r in mine}) == 1
    assert not list(tmp_path.rglob("*.tmp"))
