"""URDF ``floating`` and ``planar`` joints (`lc.from_urdf`, issue 39): each read into the tree built by hand with
`lc.Free` or `lc.Planar` (the same kernels' results to 1e-14), and q̈ against Pinocchio's own URDF reader and ABA
(its ``JointModelFreeFlyer`` and ``JointModelPlanar``) at random states, 1e-12 relative.

The URDF specification makes a planar joint's ``<axis>`` the normal of its plane (default (1, 0, 0)): lagcomp moves
the child in the plane through the joint's origin normal to the axis, its coordinates ``<joint>_x`` and
``<joint>_y`` along R e_x and R e_y and ``<joint>_theta`` about the axis, R the smallest rotation taking e_z to the
axis.  Pinocchio's reader ignores the axis (its planar joint always moves in the joint frame's x-y plane), so with
an axis other than z it is given the equivalent file: the rotation R moved into the joint's ``<origin>`` and undone
by a fixed joint before the child's link.  Tests that need yourdfpy or ``pin`` skip without them.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from random_systems import python_kernels
from scipy.spatial.transform import Rotation

import lagcomp as lc
from lagcomp.animation_bodies import BodyGeometry
from lagcomp.multibody.pinocchio_peer import urdf_accelerations
from lagcomp.multibody.urdf import normal_frame

pytest.importorskip("yourdfpy")

#: (mass, centre of mass, rpy of the inertial frame, principal moments) of the links l0 (the root), l1, l2, l3.
INERTIALS = [(1.3, (0.1, -0.2, 0.05), (0.3, -0.2, 0.9), (0.4, 0.5, 0.6)),
             (1.7, (0.2, 0.1, -0.15), (-0.7, 0.4, 0.1), (0.3, 0.45, 0.6)),
             (0.9, (-0.1, 0.25, 0.3), (1.1, 0.2, -0.5), (0.2, 0.35, 0.5)),
             (1.1, (0.05, 0.05, -0.2), (0.0, 0.6, 0.3), (0.5, 0.3, 0.6))]


def _inertial(k: int) -> str:
    mass, com, rpy, moments = INERTIALS[k]
    return (f'<inertial><origin xyz="{_text(com)}" rpy="{_text(rpy)}"/><mass value="{mass!r}"/>'
            f'<inertia ixx="{moments[0]!r}" iyy="{moments[1]!r}" izz="{moments[2]!r}" ixy="0" ixz="0" iyz="0"/>'
            '</inertial>')


def _text(numbers) -> str:
    return " ".join(repr(float(x)) for x in numbers)


def _joint(name, kind, parent, child, xyz, rpy, axis=None, extra="") -> str:
    axis_text = "" if axis is None else f'<axis xyz="{_text(axis)}"/>'
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
            f'<origin xyz="{_text(xyz)}" rpy="{_text(rpy)}"/>{axis_text}{extra}</joint>')


#: The joints of the test robot: a planar joint from the root, a revolute joint after it, a floating joint at its end.
PLANAR_AT = ((0.2, -0.1, 0.4), (0.5, -0.3, 0.2))
HINGE_AT, HINGE_AXIS = ((0.3, 0.2, -0.1), (-0.4, 0.8, 0.3)), (0.3, -0.5, 0.8)
FLOATING_AT = ((0.1, 0.4, 0.25), (1.2, 0.3, -0.6))


def _robot(axis, pinocchio: bool = False) -> str:
    """The URDF text: l0 -planar 'slide plane' (normal `axis`)- l1 -revolute 'elbow'- l2 -floating 'hand'- l3.  For
    Pinocchio (`pinocchio`), the equivalent file whose planar joint moves in its frame's x-y plane: R (the smallest
    rotation taking e_z to the axis) moved into the planar joint's origin, and a fixed joint undoing it between a
    massless link and l1."""
    links = "".join(f'<link name="l{k}">{_inertial(k)}</link>' for k in range(4))
    if pinocchio:
        R = _normal_frame(axis)
        turned = Rotation.from_euler("xyz", PLANAR_AT[1]).as_matrix() @ R
        planar = (_joint("slide plane", "planar", "l0", "plane", PLANAR_AT[0], _rpy(turned)) + '<link name="plane"/>'
                  + _joint("undo", "fixed", "plane", "l1", (0, 0, 0), _rpy(R.T)))
    else:
        planar = _joint("slide plane", "planar", "l0", "l1", *PLANAR_AT, axis=axis,
                        extra='<dynamics damping="0.4"/>')
    return (f'<robot name="planar-floating">{links}{planar}'
            + _joint("elbow", "revolute", "l1", "l2", *HINGE_AT, axis=HINGE_AXIS,
                     extra='<limit lower="-1" upper="1" effort="5" velocity="3"/>')
            + _joint("hand", "floating", "l2", "l3", *FLOATING_AT) + "</robot>")


def _rpy(R) -> np.ndarray:
    """URDF's (roll, pitch, yaw) of the rotation R = Rz(yaw) Ry(pitch) Rx(roll) (at pitch ±90° scipy picks yaw 0,
    still R, and warns)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return Rotation.from_matrix(R).as_euler("xyz")


