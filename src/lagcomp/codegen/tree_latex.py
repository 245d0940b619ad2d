r"""A kinematic tree's equations as LaTeX and text (`Model.equations()` of a `lagcomp.Tree`): the recursion itself.

A tree's equations of motion are never expanded (expanding T is what the multibody path avoids), so what is shown
is what lagcomp compiled, in the spatial-vector notation of Featherstone (*Rigid Body Dynamics Algorithms*, 2008;
6-vectors angular part first, `lagcomp.multibody.spatial`): the generic recursion, written once for every node i
(a node is one degree of freedom: a universal joint is two, a ball joint three), and a table of the nodes with each
one's data substituted: its parent λ(i), link, joint and coordinate, its placement ``X_i = rot(E) xlt(r)`` in the
parent's frame, its motion subspace S_i, its rigid-body inertia ``I_i = mcI(m, c, I_G)`` and its joint force τ_i.
The recursion is shown rather than the emitted straight-line program (its named locals ``_b000123``): the program
of a 100-link chain has thousands of assignments whose names say nothing, while the recursion and the table grow by
a few short lines per node, every one of which a reader can check against the tree and the textbook.

The lines (`lagcomp.equations.Equation`), by part:

* ``tree``: gravity, then per node: ``lambda`` (the parent; the text adds link, joint type, coordinate and axis),
  ``X``, ``S``, for a ball joint's nodes the rate ``qdot`` (q̇_i is otherwise the rate of node i's coordinate),
  ``I`` where the node has mass (massless frames have I_i = 0), ``tau`` where its joint force is not zero; then the
  base-frame placements ⁰R_i, ⁰r_i that V and the loops read;
* ``motion``: the articulated-body algorithm's three passes (a tree without loops), or M q̈ = F + Λᵀλ with the
  composite-rigid-body algorithm for M and recursive Newton–Euler for F (a tree with loops); a ball joint's MRP
  maps where the tree has one;
* ``constraint``: each loop's Φ_k(q) = d_k·(P_first − P_second) = 0;
* ``energy``: T = ½ Σ v_iᵀ I_i v_i, V of gravity from the base-frame placements, V of the joints' springs written
  out, and V.

The text of a line is sympy's `str` of its data with Featherstone's operators as calls: ``rot(rz(th1))*xlt(l0, 0,
0)``, ``mcI(m1, (c1, d1, 0), diag(J1, J1, J1))``, ``rot(mrp(s0x, s0y, s0z).T)``, ``(J(s0x, s0y, s0z)*(s0x_dot,
s0y_dot, s0z_dot))[0]``: with those operators defined, each data line parses back (tests/test_multibody_equations.py
rebuilds T and q̈ from them).  rx, ry, rz are Featherstone's coordinate rotations (E = R_x(θ)ᵀ, ...), mrp(σ) the
rotation matrix of modified Rodrigues parameters (`lagcomp.multibody.mrp`), J(σ) its rate matrix, ω = J(σ) σ̇.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.codegen.latex import TextPrinter, dotted_latex, symbol_latex
from lagcomp.equations import Equation
from lagcomp.multibody.joints import t
from lagcomp.multibody.kinematics import LocalNode, local_nodes
from lagcomp.multibody.tree import Tree

#: rx, ry, rz by the index of the axis they turn about.
_AXIS_ROTATIONS = ("rx", "ry", "rz")


class _Printer:
    """LaTeX and text of expressions over a tree's coordinates, velocities and parameters, under the user's names."""

    def __init__(self, names: dict):
        self.latex_names = {s: latex for s, (latex, _) in names.items()}
        self.text_printer = TextPrinter({s: text for s, (_, text) in names.items()})

    def latex(self, expr) -> str:
        return sp.latex(sp.sympify(expr), symbol_names=self.latex_names)

    def text(self, expr) -> str:
        return self.text_printer.doprint(sp.sympify(expr))

    def vector(self, values) -> tuple[str, str]:
        """A tuple of expressions: ``\\left(a, b, c\\right)`` and ``(a, b, c)``."""
        return (r"\left(" + ", ".join(self.latex(v) for v in values) + r"\right)",
                "(" + ", ".join(self.text(v) for v in values) + ")")

    def matrix(self, rows) -> tuple[str, str]:
        """A 3×3 matrix, in the text on one line, ``Matrix([[a, b, c], ...])``."""
        m = sp.Matrix(rows)
        text = ", ".join("[" + ", ".join(self.text(e) for e in m.row(i)) + "]" for i in range(m.rows))
        return self.latex(m), f"Matrix([{text}])"

    def inertia(self, rows) -> tuple[str, str]:
        """A 3×3 inertia: diag(...) where it is diagonal, else the whole matrix."""
        m = sp.Matrix(rows)
        if m.is_diagonal():
            values = [m[k, k] for k in range(3)]
            return (r"\operatorname{diag}" + self.vector(values)[0], "diag" + self.vector(values)[1])
        return self.matrix(m)


def tree_equations(tree: Tree) -> tuple[Equation, ...]:
    """The lines of `tree`'s equations (module docstring), in order: tree, motion, constraint, energy."""
    q = tuple(sp.Dummy(name, real=True) for name in tree.coordinate_names)
    qd = tuple(sp.Dummy(f"{name}_dot", real=True) for name in tree.coordinate_names)
    names = {}
    for name, coordinate, velocity in zip(tree.coordinate_names, q, qd, strict=True):
        names[coordinate] = (symbol_latex(name), name)
        names[velocity] = (dotted_latex(name, r"\dot"), f"{name}_dot")
    printer = _Printer(names)
    nodes = local_nodes(tree, q, qd, {t: sp.Symbol("t", real=True)})
    lines = [_line("tree", "gravity", (r"\vec{g}", "gravity"), printer.vector(tree.gravity))]
    for i, node in enumerate(nodes):
        lines += _node_lines(tree, i, node, printer)
    lines += _base_frame_lines()
    spherical = any(node.kind == "spherical" for node in nodes)
    lines += _loop_motion_lines(spherical) if tree.closures else _aba_lines(spherical)
    lines += _constraint_lines(tree, printer)
    lines += _energy_lines(nodes, printer)
    return tuple(lines)


