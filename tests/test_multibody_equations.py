r"""`Model.equations()` of a kinematic tree (issue 39): the recursion over a table of the tree's nodes.

The table's lines are read back here and run through Featherstone's spatial algebra written again with 6×6
matrices (rot, xlt, rx/ry/rz, mcI of his Table 2.2; the MRP rotation from its quaternion, its rate matrix J from
Rᵀ ∂R/∂σ): nothing of `lagcomp.multibody`'s 3-vector code.  From the table alone, T and V must equal the same system's
T and V on the Lagrangian path (as its own equations state them) and the tree's energy kernel, q̈ (composite inertia
and Newton–Euler, 6×6) the tree's ``rhs``, and the loops' Φ its constraint residuals, at random states.  The joint
table is compared with the tree's description; a loaded model shows the same equations without importing sympy;
a 100-link chain's equations stay small and quick.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
import sympy as sp
from multibody_models import (
    cart_pole,
    planar_chain,
    random_tree,
    universal_chain,
)
from sympy.parsing.sympy_parser import parse_expr
from test_multibody_loops import four_bar_tree, spatial_tree

import lagcomp as lc
from lagcomp.codegen.tree_latex import tree_equations
from lagcomp.equations import Equations
from lagcomp.examples.trees import arm5, spherical_chain

# -- Featherstone's operators, 6×6, angular part first ---------------------------------------------------------------


def _skew(r) -> sp.Matrix:
    return sp.Matrix([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])


def _rx(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[1, 0, 0], [0, c, s], [0, -s, c]])


def _ry(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, 0, -s], [0, 1, 0], [s, 0, c]])


def _rz(a):
    c, s = sp.cos(a), sp.sin(a)
    return sp.Matrix([[c, s, 0], [-s, c, 0], [0, 0, 1]])


def _rot(E) -> sp.Matrix:
    return sp.diag(sp.Matrix(E), sp.Matrix(E))


def _xlt(*r) -> sp.Matrix:
    return sp.Matrix(sp.BlockMatrix([[sp.eye(3), sp.zeros(3)], [-_skew(r), sp.eye(3)]]))


def _mcI(m, c, inertia) -> sp.Matrix:
    C = _skew(c)
    return sp.Matrix(sp.BlockMatrix([[sp.Matrix(inertia) + m * C * C.T, m * C], [m * C.T, m * sp.eye(3)]]))


def _mrp(*sigma) -> sp.Matrix:
    """The rotation (x_parent = R x_body) of the MRPs σ = n tan(θ/4), from its unit quaternion (w, x)."""
    sigma = sp.Matrix(sigma)
    s = (sigma.T * sigma)[0]
    w, x = (1 - s) / (1 + s), 2 * sigma / (1 + s)
    return (w**2 - (x.T * x)[0]) * sp.eye(3) + 2 * x * x.T + 2 * w * _skew(x)


def _rate_matrix(*sigma):
    """J with ω = J σ̇ (body axes): column k is the axial vector of Rᵀ ∂R/∂σ_k (R of `_mrp`)."""
    symbols = sp.symbols("_s0:3")
    R = _mrp(*symbols)
    columns = []
    for k in range(3):
        W = (R.T * R.diff(symbols[k])).subs(dict(zip(symbols, sigma)))
        columns.append([W[2, 1], W[0, 2], W[1, 0]])
    return sp.Matrix(columns).T


OPERATORS = {"rot": _rot, "xlt": _xlt, "rx": _rx, "ry": _ry, "rz": _rz, "mrp": _mrp, "mcI": _mcI, "diag": sp.diag,
             "J": _rate_matrix, "Matrix": sp.Matrix}


# -- the table read back --------------------------------------------------------------------------------------------


def _number(value):
    """A float, or a float array of a matrix or tuple."""
    if isinstance(value, sp.MatrixBase):
        return np.array(value.evalf(30), dtype=float)
    if isinstance(value, (sp.Tuple, tuple)):
        return np.array([float(x) for x in value])
    return float(value)


def _evaluate(text: str, values: dict):
    """The right-hand side of a text line, evaluated at `values` (names -> numbers) with Featherstone's operators
    (a parameter named like an operator, the cart-pole's J, keeps its value outside the lines that call J)."""
    rhs = text.split(" = ", 1)[1].split("   [")[0]
    names = {**values, **OPERATORS} if "J(" in rhs or "mrp(" in rhs else {**OPERATORS, **values}
    return _number(parse_expr(rhs, local_dict=names))


def table(equations: Equations, values: dict) -> dict:
    """The nodes' X (6×6), S (6), rate, I (6×6) and τ at `values`, and gravity, from the ``tree`` lines."""
    nodes, rows = {}, {}
    for line in equations.part("tree"):
        if line.label in ("gravity", "base frame"):
            rows[line.label] = line
            continue
        symbol = line.text.split(" = ", 1)[0]
        what, index = re.fullmatch(r"(lambda|X|S|qdot|I|tau)[_(](\d+)\)?", symbol).groups()
        node = nodes.setdefault(int(index), {"coordinate": line.label})
        if what == "lambda":
            node[what] = int(line.text.split(" = ")[1].split()[0])
        else:   # (X_i = 1: an identity placement)
            node[what] = np.eye(6) if line.text.endswith(" = 1") and what == "X" else _evaluate(line.text, values)
    n = len(nodes)
    out = {"gravity": _evaluate(rows["gravity"].text, values).ravel(), "n": n}
    out["parent"] = [nodes[i + 1]["lambda"] - 1 for i in range(n)]
    out["X"] = [nodes[i + 1]["X"] for i in range(n)]
    out["S"] = [nodes[i + 1]["S"].ravel() for i in range(n)]
    out["rate"] = [float(nodes[i + 1].get("qdot", values[f"{nodes[i + 1]['coordinate']}_dot"])) for i in range(n)]
    out["I"] = [nodes[i + 1].get("I", np.zeros((6, 6))) for i in range(n)]
    out["tau"] = [float(nodes[i + 1].get("tau", 0.0)) for i in range(n)]
    return out


def _crm(v):
    w, u = _skew_np(v[:3]), _skew_np(v[3:])
    return np.block([[w, np.zeros((3, 3))], [u, w]])


def _skew_np(r):
    return np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])


