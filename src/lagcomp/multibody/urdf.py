"""Robots from URDF files: `from_urdf` reads a robot description into a `lagcomp.Tree`.

The file is parsed by yourdfpy (the ``urdf`` extra: ``pip install 'lagcomp[urdf]'``), imported on first use; its
meshes are never read (the dynamics needs only the ``<inertial>`` elements).  What lagcomp builds from it:

* the URDF's root link is the fixed base (its own mass and the links fixed to it move with the ground, so they do
  not enter the dynamics); gravity is given in its frame, (0, 0, −9.81) m/s² by default.  With
  ``floating_base=True`` the root link floats instead (a legged robot, a humanoid): it gets a `Free` joint to the
  world frame, as Pinocchio's ``buildModelFromUrdf(path, JointModelFreeFlyer())`` gives it one, with the
  coordinates ``<root>_x``, ``<root>_y``, ``<root>_z`` (its origin's position in the world frame, m) and
  ``<root>_mrp1`` … ``<root>_mrp3`` (its orientation as modified Rodrigues parameters, `lagcomp.multibody.mrp`);
* every ``revolute``, ``continuous`` and ``prismatic`` joint becomes a `Revolute` or `Prismatic` joint of its child
  link, placed by the joint's ``<origin>`` (xyz, rpy: R = Rz(yaw) Ry(pitch) Rx(roll)) and turning or sliding along
  its ``<axis>`` (normalised), with the URDF ``<dynamics damping>`` as a viscous damper (``damping=False`` drops
  it; Coulomb ``friction`` is not modelled and is reported in the tree's description when nonzero);
* a ``fixed`` joint merges its child link into the link it hangs from: the masses add, the centre of mass is
  their mass-weighted mean, and each part's inertia, rotated into the link's axes (R I Rᵀ), is moved to the
  common centre of mass by the parallel-axis theorem (I + m (|d|² 1 − d dᵀ), d the part's offset from it);
* the ``<limit>`` of each joint (lower, upper, effort, velocity) is kept as a `JointLimits` in the link's
  ``limits`` and the tree's ``limits`` (by coordinate name): lagcomp carries them and uses them nowhere yet;
* a ``<mimic>`` joint is an independent coordinate, as Pinocchio's ``buildModelFromUrdf`` makes it by default;
* a ``floating`` joint becomes a `Free` joint placed by its ``<origin>``, with the coordinates ``<joint>_x``,
  ``<joint>_y``, ``<joint>_z`` (the child's origin in the joint frame, m) and ``<joint>_mrp1`` … ``<joint>_mrp3``
  (its orientation as MRPs), as Pinocchio's reader makes it a ``JointModelFreeFlyer``;
* a ``planar`` joint moves its child in the plane through the joint's origin normal to its ``<axis>`` (the URDF
  specification's meaning; default (1, 0, 0)): a `Planar` joint whose frame is the ``<origin>`` turned by N, the
  smallest rotation taking e_z to the axis (`normal_frame`), with the coordinates ``<joint>_x``, ``<joint>_y``
  (m, along N e_x and N e_y) and ``<joint>_theta`` (rad, about the axis).  The child link's URDF frame is then
  lagcomp's link frame turned back by Nᵀ (its inertial and its children are placed so); for the axis (0, 0, 1) the
  two are the same, and that is the only axis Pinocchio's reader honours (it moves a planar joint in its frame's
  x-y plane whatever the axis).  Neither joint has limits; their ``<dynamics>`` are not modelled (the description
  says so);

The coordinates are named after the URDF joints, made into Python identifiers where they are not (every character
outside letters, digits and ``_`` becomes ``_``; a name starting with a digit gets a ``q_`` prefix; repeats get a
suffix); the tree's description lists every renamed joint.  All numbers are floats of the file; rotation entries
within 1e-14 of 0 or ±1 (cos 90° = 6e-17) are taken as exactly that, so the emitted code drops the zero terms.
"""

from __future__ import annotations

