"""Kinematic trees (lc.Tree, issue 39's first step): the articulated-body rhs against the Lagrangian path and
Pinocchio, the other recursions (M, F, momenta, energy) against each other, a run's energy, and the refusals.

The Lagrangian path's models are the same systems written with lc.RigidBody and lc.rotated
(`multibody_models.lagrangian_system`): derived from T and V by sympy, so they share no code with the recursions
but the Tree's description.
"""

from __future__ import annotations

import pickle

import multibody_models as mm
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp import analysis as an
from lagcomp.tree_model import TreeModel


def _draw(data, model, scale=1.0):
    """Random parameters (0.5 to 2, by name) and a state (q, q̇ within ±2 scale) for `model`."""
    values = st.floats(0.5, 2.0, allow_nan=False)
    params = {name: data.draw(values, label=name) for name in model.parameters}
    y = np.array(data.draw(st.lists(st.floats(-2.0 * scale, 2.0 * scale, allow_nan=False), min_size=2 * model.n,
                                    max_size=2 * model.n), label="y"))
    return params, y


def _relative(a, b) -> float:
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


@pytest.mark.parametrize("name", mm.PAIRS)
@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_accelerations_and_energy_agree_with_the_lagrangian_path(tree_pair, name, data):
    tree_model, lagrange_model = tree_pair(name)
    params, y = _draw(data, tree_model)
    t = data.draw(st.floats(0.0, 10.0), label="t")
    assert tree_model.parameters == lagrange_model.parameters
    assert _relative(tree_model.rhs(t, y, params), lagrange_model.rhs(t, y, params)) <= 1e-12
    energies = [model.kernels.energy(t, y, model.parameter_vector(params)) for model in (tree_model, lagrange_model)]
    assert abs(energies[0] - energies[1]) <= 1e-12 * max(abs(energies[1]), 1.0)


@pytest.mark.parametrize("name", mm.PAIRS)
@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_mass_matrix_forcing_and_momenta_agree_with_the_lagrangian_path(tree_pair, name, data):
    tree_model, lagrange_model = tree_pair(name)
    params, y = _draw(data, tree_model)
    n = tree_model.n
    for kernel, shape in (("mass_matrix", (n, n)), ("forcing", (n,)), ("momenta", (n,))):
        got, want = np.empty(shape), np.empty(shape)
        getattr(tree_model.kernels, kernel)(0.7, y, tree_model.parameter_vector(params), got)
        getattr(lagrange_model.kernels, kernel)(0.7, y, lagrange_model.parameter_vector(params), want)
        assert _relative(got, want) <= 1e-12, kernel


def test_the_rhs_kernel_is_straight_line_code_from_the_recursion(tree_pair):
    """The articulated-body rhs of a chain holds one sine and one cosine per joint and no linear solve."""
    tree_model, _ = tree_pair("planar_chain_4")
    source = tree_model.source_path.read_text(encoding="utf-8")
    start = source.index("def rhs(")
    rhs = source[start:source.index("\ndef ", start)]
    assert rhs.count("sin(q_th") == 4 and rhs.count("cos(q_th") == 4
    assert "PIVOT" not in rhs and "solve" not in rhs and "for " not in rhs
    assert isinstance(tree_model, TreeModel)


def test_a_run_keeps_the_energy_of_a_conservative_tree(tree_pair):
    model, _ = tree_pair("universal_chain_2")
    params = {name: 1.0 for name in model.parameters} | {"g": 9.81, "A0": 0.3, "B0": 0.4, "C0": 0.2}
    sol = model.simulate((0.0, 10.0), q0=[1.0, -0.5, 0.3, 0.8], qd0=[0.0, 1.0, -1.0, 0.5], params=params,
                         rtol=1e-12, atol=1e-12)
    assert sol.success and sol.t[-1] == 10.0
    energy = sol.energy
    assert np.max(np.abs(energy - energy[0])) <= 1e-9 * abs(energy[0])
    assert np.max(np.abs(energy - energy[0])) > 0   # (a real run: the energy is evaluated along it, not a constant)


def test_a_tree_model_loads_from_the_cache_by_name(tree_pair, cache_dir):
    compiled, _ = tree_pair("rigid_double_pendulum")
    loaded = lc.load("rigid_double_pendulum", cache_dir=cache_dir)
    assert isinstance(loaded, TreeModel) and loaded.from_cache and loaded.parameters == compiled.parameters
    params = {name: 1.0 for name in loaded.parameters}
    y = np.array([0.3, -0.4, 0.5, 0.1])
    assert np.array_equal(loaded.rhs(0.0, y, params), compiled.rhs(0.0, y, params))


