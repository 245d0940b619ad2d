"""Jacobians, radau and sensitivities of kinematic trees with closed loops (`lc.Loop`), through the public API.

The reference is today's four-bar (`four_bar_linkage`, absolute angles, its constraints and their exact symbolic
Jacobians written by the Lagrangian path, `lagcomp.codegen.constrained_jacobian`), which nobody on the tree path
wrote.  The tree's coordinates are y_t = T y (T = diag(A, A), A the map (θ1, θ2, θ3) → (θ1, θ2 − θ1, θ3)), both
models' constraints are the same functions Φ(q) and their multipliers the same pin force
(`tests/test_multibody_loops.py`), so the tree's f_t(y_t) = T f(T⁻¹ y_t) and

    ∂f_t/∂y_t = T (∂f/∂y) T⁻¹,   ∂f_t/∂p = T ∂f/∂p,   ∂λ/∂y_t = (∂λ/∂y) T⁻¹,   ∂λ/∂p the same,

exactly, Baumgarte terms included, on the loop and off it: to 1e-12 relative at random states and parameters.
The DAE kernels radau integrates (`lagcomp.integrate.dae`) map likewise (`test_the_dae_kernels_are_the_examples`);
the tangent kernels of a one-column sensitivity run are the full Jacobians' product along the direction.
Runs: radau against dop853 at tight tolerance and against the example's radau; sensitivities against the example's
(the same ODE in other coordinates: S_t = T S T⁻¹) and against Richardson-extrapolated central differences of runs.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_multibody_loops import (
    FOUR_BAR_PARAMETERS,
    TO_TREE,
    four_bar_tree,
    lagrangian_with_loops,
    spatial_tree,
)

import lagcomp as lc
from lagcomp.examples.constrained import four_bar_closure, four_bar_linkage

#: The state map y_t = T y of the tree's coordinates from the example's, and its inverse.
T = np.kron(np.eye(2), TO_TREE)
T_INV = np.linalg.inv(T)


@pytest.fixture(scope="module")
def four_bars(cache_dir):
    """(the tree's model, the example's model)."""
    return lc.compile(four_bar_tree(), cache_dir=cache_dir), lc.compile(four_bar_linkage(), cache_dir=cache_dir)


def relative(x, reference) -> float:
    return float(np.max(np.abs(x - reference)) / np.max(np.abs(reference)))


def jacobians(model, y, p):
    """(f, ∂f/∂y, ∂f/∂p, ∂f/∂(y, p) and its f, ∂λ/∂(y, p)) of `model` at (y, p), each kernel's status 0."""
    N, P = model.state_size, len(model.parameters)
    f, J, Jp, full, f_full, R = (np.zeros(N), np.zeros((N, N)), np.zeros((N, P)), np.zeros((N, N + P)),
                                 np.zeros(N), np.zeros((model.k, N + P)))
    kernels = model.kernels
    assert kernels.rhs_with_jacobian(0.0, y, p, f, J) == 0
    assert kernels.rhs_parameter_jacobian(0.0, y, p, Jp) == 0
    assert kernels.rhs_with_full_jacobian(0.0, y, p, f_full, full) == 0
    assert kernels.reaction_jacobian(0.0, y, p, R) == 0
    return f, J, Jp, full, f_full, R


@settings(max_examples=30, deadline=None)
@given(theta1=st.floats(0.0, 2 * math.pi), rate=st.floats(-20.0, 20.0), off=st.tuples(*[st.floats(-0.05, 0.05)] * 2),
       rates=st.tuples(*[st.floats(-3.0, 3.0)] * 2), gains=st.tuples(*[st.floats(0.0, 5.0)] * 2),
       params=FOUR_BAR_PARAMETERS)