import keyword
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from lagcomp.errors import ModelError
from lagcomp.multibody.joints import Free, Planar, Prismatic, Revolute
from lagcomp.multibody.tree import Link, Tree

#: URDF joint types lagcomp builds a tree from, and the ones it refuses (with why).
MOVING = {"revolute": Revolute, "continuous": Revolute, "prismatic": Prismatic}
#: URDF joints of several coordinates: the suffixes of their coordinates' names (after the joint's name).
SEVERAL = {"floating": ("x", "y", "z", "mrp1", "mrp2", "mrp3"), "planar": ("x", "y", "theta")}

#: Rotation entries this close to 0 or ±1 are taken as exactly that.
SNAP = 1e-14


@dataclass(frozen=True)
class JointLimits:
    """A URDF joint's ``<limit>``: position range (rad or m; None for a continuous joint), the largest effort (N m or
    N) and speed (rad/s or m/s).  Carried with the tree for the user; lagcomp does not enforce them today."""

    lower: float | None
    upper: float | None
    effort: float | None
    velocity: float | None


def from_urdf(path, *, name: str | None = None, gravity=(0.0, 0.0, -9.81), damping: bool = True,
              floating_base: bool = False, q0=None, qd0=None, t_end: float = 10.0) -> Tree:
    """A kinematic tree of the robot described by the URDF file at `path` (module docstring says how).

    Parameters
    ----------
    path : str or Path
        The ``.urdf`` file (meshes it names need not exist).
    name : str, optional
        The tree's name (an identifier); default the URDF robot's name, made into one.
    gravity : 3 floats
        Gravitational acceleration in the root link's frame (m/s²).
    damping : bool
        Keep the joints' ``<dynamics damping>`` as viscous dampers (τ = −damping q̇); default True.
    floating_base : bool
        Let the root link float on a `Free` joint (6 coordinates first: position, then MRPs) instead of fixing it
        to the ground; default False.
    q0, qd0, t_end
        As for `Tree` (coordinates in URDF joint order, parents first).

    Returns
    -------
    Tree
        With no parameters: every number comes from the file.  ``tree.limits`` maps coordinate names to
        `JointLimits`; ``tree.description`` names the file and lists renamed joints and what was left out.

    Raises
    ------
    ModelError
        The file cannot be read or is not a tree of links (no single root, a link with two parents), or holds a
        joint of a type URDF does not define.
    ImportError
        yourdfpy is not installed.
    """
    robot = _parse(Path(path))
    walk = _walk(robot, _children(robot, path), _root(robot, path), path, floating_base)
    tree_links = [_floating_link(*walk.base, walk.parts.get(walk.base[0], []))] if walk.base else []
    tree_links += [_link(*moving, walk.parts.get(moving[0], []), damping) for moving in walk.moving]
    tree_name = name if name is not None else _Names.identifier(robot.name or "robot", "robot")
    return Tree(tree_links, gravity=gravity, name=tree_name, q0=q0, qd0=qd0, t_end=t_end,
                description=_description(robot.name, path, walk, damping))


@dataclass
class _Walk:
    """What a walk over the URDF tree found: the moving joints as (tree link name, joint, its coordinates,
    placement in the parent tree link's frame, parent tree link or None), the mass properties of each tree link's
    parts (`_part`), the joints renamed {URDF name: coordinates}, the joints with Coulomb friction or with dynamics
    lagcomp leaves out, and the floating base as (tree link name, its six coordinates), or None."""

    moving: list
    parts: dict
    renamed: dict
    frictions: list
    unmodelled: list
    base: tuple | None = None


def _children(robot, path) -> dict:
    """{URDF link name: the joints hanging from it}, the joints' types checked."""
    children = {}
    for joint in robot.joints:
        if joint.type != "fixed" and joint.type not in MOVING and joint.type not in SEVERAL:
            raise ModelError(f"{path}: joint {joint.name!r} has the unknown type {joint.type!r}: URDF joints are "
                             "revolute, continuous, prismatic, fixed, floating or planar. Give the joint one of these "
                             "types (a ball joint: build the tree with lc.Tree and an lc.Spherical joint).")
        children.setdefault(joint.parent, []).append(joint)
    return children