def test_a_tree_model_pickles_as_a_tree_model(tree_pair):
    tree_model, _ = tree_pair("cart_pole")
    copy = pickle.loads(pickle.dumps(tree_model))
    assert isinstance(copy, TreeModel) and copy.cache_key == tree_model.cache_key
    params = {name: 1.0 for name in copy.parameters}
    y = np.array([0.3, -0.4, 0.5, 0.1])
    assert np.array_equal(copy.rhs(0.2, y, params), tree_model.rhs(0.2, y, params))


# -- against Pinocchio ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", range(6))
def test_random_trees_agree_with_pinocchio(cache_dir, seed):
    """Random topologies, unaligned axes, rotated placements, prismatic joints, springs and dampers: q̈ against
    Pinocchio's ABA, M against its inverse dynamics, T + V against its energies, at random states."""
    pin = pytest.importorskip("pinocchio")
    tree, _ = mm.random_tree(seed)
    model = lc.compile(tree, cache_dir=cache_dir)
    reference = mm.pinocchio_model(tree, {})
    data = reference.createData()
    rng = np.random.default_rng(seed)
    n, p = tree.n, model.parameter_vector()
    stiffness = np.array([float(node.joint.stiffness) for node in tree.nodes])
    rest = np.array([float(node.joint.rest) for node in tree.nodes])
    damping = np.array([float(node.joint.damping) for node in tree.nodes])
    for _ in range(5):
        q, v = rng.normal(size=n), rng.normal(size=n)
        y = np.concatenate([q, v])
        tau = -stiffness * (q - rest) - damping * v
        assert _relative(model.rhs(0.0, y)[n:], pin.aba(reference, data, q, v, tau)) <= 1e-12
        M = np.empty((n, n))
        model.kernels.mass_matrix(0.0, y, p, M)
        # M's columns from Pinocchio's inverse dynamics (its crba, pin 4.1.0, leaves zeros where an unaligned
        # prismatic joint couples two others, which its own rnea contradicts)
        bias = pin.rnea(reference, data, q, np.zeros(n), np.zeros(n)).copy()
        columns = [pin.rnea(reference, data, q, np.zeros(n), e) - bias for e in np.eye(n)]
        assert _relative(M, np.column_stack(columns)) <= 1e-12
        energy = (pin.computeKineticEnergy(reference, data, q, v) + pin.computePotentialEnergy(reference, data, q)
                  + np.sum(stiffness * (q - rest) ** 2) / 2)
        assert abs(model.kernels.energy(0.0, y, p) - energy) <= 1e-12 * max(abs(energy), 1.0)


# -- refusals -------------------------------------------------------------------------------------------------------


def test_kernels_of_later_steps_are_refused_naming_the_feature_and_the_issue(tree_pair):
    tree_model, _ = tree_pair("rigid_double_pendulum")
    params = {name: 1.0 for name in tree_model.parameters}
    assert set(tree_model.operations) >= {"rhs", "mass_matrix", "forcing", "energy", "momenta"}
    with pytest.raises(lc.ModelError, match=r"energy_lanes.*issue 39"):
        _ = tree_model.kernels.energy_lanes   # (rhs_lanes: tests/test_multibody_lanes.py; Model.equations():
        # tests/test_multibody_equations.py)
    with pytest.raises(lc.ModelError, match=r"conserved_quantities.*issue 39"):
        an.conserved_quantities(tree_model)
    assert lc.kernel_accuracy(tree_model, n=2, params=params)["rhs"].max_normwise < 64   # (no longer refused:
    # tests/test_multibody_accuracy.py)


@pytest.mark.parametrize("links, culprit", [
    ([lc.Link("a", lc.Revolute("q"), parent="ghost", mass=1.0)], "ghost"),
    ([lc.Link("a", lc.Revolute("q"), mass=1.0), lc.Link("b", lc.Revolute("q"), parent="a", mass=1.0)], "['q']"),
    ([lc.Link("a", lc.Revolute("q", axis=(0, 0, 0)), mass=1.0)], "zero vector"),
    ([lc.Link("a", lc.Revolute("q", rotation=[[1, 0, 0], [0, 1, 0], [0, 0, -1]]), mass=1.0)], "not a rotation"),
    ([lc.Link("a", lc.Revolute("q"), mass=-1.0)], "negative mass"),
    ([lc.Link("a", lc.Universal(("u",)), mass=1.0)], "needs 2 coordinates"),
])
def test_bad_trees_are_refused_naming_the_culprit(links, culprit):
    with pytest.raises(lc.ModelError) as raised:
        lc.Tree(links)
    assert culprit in str(raised.value)


