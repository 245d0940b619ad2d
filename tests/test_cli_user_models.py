"""User models first-class on the command line (issue 37, part 2): a System from a file or a module through every
subcommand, inputs from CSV tables, constants and numba functions, parameters and initial state from a TOML or
JSON file, and every subcommand's help examples run."""

from __future__ import annotations

import json
import re
import shlex
import shutil
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.cli import main
from lagcomp.cli_support.help import EXAMPLES
from lagcomp.model import t

REPOSITORY = Path(__file__).resolve().parents[1]

#: m ẍ = F(t): a mass pushed by an input, from rest at 0 (no bodies) -- and a particle version (bodies).
PUSHED_MASS = '''
import sympy as sp
import lagcomp as lc

x, = lc.coordinates("x")
m = sp.Symbol("m", positive=True)
pushed = lc.System([x], T=m * x.diff(lc.t) ** 2 / 2, forces=[lc.Input("F")], name="cli_pushed_mass",
                   defaults={"m": 2.0}, q0=(0.0,), qd0=(0.0,), t_end=1.0)
'''
PUSHED_PARTICLE = '''
import sympy as sp
import lagcomp as lc

def particle(m=2.0):
    x, = lc.coordinates("x")
    mass = sp.Symbol("m", positive=True)
    return lc.System([x], bodies=[lc.Particle(mass, (x, 0, 0), name="block")], forces=[lc.Input("F")],
                     name="cli_pushed_particle", defaults={"m": m}, q0=(0.0,), qd0=(0.0,), t_end=1.0)
'''
CONTROLLER = '''
import numba

@numba.njit
def push(t, y, p):
    return 3.0 * t
'''