def _walk(robot, children: dict, root: str, path, floating_base: bool) -> _Walk:
    """The tree links from the root outwards: a moving joint starts one, a fixed joint adds its child link to the
    one it hangs from (at the pose it composes to); a floating root is a tree link of its own."""
    names, walk = _Names(), _Walk([], {}, {}, [], [])
    base = None
    if floating_base:
        base = names.link(root)
        walk.base = (base, tuple(names.coordinate(f"{root}_{part}")
                                 for part in ("x", "y", "z", "mrp1", "mrp2", "mrp3")))
    bodies = {root: (base, np.eye(4))}   # URDF link -> (the tree link it is part of, its pose in that link's frame)
    for joint in _parents_first(children, root, path):
        body, pose = bodies[joint.parent]
        placement = pose @ _matrix(joint.origin)
        if joint.type == "fixed":
            bodies[joint.child] = (body, placement)
            continue
        coordinates = _coordinates(joint, names, walk)
        link_name = names.link(joint.child)
        walk.moving.append((link_name, joint, coordinates, placement, body))
        child_pose = np.eye(4)
        if joint.type == "planar":   # the URDF child frame in lagcomp's link frame (module docstring)
            child_pose[:3, :3] = normal_frame(_axis(joint)).T
        bodies[joint.child] = (link_name, child_pose)
    if not walk.moving and not floating_base:
        raise ModelError(f"{path}: no revolute, continuous, prismatic, planar or floating joint: nothing in "
                         f"{robot.name!r} moves.")
    inertials = {link.name: link.inertial for link in robot.links}
    for urdf_link, (body, pose) in bodies.items():
        if body is not None and inertials.get(urdf_link) is not None:
            walk.parts.setdefault(body, []).append(_part(inertials[urdf_link], pose))
    return walk


def _coordinates(joint, names: _Names, walk: _Walk) -> tuple:
    """The coordinates of a moving joint, named after it (module docstring), noting in `walk` a renamed joint and
    the joint's dynamics lagcomp leaves out."""
    if joint.type in SEVERAL:
        wanted = tuple(f"{joint.name}_{part}" for part in SEVERAL[joint.type])
        if _float(getattr(joint.dynamics, "damping", None)) or _float(getattr(joint.dynamics, "friction", None)):
            walk.unmodelled.append(joint.name)
    else:
        wanted = (joint.name,)
        if _float(getattr(joint.dynamics, "friction", None)):
            walk.frictions.append(joint.name)
    coordinates = tuple(names.coordinate(text) for text in wanted)
    if coordinates != wanted:
        walk.renamed[joint.name] = ", ".join(repr(c) for c in coordinates)
    return coordinates


def _axis(joint) -> np.ndarray:
    """The joint's unit ``<axis>`` ((1, 0, 0) when it has none, as the URDF specification says)."""
    axis = np.array([1.0, 0.0, 0.0] if joint.axis is None else joint.axis, dtype=float)
    return axis / np.linalg.norm(axis)


def normal_frame(axis) -> np.ndarray:
    """The smallest rotation N taking e_z to the unit vector `axis` (a planar joint's frame: its x-y plane is the
    plane normal to the axis), by Rodrigues' formula N = 1 + [k]× + [k]×² / (1 + c) with k = e_z × axis and c = e_z ·
    axis; when c < 0, [k]×² / (1 + c) = (1 − c) (k̂ k̂ᵀ − 1) with k̂ = k / |k| (no cancellation, no underflow); for
    the axis −e_z (k = 0), the half turn about x.  Entries snapped as `_matrix`'s."""
    n = np.asarray(axis, dtype=float)
    c, k = n[2], np.array([-n[1], n[0], 0.0])
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    if c >= 0:
        N = np.eye(3) + K + K @ K / (1 + c)
    elif not k.any():
        return np.diag([1.0, -1.0, -1.0])
    else:
        unit = k / np.hypot(k[0], k[1])
        N = np.eye(3) + K + (1 - c) * (np.outer(unit, unit) - np.eye(3))
    for target in (0.0, 1.0, -1.0):
        N[np.abs(N - target) < SNAP] = target
    return N