def _line(part: str, label: str, lhs: tuple[str, str], rhs: tuple[str, str]) -> Equation:
    """The `Equation` lhs = rhs, each side given as (LaTeX, text)."""
    return Equation(part, label, lhs[0], rhs[0], f"{lhs[1]} = {rhs[1]}")


def _node_lines(tree: Tree, i: int, node: LocalNode, printer: _Printer) -> list[Equation]:
    """The table's lines of node `i` (0-based; shown as i + 1, the base being 0): its joint, X, S, rate, I, τ."""
    k, parent = i + 1, node.parent + 1
    coordinate = tree.coordinate_names[i]
    lines = [_line("tree", coordinate, (rf"\lambda({k})", f"lambda({k})"), _joint_description(tree, i, parent,
                                                                                               printer))]
    lines.append(_line("tree", coordinate, (rf"{{}}^{{{k}}}X_{{{parent}}}", f"X_{k}"), _placement(node, printer)))
    w, v = ((0, 0, 0), node.axis) if node.kind == "prismatic" else (node.axis, (0, 0, 0))
    S = printer.vector((*w, *v))
    lines.append(_line("tree", coordinate, (f"S_{{{k}}}", f"S_{k}"), (S[0] + "^{T}", S[1])))
    if node.kind == "spherical":
        lines.append(_line("tree", coordinate, (rf"\dot{{q}}_{{{k}}}", f"qdot_{k}"), _ball_rate(node, printer)))
    if node.mass != 0 or any(e != 0 for row in node.inertia for e in row):
        c, inertia = printer.vector(node.com), printer.inertia(node.inertia)
        mass = (printer.latex(node.mass), printer.text(node.mass))
        lines.append(_line("tree", coordinate, (f"I_{{{k}}}", f"I_{k}"),
                           (rf"\operatorname{{mcI}}\left({mass[0]}, {c[0]}, {inertia[0]}\right)",
                            f"mcI({mass[1]}, {c[1]}, {inertia[1]})")))
    if node.force != 0:
        lines.append(_line("tree", coordinate, (rf"\tau_{{{k}}}", f"tau_{k}"),
                           (printer.latex(node.force), printer.text(node.force))))
    return lines


