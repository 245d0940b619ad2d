"""The bench scripts keep running: each imports, the DOP853 one runs (quick), and all run in smoke mode (slow).

`bench.smoke` lists every script with the arguments of its smallest run.  A script that calls a library
function whose signature moved on (``python -m bench.bench_dop853``: "not enough arguments: expected 39,
got 37") fails here.  No timing is judged.
"""

from __future__ import annotations

import importlib
import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _smoke_module():
    """bench/smoke.py loaded from its file (standard library only), for the lists the tests are parametrized by."""
    spec = importlib.util.spec_from_file_location("_bench_smoke_lists", ROOT / "bench" / "smoke.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


SCRIPTS = sorted(_smoke_module().SCRIPTS)


@pytest.fixture
def bench(monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))  # bench/ lives at the repository root, beside src/
    import bench.smoke

    return bench.smoke


def test_every_script_of_the_package_has_a_smoke_run_or_a_reason(bench):
    modules = {path.stem for path in (ROOT / "bench").glob("*.py")}
    assert modules == set(bench.SCRIPTS) | set(bench.NOT_RUN) | bench.LIBRARY
    assert not set(bench.SCRIPTS) & set(bench.NOT_RUN)


def test_scripts_import_with_a_main(bench):
    """Importing a script compiles nothing but what it compiles eagerly: about a second for all of them."""
    for script in SCRIPTS:
        module = importlib.import_module(f"bench.{script}")
        assert callable(module.main), script


def test_dop853_script_runs_its_driver_call(bench, compiled, cache_dir, capsys):
    """Its smoke run against the session's compiled model: the driver called directly with today's arguments."""
    from bench import bench_dop853

    compiled("double_pendulum")
    bench_dop853.main(["--smoke", "--cache-dir", str(cache_dir)])
    printed = capsys.readouterr().out
    assert "| lagcomp DOP853 driver, called directly | " in printed and "| lagcomp Model.simulate | " in printed


@pytest.mark.slow  # most scripts compile their models cold in a directory of their own: 10–60 s each
@pytest.mark.parametrize("script", SCRIPTS)
def test_script_runs_in_smoke_mode(bench, script):
    if bench.missing_peer(script):
        pytest.skip(f"{script} needs {bench.missing_peer(script)}, which is not installed")
    result = bench.run(script, timeout=900)
    assert result.returncode == 0, (result.stderr or result.stdout)[-2000:]