def _parse(path: Path):
    """yourdfpy's `Robot` of the file, its meshes not loaded."""
    try:
        import yourdfpy
    except ImportError as err:
        raise ImportError("lc.from_urdf reads URDF files with yourdfpy: pip install 'lagcomp[urdf]'.") from err
    if not path.is_file():
        raise ModelError(f"from_urdf: there is no file {str(path)!r}.")
    from lxml import etree  # (yourdfpy's own dependency)

    try:   # strictly first: yourdfpy would recover what it can of a broken file, and say so only in its log
        etree.parse(str(path))
    except etree.XMLSyntaxError as err:
        raise ModelError(f"from_urdf: {path} is not well-formed XML: {err}") from err
    try:
        urdf = yourdfpy.URDF.load(str(path), build_scene_graph=False, build_collision_scene_graph=False,
                                  load_meshes=False, load_collision_meshes=False)
    except Exception as err:  # (yourdfpy's own errors: any failure to parse)
        raise ModelError(f"from_urdf: {path} is not a URDF file lagcomp can read: {err}") from err
    return urdf.robot


def _root(robot, path) -> str:
    """The one link that is no joint's child: the fixed base."""
    parents = {}
    for joint in robot.joints:
        if joint.child in parents:
            raise ModelError(f"{path}: link {joint.child!r} is the child of two joints ({parents[joint.child]!r} "
                             f"and {joint.name!r}): a URDF describes a tree, one parent joint per link.")
        parents[joint.child] = joint.name
    roots = [link.name for link in robot.links if link.name not in parents]
    if len(roots) != 1:
        raise ModelError(f"{path}: a URDF tree has one root link (no parent joint), found {roots}.")
    return roots[0]


def _parents_first(children: dict, root: str, path) -> list:
    """The joints in depth-first order from the root, each after the joint that moves its parent link; in the
    file's order among siblings."""
    order, stack, seen = [], list(reversed(children.get(root, []))), {root}
    while stack:
        joint = stack.pop()
        if joint.child in seen:
            raise ModelError(f"{path}: joint {joint.name!r} closes a loop at link {joint.child!r}.")
        seen.add(joint.child)
        order.append(joint)
        stack.extend(reversed(children.get(joint.child, [])))
    return order


def _matrix(origin) -> np.ndarray:
    """A 4×4 pose (identity when the joint or inertial has no ``<origin>``), its rotation snapped (module
    docstring)."""
    T = np.eye(4) if origin is None else np.array(origin, dtype=float)
    R = T[:3, :3]
    for target in (0.0, 1.0, -1.0):
        R[np.abs(R - target) < SNAP] = target
    return T


def _float(value) -> float:
    return 0.0 if value is None else float(value)


def _part(inertial, pose) -> tuple:
    """(mass, centre of mass, inertia about it) of a URDF ``<inertial>`` in the axes of the link at `pose`."""
    T = pose @ _matrix(inertial.origin)
    R = T[:3, :3]
    inertia = np.zeros((3, 3)) if inertial.inertia is None else np.asarray(inertial.inertia, dtype=float)
    return _float(inertial.mass), T[:3, 3].copy(), R @ inertia @ R.T