def _final_x(out: str) -> float:
    return float(out.split("final       x=")[1].split()[0])


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """A folder holding the model files and tables, made the current directory."""
    (tmp_path / "mass.py").write_text(PUSHED_MASS, encoding="utf-8")
    (tmp_path / "particle.py").write_text(PUSHED_PARTICLE, encoding="utf-8")
    (tmp_path / "controller.py").write_text(CONTROLLER, encoding="utf-8")
    # F = 3 t sampled: the cubic spline and the straight segments of a linear signal are the signal
    (tmp_path / "ramp.csv").write_text("time,value\n0,0\n0.5,1.5\n1,3\n", encoding="utf-8")
    (tmp_path / "plain.csv").write_text("0,0\n1,3\n", encoding="utf-8")
    (tmp_path / "drive.csv").write_text("t,other,force\n0,9,0\n1,9,3\n", encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize("signal", ["F=ramp.csv", "F=plain.csv@linear", "F=drive.csv:force", "F=drive.csv:force@linear",
                                    "F=controller.py:push"])
def test_a_model_file_with_an_input_follows_the_closed_form(signal, capsys, cache_dir, workdir):
    """m ẍ = 3 t from rest: x(1) = 3/(6 m) = 1/4 for m = 2 (and 1/8 for m = 4 given by --param)."""
    argv = ["--cache-dir", str(cache_dir), "run", "mass.py", "--input", signal, "--quiet"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "model       cli_pushed_mass: pushed in mass.py" in out
    assert abs(_final_x(out) - 0.25) < 1e-9
    assert main([*argv, "--param", "m=4"]) == 0
    assert abs(_final_x(capsys.readouterr().out) - 0.125) < 1e-9


def test_a_constant_input_and_a_config_file(capsys, cache_dir, workdir):
    """F = 2 constant: x(t) = t²/m; from a config file (TOML and JSON alike), whose table path is relative to
    the file, and whose values the flags override."""
    base = ["--cache-dir", str(cache_dir), "run", "mass.py:pushed", "--quiet"]
    assert main([*base, "--input", "F=2"]) == 0
    assert abs(_final_x(capsys.readouterr().out) - 0.5) < 1e-12
    folder = workdir / "runs"
    folder.mkdir()
    shutil.copy(workdir / "ramp.csv", folder / "ramp.csv")
    (folder / "run.toml").write_text('t_end = 2.0\nq0 = [1.0]\nqd0 = [0.5]\n[params]\nm = 3.0\n[inputs]\nF = 2.0\n',
                                     encoding="utf-8")
    (folder / "run.json").write_text(json.dumps({"t_end": 2.0, "q0": [1.0], "qd0": [0.5], "params": {"m": 3.0},
                                                 "inputs": {"F": 2.0}}), encoding="utf-8")
    for config in ("runs/run.toml", "runs/run.json"):
        assert main([*base, "--config", config]) == 0
        assert abs(_final_x(capsys.readouterr().out) - (1.0 + 0.5 * 2 + 2.0 * 4 / (2 * 3.0))) < 1e-7  # 8 digits shown
    # flags win over the file; a table named in the file is read from the file's folder
    (folder / "table.toml").write_text('[inputs]\nF = "ramp.csv"\n', encoding="utf-8")
    assert main([*base, "--config", "runs/table.toml", "--param", "m=4", "--t-end", "1"]) == 0
    assert abs(_final_x(capsys.readouterr().out) - 0.125) < 1e-9


def test_a_user_model_through_every_subcommand(capsys, cache_dir, workdir):
    base = ["--cache-dir", str(cache_dir)]
    assert main([*base, "show", "particle.py:particle"]) == 0
    assert "model       cli_pushed_particle: particle() in particle.py" in capsys.readouterr().out
    assert main([*base, "sweep", "particle.py:particle", "--arg", "m=1", "--param", "m=1:4:4", "--input", "F=ramp.csv",
                 "--quiet", "--out", "sweep.csv"]) == 0
    assert "4 trajectories over m" in capsys.readouterr().out
    rows = np.loadtxt("sweep.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(rows[:, -2], 0.5 / np.array([1.0, 2.0, 3.0, 4.0]), rtol=1e-9)  # x(1) = 1/(2m)
    assert main([*base, "bench", "particle.py:particle", "--input", "F=1", "--methods", "rk4", "--repeats", "1",
                 "--steps", "100", "--no-cold"]) == 0
    assert "| rk4 |" in capsys.readouterr().out
    assert main([*base, "animate", "particle.py:particle", "--input", "F=ramp.csv", "-o", "clip.html", "--fps", "10",
                 "--quiet"]) == 0
    assert "11 frames" in capsys.readouterr().out and (workdir / "clip.html").stat().st_size > 1000
    assert main([*base, "animate", "mass.py", "--input", "F=ramp.csv", "-o", "clip2.html"]) == 2
    assert "has no bodies" in capsys.readouterr().err and not (workdir / "clip2.html").exists()
    assert main([*base, "stability", "mass.py", "--param", "m", "--range", "1", "2", "--input", "F=ramp.csv"]) == 2
    assert "give --input F=VALUE (a number; a table or a function varies with time)" in capsys.readouterr().err


SPRING_WITH_INPUT = '''
import sympy as sp
import lagcomp as lc

x, = lc.coordinates("x")
m, k = sp.symbols("m k", positive=True)
spring = lc.System([x], T=m * x.diff(lc.t) ** 2 / 2, V=k * x ** 2 / 2, forces=[lc.Input("F")],
                   name="cli_spring_input", defaults={"m": 1.0, "k": 4.0}, q0=(0.0,), qd0=(0.0,))
'''


def test_stability_holds_each_input_at_the_constant_given(capsys, cache_dir, workdir):
    """m ẍ = −k x + F with F held at 2: the equilibrium x = F/k = 0.5, eigenvalues ±i √(k/m) (k = 4: ±2i at m = 1,
    ±1i at m = 4); without the input the point is not steady, and the input must be a number."""
    (workdir / "spring.py").write_text(SPRING_WITH_INPUT, encoding="utf-8")
    base = ["--cache-dir", str(cache_dir), "stability", "spring.py", "--param", "m", "--range", "1", "4", "--num", "2",
            "--q", "0.5"]
    assert main([*base, "--input", "F=2"]) == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if line.startswith("m = ")]
    assert len(lines) == 2
    for line, omega in zip(lines, (2.0, 1.0)):
        eigenvalues = sorted((complex(z) for z in line.split()[4:]), key=lambda z: z.imag)
        assert len(eigenvalues) == 2 and max(abs(z.real) for z in eigenvalues) <= 1e-12
        np.testing.assert_allclose([z.imag for z in eigenvalues], [-omega, omega], rtol=1e-12)
    assert main(base) == 2
    assert "give --input F=VALUE" in capsys.readouterr().err


def test_a_model_from_a_module(capsys, cache_dir, workdir, monkeypatch):
    package = workdir / "userpkg"
    package.mkdir()
    (package / "__init__.py").write_text("", encoding="utf-8")
    (package / "models.py").write_text(PUSHED_MASS, encoding="utf-8")
    monkeypatch.syspath_prepend(str(workdir))
    assert main(["--cache-dir", str(cache_dir), "run", "userpkg.models", "--input", "F=2", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "pushed in userpkg.models" in out and abs(_final_x(out) - 0.5) < 1e-12


def test_stability_of_a_cached_user_model_says_what_it_needs(capsys, tmp_path):
    """Before: "Unknown example 'cli_cached_oscillator'" although `run` found the model."""
    x, = lc.coordinates("x")
    m, k = sp.symbols("m k", positive=True)
    lc.compile(lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, name="cli_cached_oscillator",
                         defaults={"m": 1.0, "k": 1.0}, q0=(0.0,)), cache_dir=tmp_path)
    assert main(["--cache-dir", str(tmp_path), "stability", "cli_cached_oscillator", "--param", "k", "--range", "1",
                 "2"]) == 2
    err = capsys.readouterr().err
    assert "Unknown example" not in err and "path/to/model.py" in err


def test_the_same_file_as_module_and_the_bare_name_it_compiled_under(capsys, cache_dir, workdir):
    """Running a file records its System's name, as lagcomp.compile does: the bare name then finds it."""
    assert main(["--cache-dir", str(cache_dir), "run", "mass.py", "--input", "F=2", "--quiet"]) == 0
    capsys.readouterr()
    assert main(["--cache-dir", str(cache_dir), "run", "cli_pushed_mass", "--input", "F=2", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "compiled earlier under this name" in out and abs(_final_x(out) - 0.5) < 1e-12


@pytest.mark.parametrize("command", sorted(EXAMPLES))
def test_every_help_example_runs(command, capsys, cache_dir, tmp_path, monkeypatch):
    """Each subcommand's --help shows its examples, and each runs (from a copy of the repository's examples/cli)."""
    with pytest.raises(SystemExit):
        main([command, "--help"])
    shown = capsys.readouterr().out
    shutil.copytree(REPOSITORY / "examples" / "cli", tmp_path / "examples" / "cli")
    monkeypatch.chdir(tmp_path)
    for line in EXAMPLES[command]:
        assert line in shown.replace("\n  ", " ") or f"  {line}" in shown, line
        words = shlex.split(line)
        assert words[0] == "lagcomp"
        quiet = ["--quiet"] if command in ("run", "sweep", "animate") else []
        assert main(["--cache-dir", str(cache_dir), *words[1:], *quiet]) == 0, (line, capsys.readouterr())
        capsys.readouterr()


def test_animate_a_chain_named_by_its_length(capsys, cache_dir, tmp_path):
    """`n_link_pendulum_3` is drawn as the chain it is (before: refused, as no example of that name draws)."""
    clip = tmp_path / "chain.html"
    assert main(["--cache-dir", str(cache_dir), "animate", "n_link_pendulum_3", "-o", str(clip), "--t-end", "0.4",
                 "--fps", "5", "--quiet"]) == 0
    assert "3 frames" in capsys.readouterr().out and clip.read_text(encoding="utf-8").count("data:image/png") == 3


finite = st.floats(-1e300, 1e300, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(rows=st.lists(st.tuples(finite, finite), min_size=2, max_size=20), header=st.booleans())
def test_a_table_reads_back_the_numbers_written(rows, header, tmp_path_factory):
    """Any finite numbers written with repr come back bit for bit, with or without a header row; times and values
    in their columns."""
    from lagcomp.cli_support.run_inputs import read_table

    path = tmp_path_factory.mktemp("tables") / "table.csv"
    lines = (["time,value"] if header else []) + [f"{a!r},{b!r}" for a, b in rows]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    times, values = read_table(path, None, "--input F")
    np.testing.assert_array_equal(times, [a for a, _ in rows])
    np.testing.assert_array_equal(values, [b for _, b in rows])


@pytest.mark.parametrize("text, spec, message", [
    ("0,1,2\n1,2,3\n", "F=t.csv", "has 3 columns"),
    ("time,value\n0,1\n1,x\n", "F=t.csv", "line 3"),
    ("0,1\n1,2\n", "F=t.csv:force", "no header row"),
    ("a,b\n0,1\n", "F=t.csv:b", "no column time (or t)"),
    ("", "F=t.csv", "is empty"),
    ("time,value\n0,1\n", "F=t.csv@spline", "@cubic (the default) or @linear"),
    ("time,value\n0,1\n", "F", "must look like NAME=2.5"),
    ("time,value\n0,1\n", "F=missing.csv", "cannot read"),
])
def test_a_bad_input_is_a_message_naming_it(text, spec, message, tmp_path):
    from lagcomp.cli_support.run_inputs import parse_input

    (tmp_path / "t.csv").write_text(text, encoding="utf-8")
    with pytest.raises(lc.LagcompError, match=re.escape(message)):
        parse_input(spec, tmp_path)


@pytest.mark.parametrize("text, suffix, message", [
    ('{"params": {"m": true}}', ".json", "params.m must be a number"),
    ('{"q0": "zero"}', ".json", "q0 must be a number"),
    ("[1, 2]", ".json", "expected a table of keys"),
    ("q0 = [", ".toml", "not valid TOML"),
    ("{", ".json", "not valid JSON"),
    ("m: 1", ".yaml", "the suffix names the format: .toml or .json"),
    ('params = 3', ".toml", "`params` must be a table"),
])
def test_a_bad_config_file_is_a_message_naming_it(text, suffix, message, tmp_path):
    from lagcomp.cli_support.run_inputs import read_config

    path = tmp_path / f"run{suffix}"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(lc.LagcompError, match=re.escape(message)):
        read_config(str(path))


def test_a_swept_parameter_wins_over_its_value_in_the_config(capsys, cache_dir, workdir):
    """m ẍ = 2 from rest: x(1) = 1/m over m in the sweep, although the config file sets m = 3."""
    (workdir / "run.json").write_text(json.dumps({"params": {"m": 3.0}, "inputs": {"F": 2.0}}), encoding="utf-8")
    assert main(["--cache-dir", str(cache_dir), "sweep", "mass.py", "--config", "run.json", "--param", "m=1:2:2",
                 "--t-end", "1", "--quiet", "--out", "sweep.csv"]) == 0
    assert "2 trajectories over m" in capsys.readouterr().out
    rows = np.loadtxt("sweep.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(rows[:, 3], [1.0, 0.5], rtol=1e-12)