def _normal_frame(axis) -> np.ndarray:
    """The smallest rotation taking e_z to the unit `axis` (scipy's, independent of lagcomp's)."""
    n = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    if np.allclose(n, [0, 0, -1], rtol=0, atol=1e-15):
        return np.diag([1.0, -1.0, -1.0])     # a half turn about x (scipy's choice of axis there is its own)
    rotation, _ = Rotation.align_vectors([n], [[0.0, 0.0, 1.0]])
    return rotation.as_matrix()


def _write(tmp_path, text: str, name: str) -> str:
    path = tmp_path / f"{name}.urdf"
    path.write_text(text, encoding="utf-8")
    return str(path)


def _part(k: int, pose=None):
    """Link k's (mass, com, inertia) in a frame turned by `pose` from the URDF link's own (default: its own)."""
    pose = np.eye(3) if pose is None else pose
    mass, com, rpy, moments = INERTIALS[k]
    E = pose @ Rotation.from_euler("xyz", rpy).as_matrix()
    inertia = E @ np.diag(moments) @ E.T
    return {"mass": mass, "com": tuple(pose @ np.array(com)), "inertia": ((inertia + inertia.T) / 2).tolist()}


def _by_hand(axis) -> lc.Tree:
    """The robot of `_robot` built with lc.Link, lc.Planar, lc.Revolute and lc.Free: the planar joint's frame turned
    by R so that its z is the axis, so l1's URDF frame sits in lagcomp's link frame at the rotation Rᵀ (its inertial
    and its child joint's placement turned by it; l2 and l3 have their URDF frames)."""
    R = _normal_frame(axis)
    origin = Rotation.from_euler("xyz", PLANAR_AT[1]).as_matrix()
    hinge = Rotation.from_euler("xyz", HINGE_AT[1]).as_matrix()
    hand = Rotation.from_euler("xyz", FLOATING_AT[1]).as_matrix()
    return lc.Tree([
        lc.Link("l1", lc.Planar(("slide_plane_x", "slide_plane_y", "slide_plane_theta"), origin=PLANAR_AT[0],
                                rotation=(origin @ R).tolist()), **_part(1, R.T)),
        lc.Link("l2", lc.Revolute("elbow", axis=tuple(np.array(HINGE_AXIS) / np.linalg.norm(HINGE_AXIS)),
                                  origin=tuple(R.T @ np.array(HINGE_AT[0])), rotation=(R.T @ hinge).tolist()),
                parent="l1", **_part(2)),
        lc.Link("l3", lc.Free(tuple(f"hand_{p}" for p in ("x", "y", "z", "mrp1", "mrp2", "mrp3")),
                              origin=FLOATING_AT[0], rotation=hand.tolist()), parent="l2", **_part(3)),
    ], gravity=(0.0, 0.0, -9.81), name="by_hand")


AXES = [(0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 0.0, -1.0), (0.3, -0.7, 0.5)]


