"""The on-demand kernels of kinematic trees (`lagcomp.codegen.tree_companion`): the articulated-body algorithm and
recursive Newton–Euler differentiated in forward mode over their programs (`lagcomp.multibody.forward_mode`).

References nobody here wrote: the Lagrangian path's Jacobians (sympy derivation of the same systems written with
lc.RigidBody), central differences of an independent sympy derivation evaluated with mpmath at 40 digits, the
double pendulum's normal-mode frequencies in closed form, dop853 runs, and finite differences of runs.
"""

from __future__ import annotations

import mpmath
import multibody_models as mm
import numpy as np
import pytest
import sympy as sp
from compile_probe import run_probe
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from random_systems import python_kernels

import lagcomp as lc
from lagcomp import analysis as an
from lagcomp.codegen.kinds import TREE_KINDS


def _draw(data, model):
    """Random parameters (0.5 to 2, by name) and a state (q, q̇ within ±2) for `model`."""
    values = st.floats(0.5, 2.0, allow_nan=False)
    params = {name: data.draw(values, label=name) for name in model.parameters}
    y = np.array(data.draw(st.lists(st.floats(-2.0, 2.0, allow_nan=False), min_size=2 * model.n,
                                    max_size=2 * model.n), label="y"))
    return params, y


def _relative(a, b) -> float:
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


# -- against the Lagrangian path ----------------------------------------------------------------------------------

#: {model name: its kernels as plain Python (`_python_jacobians`)}, for the run.
_PYTHON_KERNELS: dict = {}


def _python_jacobians(model: lc.Model) -> dict:
    """The Lagrangian path's eager module and its companion of the Jacobians (``rhs_jacobian``,
    ``rhs_parameter_jacobian``) run as plain Python: the reference is the same emitted code, which numba need not
    compile here (its compiled Jacobians are tests/test_rhs_jacobian.py's subject; ~15 s of numba for the four
    pairs)."""
    if model.name not in _PYTHON_KERNELS:
        companion = model.on_demand_entry("jacobians").path.read_text(encoding="utf-8")
        _PYTHON_KERNELS[model.name] = python_kernels(companion, model.source_path.read_text(encoding="utf-8"))
    return _PYTHON_KERNELS[model.name]



@pytest.mark.parametrize("name", mm.PAIRS)
@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_jacobians_agree_with_the_lagrangian_path(tree_pair, name, data):
    """∂f/∂y and ∂f/∂p of the tree (forward mode over the recursion) against the Lagrangian path's (derived from
    the expanded T and V), to 1e-12 relative; the full Jacobian is both side by side."""
    tree_model, lagrange_model = tree_pair(name)
    params, y = _draw(data, tree_model)
    t = data.draw(st.floats(0.0, 10.0), label="t")
    assert tree_model.parameters == lagrange_model.parameters
    size, p = 2 * tree_model.n, tree_model.parameter_vector(params)
    lagrange = _python_jacobians(lagrange_model)
    want, want_p = np.empty((size, size)), np.empty((size, len(tree_model.parameters)))
    lagrange_p = lagrange_model.parameter_vector(params)
    assert lagrange["rhs_jacobian"](t, y, lagrange_p, want) == 0
    assert lagrange["rhs_parameter_jacobian"](t, y, lagrange_p, want_p) == 0
    assert _relative(tree_model.jacobian(t, y, params), want) <= 1e-12
    tree_p = tree_model.rhs_parameter_jacobian(t, y, params)
    assert _relative(tree_p, want_p) <= 1e-12
    ydot, full = np.empty(size), np.empty((size, size + len(p)))
    assert tree_model.kernels.rhs_with_full_jacobian(t, y, p, ydot, full) == 0
    assert np.array_equal(full, np.hstack([tree_model.jacobian(t, y, params), tree_p]))


