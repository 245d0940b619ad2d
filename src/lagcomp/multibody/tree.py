"""A kinematic tree of rigid links connected by joints: the description the multibody path compiles.

A `Tree` lists its `Link` s parents first.  Each link has a frame, placed by its joint in the parent link's frame
(the tree's fixed base frame for a root link; `lagcomp.multibody.joints`), and its mass properties in that frame:
mass (kg), centre of mass (m, link axes) and inertia about the centre of mass (kg m², link axes).  Gravity is a
3-vector in the base frame (m/s², e.g. (0, 0, −g)).  Quantities are numbers or sympy expressions of parameters,
which the tree collects (sorted by name) like a `lagcomp.System`; a joint's torque may also read t, the coordinates
and their velocities.

Internally each joint is a chain of one-degree-of-freedom `Node` s (a universal joint is two, the first with a
massless frame): the recursions (`lagcomp.multibody.aba`, ...) run over the nodes, in order, parents first.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import sympy as sp

from lagcomp.codegen.kinds import TREE_KINDS
from lagcomp.errors import InitialConditionError, ModelError, ParameterError
from lagcomp.model.bodies import inertia_matrix
from lagcomp.model.friction import Friction
from lagcomp.model.system import _unique_names as unique_names
from lagcomp.multibody.joints import ISSUE, Elementary, Joint, t
from lagcomp.multibody.loops import closures
from lagcomp.multibody.shadow import shadow_events
from lagcomp.multibody.user_events import checked_events, event_roles

ZERO_INERTIA = sp.zeros(3, 3)


@dataclass(frozen=True, eq=False)
class Link:
    """A rigid link of a `Tree`.

    Parameters
    ----------
    name : str
        An identifier; other links name it as their `parent`.
    joint : lagcomp.Revolute, Prismatic, Universal, Cylindrical, Planar, Spherical or Free
        How the link moves relative to its parent, and where the joint sits in the parent's frame.
    parent : str, optional
        The parent link's name; None (default) for a link jointed to the fixed base.
    mass : expression
        Mass (kg), ≥ 0.
    com : 3 expressions
        Centre of mass in the link's frame (m).
    inertia : 3 principal moments or 3×3 tensor
        Inertia about the centre of mass, link axes (kg m²); symmetric, positive semidefinite.
    limits : dict, optional
        {coordinate name: limits} of the joint's coordinates (`lc.from_urdf` gives a
        `lagcomp.multibody.urdf.JointLimits`): carried for the user in ``Tree.limits``; no kernel, driver or event
        reads them today.
    """

    name: str
    joint: Joint
    parent: str | None = None
    mass: object = 0
    com: object = (0, 0, 0)
    inertia: object = (0, 0, 0)
    limits: object = None


@dataclass(frozen=True)
class Node:
    """One degree of freedom of the tree: the node index of its parent (−1: the base), its joint, and the mass
    properties of the frame it moves (zero for the massless frames inside a composite joint)."""

    parent: int
    joint: Elementary
    link: str
    mass: sp.Expr
    com: tuple
    inertia: sp.Matrix


class Tree:
    """A kinematic tree of rigid links, compiled by ``lc.compile(tree)`` from recursive multibody algorithms.

    Parameters
    ----------
    links : sequence of Link
        Parents before children.
    gravity : 3 expressions, optional
        Gravitational acceleration in the base frame (m/s²); default none.
    name : str
        An identifier: the compiled model's name.
    description : str, optional
    defaults : dict, optional
        Parameter values by name (or Symbol).
    q0, qd0 : sequences, optional
        Default initial coordinates and velocities, in `coordinate_names` order.
    t_end : float
        Suggested run length (s).
    loops : sequence of lagcomp.Loop, optional
        Cut joints closing kinematic loops: holonomic constraints on the tree (`lagcomp.multibody.loops`).
    events : sequence of lagcomp.Event, lagcomp.Contact or lagcomp.Friction, optional
        The user's events, contacts and friction elements (pressed by a contact or an expression), in the tree's
        coordinates, their velocities, t and parameters (a link's point through `lagcomp.multibody.link_point`);
        compiled as a System's are (`lagcomp.multibody.user_events`).

    Attributes
    ----------
    nodes : tuple of Node
        The degrees of freedom, parents first; node i moves coordinate i.
    limits : dict
        {coordinate name: limits} gathered from the links' `limits` (not used by lagcomp yet).
    coordinates : tuple
        The joints' coordinates q_i(t), in node order.
    parameters : tuple of Symbol
        Every symbol of the description other than t, sorted by name.
    closures : tuple of lagcomp.multibody.loops.Closure
        The checked loops.
    events : tuple of lagcomp.Event
        The spherical joints' shadow switches (`lagcomp.multibody.shadow`), then the user's `events`.
    user_events : tuple of lagcomp.Event
        The user's events alone.
    """

    def __init__(self, links, *, gravity=(0, 0, 0), name: str = "tree", description: str = "", defaults=None,
                 q0=None, qd0=None, t_end: float = 10.0, loops=(), events=()):
        if not isinstance(name, str) or not name.isidentifier():
            raise ModelError(f"Tree: the name must be a Python identifier like 'arm', got {name!r}.")
        self.name, self.description = name, str(description)
        self.links = tuple(links) if not isinstance(links, Link) else (links,)
        self.gravity = _vector(gravity, f"{name}: gravity")
        self.nodes = _nodes(self.links, name)
        self.coordinates = tuple(node.joint.coordinate for node in self.nodes)
        names = self.coordinate_names
        repeated = sorted({c for c in names if names.count(c) > 1})
        if repeated:
            raise ModelError(f"{name}: the coordinate(s) {repeated} move more than one joint: give each its own name.")
        self.closures = closures(loops, [link.name for link in self.links], name)
        self.events = shadow_events(self.nodes)   # (the spherical joints' MRP switches; none without them)
        self.user_events = checked_events(events, self)
        self.events += self.user_events
        self.parameters = _parameters(self)
        self.defaults = _defaults(self, defaults or {})
        self.q0, self.qd0 = _initial(q0, "q0", self), _initial(qd0, "qd0", self)
        if not (isinstance(t_end, (int, float)) and math.isfinite(t_end) and t_end > 0):
            raise ModelError(f"{name}: `t_end` must be a positive duration, got {t_end!r}.")
        self.t_end = float(t_end)
        self.limits = _limits(self.links, names, name)

    @property
    def n(self) -> int:
        """Degrees of freedom."""
        return len(self.nodes)

    @property
    def coordinate_names(self) -> tuple[str, ...]:
        return tuple(q.func.__name__ for q in self.coordinates)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.parameters)

    @property
    def constraint_names(self) -> tuple[str, ...]:
        """The loops' holonomic constraints (one per closing direction), in order: the reactions' names."""
        return tuple(name for closure in self.closures for name in closure.names)

    @property
    def event_names(self) -> tuple[str, ...]:
        """The events' names in kernel order: the shadow switches, then the user's."""
        return tuple(e.name for e in self.events)

    @property
    def chart_events(self) -> tuple[str, ...]:
        """The names of the events that change charts, not the motion: the spherical joints' shadow switches
        (`lagcomp.multibody.shadow`), which a method may apply anywhere past their zero without locating it
        (`lagcomp.integrate.methods.Method.switches_charts`)."""
        return tuple(e.name for e in self.events[:len(self.events) - len(self.user_events)])

    @property
    def contacts(self) -> tuple:
        """The user's `lagcomp.Contact` s, in order."""
        from lagcomp.model.contacts import Contact

        return tuple(e for e in self.user_events if isinstance(e, Contact))

    def expressions(self) -> dict:
        """Every expression of the description by role (for parameters, checks and the fingerprint)."""
        roles = {"gravity": sp.Matrix(self.gravity)}
        for i, node in enumerate(self.nodes):
            j = node.joint
            roles[f"node {i} ({node.link})"] = sp.Matrix([
                node.mass, *node.com, *node.inertia, *j.axis, *j.origin, *(e for row in j.rotation for e in row),
                j.stiffness, j.rest, j.damping])
            roles[f"torque of {j.coordinate.func.__name__}"] = sp.sympify(j.torque)
        for closure in self.closures:
            roles[f"points of loop {closure.loop}"] = sp.Matrix([*closure.first_point, *closure.second_point])
        return roles | event_roles(self.user_events)

    def fingerprint(self) -> str:
        """A canonical text of everything the kernels depend on (for the cache key)."""
        parts = ["multibody tree", self.name, repr(self.coordinate_names), repr(self.parameter_names),
                 repr([(node.parent, node.joint.kind) for node in self.nodes])]
        if self.closures:   # (only then: the keys of trees without loops stay as they were)
            parts.append(repr([(c.first, c.second, c.directions, c.names) for c in self.closures]))
        if self.user_events:   # (only then, likewise; the expressions are among the roles below)
            parts.append(repr([(type(e).__name__, e.name, e.direction, e.terminal, e.changes_state,
                                getattr(e, "normal", None)) for e in self.user_events]))   # (a contact's name)
        return "\n".join(parts + [f"{role}={sp.srepr(expr)}" for role, expr in self.expressions().items()])

    def on_demand_refusal(self, what: str, kind: str | None = None) -> str | None:
        """Why a tree model has no `what` (an on-demand kernel and its feature, or an analysis that reads a System's
        T and V) yet; None when `what` is a kernel of the on-demand `kind` the tree path builds
        (`lagcomp.codegen.kinds.TREE_KINDS`: its recursions differentiated, `lagcomp.codegen.tree_companion`)."""
        if kind in TREE_KINDS:   # (with loops too: `lagcomp.codegen.tree_loop_companion`)
            return None
        return (f"{what} is not available for the kinematic tree {self.name!r} yet: the multibody path emits rhs, "
                "energy and momenta, and on demand mass_matrix, forcing, the Jacobians, the tangent kernels, "
                "rest_partials (radau, sensitivities, lagcomp.analysis.linearize), the links' geometry "
                "(animation), the power of the energy balance, the canonical kernels (gauss1/2/3), the Taylor "
                "coefficients (method='taylor'), the equations (Model.equations()) and the lanes of batched sweeps; "
                f"the other kernels are not built for trees ({ISSUE}). Use those methods, "
                "or write the system as a lc.System with lc.RigidBody for this feature.")

    def lanes_refusal(self) -> str | None:
        """What the tree's motion has besides its articulated-body ``rhs``, which the lanes of a batched sweep
        (``rhs_lanes``, `lagcomp.codegen.tree_lanes`) do not evaluate: closed loops (an augmented solve), contacts
        and friction elements (modes that switch per trajectory); None when there is nothing.  Such a tree's kind
        "lanes" is empty (as a constrained System's), and its batched sweep says this (`lagcomp.integrate.sweep`)."""
        frictions = [e.name for e in self.user_events if isinstance(e, Friction)]
        reasons = [f"closed loops {[c.loop for c in self.closures]}"] * bool(self.closures)
        reasons += [f"contacts {[c.name for c in self.contacts]}"] * bool(self.contacts)
        reasons += [f"friction elements {frictions}"] * bool(frictions)
        return " and ".join(reasons) or None

    def __repr__(self) -> str:
        return f"Tree({self.name!r}, links={[link.name for link in self.links]}, n={self.n})"


def _vector(value, what: str) -> tuple:
    try:
        v = tuple(sp.sympify(x) for x in value)
    except (TypeError, sp.SympifyError) as err:
        raise ModelError(f"{what} must be three expressions, got {value!r}.") from err
    if len(v) != 3:
        raise ModelError(f"{what} must be three expressions, got {value!r}.")
    return v


def _nodes(links, name: str) -> tuple[Node, ...]:
    """The degrees of freedom of `links`, parents first (`Node`), with the links' checked mass properties."""
    nodes, last_node = [], {}
    for link in links:
        if not isinstance(link, Link):
            raise ModelError(f"{name}: a tree is a sequence of lc.Link, got {link!r}.")
        if not isinstance(link.name, str) or not link.name.isidentifier() or link.name in last_node:
            raise ModelError(f"{name}: link name {link.name!r} must be an identifier, and each link's own.")
        if link.parent is not None and link.parent not in last_node:
            raise ModelError(f"{name}: link {link.name!r} names the parent {link.parent!r}, which is not a link "
                             "listed before it: list parents first.")
        if not isinstance(link.joint, Joint):
            raise ModelError(f"{name}: link {link.name!r} needs a joint (lc.Revolute, lc.Prismatic, ...), got "
                             f"{link.joint!r}.")
        mass = sp.sympify(link.mass)
        if mass.is_negative:
            raise ModelError(f"{name}: link {link.name!r} has the negative mass {mass}.")
        com = _vector(link.com, f"{name}: link {link.name!r}: com")
        inertia = inertia_matrix(link.inertia, None, f"{name}: link {link.name!r}")
        steps = link.joint.elementary()
        parent = -1 if link.parent is None else last_node[link.parent]
        for k, step in enumerate(steps):
            last = k == len(steps) - 1
            nodes.append(Node(parent, step, link.name, mass if last else sp.S.Zero, com if last else (0, 0, 0),
                              inertia if last else ZERO_INERTIA))
            parent = len(nodes) - 1
        last_node[link.name] = parent
    if not nodes:
        raise ModelError(f"{name}: a tree needs at least one link.")
    return tuple(nodes)


def _parameters(tree: Tree) -> tuple:
    """The symbols of `tree` other than t, sorted by name; only a joint's torque and the user's events may read t
    and the coordinates."""
    coordinates = set(tree.coordinates)
    found = set()
    for role, expr in tree.expressions().items():
        allowed = coordinates if role.startswith(("torque", "event")) else set()
        if not allowed and expr.has(t):
            raise ModelError(f"{tree.name}: {role} depends on t: only a joint's torque and an event may (the links' "
                             "mass properties and the joints' placements, axes, springs and dampers are constant).")
        for f in expr.atoms(sp.core.function.AppliedUndef):
            if f not in allowed:
                raise ModelError(f"{tree.name}: {f} in {role} is not allowed there: only a joint's torque and an "
                                 "event may read t, the tree's coordinates and their velocities.")
        found |= {s for s in expr.free_symbols if s != t}
    unique_names([s.name for s in found], "parameters")   # (values are passed by name)
    impostor = next((s for s in found if s.name == t.name), None)
    if impostor is not None:
        raise ModelError(f"{tree.name}: a symbol named t that is not lagcomp's time symbol (lc.t) would become a "
                         "parameter: write time dependence with lc.t.")
    return tuple(sorted(found, key=lambda s: s.name))


def _defaults(tree: Tree, defaults) -> dict:
    if not hasattr(defaults, "items"):
        raise ParameterError(f"{tree.name}: `defaults` must be a mapping of parameter name to value, got "
                             f"{defaults!r}.")
    names, checked = set(tree.parameter_names), {}
    for key, value in defaults.items():
        key = key.name if isinstance(key, sp.Symbol) else key
        if key not in names:
            raise ParameterError(f"{tree.name}: default value given for unknown parameter {key!r}; parameters are "
                                 f"{sorted(names)}.")
        try:
            checked[key] = float(value)
        except (TypeError, ValueError) as err:
            raise ParameterError(f"{tree.name}: default of `{key}` must be a number, got {value!r}.") from err
        if not math.isfinite(checked[key]):
            raise ParameterError(f"{tree.name}: default of `{key}` is {value}; it must be finite.")
    return checked


def _initial(values, what: str, tree: Tree):
    if values is None:
        return None
    try:
        values = tuple(float(v) for v in values)
    except (TypeError, ValueError) as err:
        raise InitialConditionError(f"{tree.name}: `{what}` must be {tree.n} numbers, got {values!r}.") from err
    if len(values) != tree.n or not all(math.isfinite(v) for v in values):
        raise InitialConditionError(f"{tree.name}: `{what}` must be {tree.n} finite numbers (one per coordinate "
                                    f"{list(tree.coordinate_names)}), got {list(values)}.")
    return values


def _limits(links, coordinate_names, name: str) -> dict:
    """The links' `limits` merged by coordinate name; each key must name a coordinate of the tree."""
    merged = {}
    for link in links:
        if link.limits is None:
            continue
        if not hasattr(link.limits, "items"):
            raise ModelError(f"{name}: link {link.name!r}: `limits` must be a mapping of coordinate name to limits, "
                             f"got {link.limits!r}.")
        unknown = sorted(set(link.limits) - set(coordinate_names))
        if unknown:
            raise ModelError(f"{name}: link {link.name!r} gives limits of {unknown}, which are not coordinates of "
                             f"the tree {list(coordinate_names)}.")
        merged.update(link.limits)
    return merged