def test_the_jacobians_are_the_examples_in_the_trees_coordinates(four_bars, theta1, rate, off, rates, gains, params):
    """∂f/∂y, ∂f/∂p (alone and together) and ∂λ/∂(y, p) to 1e-12 relative (module docstring), off the loop
    (Φ ≠ 0, Λ q̇ ≠ 0) with Baumgarte gains; f of every kernel is `rhs`'s bitwise; `Model.jacobian` is the kernel's."""
    tree, example = four_bars
    q, qd = (np.array(v) for v in four_bar_closure(params, theta1, rate))
    q[1:] += off
    qd[1:] += rates
    y = np.concatenate([q, qd])
    p_tree, p = tree.parameter_vector(params, baumgarte=gains), example.parameter_vector(params, baumgarte=gains)
    f_t, J_t, Jp_t, full_t, f_full_t, R_t = jacobians(tree, T @ y, p_tree)
    _, J, Jp, _, _, R = jacobians(example, y, p)
    order = [tree.parameters.index(name) for name in example.parameters]   # (the tree lists them sorted)
    N = tree.state_size
    assert relative(J_t, T @ J @ T_INV) <= 1e-12
    assert relative(Jp_t[:, order], T @ Jp) <= 1e-12
    assert relative(full_t[:, :N], J_t) <= 1e-13 and relative(full_t[:, N:], Jp_t) <= 1e-13
    assert relative(R_t[:, :N], R[:, :N] @ T_INV) <= 1e-12
    assert relative(R_t[:, N:][:, order], R[:, N:]) <= 1e-12
    rhs = np.zeros(N)
    assert tree.kernels.rhs(0.0, T @ y, p_tree, rhs) == 0
    assert np.array_equal(f_t, rhs) and np.array_equal(f_full_t, rhs)
    if gains == (0.0, 0.0):   # (Model.jacobian takes the model's default gains)
        assert np.array_equal(tree.jacobian(0.0, T @ y, params=params), J_t)


def test_the_jacobian_is_the_derivative_of_rhs(four_bars):
    """Against no other model: ∂f/∂y and ∂f/∂p of the tree against central differences of its own ``rhs``
    (Richardson-extrapolated twice, error O(h⁶)), off the loop with gains, to 1e-9 of the largest entry."""
    tree, _ = four_bars
    y = tree.initial_state() + np.array([0.0, 0.03, -0.02, 0.4, -0.3, 0.2])
    p = tree.parameter_vector(baumgarte=(1.5, 2.5))
    N, P = tree.state_size, len(tree.parameters)

    def f(x):
        out = np.zeros(N)
        assert tree.kernels.rhs(0.0, x[:N], np.concatenate([x[N:], p[P:]]), out) == 0
        return out

    x, differences = np.concatenate([y, p[:P]]), np.empty((N, N + P))
    for j in range(N + P):
        def central(h, j=j):
            step = np.zeros(N + P)
            step[j] = h
            return (f(x + step) - f(x - step)) / (2 * h)
        h = 1e-3 * max(abs(x[j]), 1.0)
        d1, d2, d4 = central(h), central(h / 2), central(h / 4)
        differences[:, j] = (16 * ((4 * d4 - d2) / 3) - ((4 * d2 - d1) / 3)) / 15
    _, J, Jp, _, _, _ = jacobians(tree, y, p)
    assert relative(np.hstack([J, Jp]), differences) <= 1e-9


