"""The command line met by a new user (issue 24, items 3 and 5): messages, not tracebacks; user models first-class.

Each test reproduces a report of the issue through `lagcomp.cli.main`.
"""

from __future__ import annotations

import sympy as sp

import lagcomp as lc
from lagcomp.cli import main
from lagcomp.cli_support.outputs import check_writable
from lagcomp.model import t
from lagcomp.numba_cache import cache_directory

x, = lc.coordinates("x")
m, k = sp.symbols("m k", positive=True)


def _user_model(cache_dir, name="cli_user_oscillator", **extra):
    """x'' = −(k/m) x, compiled under `name` (no default q0 unless given)."""
    return lc.compile(lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, name=name, defaults={"m": 1.0},
                                **extra), cache_dir=cache_dir)


def _one_line_error(err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("lagcomp: ") and "Traceback" not in err, err
    return lines[0]


def test_an_argument_the_example_does_not_take_is_a_message(capsys, cache_dir):
    assert main(["--cache-dir", str(cache_dir), "run", "n_link_pendulum", "--arg", "m=3"]) == 2
    line = _one_line_error(capsys.readouterr().err)
    assert "--arg m" in line and "takes n=..." in line
    assert main(["--cache-dir", str(cache_dir), "run", "n_link_pendulum", "--arg", "n=-2"]) == 2
    _one_line_error(capsys.readouterr().err)


def test_an_unwritable_output_path_is_refused_before_the_run(capsys, cache_dir, monkeypatch):
    def no_run(*args, **kwargs):
        raise AssertionError("the run started although its output cannot be saved")
    monkeypatch.setattr(lc.Model, "simulate", no_run)
    for option in ("--out", "--plot"):
        assert main(["--cache-dir", str(cache_dir), "run", "simple_pendulum", option, "/nonexistent/dir/x.npz"]) == 2
        line = _one_line_error(capsys.readouterr().err)
        assert "/nonexistent/dir" in line and "does not exist" in line
    assert main(["--cache-dir", str(cache_dir), "sweep", "simple_pendulum", "--grid", "theta=0:1:2",
                 "--out", "/nonexistent/dir/x.npz"]) == 2
    assert "does not exist" in _one_line_error(capsys.readouterr().err)


def test_ctrl_c_during_compile_is_one_line_and_exit_130(capsys, tmp_path, monkeypatch):
    import lagcomp.runtime

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt
    monkeypatch.setattr(lagcomp.runtime, "build", interrupted)
    assert main(["--cache-dir", str(tmp_path), "run", "simple_pendulum"]) == 130
    line = _one_line_error(capsys.readouterr().err)
    assert "interrupted" in line and "cache is intact" in line
    assert not list((tmp_path / "index").glob("*.json"))  # nothing half-written was recorded


def test_show_and_bench_take_a_users_model_by_name(capsys, tmp_path):
    _user_model(tmp_path)
    assert main(["--cache-dir", str(tmp_path), "show", "cli_user_oscillator"]) == 0
    out = capsys.readouterr().out
    assert "coordinates q  = (x)" in out and "parameters  p  = (k, m)" in out and "generated module" in out
    # no default q0 and no default k: bench needs --q0 and --param (it had neither)
    bench = ["--cache-dir", str(tmp_path), "bench", "cli_user_oscillator", "--no-cold", "--methods", "rk4",
             "--repeats", "1", "--steps", "1000"]
    assert main(bench) == 2
    assert "q0" in _one_line_error(capsys.readouterr().err)
    assert main([*bench, "--q0", "1.0", "--param", "k=4"]) == 0
    out = capsys.readouterr().out
    assert "| rk4 |" in out and "failed" not in out


class _FlagAfterFirstChunk:
    """The Ctrl-C flag of `deferred_interrupt`, raised once the first chunk of a sweep is done."""

    def __init__(self):
        self.reads = 0

    def __getitem__(self, index):
        self.reads += 1
        return self.reads > 1


def test_sweep_interrupted_reports_the_rate_of_the_trajectories_done(capsys, cache_dir, monkeypatch):
    import contextlib

    import lagcomp.integrate.sweep as sweep_module

    monkeypatch.setattr(sweep_module, "deferred_interrupt", lambda: contextlib.nullcontext(_FlagAfterFirstChunk()))
    code = main(["--cache-dir", str(cache_dir), "sweep", "simple_pendulum", "--grid", "theta=0:1:400",
                 "--t-end", "0.5", "--workers", "1", "--quiet"])
    out = capsys.readouterr().out
    assert code == 130
    done = int(out.split("interrupted ")[1].split()[0])
    assert 0 < done < 400 and f"{done} of 400 trajectories done" in out
    assert f"over the {done} done" in out


def test_run_separates_numba_compilation_from_integration(capsys, cache_dir):
    assert main(["--cache-dir", str(cache_dir), "run", "simple_pendulum", "--t-end", "0.5", "--quiet"]) == 0
    captured = capsys.readouterr()
    assert "numba: kernels and driver ready in" in captured.err
    (wall,) = [line for line in captured.out.splitlines() if line.startswith("wall time")]
    assert "(integration; numba compilation or loading before it:" in wall


def test_check_writable_accepts_a_plain_file_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    check_writable("x.npz", "--out")  # the current directory
    check_writable(str(tmp_path / "x.npz"), "--out")


def test_ctrl_c_while_numba_compiles_stops_the_command(capsys, cache_dir, monkeypatch):
    """Ctrl-C lands in the first (warm-up) call, where numba compiles: the command stops there (the
    warm-up reaches its end in that call, so before it was swallowed and the whole run went on)."""
    import contextlib

    import lagcomp.integrate.simulate as simulate_module

    monkeypatch.setattr(simulate_module, "deferred_interrupt", lambda: contextlib.nullcontext([True]))
    assert main(["--cache-dir", str(cache_dir), "run", "simple_pendulum", "--t-end", "100", "--quiet"]) == 130
    out, err = capsys.readouterr()
    assert "final" not in out and "interrupted" in _one_line_error(err.split("\n", 1)[1])


def test_cache_warnings_are_one_line(capsys, tmp_path):
    model = _user_model(tmp_path, name="cli_warned")
    for data in cache_directory(model.source_path).glob("*.nbi"):
        data.write_bytes(b"broken")
    import sys

    for name in [n for n in sys.modules if n.startswith("lagcomp_generated_cli_warned_")]:
        del sys.modules[name]
    assert main(["--cache-dir", str(tmp_path), "show", "cli_warned"]) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err and all(line.startswith("lagcomp: warning: ") for line in err.splitlines())


def test_plot_without_matplotlib_is_refused_before_the_run(capsys, cache_dir, tmp_path, monkeypatch):
    import importlib.util

    find_spec = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *rest: None if name == "matplotlib" else find_spec(name, *rest))
    assert main(["--cache-dir", str(cache_dir), "run", "simple_pendulum", "--plot", str(tmp_path / "p.png")]) == 2
    out, err = capsys.readouterr()
    assert "final" not in out and "lagcomp[plots]" in _one_line_error(err)