def _states(n: int, count: int, seed: int):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        q, v = rng.uniform(-1.5, 1.5, n), rng.uniform(-1.5, 1.5, n)
        q[-3:] = rng.uniform(-0.6, 0.6, 3)     # the floating joint's MRPs, |σ| < 1 (off the shadow switch)
        yield q, v


@pytest.mark.parametrize("axis", AXES)
def test_planar_and_floating_joints_read_as_the_tree_built_by_hand(cache_dir, tmp_path, axis):
    tree = lc.from_urdf(_write(tmp_path, _robot(axis), "robot"))
    assert tree.coordinate_names == ("slide_plane_x", "slide_plane_y", "slide_plane_theta", "elbow",
                                     "hand_x", "hand_y", "hand_z", "hand_mrp1", "hand_mrp2", "hand_mrp3")
    assert isinstance(tree.links[0].joint, lc.Planar) and isinstance(tree.links[2].joint, lc.Free)
    assert "'slide plane' -> 'slide_plane_x', 'slide_plane_y', 'slide_plane_theta'" in tree.description
    assert "damping and friction of ['slide plane'] not modelled" in tree.description
    got, hand = lc.compile(tree, cache_dir=cache_dir), lc.compile(_by_hand(axis), cache_dir=cache_dir)
    # the hand-built tree's rhs, the reference, runs as plain Python (the same emitted code; numba compiles got's)
    hand_rhs, p = python_kernels(hand.source_path.read_text(encoding="utf-8"))["rhs"], hand.parameter_vector()
    for q, v in _states(tree.n, 5, 7):
        y, expected = np.concatenate([q, v]), np.empty(2 * tree.n)
        assert hand_rhs(0.0, y, p, expected) == 0
        assert np.max(np.abs(got.rhs(0.0, y) - expected)) <= 1e-14 * np.max(np.abs(expected))


@pytest.mark.parametrize("axis", AXES)
def test_planar_and_floating_joints_agree_with_pinocchio(cache_dir, tmp_path, axis):
    """Pinocchio reads the planar joint as JointModelPlanar (x-y plane of its frame, q = (x, y, cos θ, sin θ), v in
    the child's axes) and the floating one as JointModelFreeFlyer; its model of the equivalent file (module
    docstring) gives q̈ within 1e-12 of lagcomp's at random states.  Pinocchio keeps no damping on these joints,
    nor does lagcomp."""
    pin = pytest.importorskip("pinocchio")
    tree = lc.from_urdf(_write(tmp_path, _robot(axis), "robot"))
    reference = pin.buildModelFromUrdf(_write(tmp_path, _robot(axis, pinocchio=True), "pinocchio"))
    assert [joint.shortname() for joint in reference.joints[1:]] == ["JointModelPlanar", "JointModelRevoluteUnaligned",
                                                                     "JointModelFreeFlyer"]
    model, data = lc.compile(tree, cache_dir=cache_dir), reference.createData()
    for q, v in _states(tree.n, 8, 11):
        got = model.rhs(0.0, np.concatenate([q, v]))[tree.n:]
        expected = urdf_accelerations(pin, reference, data, tree.coordinate_names, q, v)
        assert np.max(np.abs(got - expected)) <= 1e-12 * np.max(np.abs(expected))


def test_a_floating_joint_from_the_root_is_pinocchios_free_flyer(cache_dir, tmp_path):
    """The usual way a URDF floats its base: a floating joint from a massless 'world' link, read by Pinocchio's own
    reader (no equivalent file needed), against lagcomp's q̈ at random states."""
    pin = pytest.importorskip("pinocchio")
    text = ('<robot name="float"><link name="world"/>' + "".join(f'<link name="l{k}">{_inertial(k)}</link>'
                                                                  for k in range(2))
            + _joint("base", "floating", "world", "l0", (0.1, 0.2, 0.3), (0.2, 0.1, -0.4))
            + _joint("knee", "continuous", "l0", "l1", *HINGE_AT, axis=HINGE_AXIS) + "</robot>")
    path = _write(tmp_path, text, "float")
    tree = lc.from_urdf(path)
    assert tree.coordinate_names == ("base_x", "base_y", "base_z", "base_mrp1", "base_mrp2", "base_mrp3", "knee")
    reference = pin.buildModelFromUrdf(path)
    model, data = lc.compile(tree, cache_dir=cache_dir), reference.createData()
    rng = np.random.default_rng(3)
    for _ in range(8):
        q, v = rng.uniform(-1.5, 1.5, 7), rng.uniform(-1.5, 1.5, 7)
        q[3:6] = rng.uniform(-0.6, 0.6, 3)
        got = model.rhs(0.0, np.concatenate([q, v]))[7:]
        expected = urdf_accelerations(pin, reference, data, tree.coordinate_names, q, v)
        assert np.max(np.abs(got - expected)) <= 1e-12 * np.max(np.abs(expected))