def velocities(tab) -> list:
    v = []
    for i in range(tab["n"]):
        parent = np.zeros(6) if tab["parent"][i] < 0 else v[tab["parent"][i]]
        v.append(tab["X"][i] @ parent + tab["S"][i] * tab["rate"][i])
    return v


def kinetic(tab) -> float:
    return sum(v @ I @ v for v, I in zip(velocities(tab), tab["I"])) / 2


def base_frames(tab) -> tuple[list, list]:
    """⁰R_i and ⁰r_i of each node from X_i = rot(E) xlt(r): E = X[:3, :3], r× = −Eᵀ X[3:, :3]."""
    R, r = [], []
    for i in range(tab["n"]):
        E = tab["X"][i][:3, :3]
        shift = -E.T @ tab["X"][i][3:, :3]
        local = np.array([shift[2, 1], shift[0, 2], shift[1, 0]])
        R0, r0 = (np.eye(3), np.zeros(3)) if tab["parent"][i] < 0 else (R[tab["parent"][i]], r[tab["parent"][i]])
        R.append(R0 @ E.T)
        r.append(r0 + R0 @ local)
    return R, r


def potential(tab, equations: Equations, values: dict) -> float:
    R, r = base_frames(tab)
    V = 0.0
    for i, inertia in enumerate(tab["I"]):
        m = inertia[5, 5]
        if m != 0:
            mc = inertia[:3, 3:]
            V -= m * tab["gravity"] @ (r[i] + R[i] @ (np.array([mc[2, 1], mc[0, 2], mc[1, 0]]) / m))
    springs = [line for line in equations.part("energy") if line.label == "V springs"]
    return V + (float(_evaluate(springs[0].text, values)) if springs else 0.0)