def test_the_tangent_kernels_are_the_full_jacobians_along_a_direction(four_bars):
    """``rhs_directional``, ``rhs_tangent`` and ``rhs_tangent_parameters`` (what a run of one sensitivity column
    calls): f bitwise ``rhs``'s, the derivative J v + (∂f/∂p) w to 1e-13 of the full Jacobians' product, off the
    loop with gains, at random directions."""
    tree, _ = four_bars
    rng = np.random.default_rng(5)
    N, P = tree.state_size, len(tree.parameters)
    for _ in range(5):
        y = tree.initial_state() + rng.uniform(-0.05, 0.05, N)
        p = tree.parameter_vector(baumgarte=tuple(rng.uniform(0, 4, 2)))
        v, w = rng.normal(size=N), rng.normal(size=P)
        f, _, _, full, _, _ = jacobians(tree, y, p)
        ydot, out = np.zeros(N), np.zeros(N)
        assert tree.kernels.rhs_directional(0.0, y, p, v, w, ydot, out) == 0
        assert np.array_equal(ydot, f) and relative(out, full @ np.concatenate([v, w])) <= 1e-13
        out = np.zeros(2 * N)
        assert tree.kernels.rhs_tangent(0.0, np.concatenate([y, v]), p, out) == 0
        assert np.array_equal(out[:N], f) and relative(out[N:], full[:, :N] @ v) <= 1e-13
        assert tree.kernels.rhs_tangent_parameters(0.0, np.concatenate([y, v]), np.concatenate([p, w]), out) == 0
        assert np.array_equal(out[:N], f) and relative(out[N:], full @ np.concatenate([v, w])) <= 1e-13


def dae_residual(model, z, p):
    out = np.zeros(z.size)
    assert model.kernels.dae_residual(0.0, z, p, out) == 0
    return out


def dae_jacobian(model, z, p):
    out = np.zeros((z.size, z.size))
    assert model.kernels.dae_jacobian(0.0, z, p, out) == 0
    return out


@settings(max_examples=20, deadline=None)
@given(z=st.lists(st.floats(-2.0, 2.0), min_size=13, max_size=13), params=FOUR_BAR_PARAMETERS)
def test_the_dae_kernels_are_the_examples(four_bars, z, params):
    """G(t, z) and ∂G/∂z of the index-2 DAE at random z = (q, v, w, λ, μ) (n = 3, k = kh = 2), to 1e-12.

    With A the coordinates' map and S = diag(A, A, A, 1, 1) (z_t = S z), the tree's rows are the example's
    mapped: v_t + Λ_tᵀ μ = A v + A⁻ᵀ Λᵀ μ (Λ_t = Λ A⁻¹), w_t = A w, M_t w_t − F_t − Λ_tᵀ λ = A⁻ᵀ (M w − F − Λᵀ λ),
    Λ v and Φ as they are: G_t(S z) = B G(z) + C z with B = diag(A⁻ᵀ, A, A⁻ᵀ, 1, 1) and C adding (A − A⁻ᵀ) v to
    the first rows, so ∂G_t/∂z_t = (B ∂G/∂z + C) S⁻¹."""
    tree, example = four_bars
    assert tree.kernels.DAE_SIZE == example.kernels.DAE_SIZE == 13
    A, A_inv_T = TO_TREE, np.linalg.inv(TO_TREE).T
    z = np.array(z)
    S, B, C = np.eye(13), np.eye(13), np.zeros((13, 13))
    for block in range(3):
        S[3 * block:3 * block + 3, 3 * block:3 * block + 3] = A
        B[3 * block:3 * block + 3, 3 * block:3 * block + 3] = A_inv_T if block != 1 else A
    C[0:3, 3:6] = A - A_inv_T
    p_tree, p = tree.parameter_vector(params), example.parameter_vector(params)
    assert relative(dae_residual(tree, S @ z, p_tree), B @ dae_residual(example, z, p) + C @ z) <= 1e-12
    expected = (B @ dae_jacobian(example, z, p) + C) @ np.linalg.inv(S)
    assert relative(dae_jacobian(tree, S @ z, p_tree), expected) <= 1e-12


