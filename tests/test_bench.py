"""Smoke tests of the benchmarks: `python -m bench` and `lagcomp bench NAME` run on a tiny case.

No timing is asserted anywhere: the figures depend on the machine and its load.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def bench_package(monkeypatch):
    monkeypatch.syspath_prepend(str(ROOT))  # bench/ lives at the repository root, beside src/
    from bench import run

    return run


def test_bench_entry_point_prints_the_table(bench_package, compiled, cache_dir, tmp_path, capsys):
    compiled("simple_pendulum")  # the session's compiled model: the bench finds it in the same cache
    out = tmp_path / "bench.md"
    code = bench_package.main(["--cases", "simple_pendulum", "--only", "kernels", "--repeats", "1", "--no-peers",
                               "--cache-dir", str(cache_dir), "--out", str(out)])
    printed = capsys.readouterr().out
    assert code == 0
    assert "| simple_pendulum | lagcomp rhs, in a loop |" in printed
    assert "closed-form numba (loops), in a loop" in printed
    assert "### Issue 8 targets" in printed and "Reproduce: `python -m bench`" in printed
    assert out.read_text().count("| simple_pendulum |") == printed.count("| simple_pendulum |")


def test_bench_is_a_package_with_a_main():
    assert (ROOT / "bench" / "__init__.py").is_file() and (ROOT / "bench" / "__main__.py").is_file()
    assert (ROOT / "bench" / "data" / "double_pendulum_reference.json").is_file()


def test_lagcomp_bench_reports_one_model(compiled, cache_dir, capsys):
    from lagcomp.cli import main

    compiled("simple_pendulum")
    code = main(["--cache-dir", str(cache_dir), "bench", "simple_pendulum", "--repeats", "1", "--steps", "100",
                 "--methods", "rk4", "--no-cold"])
    printed = capsys.readouterr().out
    assert code == 0
    assert "| rhs in a compiled loop |" in printed and "| rhs from Python |" in printed
    assert "| rk4 | dt 0.001 | 100 |" in printed
    assert "| rhs | " in printed  # the op counts


def test_lagcomp_bench_of_an_unknown_name_is_a_clear_error(cache_dir, capsys):
    from lagcomp.cli import main

    assert main(["--cache-dir", str(cache_dir), "bench", "no_such_model_anywhere"]) == 2
    assert "'no_such_model_anywhere' is neither a bundled example" in capsys.readouterr().err  # as run, sweep, show say


def test_python_dash_m_bench_help_runs():
    import subprocess

    out = subprocess.run([sys.executable, "-m", "bench", "--help"], cwd=ROOT, capture_output=True, text=True,
                         env={**__import__("os").environ, "PYTHONPATH": str(ROOT / "src")})
    assert out.returncode == 0 and "--quick" in out.stdout


def test_bench_tiers_runs(bench_package, cache_dir):
    """`python -m bench.bench_tiers` (section ``tiers``) on a few steps and one round: its three tables."""
    from bench import bench_tiers

    tables = bench_tiers.measure(rounds=1, steps=1000, cache_dir=cache_dir)
    titles = [table.title for table in tables]
    assert titles[0].startswith("RK4, double pendulum") and titles[1].startswith("DOP853, double pendulum")
    assert [row[0] for row in tables[2].rows] == ["every step (the default)", "`t_eval`, 1001 points",
                                                   "`save_every=10`", "`record=\"summary\"`",
                                                   "every step, then `Solution.summary` read"]