@pytest.mark.parametrize("name", mm.PAIRS)
def test_the_kernels_that_write_f_write_rhs_bitwise(tree_pair, name):
    """rhs_with_jacobian, rhs_with_full_jacobian and the tangent kernels run the eager rhs's program first: the
    same f, bit for bit; the tangent kernels' J v is the Jacobian's product (to rounding: other sums)."""
    tree_model, _ = tree_pair(name)
    rng = np.random.default_rng(3)
    p = tree_model.parameter_vector({name: float(v) for name, v in
                                     zip(tree_model.parameters, rng.uniform(0.5, 2, len(tree_model.parameters)))})
    size, P = 2 * tree_model.n, len(tree_model.parameters)
    k = tree_model.kernels
    for _ in range(3):
        y, v, w = rng.normal(size=size), rng.normal(size=size), rng.normal(size=P)
        f, ydot, J, full = np.empty(size), np.empty(size), np.empty((size, size)), np.empty((size, size + P))
        k.rhs(0.4, y, p, f)
        assert k.rhs_with_jacobian(0.4, y, p, ydot, J) == 0 and np.array_equal(ydot, f)
        assert k.rhs_with_full_jacobian(0.4, y, p, ydot, full) == 0 and np.array_equal(ydot, f)
        out = np.empty(2 * size)
        assert k.rhs_tangent(0.4, np.concatenate([y, v]), p, out) == 0
        assert np.array_equal(out[:size], f) and _relative(out[size:], J @ v) <= 1e-13
        assert k.rhs_tangent_parameters(0.4, np.concatenate([y, v]), np.concatenate([p, w]), out) == 0
        assert np.array_equal(out[:size], f) and _relative(out[size:], full @ np.concatenate([v, w])) <= 1e-13


# -- against an independent derivation, in 40 digits -------------------------------------------------------------


def _double_pendulum_acceleration():
    """q̈(q, q̇, parameters) of `mm.planar_chain(2)` by Euler–Lagrange from T and V written here (absolute angles
    θ0 and θ0 + θ1, centres of mass at (c_i, d_i) of each link, link 1 hinged at (l0, 0) of link 0, inertia J_i
    about z, gravity −g along y), as an mpmath function of (y, parameters by name)."""
    th0, th1, w0, w1 = sp.symbols("th0 th1 w0 w1")
    m0, m1, c0, c1, d0, d1, J0, J1, l0, g = sp.symbols("m0 m1 c0 c1 d0 d1 J0 J1 l0 g")

    def rotate(angle, x, y):
        return sp.Matrix([x * sp.cos(angle) - y * sp.sin(angle), x * sp.sin(angle) + y * sp.cos(angle)])

    q, qd = sp.Matrix([th0, th1]), sp.Matrix([w0, w1])
    G0 = rotate(th0, c0, d0)
    G1 = rotate(th0, l0, 0) + rotate(th0 + th1, c1, d1)
    v0, v1 = G0.jacobian(q) * qd, G1.jacobian(q) * qd
    T = (m0 * v0.dot(v0) + m1 * v1.dot(v1) + J0 * w0 ** 2 + J1 * (w0 + w1) ** 2) / 2
    V = g * (m0 * G0[1] + m1 * G1[1])
    L = T - V
    M = sp.hessian(T, qd)
    F = sp.Matrix([L]).jacobian(q).T - sp.Matrix([L]).jacobian(qd).jacobian(q) * qd
    names = ("th0", "th1", "w0", "w1", "m0", "m1", "c0", "c1", "d0", "d1", "J0", "J1", "l0", "g")
    M_of, F_of = (sp.lambdify(sp.symbols(names), e, "mpmath") for e in (M, F))

    def acceleration(y, params):
        args = [*y, *(params[name] for name in names[4:])]
        return mpmath.lu_solve(mpmath.matrix(M_of(*args)), mpmath.matrix(F_of(*args)))

    return acceleration


def test_the_jacobian_agrees_with_40_digit_central_differences_of_an_independent_derivation(tree_pair):
    """∂q̈/∂y of the double pendulum tree against central differences (step 1e-15) of q̈ from T and V derived here,
    evaluated with mpmath at 40 digits: the difference's error is ~1e-30 of J, below the kernel's rounding."""
    tree_model, _ = tree_pair("rigid_double_pendulum")
    acceleration = _double_pendulum_acceleration()
    rng = np.random.default_rng(11)
    with mpmath.workdps(40):
        for _ in range(3):
            params = {name: float(v) for name, v in zip(tree_model.parameters,
                                                        rng.uniform(0.5, 2.0, len(tree_model.parameters)))}
            y = rng.uniform(-2.0, 2.0, 4)
            h = mpmath.mpf("1e-15")
            reference = np.empty((2, 4))
            for j in range(4):
                up, down = [mpmath.mpf(v) for v in y], [mpmath.mpf(v) for v in y]
                up[j] += h
                down[j] -= h
                params_mp = {k: mpmath.mpf(v) for k, v in params.items()}
                column = (acceleration(up, params_mp) - acceleration(down, params_mp)) / (2 * h)
                reference[:, j] = [float(x) for x in column]
            got = tree_model.jacobian(0.0, y, params)
            assert _relative(got[2:], reference) <= 1e-13
            assert np.array_equal(got[:2], np.hstack([np.zeros((2, 2)), np.eye(2)]))


# -- what uses them: radau, linearize, sensitivities ---------------------------------------------------------------