def test_a_spatial_loop_has_the_jacobians_of_the_lagrangian_path(cache_dir):
    """The spatial loop of `test_multibody_loops` (universal joints, a slide with Coriolis terms, a ball-joint
    closure in x, y, z) against the Lagrangian path with Φ from sympy's rotation matrices: every Jacobian to 1e-12
    at random states, gains and parameters (±50 % about the defaults)."""
    tree = spatial_tree()
    tree_model = lc.compile(tree, cache_dir=cache_dir)
    lagrange = lc.compile(lagrangian_with_loops(tree), cache_dir=cache_dir)
    assert tree_model.parameters == lagrange.parameters
    rng = np.random.default_rng(3)
    for _ in range(10):
        y = np.concatenate([rng.uniform(-1, 1, 2), rng.uniform(-0.3, 0.3, 1), rng.uniform(-1, 1, 2),
                            rng.uniform(-2, 2, 5)])
        params = {name: value * rng.uniform(0.5, 1.5) for name, value in tree.defaults.items()}
        gains = tuple(rng.uniform(0, 4, 2))
        mine = jacobians(tree_model, y, tree_model.parameter_vector(params, baumgarte=gains))
        theirs = jacobians(lagrange, y, lagrange.parameter_vector(params, baumgarte=gains))
        for got, expected in zip(mine, theirs):
            assert relative(got, expected) <= 1e-12


# -- runs --------------------------------------------------------------------------------------------------------------

def test_radau_runs_the_four_bar_tree_as_a_dae(four_bars):
    """radau (the DAE, no projection) at rtol 1e-10 against dop853 at 1e-13 with projection, and against the
    example's radau: the crank turns about four times in 2 s; the loop stays closed without projection.  Measured:
    states 1.9e-11 of their largest entry from either, residual 2.5e-11, reactions 4.5e-11."""
    tree, example = four_bars
    ts = np.linspace(0.0, 2.0, 41)
    tight = tree.simulate((0.0, 2.0), t_eval=ts, method="dop853", rtol=1e-13, atol=1e-13, projection=True,
                          max_residual=1e-12)
    run = tree.simulate((0.0, 2.0), t_eval=ts, method="radau", rtol=1e-10, atol=1e-10)
    theirs = example.simulate((0.0, 2.0), t_eval=ts, method="radau", rtol=1e-10, atol=1e-10)
    assert tight.success and run.success and theirs.success, (run.message, theirs.message)
    assert run.q[-1, 0] - run.q[0, 0] > 6 * math.pi   # (not a trivial run)
    assert np.max(np.abs(run.y - tight.y)) <= 1e-9 * np.max(np.abs(tight.y))
    assert np.max(np.abs(run.y - theirs.y @ T.T)) <= 1e-9 * np.max(np.abs(tight.y))
    assert run.constraint_residual <= 1e-9
    for name in tree.constraints:
        assert relative(run.reactions[name], tight.reactions[name]) <= 1e-8


def test_a_radau_sweep_of_the_loop_tree_runs_each_point_as_simulate_does(four_bars):
    """sweep(method="radau") takes the tree's DAE kernels too: each final state is simulate's, to 1e-12."""
    tree, _ = four_bars
    masses = [0.5, 1.0, 1.5]
    sweep = tree.sweep((0.0, 0.5), {"m2": masses}, method="radau", rtol=1e-9, atol=1e-9)
    assert list(sweep.status) == [0, 0, 0]
    for mass, final in zip(masses, sweep.final, strict=True):
        run = tree.simulate((0.0, 0.5), params={"m2": mass}, method="radau", rtol=1e-9, atol=1e-9)
        assert relative(final, run.y[-1]) <= 1e-12


@pytest.fixture(scope="module")
def sensitivity_runs(four_bars):
    """The tree's and the example's runs to t = 2 with the sensitivities to (q0, qd0) and to m2 and g, and the
    runs' options."""
    tree, example = four_bars
    options = {"rtol": 1e-12, "atol": 1e-12, "t_eval": np.linspace(0.0, 2.0, 9), "progress": False}
    return (tree.simulate((0.0, 2.0), sensitivities=("q0", "qd0", "m2", "g"), **options),
            example.simulate((0.0, 2.0), sensitivities=("q0", "qd0", "m2", "g"), **options), options)


