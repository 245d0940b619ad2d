"""A library driver never runs stale code from numba's cache after a library source it compiles in has changed.

numba keys a function's cache files on its own source file only, while a driver's machine code holds
the event helpers, `kernel_support`, the status codes, the tableaux and the run-state slots of other
files.  `lagcomp.numba_cache.refresh_stale_drivers` keeps a digest of those sources beside the
drivers' cache files and removes the files when it differs.  The test works on a copy of the package
(as `tests/test_cache_key.py` does): a small cached driver module added to the copy's drivers reads a
constant of ``events.py``; the constant is edited in the copy (same size, so numba's own stamp of the
probe's file cannot notice) and the next process must compile the probe again and return the new value.
"""

from __future__ import annotations

import ast
import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import lagcomp
from lagcomp import numba_cache
from lagcomp.source_digest import hashed_files

#: A driver module of the copy: its code inlines a constant from another library file, as every driver does.
STALENESS_PROBE_MODULE = textwrap.dedent(
    """
    from numba import njit, types

    from lagcomp.integrate.drivers.events import ACTION_TERMINAL


    @njit(types.int64(), cache=True)
    def terminal_action():
        return ACTION_TERMINAL
    """
)

PROBE = textwrap.dedent(
    """
    import json, warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        from lagcomp.integrate.drivers.staleness_probe import terminal_action
    print(json.dumps({"value": terminal_action(), "misses": sum(terminal_action.stats.cache_misses.values()),
                      "warnings": [str(w.message) for w in caught if w.category.__name__ == "CacheWarning"]}))
    """
)


def test_a_driver_is_compiled_again_when_a_library_file_it_inlines_changes(tmp_path):
    copy = tmp_path / "site"
    shutil.copytree(Path(lagcomp.__file__).parent, copy / "lagcomp", ignore=shutil.ignore_patterns("__pycache__"))
    (copy / "lagcomp" / "integrate" / "drivers" / "staleness_probe.py").write_text(STALENESS_PROBE_MODULE)
    env = {**os.environ, "PYTHONPATH": str(copy), "NUMBA_CACHE_DIR": str(tmp_path / "numba")}

    def probe() -> dict:
        out = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, env=env, check=True)
        return json.loads(out.stdout.strip().splitlines()[-1])

    assert probe() == {"value": 2, "misses": 1, "warnings": []}  # compiled into an empty cache
    assert probe() == {"value": 2, "misses": 0, "warnings": []}  # and loaded from it
    events = copy / "lagcomp" / "integrate" / "drivers" / "events.py"
    source = events.read_text()
    edited = source.replace("ACTION_IGNORE, ACTION_RECORD, ACTION_TERMINAL, ACTION_RESET = 0, 1, 2, 3",
                            "ACTION_IGNORE, ACTION_RECORD, ACTION_TERMINAL, ACTION_RESET = 0, 1, 5, 3")
    assert edited != source and len(edited) == len(source)
    events.write_text(edited)
    refreshed = probe()
    assert refreshed["value"] == 5 and refreshed["misses"] == 1, refreshed
    (warning,) = refreshed["warnings"]
    assert "library sources changed" in warning
    assert probe() == {"value": 5, "misses": 0, "warnings": []}  # the new code cached, the stamp renewed


#: A bouncing ball compiled by `lagcomp.compile` in a fresh process, its impact at the floor computed by the generated
#: ``event_reset``, which calls `kernel_support.resting.contact_event` (by symbol), which calls
#: `kernel_support.impacts.contact_impacts`: the path of an impact in any driver's run, without compiling a driver
#: (a driver's machine code calls ``event_reset`` through its address, so it holds none of that code; compiling
#: dopri5's driver into the empty numba cache, twice, was most of this test's CPU).
BALL = textwrap.dedent(
    """
    import json, warnings

    import numpy as np

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        import lagcomp as lc

        x, = lc.coordinates("x")
        ball = lc.System([x], T=x.diff(lc.t) ** 2 / 2, V=9.81 * x, name="stale_ball",
                         events=[lc.Contact("floor", x, restitution=0.5)])
        model = lc.compile(ball)
        before = np.array([0.0, -(2 * 9.81) ** 0.5])     # at the floor, falling as from 1 m
        after = np.empty(2)
        status = model.kernels.event_reset(0.0, before, model.parameter_vector(), 0, after)
    print(json.dumps({"status": int(status), "v": [float(before[1]), float(after[1])],
                      "warnings": [str(w.message) for w in caught if w.category.__name__ == "CacheWarning"]}))
    """
)