def accelerations(tab) -> np.ndarray:
    """q̈ = M⁻¹ (τ − C): M column by column and C by Newton–Euler (6×6), from the table."""
    n = tab["n"]

    def inverse_dynamics(qdd, moving: bool):
        v = velocities(tab) if moving else [np.zeros(6)] * n
        a, f = [], []
        for i in range(n):
            parent = np.concatenate([np.zeros(3), -tab["gravity"]]) if moving else np.zeros(6)
            parent = parent if tab["parent"][i] < 0 else a[tab["parent"][i]]
            rate = tab["S"][i] * (tab["rate"][i] if moving else 0.0)
            a.append(tab["X"][i] @ parent + tab["S"][i] * qdd[i] + _crm(v[i]) @ rate)
            f.append(tab["I"][i] @ a[i] - _crm(v[i]).T @ tab["I"][i] @ v[i])
        for i in reversed(range(n)):
            if tab["parent"][i] >= 0:
                f[tab["parent"][i]] = f[tab["parent"][i]] + tab["X"][i].T @ f[i]
        return np.array([S @ fi for S, fi in zip(tab["S"], f)])

    M = np.column_stack([inverse_dynamics(np.eye(n)[j], moving=False) for j in range(n)])
    return np.linalg.solve(M, np.array(tab["tau"]) - inverse_dynamics(np.zeros(n), moving=True))


def random_values(tree: lc.Tree, rng) -> dict:
    """Coordinates, velocities, parameters (in [0.5, 1.5]: masses and inertias positive) and t, by name."""
    values = {name: float(rng.uniform(-1, 1)) for name in tree.coordinate_names}
    values.update({f"{name}_dot": float(rng.uniform(-1, 1)) for name in tree.coordinate_names})
    values.update({name: float(rng.uniform(0.5, 1.5)) for name in tree.parameter_names})
    values["t"] = float(rng.uniform(0, 2))
    return values


def state(tree: lc.Tree, values: dict) -> tuple[np.ndarray, dict]:
    y = np.array([values[c] for c in tree.coordinate_names] + [values[f"{c}_dot"] for c in tree.coordinate_names])
    return y, {name: values[name] for name in tree.parameter_names}


def relative(x, reference) -> float:
    return float(np.max(np.abs(np.asarray(x) - reference)) / max(np.max(np.abs(reference)), 1e-300))


def floating_pair() -> lc.Tree:
    """A free body (translations, then MRPs) carrying a link on a hinge about an unaligned axis."""
    m, M, k = sp.symbols("m M k", positive=True)
    return lc.Tree([
        lc.Link("body", lc.Free(("x", "y", "z", "s1", "s2", "s3")), mass=M, com=(0.1, 0, 0.2), inertia=(1, 2, 3)),
        lc.Link("flap", lc.Revolute("q", axis=(1, 1, 0), origin=(0.5, 0, 0), stiffness=k, rest=0.3), parent="body",
                mass=m, com=(0.2, 0.1, 0), inertia=((1, 0.1, 0), (0.1, 2, 0), (0, 0, 2.5))),
    ], gravity=(0, 0, -sp.Symbol("g")), name="floating_pair")


# -- content ----------------------------------------------------------------------------------------------------------

JOINT = re.compile(r"lambda\((\d+)\) = (\d+)   \[(\w+) on (\w+|the base): (\w+)(?: (\d) of (\d))?, (\w+) "
                   r"(about|along) \((.*)\)\]")


@pytest.mark.parametrize("tree", [planar_chain(3), cart_pole(), universal_chain(2), spherical_chain(2),
                                  random_tree(3)[0], spatial_tree(), floating_pair(), arm5()],
                         ids=lambda tree: tree.name)