def _escaped(name: str) -> str:
    """A link's name inside ``\\text{}`` (an identifier: only its underscores need escaping)."""
    return name.replace("_", r"\_")


def _joint_description(tree: Tree, i: int, parent: int, printer: _Printer) -> tuple[str, str]:
    """λ(i) with what the node is: its link on the parent's, the joint's type (and which of its degrees of
    freedom), the coordinate and the axis, in LaTeX and text."""
    node = tree.nodes[i]
    link = next(link for link in tree.links if link.name == node.link)
    joint = type(link.joint).__name__
    own = [j for j, other in enumerate(tree.nodes) if other.link == node.link]
    if len(own) > 1:
        joint += f" {own.index(i) + 1} of {len(own)}"
    on = "the base" if link.parent is None else link.parent
    coordinate = tree.coordinate_names[i]
    axis = printer.vector(node.joint.axis)
    along = "about" if node.joint.kind != "prismatic" else "along"
    latex = (rf"{parent} \quad \text{{({_escaped(node.link)} on {_escaped(on)}: {joint}, }} "
             rf"{symbol_latex(coordinate)} \text{{ {along} }} {axis[0]}\text{{)}}")
    return latex, f"{parent}   [{node.link} on {on}: {joint}, {coordinate} {along} {axis[1]}]"


def _placement(node: LocalNode, printer: _Printer) -> tuple[str, str]:
    """X_i = X_J(q_i) X_T, X_T = rot(E_T) xlt(r_T) (Featherstone's order; identity factors left out)."""
    factors = [_joint_transform(node, printer)]
    rotation = sp.Matrix(node.rotation)
    if rotation != sp.eye(3):
        E = printer.matrix(rotation.T)
        factors.append((rf"\operatorname{{rot}}\left({E[0]}\right)", f"rot({E[1]})"))
    if any(e != 0 for e in node.origin):
        r = printer.vector(node.origin)
        factors.append((rf"\operatorname{{xlt}}{r[0]}", f"xlt{r[1]}"))
    factors = [f for f in factors if f is not None]
    if not factors:
        return r"\mathbf{1}", "1"
    return " ".join(f[0] for f in factors), "*".join(f[1] for f in factors)


def _joint_transform(node: LocalNode, printer: _Printer) -> tuple[str, str] | None:
    """X_J(q): rot(rx/ry/rz(±q)) or rot(E_J) about an axis; xlt(a q) along one; rot(mrp(σ)ᵀ) of a ball joint's
    first node (the other two: None, the identity)."""
    if node.kind == "spherical":
        if node.part > 0:
            return None
        sigma = printer.vector(node.sigma)
        return (rf"\operatorname{{rot}}\left(\operatorname{{mrp}}{sigma[0]}^{{T}}\right)", f"rot(mrp{sigma[1]}.T)")
    if node.kind == "prismatic":
        shift = printer.vector([a * node.q for a in node.axis])
        return rf"\operatorname{{xlt}}{shift[0]}", f"xlt{shift[1]}"
    axis = list(node.axis)
    along = [k for k, a in enumerate(axis) if a != 0]
    if len(along) == 1 and abs(axis[along[0]]) == 1:   # ±x, ±y or ±z: Featherstone's rx, ry, rz
        k = along[0]
        angle = axis[k] * node.q
        name = _AXIS_ROTATIONS[k]
        return (rf"\operatorname{{rot}}\left(\operatorname{{{name}}}\left({printer.latex(angle)}\right)\right)",
                f"rot({name}({printer.text(angle)}))")
    E = printer.matrix(_rodrigues(axis, node.q).T)
    return rf"\operatorname{{rot}}\left({E[0]}\right)", f"rot({E[1]})"


def _rodrigues(axis, angle) -> sp.Matrix:
    """R_J = cos q 1 + sin q [a]× + (1 − cos q) a aᵀ: the rotation by `angle` about the unit `axis`."""
    a = sp.Matrix(axis)
    skew = sp.Matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return sp.cos(angle) * sp.eye(3) + sp.sin(angle) * skew + (1 - sp.cos(angle)) * a * a.T


