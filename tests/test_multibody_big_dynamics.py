"""The on-demand kind "dynamics" (``Model.mass_matrix``, ``Model.forcing``) of big trees (issue 39, issue 35's compile
cost): M and F against `lagcomp.accuracy.tree_reference` (d'Alembert's principle in many digits, none of the
recursions' code), M symmetric positive definite, and M q̈ = F against the articulated-body ``rhs``.

A long chain's M has n² entries formed by n² / 2 steps of the composite-rigid-body algorithm (and, with ball
joints, n² / 3 block products by the MRP chart's Jᵀ): emitted as calls of a few shared helpers
(`lagcomp.codegen.outline`), so the kernel compiles in time linear in its size; the arithmetic is the same as
inline (`test_stepping_the_chart_changes_no_assignment`).
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import sympy as sp
from random_systems import python_kernels

import lagcomp as lc
from lagcomp.accuracy import tree_reference
from lagcomp.codegen.tree_locals import tree_locals
from lagcomp.examples.trees import planar_chain, spherical_chain
from lagcomp.multibody.charts import mass_matrix_in_coordinates
from lagcomp.multibody.crba import mass_matrix
from lagcomp.multibody.program import Program

#: Normwise relative error allowed against the reference (exact to 25 digits): about 4,500 ulps of the largest
#: entry, room for the round-off of sums over the 30 to 45 links' composite inertias, far below any wrong term.
RELATIVE = 1e-12


def ball_and_hinge_tree() -> lc.Tree:
    """A branched tree of 45 coordinates: a ball-jointed trunk of 5 links, each carrying a ball-jointed arm of one
    link and a hinged (z) finger on it, gravity −g along z."""
    g = sp.Symbol("g", positive=True)
    links = []
    for i in range(5):
        m, c, A, B, C, l = sp.symbols(f"m{i} c{i} A{i} B{i} C{i} l{i}")
        links.append(lc.Link(f"trunk{i}", lc.Spherical((f"s{i}x", f"s{i}y", f"s{i}z"),
                                                       origin=(0, 0, 0) if i == 0 else (0, 0, -l)),
                             parent=None if i == 0 else f"trunk{i - 1}", mass=m, com=(0, 0, -c), inertia=(A, B, C)))
        a, k = sp.symbols(f"a{i} k{i}")
        links.append(lc.Link(f"arm{i}", lc.Spherical((f"u{i}x", f"u{i}y", f"u{i}z"), origin=(a, 0, 0)),
                             parent=f"trunk{i}", mass=k, com=(a / 2, 0, 0), inertia=(k, 2 * k, 2 * k)))
        links.append(lc.Link(f"finger{i}", lc.Revolute(f"f{i}", axis="z", origin=(a, 0, 0)), parent=f"arm{i}",
                             mass=k / 3, com=(a / 4, a / 5, 0), inertia=(k / 7, k / 5, k / 3)))
    return lc.Tree(links, gravity=(0, 0, -g), name="ball_and_hinge_tree")


def _parameters(tree, rng) -> dict:
    return {name: (9.81 if name == "g" else float(rng.uniform(0.8, 1.4))) for name in tree.parameter_names}


def _check(tree, cache_dir, states: int):
    """M, F at `states` random states: against the reference, M symmetric positive definite, M q̈ = F with rhs's q̈
    (the articulated-body ``rhs`` run as plain Python: a reference here, which numba need not compile)."""
    model = lc.compile(tree, cache_dir=cache_dir)
    rhs = python_kernels(model.source_path.read_text(encoding="utf-8"))["rhs"]
    reference = tree_reference(tree)
    rng = np.random.default_rng(39)
    params = _parameters(tree, rng)
    p = model.parameter_vector(params)
    for _ in range(states):
        q, qd = rng.uniform(-0.6, 0.6, model.n), rng.uniform(-1.0, 1.0, model.n)
        M, F = model.mass_matrix(q, params=params), model.forcing(q, qd, params=params)
        M_ref, F_ref = reference.mass_matrix_and_forcing(0.0, np.concatenate([q, qd]), p, 25)
        with mpmath.workdps(25):
            M_ref = np.array([[float(x) for x in row] for row in M_ref])
            F_ref = np.array([float(x) for x in F_ref])
        assert np.max(np.abs(M - M_ref)) <= RELATIVE * np.max(np.abs(M_ref))
        assert np.max(np.abs(F - F_ref)) <= RELATIVE * np.max(np.abs(F_ref))
        assert np.array_equal(M, M.T)                   # each pair of entries is one local, stored twice
        assert np.all(np.diag(np.linalg.cholesky(M)) > 0)
        ydot = np.empty(2 * model.n)
        assert rhs(0.0, np.concatenate([q, qd]), p, ydot) == 0
        qdd = ydot[model.n:]
        assert np.max(np.abs(M @ qdd - F)) <= RELATIVE * (np.max(np.abs(M)) * np.max(np.abs(qdd)) + np.max(np.abs(F)))


def test_a_30_link_planar_chain(cache_dir):
    """30 hinges (435 column steps of the composite-rigid-body algorithm, all calls of one helper)."""
    _check(planar_chain(30), cache_dir, states=3)


@pytest.mark.slow
@pytest.mark.parametrize("build", [lambda: spherical_chain(10), ball_and_hinge_tree], ids=["spherical_10", "branched"])
def test_ball_jointed_trees(build, cache_dir):
    """30 and 45 coordinates on ball joints: the chart's block products are calls too."""
    _check(build(), cache_dir, states=2)


@pytest.mark.parametrize("build", [lambda: spherical_chain(4), ball_and_hinge_tree], ids=["spherical_4", "branched"])
def test_stepping_the_chart_changes_no_assignment(build):
    """M_σ = Tᵀ M_ω T formed in steps (what the kernel emits) and without: the same assignments, in the same order,
    with the same local names, and the same entries; only the steps they are tagged with differ, so the emitted
    arithmetic is the same (`lagcomp.codegen.outline` emits a step's assignments unchanged)."""
    nodes = list(tree_locals(build()).nodes)
    programs, results = [], []
    for stepped in (False, True):
        prog = Program()
        results.append(mass_matrix_in_coordinates(prog, nodes, mass_matrix(prog, nodes), stepped=stepped))
        programs.append(prog)
    assert results[0] == results[1]
    assert programs[0].assignments == programs[1].assignments
    chart_steps = {key for key in programs[1].step_of.values() if key and str(key[0]).startswith("chart")}
    assert len(chart_steps) >= len(nodes)          # each block product its own step
    assert not any(key and str(key[0]).startswith("chart") for key in programs[0].step_of.values())