def test_a_measured_axis_keeps_every_digit(cache_dir):
    """A revolute axis given as floats with a small component (a URDF's, 0.889, −1.2e-7, −8.2e-5) is normalised
    in floats, not rounded to a 'simple' number (sympy's nsimplify had lost ~(8e-5)² relative: q̈ off by 7e-9);
    q̈ of one link against its closed form in 40 digits: q̈ = a·(R c × m g) / (aᵀ I_c a + m (|c|² − (a·c)²)),
    R the rotation by q about the unit axis a (which aᵀR leaves unchanged), to 1e-14."""
    import mpmath as mp

    axis = ("0.8890544428788574", "-1.192092896e-07", "-8.201873536694457e-05")
    c, moments, mass, g = ("-0.34", "-0.13", "0.29"), ("0.94", "0.76", "1.63"), "0.89", "-9.81"
    tree = lc.Tree([lc.Link("arm", lc.Revolute("q", axis=tuple(float(x) for x in axis)), mass=float(mass),
                            com=tuple(float(x) for x in c), inertia=tuple(float(x) for x in moments))],
                   gravity=(0, 0, float(g)), name="measured_axis")
    model = lc.compile(tree, cache_dir=cache_dir)
    with mp.workdps(40):
        a = mp.matrix([mp.mpf(float(x)) for x in axis])
        a /= mp.norm(a)
        cv, m = mp.matrix([mp.mpf(float(x)) for x in c]), mp.mpf(float(mass))
        inertia = sum(a[k] ** 2 * mp.mpf(float(moments[k])) for k in range(3)) + m * (
            mp.fdot(cv, cv) - mp.fdot(a, cv) ** 2)
        K = mp.matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
        for q in (0.3, -1.7, 2.9):
            R = mp.eye(3) + mp.sin(q) * K + (1 - mp.cos(q)) * K * K
            r = R * cv
            weight = mp.matrix([0, 0, m * mp.mpf(float(g))])
            torque = mp.fdot(a, mp.matrix([r[1] * weight[2] - r[2] * weight[1], r[2] * weight[0] - r[0] * weight[2],
                                           r[0] * weight[1] - r[1] * weight[0]]))
            exact = float(torque / inertia)
            assert abs(model.rhs(0.0, np.array([q, 0.0]))[1] - exact) <= 1e-14 * abs(exact)


# -- repeated steps emitted once (lagcomp.codegen.outline) ----------------------------------------------------------


def test_a_chains_repeated_steps_are_shared_helpers_that_compute_the_same_bits(tmp_path, monkeypatch):
    """A 3D chain of four universal-jointed links (the fewest whose rhs has helpers; three have
    none): its rhs calls helpers for the steps the links repeat, compiles fewer operations than it evaluates, and
    gives bit for bit the q̈ of the same rhs emitted without helpers, whether LLVM inlines them (a small kernel) or
    calls them (past `INLINE_LIMIT`)."""
    from lagcomp.codegen import outline
    from lagcomp.codegen.tree_lower import lower_tree

    tree = mm.universal_chain(4)
    rhs = next(k for k in lower_tree(tree).kernels if k.name == "rhs")
    assert rhs.helpers and rhs.operation_count < outline.evaluated_operations(rhs)
    shared = lc.compile(tree, cache_dir=tmp_path / "shared")
    source = shared.source_path.read_text(encoding="utf-8")
    assert "forceinline=True" in source and "= _rhs_step0(" in source
    monkeypatch.setattr(outline, "INLINE_LIMIT", 0)
    called = lc.compile(tree, cache_dir=tmp_path / "called")
    assert "forceinline=False" in called.source_path.read_text(encoding="utf-8")
    monkeypatch.setattr(outline, "MIN_CALLS", 10 ** 9)
    inline = lc.compile(tree, cache_dir=tmp_path / "inline")
    assert "_rhs_step" not in inline.source_path.read_text(encoding="utf-8")
    rng = np.random.default_rng(7)
    for _ in range(5):
        params = {name: float(rng.uniform(0.5, 2.0)) for name in shared.parameters}
        y = rng.uniform(-2.0, 2.0, size=2 * tree.n)
        expected = inline.rhs(0.3, y, params)
        assert np.array_equal(shared.rhs(0.3, y, params), expected)
        assert np.array_equal(called.rhs(0.3, y, params), expected)


def test_a_long_planar_chain_agrees_with_pinocchio(cache_dir):
    """Twelve links (helpers shared by ten of them) against Pinocchio's ABA at random states."""
    pin = pytest.importorskip("pinocchio")
    tree = mm.planar_chain(12)
    model = lc.compile(tree, cache_dir=cache_dir)
    rng = np.random.default_rng(12)
    for _ in range(5):
        values = {name: float(rng.uniform(0.5, 1.5)) for name in model.parameters}
        reference = mm.pinocchio_model(tree, values)
        q, v = rng.normal(size=tree.n), rng.normal(size=tree.n)
        expected = pin.aba(reference, reference.createData(), q, v, np.zeros(tree.n))
        assert _relative(model.rhs(0.0, np.concatenate([q, v]), values)[tree.n:], expected) <= 1e-12
