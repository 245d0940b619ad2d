"""The command line on a kinematic tree (issue 39): ``lagcomp run``, ``show``, ``sweep``, ``precompile`` and ``bench``
take a file's function returning an `lc.Tree` (``show --latex`` prints its recursion, `Model.equations()`);
``stability`` refuses it by name, without a traceback (`lagcomp.cli_support.trees`).

References: the same tree run through the Python API (``lc.compile(tree).simulate``), whose final state and energy
balance the command's report must print.
"""

from __future__ import annotations

import importlib.util
import re

import numpy as np
import pytest

import lagcomp as lc
from lagcomp.cli import main

#: A damped, driven 2-link planar chain (c a parameter, default 0.2), 1 s by default.
CHAIN = '''import lagcomp as lc
import sympy as sp


def chain():
    q0, q1 = lc.coordinates("q0 q1")
    c = sp.Symbol("c")
    return lc.Tree([
        lc.Link("upper", lc.Revolute(q0, axis="z", damping=c, torque=0.5 * sp.sin(3 * lc.t)), mass=1.0,
                com=(0.5, 0, 0), inertia=(0.05, 0.05, 0.1)),
        lc.Link("lower", lc.Revolute(q1, axis="z", origin=(1, 0, 0), damping=0.05), parent="upper", mass=1.0,
                com=(0.5, 0, 0), inertia=(0.05, 0.05, 0.1)),
    ], gravity=(0, -9.81, 0), name="cli_tree_chain", defaults={"c": 0.2}, q0=[0.4, -0.2], t_end=1.0)
'''


@pytest.fixture(scope="module")
def chain_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("cli_trees") / "my_tree.py"
    path.write_text(CHAIN, encoding="utf-8")
    return path


def _lagcomp(cache_dir, *argv) -> int:
    return main(["--cache-dir", str(cache_dir), *map(str, argv)])


def _tree(chain_file) -> lc.Tree:
    spec = importlib.util.spec_from_file_location("cli_tree_file", chain_file)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.chain()


def test_run_integrates_a_tree_from_a_file_and_balances_its_energy(cache_dir, chain_file, capsys):
    assert _lagcomp(cache_dir, "run", f"{chain_file}:chain", "--rtol", "1e-10", "--atol", "1e-12") == 0
    out = capsys.readouterr().out
    sol = lc.compile(_tree(chain_file), cache_dir=cache_dir).simulate((0.0, 1.0), rtol=1e-10, atol=1e-12)
    final = dict(item.strip().split("=") for item in out.split("final", 1)[1].splitlines()[0].split(","))
    assert [float(final["q0"]), float(final["q1"])] == pytest.approx(sol.q[-1], rel=1e-7)
    balance = sol.energy_balance()   # the damper and the torque: the report shows the balance, not the drift
    line = next(line for line in out.splitlines() if line.startswith("balance"))
    assert "T + V" in line
    for term in ("forces", "dissipation"):
        shown = float(re.search(rf"{term} (\S+?)[,)]", line).group(1))
        assert shown == pytest.approx(balance.work[term][-1], rel=1e-5) and abs(shown) > 0.1


def test_sweep_of_a_tree_reports_its_energy_balance(cache_dir, chain_file, capsys):
    assert _lagcomp(cache_dir, "sweep", f"{chain_file}:chain", "--param", "c=0:0.5:3", "--output",
                    "max-energy-error") == 0
    out = capsys.readouterr().out
    assert "3 trajectories over c (3 values)" in out
    line = next(line for line in out.splitlines() if line.startswith("energy"))
    assert "energy balance residual" in line and float(line.rsplit("max ", 1)[1]) < 1e-6


def test_show_lists_a_trees_links_and_joints(cache_dir, chain_file, capsys):
    assert _lagcomp(cache_dir, "show", f"{chain_file}:chain") == 0
    out = capsys.readouterr().out
    assert "[kinematic tree]" in out and "coordinates q  = (q0, q1)" in out and "parameters  p  = (c)" in out
    assert "upper        on (base)       Revolute(q0)" in out and "lower        on upper        Revolute(q1)" in out
    assert "articulated-body algorithm" in out and "| power" not in out and "power" in out   # (its operations)


def test_show_latex_prints_a_trees_recursion(cache_dir, chain_file, capsys):
    assert _lagcomp(cache_dir, "show", f"{chain_file}:chain", "--latex") == 0
    out = capsys.readouterr().out
    assert out == lc.compile(_tree(chain_file), cache_dir=cache_dir).equations().latex + "\n"
    lines = out.splitlines()
    assert r"{}^{2}X_{1} &= \operatorname{rot}\left(\operatorname{rz}\left(q_{1}\right)\right) " \
           r"\operatorname{xlt}\left(1, 0, 0\right) \\" in lines
    assert r"\tau_{1} &= - \dot{q}_{0} c + 0.5 \sin{\left(3 t \right)} \\" in lines   # (sympy's order)


@pytest.mark.parametrize(("argv", "message"), [
    (("stability", "--param", "c", "--range", "0", "1", "--q", "0", "0"),
     "lagcomp stability is not available for the kinematic tree 'cli_tree_chain'.*lagcomp.analysis.linearize"),
])
def test_what_a_tree_lacks_is_refused_by_name(cache_dir, chain_file, capsys, argv, message):
    command, *options = argv
    assert _lagcomp(cache_dir, command, f"{chain_file}:chain", *options) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert re.search(message, err), err


def test_precompile_all_builds_a_trees_kinds_and_bench_skips_what_it_lacks(cache_dir, chain_file, capsys):
    assert _lagcomp(cache_dir, "precompile", f"{chain_file}:chain", "--all") == 0
    out = capsys.readouterr().out
    assert "on-demand kernels (power)" in out and "on-demand kernels (taylor)" in out
    assert _lagcomp(cache_dir, "bench", f"{chain_file}:chain", "--methods", "rk4", "taylor", "gauss2",
                    "--repeats", "1", "--steps", "200", "--no-cold") == 0
    rows = {line.split("|")[1].strip(): line for line in capsys.readouterr().out.splitlines()
            if line.startswith("| ") and line.count("|") == 7}
    assert np.isfinite(float(rows["taylor"].split("|")[4].split()[0]))   # (the tree's Taylor program)
    assert np.isfinite(float(rows["gauss2"].split("|")[4].split()[0]))   # the tree's canonical kind
    assert np.isfinite(float(rows["rk4"].split("|")[4].split()[0]))
