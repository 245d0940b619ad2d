"""A cache that heals itself (issue 24, items 1 and 7): numba's own files and the name records included.

numba reads its machine code lazily, at a function's first call: a damaged
``.nbc`` file used to raise an unpickling error on every run, forever.  Each
test here damages a file the way a crash or a bad disk would, and checks the
next load warns with a `CacheWarning`, rebuilds, and gives the right answer.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.model import t
from lagcomp.numba_cache import cache_directory

x, = lc.coordinates("x")
m, k = sp.symbols("m k", positive=True)


def _oscillator(name: str) -> lc.System:
    return lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, name=name, defaults={"m": 1.0, "k": 4.0},
                     q0=(1.0,))


def _fresh_load(system, cache_dir):
    """compile() as a new process would: the module is executed again, so numba reads its disk cache."""
    for name in [n for n in sys.modules if n.startswith(f"lagcomp_generated_{system.name}_")]:
        del sys.modules[name]
    return lc.compile(system, cache_dir=cache_dir)


def _period_error(model) -> float:
    """|x(π) − 1| for x'' = −4x, x(0) = 1: x = cos 2t, so x(π) = 1 exactly."""
    sol = model.simulate((0.0, np.pi), method="rk4", dt=1e-3, progress=False)
    return abs(sol.q[-1, 0] - 1.0)


def test_unreadable_numba_cache_files_are_removed_and_rebuilt(tmp_path):
    system = _oscillator("healing_oscillator")
    model = lc.compile(system, cache_dir=tmp_path)
    assert _period_error(model) < 1e-13  # RK4 at dt = 1e-3 over one period: measured 2.6e-15
    pycache = cache_directory(model.source_path)
    data_files = sorted(pycache.glob("*.nbc"))
    assert data_files, "numba wrote no cache files"
    rng = np.random.default_rng(24)
    for path in data_files:
        path.write_bytes(rng.bytes(300))  # what issue 24 did: overwrite with random bytes
    with pytest.warns(lc.CacheWarning, match="unreadable and removed"):
        model = _fresh_load(system, tmp_path)
    assert _period_error(model) < 1e-13
    with warnings.catch_warnings():
        warnings.simplefilter("error", lc.CacheWarning)  # healed: a third load finds every file sound
        model = _fresh_load(system, tmp_path)
        assert _period_error(model) < 1e-13
    assert sorted(pycache.glob("*.nbc")), "numba did not write its cache again"


def test_truncated_numba_index_is_removed_and_rebuilt(tmp_path):
    system = _oscillator("healing_index")
    model = lc.compile(system, cache_dir=tmp_path)
    _period_error(model)
    for path in cache_directory(model.source_path).glob("*.nbi"):
        path.write_bytes(path.read_bytes()[:20])
    with pytest.warns(lc.CacheWarning, match="unreadable"):
        model = _fresh_load(system, tmp_path)
    assert _period_error(model) < 1e-13


def test_corrupt_name_record_says_so_and_is_rebuilt(tmp_path):
    system = _oscillator("healing_name")
    lc.compile(system, cache_dir=tmp_path)
    (record,) = (tmp_path / "names").glob("healing_name*.json")
    record.write_text('{"name": "healing_name", "key": ')
    with pytest.raises(lc.ModelError, match="corrupt") as info:
        lc.load("healing_name", cache_dir=tmp_path)
    assert "No compiled model" not in str(info.value) and str(record) in str(info.value)
    assert not record.exists()
    lc.compile(system, cache_dir=tmp_path)  # records it again
    assert json.loads(record.read_text())["name"] == "healing_name"
    assert lc.load("healing_name", cache_dir=tmp_path).name == "healing_name"


def test_corrupt_name_record_of_an_example_is_rebuilt_by_the_cli(tmp_path, capsys):
    from lagcomp.cli import main

    arguments = ["--cache-dir", str(tmp_path), "run", "simple_pendulum", "--t-end", "0.1", "--quiet"]
    assert main(arguments) == 0
    for record in (tmp_path / "names").glob("example.simple_pendulum*.json"):
        record.write_bytes(b"\x00garbage")
    assert main(arguments) == 0
    assert "derived and emitted" in capsys.readouterr().err


def test_temporary_fallback_cache_is_removed_at_exit(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    script = ("import warnings; from lagcomp.cache import Cache, fallback_root\n"
              f"cache = Cache({str(blocker / 'cache')!r})\n"
              "with warnings.catch_warnings(record=True):\n"
              "    cache.store('k' * 32, 'x = 1\\n', 'fallen', {})\n"
              "print(cache.root); assert cache.root == fallback_root() and (cache.root / 'modules').is_dir()\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    root = done.stdout.strip()
    assert "lagcomp-cache-" in root
    assert not os.path.exists(root), f"{root} was left behind"