def test_radau_on_a_tree_agrees_with_dop853(tree_pair):
    """The 3D universal-joint chain, radau (the tree's exact Jacobian) against dop853, both at tight tolerance."""
    tree_model, _ = tree_pair("universal_chain_2")
    params = {name: 1.0 for name in tree_model.parameters} | {"g": 9.81, "A0": 0.3, "B0": 0.4, "C0": 0.2}
    start = dict(q0=[1.0, -0.5, 0.3, 0.8], qd0=[0.0, 1.0, -1.0, 0.5], params=params)
    radau = tree_model.simulate((0.0, 3.0), method="radau", rtol=1e-12, atol=1e-12, **start)
    dop853 = tree_model.simulate((0.0, 3.0), method="dop853", rtol=1e-13, atol=1e-13, **start)
    assert radau.success and dop853.success and radau.t[-1] == dop853.t[-1] == 3.0
    assert _relative(radau.y[-1], dop853.y[-1]) <= 1e-9


def _double_pendulum_frequencies(m1, m2, l1, l2, g):
    """Normal-mode ω of the point-mass double pendulum (masses m1, m2 at lengths l1, l2) hanging down, ascending:
    with absolute angles, M = [[(m1+m2) l1², m2 l1 l2], [m2 l1 l2, m2 l2²]], K = g diag((m1+m2) l1, m2 l2), and
    det(K − ω² M) = 0 divided by m2 l1 l2 is m1 l1 l2 ω⁴ − (m1+m2) g (l1+l2) ω² + (m1+m2) g² = 0."""
    a, b, c = m1 * l1 * l2, -(m1 + m2) * g * (l1 + l2), (m1 + m2) * g ** 2
    root = np.sqrt(b * b - 4 * a * c)
    return np.sqrt(np.array([(-b - root) / (2 * a), (-b + root) / (2 * a)]))


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(m1=st.floats(0.2, 5.0), m2=st.floats(0.2, 5.0), l1=st.floats(0.2, 3.0), l2=st.floats(0.2, 3.0))
def test_linearize_of_a_tree_double_pendulum_gives_the_closed_form_frequencies(tree_pair, m1, m2, l1, l2):
    """The planar chain with point masses at the links' ends, hanging down (θ0 = −π/2: link 0's x along −y)."""
    tree_model, _ = tree_pair("rigid_double_pendulum")
    params = dict(m0=m1, m1=m2, c0=l1, l0=l1, c1=l2, d0=0.0, d1=0.0, J0=0.0, J1=0.0, g=9.81)
    modes = an.normal_modes(tree_model, [-np.pi / 2, 0.0], params)
    assert modes.stability == "stable"
    assert _relative(modes.frequencies, _double_pendulum_frequencies(m1, m2, l1, l2, 9.81)) <= 1e-12


@pytest.mark.parametrize("name", ["planar_chain_4", "cart_pole"])
def test_linearize_of_a_tree_agrees_with_the_lagrangian_path(tree_pair, name):
    """M₀, K₀, G₀, D₀ (the cart-pole's dampers give D₀) at a random configuration, the tree's rest_partials by
    forward mode over recursive Newton–Euler against the Lagrangian path's symbolic ones."""
    tree_model, lagrange_model = tree_pair(name)
    rng = np.random.default_rng(5)
    params = {k: float(v) for k, v in zip(tree_model.parameters, rng.uniform(0.5, 2.0, len(tree_model.parameters)))}
    q = rng.uniform(-2.0, 2.0, tree_model.n)
    tree, lagrange = an.linearize(tree_model, q, params, t=0.3), an.linearize(lagrange_model, q, params, t=0.3)
    for block in ("M", "K", "D"):
        assert _relative(getattr(tree, block), getattr(lagrange, block)) <= 1e-12, block
    assert np.max(np.abs(tree.G - lagrange.G)) <= 1e-12 * np.max(np.abs(lagrange.K))
    if name == "cart_pole":
        assert np.max(np.abs(tree.D)) > 0   # (the dampers: ∂F/∂q̇ is exercised)


