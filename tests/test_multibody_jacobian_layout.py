"""The on-demand kind "jacobians" of a tree laid out for numba's compile (issue 39, issue 35's compile cost).

Forward mode over the articulated-body algorithm (`lagcomp.multibody.forward_mode`) forms tens of thousands of
derivative assignments for a long chain.  numba's compile time grows with the code it types, so past
`lagcomp.codegen.tree_companion.STEP_ABOVE` assignments the Jacobians are stored flat (``_jac``: `out` seen 1-D)
and the derivatives carry the steps of the recursion they differentiate (its partials, then one direction after
another), so that `lagcomp.codegen.outline` emits the repeated ones once as shared helpers, as it does the
recursion's; a smaller tree's kernels stay the straight-line code they were.  Neither may change a bit: the stepped program
has the unstepped one's assignments in another (topological) order, and the helpers add and multiply in the
inline code's order.  A 20-link chain's Jacobian is checked against Richardson-extrapolated central differences of
its ``rhs`` (no code of forward mode's).
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.codegen import outline, tree_companion
from lagcomp.codegen.tree_companion import lower_tree_kind
from lagcomp.codegen.tree_locals import tree_locals
from lagcomp.codegen.tree_lower import motion
from lagcomp.examples.trees import planar_chain, spherical_chain
from lagcomp.multibody.forward_mode import derivatives
from lagcomp.multibody.program import PREFIX, Program


def _jacobian_program(tree, step_above):
    """(program, f, its derivatives) of the tree's Jacobians along (q, q̇, p), as the kind "jacobians" forms them."""
    local = tree_locals(tree)
    prog = Program()
    f = motion(prog, list(local.nodes), list(local.qd), list(local.gravity))
    start = len(prog.assignments)
    seeds = {s: {j: sp.S.One} for j, s in enumerate((*local.q, *local.qd, *local.p))}
    return prog, start, f, derivatives(prog, f, seeds, step_above=step_above)


def test_stepping_the_derivatives_changes_no_assignment():
    """The same locals bound to the same expressions, only emitted in another order, which reads no local before
    its assignment; each derivative of a step of the recursion is tagged by that step and "partials" or its
    direction, and the directions repeat over the chain's links."""
    tree = spherical_chain(2)
    plain, start, f, tangent = _jacobian_program(tree, None)
    stepped, start_stepped, f_stepped, tangent_stepped = _jacobian_program(tree, 0)
    assert (start_stepped, f_stepped, tangent_stepped) == (start, f, tangent)
    assert dict(stepped.assignments) == dict(plain.assignments)
    assert [a for a, _ in stepped.assignments] != [a for a, _ in plain.assignments]
    assert stepped.assignments[:start] == plain.assignments[:start]
    formed = set()
    for local, expr in stepped.assignments:
        assert {s for s in expr.free_symbols if s.name.startswith(PREFIX)} <= formed, local
        formed.add(local)
    keys = [stepped.step_of[local] for local, _ in stepped.assignments[start:]]
    assert all(plain.step_of[local] is None for local, _ in plain.assignments[start:])
    tagged = [key for key in keys if key is not None]
    assert len(tagged) > 0.9 * len(keys)
    assert {kind for _, kind in tagged} >= {"partials", *range(2 * tree.n)}
    assert len({step for step, _ in tagged}) == len({plain.step_of[local] for local, _ in plain.assignments[:start]}
                                                    - {None})


def test_a_small_trees_jacobians_stay_straight_line_and_a_larger_ones_are_outlined():
    """Below STEP_ABOVE the kernels are the unstepped program's (helpers inlined by LLVM ran a small tree's Jacobian
    ~25% slower); a larger tree's derivatives are outlined: they evaluate the same operations, compile fewer than
    half of them."""
    assert lower_tree_kind(planar_chain(2), "jacobians") == _unstepped(lambda: lower_tree_kind(planar_chain(2),
                                                                                                 "jacobians"))
    large = next(k for k in lower_tree_kind(planar_chain(8), "jacobians").kernels if k.name == "rhs_with_jacobian")
    plain = next(k for k in _unstepped(lambda: lower_tree_kind(planar_chain(8), "jacobians")).kernels
                 if k.name == "rhs_with_jacobian")
    assert outline.evaluated_operations(large) == outline.evaluated_operations(plain)
    assert large.operation_count < 0.5 * plain.operation_count


def _unstepped(build):
    """`build()` with the derivatives never stepped."""
    saved, tree_companion.STEP_ABOVE = tree_companion.STEP_ABOVE, None
    try:
        return build()
    finally:
        tree_companion.STEP_ABOVE = saved