def test_a_model_runs_the_new_code_of_a_kernel_support_function_called_from_an_unchanged_file(tmp_path):
    """The impact law of `impacts.py` is edited in a copy of the package (restitution e → e/4); `resting.py`, whose
    cached machine code holds the old law, is not.  The next process must see the new law: v⁺ = −(e/4) v⁻."""
    copy = tmp_path / "site"
    shutil.copytree(Path(lagcomp.__file__).parent, copy / "lagcomp", ignore=shutil.ignore_patterns("__pycache__"))
    env = {**os.environ, "PYTHONPATH": str(copy), "NUMBA_CACHE_DIR": str(tmp_path / "numba"),
           "LAGCOMP_CACHE_DIR": str(tmp_path / "lagcomp")}

    def run() -> dict:
        out = subprocess.run([sys.executable, "-c", BALL], capture_output=True, text=True, env=env)
        assert out.returncode == 0, out.stderr
        return json.loads(out.stdout.strip().splitlines()[-1])

    before = run()
    v_minus, v_plus = before["v"]
    assert before["status"] == 0 and v_minus < 0.0 and before["warnings"] == []
    assert v_plus == pytest.approx(-0.5 * v_minus, rel=1e-15, abs=0)
    impacts = copy / "lagcomp" / "kernel_support" / "impacts.py"
    source = impacts.read_text()
    edited = source.replace("e[row] = restitution[d]", "e[row] = 0.25 * restitution[d]")
    assert edited.count("0.25 * restitution[d]") == 1
    impacts.write_text(edited)
    after = run()
    assert after["status"] == 0 and after["v"][0] == v_minus
    assert after["v"][1] == pytest.approx(-0.125 * v_minus, rel=1e-15, abs=0), after
    assert any("lagcomp.kernel_support" in warning for warning in after["warnings"]), after["warnings"]


#: Imported by the drivers' package to run the refresh: it compiles nothing into a driver.
NOT_COMPILED_IN = {"lagcomp.numba_cache"}


def _module_file(name: str, root: Path) -> Path | None:
    """The file of the lagcomp module `name` (a package's ``__init__.py``), None if there is none."""
    relative = Path(*name.split(".")[1:])
    for candidate in (root / relative.parent / f"{relative.name}.py", root / relative / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


def _imported_files(path: Path, root: Path) -> set[Path]:
    """The lagcomp module files that `path` imports (at its top or inside a function): ``from package import
    module`` names the module's file, ``from module import name`` the module's."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("lagcomp"):
            for alias in node.names:
                submodule = f"{node.module}.{alias.name}"
                names.add(submodule if _module_file(submodule, root) else node.module)
        elif isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names if alias.name.startswith("lagcomp.")}
    return {_module_file(name, root) for name in names - NOT_COMPILED_IN} - {None}


def test_the_digest_covers_every_library_file_a_driver_imports():
    root = Path(lagcomp.__file__).parent
    sources = set(hashed_files(numba_cache.LIBRARY_SOURCES))
    missing = {str(imported.relative_to(root)): str(source.relative_to(root))
               for source in sources for imported in _imported_files(source, root) - sources}
    assert not missing, f"add these to numba_cache.LIBRARY_SOURCES (imported by): {missing}"


def test_the_digest_covers_every_library_file_kernel_support_imports():
    """The sources kernel_support's cache is keyed on are closed under its imports, and they are those the generated
    modules' file names are keyed on (`lagcomp.cache.source_key`): a generated module compiles only those in."""
    root = Path(lagcomp.__file__).parent
    sources = set(hashed_files(numba_cache.KERNEL_SUPPORT_SOURCES))
    missing = {str(imported.relative_to(root)): str(source.relative_to(root))
               for source in sources for imported in _imported_files(source, root) - sources}
    assert not missing, f"add these to numba_cache.KERNEL_SUPPORT_SOURCES (imported by): {missing}"
    assert numba_cache.KERNEL_SUPPORT_SOURCES == lagcomp.cache.KERNEL_LIBRARY