def _ball_rate(node: LocalNode, printer: _Printer) -> tuple[str, str]:
    """A ball joint's node rate: component `part` of its body-axis angular velocity ω = J(σ) σ̇."""
    sigma, rates = printer.vector(node.sigma), printer.vector(node.sigma_dot)
    return (rf"\left(J{sigma[0]} {rates[0]}^{{T}}\right)_{{{'xyz'[node.part]}}}",
            f"(J{sigma[1]}*Matrix({rates[1]}))[{node.part}]")


def _base_frame_lines() -> list[Equation]:
    """The nodes' frames in the base's, from X_i = rot(E_i) xlt(r_i): what V and the loops read (no kernel forms
    them for V: `lagcomp.multibody.energy` dots gravity into each placement instead)."""
    return [
        _line("tree", "base frame", (r"{}^{0}R_{i}", "R0_i"),
              ((r"{}^{0}R_{\lambda(i)} E_{i}^{T}, \quad {}^{0}r_{i} = {}^{0}r_{\lambda(i)} + {}^{0}R_{\lambda(i)} r_{i}"
               r" \quad \left({}^{i}X_{\lambda(i)} = \operatorname{rot}(E_{i}) \operatorname{xlt}(r_{i}),\ "
               r"{}^{0}R_{0} = \mathbf{1},\ {}^{0}r_{0} = 0\right)"),
               ("R0_lambda(i)*E_i.T,  r0_i = r0_lambda(i) + R0_lambda(i)*r_i  (X_i = rot(E_i)*xlt(r_i), R0_0 = 1, "
               "r0_0 = 0)"))),
    ]


#: The articulated-body algorithm (`lagcomp.multibody.aba`) as (label, LaTeX lhs, LaTeX rhs, text).
_ABA = (
    ("velocity", "v_{i}", r"{}^{i}X_{\lambda(i)} v_{\lambda(i)} + S_{i} \dot{q}_{i} \quad (i = 1, \dots, n;\ v_{0} = 0)",
     "v_i = X_i*v_lambda(i) + S_i*qdot_i   (i = 1..n; v_0 = 0)"),
    ("velocity product", "c_{i}", r"v_{i} \times S_{i} \dot{q}_{i}", "c_i = v_i x S_i*qdot_i"),
    ("articulated inertia", "I^{A}_{i}",
     r"I_{i} + \sum_{j:\,\lambda(j) = i} {}^{j}X_{i}^{T} I^{a}_{j}\, {}^{j}X_{i} \quad (i = n, \dots, 1)",
     "IA_i = I_i + sum_{j: lambda(j) = i} X_j.T*Ia_j*X_j   (i = n..1)"),
    ("bias force", "p^{A}_{i}", r"v_{i} \times^{*} I_{i} v_{i} + \sum_{j:\,\lambda(j) = i} {}^{j}X_{i}^{T} p^{a}_{j}",
     "pA_i = v_i x* I_i*v_i + sum_{j: lambda(j) = i} X_j.T*pa_j"),
    ("U", "U_{i}", r"I^{A}_{i} S_{i}", "U_i = IA_i*S_i"),
    ("D", "D_{i}", r"S_{i}^{T} U_{i}", "D_i = S_i.T*U_i"),
    ("u", "u_{i}", r"\tau_{i} - S_{i}^{T} p^{A}_{i}", "u_i = tau_i - S_i.T*pA_i"),
    ("articulated inertia passed on", "I^{a}_{i}", r"I^{A}_{i} - U_{i} D_{i}^{-1} U_{i}^{T}",
     "Ia_i = IA_i - U_i*U_i.T/D_i"),
    ("bias force passed on", "p^{a}_{i}", r"p^{A}_{i} + I^{a}_{i} c_{i} + U_{i} D_{i}^{-1} u_{i}",
     "pa_i = pA_i + Ia_i*c_i + U_i*u_i/D_i"),
    ("acceleration before the joint", "a'_{i}",
     r"{}^{i}X_{\lambda(i)} a_{\lambda(i)} + c_{i} \quad (i = 1, \dots, n;\ a_{0} = (0, -\vec{g}))",
     "a'_i = X_i*a_lambda(i) + c_i   (i = 1..n; a_0 = (0, -gravity))"),
    ("joint acceleration", r"\ddot{q}_{i}", r"D_{i}^{-1} \left(u_{i} - U_{i}^{T} a'_{i}\right)",
     "qddot_i = (u_i - U_i.T*a'_i)/D_i"),
    ("acceleration", "a_{i}", r"a'_{i} + S_{i} \ddot{q}_{i}", "a_i = a'_i + S_i*qddot_i"),
)