def test_a_planar_joint_moves_in_the_plane_normal_to_its_axis(tmp_path):
    """The link frame of a planar joint of axis n at the origin, through the kernel the animation calls: its origin
    moves by x R e_x + y R e_y (normal to n) and its axes are R's turned by θ about n.  (That is lagcomp's link
    frame; the URDF link's frame is it turned back by Rᵀ, so the two coincide for an axis along z.)"""
    axis = np.array([0.3, -0.7, 0.5])
    n = axis / np.linalg.norm(axis)
    text = (f'<robot name="slab"><link name="ground"/><link name="slab">{_inertial(1)}</link>'
            + _joint("p", "planar", "ground", "slab", (0, 0, 0), (0, 0, 0), axis=axis) + "</robot>")
    model = lc.compile(lc.from_urdf(_write(tmp_path, text, "slab")), cache_dir=tmp_path)
    geometry = BodyGeometry.of(model, model.parameter_vector(None))
    R = _normal_frame(axis)
    for x, y, theta in [(0.4, -0.3, 0.7), (-1.2, 0.5, -2.1)]:
        frames = geometry.frames(np.zeros(1), np.array([[x, y, theta]]))
        origin, C = frames.centres["slab"][0], frames.rotations["slab"][0]
        assert abs(origin @ n) <= 1e-15
        np.testing.assert_allclose(origin, x * R[:, 0] + y * R[:, 1], rtol=0, atol=1e-15)
        np.testing.assert_allclose(C, Rotation.from_rotvec(theta * n).as_matrix() @ R, rtol=0, atol=1e-15)


def test_joint_types_urdf_does_not_define_are_refused(tmp_path):
    text = (f'<robot name="bot"><link name="ground"/><link name="arm">{_inertial(1)}</link>'
            + _joint("shoulder", "ball", "ground", "arm", (0, 0, 0), (0, 0, 0)) + "</robot>")
    with pytest.raises(lc.ModelError, match="joint 'shoulder' has the unknown type 'ball'"):
        lc.from_urdf(_write(tmp_path, text, "bot"))


@settings(max_examples=200, deadline=None)
@given(axis=st.tuples(*[st.floats(-1, 1, allow_nan=False)] * 3).filter(lambda a: np.linalg.norm(a) > 1e-3))
def test_the_planar_frame_is_the_smallest_rotation_onto_the_axis(axis):
    """`normal_frame` of any unit axis n: a rotation (NᵀN = 1, det 1) taking e_z to n, about an axis normal to both
    (the smallest: its angle is acos(n_z)), scipy's `align_vectors` up to rounding (except at n = −e_z, where the
    half turn about x is lagcomp's choice)."""
    n = np.array(axis) / np.linalg.norm(axis)
    N = normal_frame(n)
    tol = 3e-14   # (entries within 1e-14 of 0 or ±1 are snapped to them, `lagcomp.multibody.urdf.SNAP`)
    np.testing.assert_allclose(N.T @ N, np.eye(3), rtol=0, atol=tol)
    assert abs(np.linalg.det(N) - 1) < tol
    np.testing.assert_allclose(N[:, 2], n, rtol=0, atol=tol)
    if n[2] > -1 + 1e-6:
        np.testing.assert_allclose(N, _normal_frame(n), rtol=0, atol=1e-9)