@pytest.mark.parametrize("columns", [("q0:th",), ("p:m",), ("q0", "qd0", "params")])
def test_sensitivities_on_a_tree_agree_with_finite_differences_of_runs(tree_pair, columns):
    """The cart-pole (spring, dampers, a forcing in t): one column (a tangent kernel), and all of them (the full
    Jacobians), against central differences of runs at rtol 1e-12 (step 1e-5: truncation ~1e-10, rounding of
    the runs ~1e-7 relative to the sensitivities), and against the Lagrangian path's sensitivities."""
    tree_model, lagrange_model = tree_pair("cart_pole")
    params = {name: 1.0 for name in tree_model.parameters} | {"g": 9.81, "c": 0.7, "k": 3.0, "w": 2.0}
    q0, qd0 = np.array([0.2, 0.5]), np.array([0.1, -0.3])
    options = dict(rtol=1e-12, atol=1e-12, t_eval=np.linspace(0.0, 2.0, 5))
    sol = tree_model.simulate((0.0, 2.0), q0=q0, qd0=qd0, params=params, sensitivities=columns, **options)
    other = lagrange_model.simulate((0.0, 2.0), q0=q0, qd0=qd0, params=params, sensitivities=columns, **options)
    assert sol.success and sol.sensitivity_names == other.sensitivity_names
    assert _relative(sol.sensitivities, other.sensitivities) <= 1e-8
    h = 1e-5
    for c, label in enumerate(sol.sensitivity_names):
        group, what = label.split(":")
        runs = []
        for sign in (1, -1):
            q, qd, p = q0.copy(), qd0.copy(), dict(params)
            if group == "p":
                p[what] += sign * h
            else:
                target, index = (q, tree_model.coordinates.index(what)) if group == "q0" else (
                    qd, tree_model.state_names.index(what) - tree_model.n)
                target[index] += sign * h
            runs.append(tree_model.simulate((0.0, 2.0), q0=q, qd0=qd, params=p, **options).y)
        difference = (runs[0] - runs[1]) / (2 * h)
        assert np.max(np.abs(sol.sensitivities[:, :, c] - difference)) <= 1e-6 * max(np.max(np.abs(difference)), 1.0)


# -- the companion modules -------------------------------------------------------------------------------------


def test_a_tree_has_its_kinds_and_names_the_others(tree_pair):
    tree_model, _ = tree_pair("planar_chain_4")
    assert set(tree_model.on_demand_entries) == set(TREE_KINDS)
    assert tree_model.on_demand_entry("jacobians").path.exists()
    with pytest.raises(lc.ModelError, match=r"energy_lanes kernels.*summary.*kinematic tree 'planar_chain_4'"):
        tree_model.on_demand_entry("energy_lanes")
    with pytest.raises(lc.ModelError, match=r"`energy_lanes`.*issue 39"):
        _ = tree_model.kernels.energy_lanes


def test_the_jacobian_costs_less_than_2n_times_rhs(tree_pair):
    """Forward mode carries only the nonzero derivatives (a link's outward quantities depend on its ancestors'
    coordinates only): ∂f/∂y of the 4-link chain costs less than 2n times rhs's operations."""
    tree_model, _ = tree_pair("planar_chain_4")
    operations = tree_model.operations
    assert operations["rhs_with_jacobian"] < 0.8 * 2 * tree_model.n * operations["rhs"]
    assert operations["rhs_tangent"] < 3.5 * operations["rhs"]


#: A fresh process: compile (or `lagcomp.load`) the tree `planar_chain(2, name)`, run radau and a one-column
#: sensitivity run; report the kernels numba compiled, the cache's modules and whether the lowering was imported.
SCRIPT = """
    name, how, root = sys.argv[1:4]
    if how == "load":
        model = lc.load(name, cache_dir=root)
    else:
        import multibody_models as mm
        model = lc.compile(mm.planar_chain(2, name), cache_dir=root)
    params = {p: 1.0 for p in model.parameters}
    model.simulate((0, 0.5), q0=[0.3, 0.2], qd0=[0.0, 0.0], params=params, method="radau", progress=False)
    model.simulate((0, 0.5), q0=[0.3, 0.2], qd0=[0.0, 0.0], params=params, sensitivities="th0", progress=False)
    modules = sorted(p.name for p in Path(root, "modules").glob("*.py"))
    print(json.dumps({"compiled": compiled, "modules": modules,
                      "lowering": "lagcomp.codegen.tree_companion" in sys.modules}))
"""


def _run(name: str, how: str, root) -> dict:
    return run_probe(SCRIPT, name, how, root)[0]


def test_a_tree_builds_its_companions_once_and_a_second_process_reuses_them(tmp_path):
    first = _run("reused_tree", "compile", tmp_path)
    companions = [m for m in first["modules"] if "_on_demand_" in m]
    assert sorted(kind for kind in TREE_KINDS for m in companions if f"_on_demand_{kind}_" in m) == [
        "directional", "jacobians"]
    assert {"rhs_with_jacobian", "rhs_tangent"} <= {f for _, f in first["compiled"]}
    second = _run("reused_tree", "load", tmp_path)
    assert second["modules"] == first["modules"]
    assert second["compiled"] == [] and not second["lowering"]