#: A ball joint's maps (`lagcomp.multibody.mrp`, `lagcomp.multibody.charts`), for a tree that has one.
_BALL = (
    ("mrp", r"\operatorname{mrp}(\sigma)",
     r"\mathbf{1} + \frac{8 [\sigma]_{\times}^{2} + 4 (1 - \sigma^{T}\sigma) [\sigma]_{\times}}{(1 + \sigma^{T}\sigma)^{2}}",
     "mrp(sigma) = 1 + (8*[sigma]x**2 + 4*(1 - sigma.sigma)*[sigma]x)/(1 + sigma.sigma)**2"),
    ("J", r"J(\sigma)", (r"\frac{4}{(1 + \sigma^{T}\sigma)^{2}} \left((1 - \sigma^{T}\sigma) \mathbf{1} - 2 [\sigma]_{\times}"
     r" + 2 \sigma \sigma^{T}\right)"), ("J(sigma) = 4*((1 - sigma.sigma)*1 - 2*[sigma]x + 2*sigma*sigma.T)/(1 + "
     "sigma.sigma)**2")),
    ("ball joint velocity product", r"c_{k+2}", (r"v_{k+2} \times (\omega, 0) + (\dot{J} \dot{\sigma}, 0), \quad "
     r"c_{k} = c_{k+1} = 0 \quad (\text{nodes } k, k+1, k+2 \text{ of a ball joint}, \omega = J(\sigma) \dot{\sigma})"),
     ("c_(k+2) = v_(k+2) x (omega, 0) + (Jdot*sigma_dot, 0),  c_k = c_(k+1) = 0  (nodes k, k+1, k+2 of a ball joint, "
     "omega = J(sigma)*sigma_dot)")),
)

_BALL_ACCELERATION = (
    "ball joint", r"\ddot{\sigma}", r"J(\sigma)^{-1} \left(\ddot{q}_{k}, \ddot{q}_{k+1}, \ddot{q}_{k+2}\right)^{T}",
    "sigma_ddot = J(sigma)**-1*(qddot_k, qddot_(k+1), qddot_(k+2))")


def _template(rows) -> list[Equation]:
    """`Equation` s of the ``motion`` part from (label, LaTeX lhs, LaTeX rhs, text) rows."""
    return [Equation("motion", label, lhs, rhs, text) for label, lhs, rhs, text in rows]


def _aba_lines(spherical: bool) -> list[Equation]:
    """The articulated-body algorithm, and a ball joint's maps where the tree has one."""
    return _template(_ABA + ((*_BALL, _BALL_ACCELERATION) if spherical else ()))


#: A tree with loops: the augmented system, M by the composite-rigid-body algorithm, F by recursive Newton–Euler.
_LOOPS = (
    ("augmented system", r"M(q) \ddot{q}", (r"F(q, \dot{q}, t) + \Lambda(q)^{T} \lambda, \quad \Lambda = "
     r"\partial \Phi / \partial q"), "M(q)*qddot = F(q, qdot, t) + Lambda(q).T*lambda,  Lambda = dPhi/dq"),
    ("velocity", "v_{i}", r"{}^{i}X_{\lambda(i)} v_{\lambda(i)} + S_{i} \dot{q}_{i} \quad (i = 1, \dots, n;\ v_{0} = 0)",
     "v_i = X_i*v_lambda(i) + S_i*qdot_i   (i = 1..n; v_0 = 0)"),
    ("acceleration at rest", "a_{i}", (r"{}^{i}X_{\lambda(i)} a_{\lambda(i)} + v_{i} \times S_{i} \dot{q}_{i} "
     r"\quad (a_{0} = (0, -\vec{g}))"), "a_i = X_i*a_lambda(i) + v_i x S_i*qdot_i   (a_0 = (0, -gravity))"),
    ("force", "f_{i}", r"I_{i} a_{i} + v_{i} \times^{*} I_{i} v_{i} + \sum_{j:\,\lambda(j) = i} {}^{j}X_{i}^{T} f_{j}",
     "f_i = I_i*a_i + v_i x* I_i*v_i + sum_{j: lambda(j) = i} X_j.T*f_j"),
    ("forcing", "F_{i}", r"\tau_{i} - S_{i}^{T} f_{i}", "F_i = tau_i - S_i.T*f_i"),
    ("composite inertia", "I^{C}_{i}", r"I_{i} + \sum_{j:\,\lambda(j) = i} {}^{j}X_{i}^{T} I^{C}_{j}\, {}^{j}X_{i}",
     "IC_i = I_i + sum_{j: lambda(j) = i} X_j.T*IC_j*X_j"),
    ("mass matrix", "M_{ji} = M_{ij}", (r"S_{j}^{T} \left({}^{i}X_{j}\right)^{T} I^{C}_{i} S_{i} \quad "
     r"(j = i \text{ or an ancestor of } i)"), "M_ji = M_ij = S_j.T*X(j<-i).T*IC_i*S_i   (j = i or an ancestor of i)"),
)