def test_the_joint_table_is_the_trees(tree):
    lines = Equations(tree.name, tree_equations(tree)).part("tree")
    assert all("\n" not in line.text for line in lines)   # (a matrix's text on one line)
    joints = [JOINT.fullmatch(line.text) for line in lines if line.text.startswith("lambda(")]
    assert len(joints) == tree.n and all(joints)
    links = {link.name: link for link in tree.links}
    for i, (match, node) in enumerate(zip(joints, tree.nodes)):
        index, parent, link, on, kind, k, of, coordinate, _, axis = match.groups()
        assert (int(index), int(parent), link, coordinate) == (i + 1, node.parent + 1, node.link,
                                                              tree.coordinate_names[i])
        assert on == (links[link].parent or "the base") and kind == type(links[link].joint).__name__
        own = [j for j, other in enumerate(tree.nodes) if other.link == link]
        assert (k, of) == ((None, None) if len(own) == 1 else (str(own.index(i) + 1), str(len(own))))
        assert [float(sp.sympify(a)) for a in axis.split(", ")] == pytest.approx([float(a) for a in node.joint.axis])


@pytest.mark.parametrize("name", ["rigid_double_pendulum", "universal_chain_2", "cart_pole"])   # (planar_chain_4's
# T is longer than the 4000 characters a System's equations print)
def test_T_and_V_from_the_table_are_the_lagrangian_twins(tree_pair, name, rng):
    """T and V rebuilt from the table equal T and V of the same system on the Lagrangian path, as its equations
    print them (sympy's expressions of its bodies), and T + V the tree's energy kernel."""
    model, twin = tree_pair(name)
    tree = model.system
    equations, twin_energy = model.equations(), {e.label: e.text for e in twin.equations().part("energy")}
    for _ in range(5):
        values = random_values(tree, rng)
        tab = table(equations, values)
        T, V = kinetic(tab), potential(tab, equations, values)
        assert T == pytest.approx(float(_evaluate(twin_energy["T"], values)), rel=1e-12)
        assert V == pytest.approx(float(_evaluate(twin_energy["V"], values)), rel=1e-12, abs=1e-12)
        y, params = state(tree, values)
        assert T + V == pytest.approx(model.energy(y[:tree.n], y[tree.n:], values["t"], params), rel=1e-12)


@pytest.mark.parametrize("tree", [spherical_chain(2), random_tree(5)[0], spatial_tree(), floating_pair()],
                         ids=lambda tree: tree.name)
def test_T_plus_V_from_the_table_is_the_energy_kernel(tree, cache_dir, rng):
    """Ball and free joints (mrp, J), rotated placements and unaligned axes (explicit E), springs, a loop's tree."""
    model = lc.compile(tree, cache_dir=cache_dir)
    equations = model.equations()
    for _ in range(4):
        values = random_values(tree, rng)
        y, params = state(tree, values)
        tab = table(equations, values)
        energy = kinetic(tab) + potential(tab, equations, values)
        assert energy == pytest.approx(model.energy(y[:tree.n], y[tree.n:], values["t"], params), rel=1e-12)


@pytest.mark.parametrize("tree", [cart_pole(), universal_chain(2), random_tree(3)[0], random_tree(7)[0], arm5()],
                         ids=lambda tree: tree.name)
def test_qdd_from_the_table_is_rhs(tree, cache_dir, rng):
    """The table's placements, subspaces, inertias, joint forces (springs, dampers, a driving force of t) and
    gravity give the tree's q̈ (M and C by 6×6 Newton–Euler): the recursion shown is the one compiled."""
    model = lc.compile(tree, cache_dir=cache_dir)
    equations = model.equations()
    for _ in range(4):
        values = random_values(tree, rng)
        y, params = state(tree, values)
        assert relative(accelerations(table(equations, values)), model.rhs(values["t"], y, params)[tree.n:]) < 1e-11


def _placed(R, r):
    """point(j, p): the point p of node j's frame in the base frame, ⁰r_j + ⁰R_j p (nodes numbered from 1)."""
    return lambda j, p: r[j - 1] + R[j - 1] @ np.array([float(x) for x in p])