def test_sensitivities_are_the_examples_in_the_trees_coordinates(four_bars, sensitivity_runs):
    """The same ODE in other coordinates: S_t = T S T⁻¹ for the initial state's columns, T S for a parameter's,
    the reactions' (∂λ/∂y0) T⁻¹ and ∂λ/∂p, to 1e-10 of each block's largest entry (both runs at rtol 1e-12;
    measured 1.3e-12)."""
    tree, _ = four_bars
    mine, theirs, _ = sensitivity_runs
    assert mine.success and theirs.success
    N = tree.state_size
    columns = [mine.sensitivity_names.index(f"p:{name}") for name in ("m2", "g")]
    their_columns = [theirs.sensitivity_names.index(f"p:{name}") for name in ("m2", "g")]
    states, reactions = mine.sensitivities, mine.reaction_sensitivities
    assert relative(states[:, :, :N], np.einsum("ij,mjk,kl->mil", T, theirs.sensitivities[:, :, :N], T_INV)) <= 1e-10
    parameters = np.einsum("ij,mjk->mik", T, theirs.sensitivities[:, :, their_columns])
    assert relative(states[:, :, columns], parameters) <= 1e-10
    assert relative(reactions[:, :, :N], theirs.reaction_sensitivities[:, :, :N] @ T_INV) <= 1e-10
    assert relative(reactions[:, :, columns], theirs.reaction_sensitivities[:, :, their_columns]) <= 1e-10


def test_a_one_column_run_takes_the_tangent_kernel_and_agrees(four_bars, sensitivity_runs):
    """A run of g's column alone (``rhs_tangent_parameters`` as its rhs) against the same column of the run of
    every column (the full Jacobians), same tolerances: the same ODE, to 1e-10 of the column's largest entry
    (measured 1.0e-11)."""
    tree, _ = four_bars
    solution, _, options = sensitivity_runs
    alone = tree.simulate((0.0, 2.0), sensitivities="g", **options)
    column = solution.sensitivity_names.index("p:g")
    assert relative(alone.sensitivities[:, :, 0], solution.sensitivities[:, :, column]) <= 1e-10
    assert relative(alone.reaction_sensitivities[:, :, 0], solution.reaction_sensitivities[:, :, column]) <= 1e-10


@pytest.mark.parametrize("parameter", ["m2", "g"])
def test_parameter_sensitivities_against_differences_of_runs(four_bars, sensitivity_runs, parameter):
    """∂y/∂p and ∂λ/∂p against central differences of runs at p ± h, p ± h/2 extrapolated once, to 1e-8 of each
    block's largest entry (m2 and g leave the initial state on the loop; a, b, c, d would move it off; measured
    1.6e-10 to 5.1e-10, the differences' own error)."""
    tree, _ = four_bars
    solution, _, options = sensitivity_runs
    value = solution.params[parameter]

    def trajectory(h):
        run = tree.simulate((0.0, 2.0), params={parameter: value + h}, **options)
        return np.hstack([run.y, np.column_stack([run.reactions[name] for name in tree.constraints])])

    d1, d2 = ((trajectory(h) - trajectory(-h)) / (2 * h) for h in (1e-3 * value, 5e-4 * value))
    reference = (4 * d2 - d1) / 3
    column = solution.sensitivity_names.index(f"p:{parameter}")
    N = tree.state_size
    assert relative(solution.sensitivities[:, :, column], reference[:, :N]) <= 1e-8
    assert relative(solution.reaction_sensitivities[:, :, column], reference[:, N:]) <= 1e-8


# -- what stays refused ------------------------------------------------------------------------------------------------

def test_linearize_refuses_the_loop_tree_as_it_refuses_the_example(four_bars):
    """lagcomp.analysis.linearize needs an unconstrained system, on either path."""
    from lagcomp import analysis as an

    for model in four_bars:
        with pytest.raises(lc.ModelError, match="needs an unconstrained system"):
            an.linearize(model, model.initial_state()[:3])