def combined(parts) -> tuple:
    """(mass, centre of mass, inertia about it) of rigidly joined `parts`, each (m, c, I about its c), all in one
    frame: masses add, c is the mass-weighted mean, I = Σ I_k + m_k (|d_k|² 1 − d_k d_kᵀ) with d_k = c_k − c
    (the parallel-axis theorem).  A massless whole has its centre at the origin."""
    mass = sum(m for m, _, _ in parts)
    com = sum((m * c for m, c, _ in parts), np.zeros(3)) / mass if mass > 0 else np.zeros(3)
    inertia = np.zeros((3, 3))
    for m, c, I in parts:
        d = c - com
        inertia = inertia + I + m * (d @ d * np.eye(3) - np.outer(d, d))
    return mass, com, (inertia + inertia.T) / 2


def _link(name: str, joint, coordinates: tuple, placement, parent, parts, damping: bool) -> Link:
    mass, com, inertia = combined(parts)
    origin = tuple(float(x) for x in placement[:3, 3])
    if joint.type in SEVERAL:
        if joint.type == "floating":
            moving = Free(coordinates, origin=origin, rotation=placement[:3, :3].tolist())
        else:
            turned = placement[:3, :3] @ normal_frame(_axis(joint))
            moving = Planar(coordinates, origin=origin, rotation=turned.tolist())
        return Link(name, moving, parent=parent, mass=float(mass), com=tuple(float(x) for x in com),
                    inertia=inertia.tolist())
    coordinate = coordinates[0]
    limit = joint.limit
    limits = None if limit is None else JointLimits(
        None if joint.type == "continuous" or limit.lower is None else float(limit.lower),
        None if joint.type == "continuous" or limit.upper is None else float(limit.upper),
        None if limit.effort is None else float(limit.effort), None if limit.velocity is None else float(limit.velocity))
    axis = np.array([1.0, 0.0, 0.0] if joint.axis is None else joint.axis, dtype=float)
    c = _float(getattr(joint.dynamics, "damping", None)) if damping else 0.0
    moving = MOVING[joint.type](coordinate, axis=tuple(float(a) for a in axis), damping=c, origin=origin,
                                rotation=placement[:3, :3].tolist())
    return Link(name, moving, parent=parent, mass=float(mass), com=tuple(float(x) for x in com),
                inertia=inertia.tolist(), limits=None if limits is None else {coordinate: limits})


def _floating_link(name: str, coordinates: tuple, parts) -> Link:
    """The floating root link: a `Free` joint to the world frame, its mass properties those of the parts fixed to
    it."""
    mass, com, inertia = combined(parts)
    return Link(name, Free(coordinates), mass=float(mass), com=tuple(float(x) for x in com), inertia=inertia.tolist())


class _Names:
    """Identifiers for the URDF's joint and link names, each unique among its kind."""

    def __init__(self):
        self.used = {"coordinate": {"t"}, "link": set()}   # t: lagcomp's time

    @staticmethod
    def identifier(text: str, prefix: str) -> str:
        name = re.sub(r"\W", "_", text, flags=re.ASCII)
        if not name or name[0].isdigit():
            name = f"{prefix}_{name}"
        return name + "_" if keyword.iskeyword(name) else name

    def _unique(self, text: str, kind: str, prefix: str) -> str:
        name, used = self.identifier(text, prefix), self.used[kind]
        base, k = name, 2
        while name in used:
            name, k = f"{base}_{k}", k + 1
        used.add(name)
        return name

    def coordinate(self, joint_name: str) -> str:
        return self._unique(joint_name, "coordinate", "q")

    def link(self, link_name: str) -> str:
        return self._unique(link_name, "link", "link")


def _description(robot_name, path, walk: _Walk, damping: bool) -> str:
    text = f"{robot_name} from {path}" + (f", floating on its root link {walk.base[0]!r}" if walk.base else "")
    if walk.renamed:
        text += "; joints renamed as coordinates: " + ", ".join(f"{a!r} -> {b}" for a, b in walk.renamed.items())
    if walk.frictions:
        text += f"; Coulomb friction of {walk.frictions} not modelled"
    if walk.unmodelled:
        text += f"; damping and friction of {walk.unmodelled} not modelled (floating and planar joints)"
    if not damping:
        text += "; joint damping left out"
    return text + "."