@pytest.mark.parametrize("tree", [four_bar_tree(), spatial_tree()], ids=lambda tree: tree.name)
def test_the_loops_closure_is_the_models_constraint(tree, cache_dir, rng):
    model = lc.compile(tree, cache_dir=cache_dir)
    equations = model.equations()
    assert [e.label for e in equations.part("constraint")] == list(tree.constraint_names)
    assert any("Lambda" in e.text for e in equations.part("motion"))   # (the augmented system, not the ABA)
    for _ in range(3):
        values = random_values(tree, rng)
        y, params = state(tree, values)
        names = {**values, "point": _placed(*base_frames(table(equations, values))),
                 "dot": lambda d, x: float(np.dot([float(e) for e in d], x))}
        residuals = model.constraint_residuals(values["t"], y, params)
        for line in equations.part("constraint"):
            phi = eval(line.text.split(" = ")[0], {"__builtins__": {}}, names)
            assert phi == pytest.approx(residuals[line.label], rel=1e-12, abs=1e-13)


def test_the_lines_read_as_the_textbook():
    equations = Equations("chain", tree_equations(planar_chain(2)))
    assert repr(equations) == "Equations('chain': 10 tree, 12 motion, 3 energy)"
    lines = equations.lines
    assert r"{}^{2}X_{1} &= \operatorname{rot}\left(\operatorname{rz}\left(th_{1}\right)\right) " \
           r"\operatorname{xlt}\left(l_{0}, 0, 0\right)" in lines
    assert r"\ddot{q}_{i} &= D_{i}^{-1} \left(u_{i} - U_{i}^{T} a'_{i}\right)" in lines
    assert str(equations).splitlines()[2] == "Kinematic tree (nodes i = 1..n, parents first; the base is node 0):"


def test_every_line_renders(cache_dir):
    """matplotlib's mathtext parses every LaTeX line of a tree with loops, ball joints, springs and torques."""
    mathtext = pytest.importorskip("matplotlib.mathtext")
    parser = mathtext.MathTextParser("path")
    for tree in (spatial_tree(), spherical_chain(1), cart_pole(), random_tree(3)[0], four_bar_tree()):
        for line in Equations(tree.name, tree_equations(tree)).lines:
            # (mathtext has no environments: a matrix's is parsed as a group, its & and \\ as spaces)
            for environment, group in ((r"\begin{matrix}", "{"), (r"\end{matrix}", "}"), ("&=", "="), ("&", r"\;"),
                                       (r"\\", r"\;")):
                line = line.replace(environment, group)
            parser.parse(f"${line}$")


# -- cost, the cache without sympy ------------------------------------------------------------------------------------


def test_a_100_link_chains_equations_are_small_and_quick():
    """A per-node table grows linearly: 100 links take well under a second and under 100 kB of LaTeX."""
    sizes = {}
    for n in (50, 100):
        tree = planar_chain(n)
        start = time.process_time()
        equations = Equations(tree.name, tree_equations(tree))
        elapsed = time.process_time() - start
        sizes[n] = len(equations.latex) + len(str(equations))
        assert len(equations) <= 4 * n + 20
    assert elapsed < 2.0 and len(equations.latex) < 100_000, (elapsed, len(equations.latex))
    assert sizes[100] < 2.1 * sizes[50]


LOAD_PROBE = textwrap.dedent(
    """
    import json, sys
    import lagcomp as lc

    equations = lc.load("equations_loaded_tree", cache_dir=sys.argv[1]).equations()
    print(json.dumps({"sympy_imported": "sympy" in sys.modules, "equations": equations.equations,
                      "latex": equations.latex}))
    """
)


def test_a_loaded_tree_has_the_same_equations_without_sympy(tmp_path):
    tree = lc.Tree(cart_pole().links, gravity=(0, -sp.Symbol("g"), 0), name="equations_loaded_tree")
    equations = lc.compile(tree, cache_dir=tmp_path).equations()   # (builds the companion: as a System's)
    env = {k: v for k, v in os.environ.items() if k != "LAGCOMP_CACHE_DIR"}
    out = subprocess.run([sys.executable, "-c", LOAD_PROBE, str(tmp_path)], capture_output=True, text=True,
                         env=env, check=True)
    loaded = json.loads(out.stdout.strip().splitlines()[-1])
    assert loaded == {"sympy_imported": False, "equations": [list(e) for e in equations], "latex": equations.latex}
