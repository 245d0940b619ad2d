"""What `lagcomp run` / `sweep` write (issue 36, items 2.4 and 2.5): the file the user named, in the
format its suffix names, or a refusal before the run; and which model a name on the command line ran."""

from __future__ import annotations

import csv

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.cli import main
from lagcomp.model import t

RUN = ["run", "simple_pendulum", "--t-end", "0.5", "--quiet"]


def _saved_line(out: str) -> str:
    (line,) = [line for line in out.splitlines() if line.startswith("saved")]
    return line


def test_out_csv_writes_csv_under_the_name_given(capsys, cache_dir, tmp_path):
    target = tmp_path / "run.csv"
    assert main(["--cache-dir", str(cache_dir), *RUN, "--out", str(target)]) == 0
    assert str(target) in _saved_line(capsys.readouterr().out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.csv"]
    with target.open(newline="") as handle:
        rows = list(csv.reader(handle))
    assert rows[0][:3] == ["t", "theta", "theta_dot"] and "energy" in rows[0]
    table = np.array(rows[1:], dtype=float)
    npz = tmp_path / "run.npz"
    assert main(["--cache-dir", str(cache_dir), *RUN, "--out", str(npz)]) == 0
    with np.load(npz) as data:  # the same run: the CSV holds its rows, to the 17 digits written
        np.testing.assert_array_equal(table[:, 0], data["t"])
        np.testing.assert_array_equal(table[:, 1], data["q"][:, 0])
        np.testing.assert_array_equal(table[:, 2], data["qd"][:, 0])


def test_out_netcdf_through_xarray(capsys, cache_dir, tmp_path):
    xr = pytest.importorskip("xarray")
    target = tmp_path / "run.nc"
    assert main(["--cache-dir", str(cache_dir), *RUN, "--out", str(target)]) == 0
    assert str(target) in _saved_line(capsys.readouterr().out)
    with xr.open_dataset(target) as data:
        assert data["t"].values[-1] == 0.5 and data["theta"].shape == data["t"].shape


@pytest.mark.parametrize("name", ["run.txt", "run", "run.npz.bak"])
def test_out_with_another_suffix_is_refused_before_the_run(capsys, cache_dir, tmp_path, monkeypatch, name):
    monkeypatch.setattr(lc.Model, "simulate", lambda *a, **k: pytest.fail("the run started"))
    assert main(["--cache-dir", str(cache_dir), *RUN, "--out", str(tmp_path / name)]) == 2
    err = capsys.readouterr().err
    assert name in err and ".npz" in err and ".csv" in err and ".nc" in err
    assert not list(tmp_path.iterdir())


def test_plot_writes_the_file_named_or_refuses(capsys, cache_dir, tmp_path):
    pytest.importorskip("matplotlib")
    assert main(["--cache-dir", str(cache_dir), *RUN, "--plot", str(tmp_path / "runplot")]) == 2
    err = capsys.readouterr().err
    assert "runplot" in err and ".png" in err and not list(tmp_path.iterdir())
    target = tmp_path / "runplot.pdf"
    assert main(["--cache-dir", str(cache_dir), *RUN, "--plot", str(target)]) == 0
    (line,) = [line for line in capsys.readouterr().out.splitlines() if line.startswith("plotted")]
    assert str(target) in line and target.read_bytes().startswith(b"%PDF")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["runplot.pdf"]


def test_sweep_out_by_suffix(capsys, cache_dir, tmp_path):
    argv = ["--cache-dir", str(cache_dir), "sweep", "simple_pendulum", "--grid", "theta=0.1:0.3:3", "--t-end", "0.5",
            "--quiet", "--out"]
    target = tmp_path / "sweep.csv"
    assert main([*argv, str(target)]) == 0
    assert str(target) in _saved_line(capsys.readouterr().out)
    with target.open(newline="") as handle:
        rows = list(csv.reader(handle))
    assert rows[0][:2] == ["theta", "status"] and len(rows) == 4
    np.testing.assert_array_equal(np.array([r[0] for r in rows[1:]], dtype=float), [0.1, 0.2, 0.3])
    assert main([*argv, str(tmp_path / "sweep.json")]) == 2
    assert "sweep.json" in capsys.readouterr().err


def test_a_users_model_named_like_an_example(capsys, tmp_path):
    """The rule: a bare name is the bundled example; the user's model of that name runs with --cached (or from
    its file), and every command says which one it ran."""
    x, = lc.coordinates("x")
    m, k = sp.symbols("m k", positive=True)
    lc.compile(lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, name="double_pendulum",
                         defaults={"m": 1.0, "k": 4.0}, q0=(1.0,)), cache_dir=tmp_path)
    assert main(["--cache-dir", str(tmp_path), "run", "double_pendulum", "--t-end", "0.1", "--quiet"]) == 0
    out, err = capsys.readouterr()
    assert "model       double_pendulum: the bundled example" in out and "theta1=" in out
    assert "--cached" in err  # the note that the user's own model of that name was not the one run
    assert main(["--cache-dir", str(tmp_path), "run", "double_pendulum", "--cached", "--t-end", "1.0",
                 "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "model       double_pendulum: compiled earlier under this name" in out
    final = float(out.split("final       x=")[1].split()[0])
    assert abs(final - np.cos(2.0)) < 1e-7