def _jacobians(model, y, p, P):
    """Every output of the four Jacobian kernels at (y, p), concatenated."""
    size = y.size
    ydot, out, full = np.empty(size), np.empty((size, size)), np.empty((size, size + P))
    ydot_full, parameters, alone = np.empty(size), np.empty((size, P)), np.empty((size, size))
    kernels = model.kernels
    assert kernels.rhs_with_jacobian(0.3, y, p, ydot, out) == 0
    assert kernels.rhs_with_full_jacobian(0.3, y, p, ydot_full, full) == 0
    assert kernels.rhs_parameter_jacobian(0.3, y, p, parameters) == 0
    assert kernels.rhs_jacobian(0.3, y, p, alone) == 0
    return np.concatenate([ydot, out.ravel(), ydot_full, full.ravel(), parameters.ravel(), alone.ravel()])


def test_outlined_jacobians_compute_the_straight_line_bits(tmp_path, monkeypatch):
    """A 3-link chain's four Jacobian kernels stepped (helpers inlined by LLVM, or called past INLINE_LIMIT) give bit
    for bit what the unstepped straight-line kernels give, f bitwise ``rhs``'s."""
    tree = planar_chain(3)
    monkeypatch.setattr(tree_companion, "STEP_ABOVE", None)
    straight = lc.compile(tree, progress=False, cache_dir=tmp_path / "straight")
    assert straight.kernels.rhs_with_jacobian is not None
    monkeypatch.setattr(tree_companion, "STEP_ABOVE", 0)
    inlined = lc.compile(tree, progress=False, cache_dir=tmp_path / "inlined")
    assert inlined.kernels.rhs_with_jacobian is not None
    monkeypatch.setattr(outline, "INLINE_LIMIT", 0)
    called = lc.compile(tree, progress=False, cache_dir=tmp_path / "called")
    source = called.kernels.companion.entry("jacobians").path.read_text(encoding="utf-8")
    assert "forceinline=False" in source and "= _rhs_with_jacobian_step" in source
    rng = np.random.default_rng(3)
    P = len(tree.parameter_names)
    for _ in range(4):
        p = straight.parameter_vector({name: float(rng.uniform(0.5, 2.0)) for name in straight.parameters})
        y = rng.uniform(-2.0, 2.0, size=2 * tree.n)
        expected = _jacobians(straight, y, p, P)
        assert np.array_equal(_jacobians(inlined, y, p, P), expected)
        assert np.array_equal(_jacobians(called, y, p, P), expected)
        ydot = np.empty(2 * tree.n)
        straight.kernels.rhs(0.3, y, p, ydot)
        assert np.array_equal(expected[:2 * tree.n], ydot)


def _extrapolated_columns(rhs, y, h):
    """∂f/∂y by central differences of step h and h/2, Richardson-extrapolated (error O(h⁴)), and the difference
    between the extrapolation and the finer difference (an estimate of the latter's error, above the former's)."""
    def central(step):
        columns = []
        for j in range(y.size):
            e = np.zeros(y.size)
            e[j] = step
            columns.append((rhs(y + e) - rhs(y - e)) / (2 * step))
        return np.array(columns).T
    coarse, fine = central(h), central(h / 2)
    extrapolated = fine + (fine - coarse) / 3
    return extrapolated, np.max(np.abs(extrapolated - fine))


@pytest.mark.slow
def test_a_twenty_link_chains_jacobian_matches_extrapolated_differences_of_its_rhs(tmp_path):
    """planar_chain(20) (stepped: its helpers called): ∂f/∂y of ``rhs_with_jacobian`` against Richardson-extrapolated
    central differences of the eager ``rhs`` at random states, to 1e-8 of the largest entry (the extrapolation's
    truncation, h⁴ ~ 1e-10 times f's fifth derivatives, and round-off, 1e-16 / h ~ 1e-13, are both far below; a
    wrong term is O(1))."""
    tree = planar_chain(20)
    model = lc.compile(tree, progress=False, cache_dir=tmp_path)
    rng = np.random.default_rng(20)
    p = model.parameter_vector({name: float(rng.uniform(0.5, 1.5)) for name in model.parameters})
    size = 2 * tree.n

    def rhs(y):
        out = np.empty(size)
        assert model.kernels.rhs(0.0, y, p, out) == 0
        return out

    for _ in range(2):
        y = np.concatenate([rng.uniform(-0.6, 0.6, tree.n), rng.uniform(-1.0, 1.0, tree.n)])
        ydot, jacobian = np.empty(size), np.empty((size, size))
        assert model.kernels.rhs_with_jacobian(0.0, y, p, ydot, jacobian) == 0
        assert np.array_equal(ydot, rhs(y))
        reference, moved = _extrapolated_columns(rhs, y, 1e-3)
        scale = np.max(np.abs(reference))
        assert moved < 1e-6 * scale   # (the differences converge: the fine one is within 1e-6 already)
        assert np.max(np.abs(jacobian - reference)) <= 1e-8 * scale