_BALL_COORDINATES = (
    "ball joint coordinates", r"M_{\sigma}, F_{\sigma}, \Lambda_{\sigma}",
    r"J^{T} M J,\ J^{T} F,\ \Lambda J \quad (\text{each ball joint's rows and columns}, \omega = J(\sigma) \dot{\sigma})",
    ("M_sigma, F_sigma, Lambda_sigma = J.T*M*J, J.T*F, Lambda*J   (each ball joint's rows and columns, "
    "omega = J(sigma)*sigma_dot)"))


def _loop_motion_lines(spherical: bool) -> list[Equation]:
    """The augmented system and its recursions, and a ball joint's maps where the tree has one."""
    return _template(_LOOPS + ((*_BALL, _BALL_COORDINATES) if spherical else ()))


def _constraint_lines(tree: Tree, printer: _Printer) -> list[Equation]:
    """Φ_k = d_k·(P_first − P_second) = 0 per loop direction, P = ⁰r_j + ⁰R_j p of the link's last node j."""
    last = {node.link: j + 1 for j, node in enumerate(tree.nodes)}
    lines = []
    for closure in tree.closures:
        ends = []
        for link, point in ((closure.first, closure.first_point), (closure.second, closure.second_point)):
            p = printer.vector(point)
            if link is None:
                ends.append(p)
            else:
                j = last[link]
                ends.append((rf"{{}}^{{0}}r_{{{j}}} + {{}}^{{0}}R_{{{j}}} {p[0]}", f"point({j}, {p[1]})"))
        for name, d in zip(closure.names, closure.directions, strict=True):
            direction = printer.vector(d)
            lhs = (rf"{direction[0]} \cdot \left({ends[0][0]} - \left({ends[1][0]}\right)\right)",
                   f"dot({direction[1]}, {ends[0][1]} - {ends[1][1]})")
            lines.append(_line("constraint", name, lhs, ("0", "0")))
    return lines


def _energy_lines(nodes, printer: _Printer) -> list[Equation]:
    """T and V: templates over the table, the springs written out (`lagcomp.multibody.energy`)."""
    lines = [
        Equation("energy", "T", "T", r"\frac{1}{2} \sum_{i=1}^{n} v_{i}^{T} I_{i} v_{i}", "T = sum_i v_i.T*I_i*v_i/2"),
        Equation("energy", "V gravity", "V_{g}", r"-\sum_{i=1}^{n} m_{i}\, \vec{g} \cdot \left({}^{0}r_{i} + "
                 r"{}^{0}R_{i} c_{i}\right) \quad (I_{i} = \operatorname{mcI}(m_{i}, c_{i}, I_{G,i}))",
                 "V_g = -sum_i m_i*dot(gravity, r0_i + R0_i*c_i)   (I_i = mcI(m_i, c_i, IG_i))"),
    ]
    springs = sp.Add(*(node.stiffness * (node.q - node.rest) ** 2 / 2 for node in nodes if node.stiffness != 0))
    if springs != 0:
        lines.append(_line("energy", "V springs", ("V_{s}", "V_s"), (printer.latex(springs), printer.text(springs))))
        lines.append(Equation("energy", "V", "V", "V_{g} + V_{s}", "V = V_g + V_s"))
    else:
        lines.append(Equation("energy", "V", "V", "V_{g}", "V = V_g"))
    return lines
