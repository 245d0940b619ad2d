"""Robots from URDF files (`lc.from_urdf`, issue 39): q̈ against Pinocchio's own URDF reader and ABA, on the Panda
and UR5 arms of example-robot-data and on small URDFs written here at random; fixed joints merged against the
parallel-axis theorem in closed form; names, limits and the refusals.

Pinocchio (``pin``) parses the file with its own reader (urdfdom) and computes q̈ with its own ABA, so it shares
nothing with lagcomp's path but the file.  Tests that need it, yourdfpy or example-robot-data skip without them.
"""

from __future__ import annotations

import importlib.metadata
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.multibody.pinocchio_peer import (
    fixed_base_accelerations,
    free_flyer_accelerations,
)
from lagcomp.multibody.urdf import JointLimits, combined

pytest.importorskip("yourdfpy")


def _robot_file(relative: str) -> Path:
    """A URDF of example-robot-data (installed under its cmeel prefix), or a skip."""
    try:
        files = importlib.metadata.files("example-robot-data") or []
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("example-robot-data is not installed")
    for file in files:
        if str(file).endswith(relative):
            return Path(file.locate())
    pytest.skip(f"example-robot-data ships no {relative}")


def _relative(a, b) -> float:
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def _agree_with_pinocchio(path: Path, model, states: int, rng) -> float:
    pin = pytest.importorskip("pinocchio")
    reference = pin.buildModelFromUrdf(str(path))
    data = reference.createData()
    assert reference.nv == model.n
    worst = 0.0
    for _ in range(states):
        q, v = rng.uniform(-2, 2, model.n), rng.uniform(-2, 2, model.n)
        got = model.rhs(0.0, np.concatenate([q, v]))[model.n:]
        worst = max(worst, _relative(got, fixed_base_accelerations(pin, reference, data, model.coordinates, q, v)))
    return worst


# -- real robots ------------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("relative, joints", [
    ("panda_description/urdf/panda.urdf", ["panda_joint1", "panda_joint2", "panda_joint3", "panda_joint4",
                                           "panda_joint5", "panda_joint6", "panda_joint7", "panda_finger_joint1",
                                           "panda_finger_joint2"]),
    ("ur_description/urdf/ur5_robot.urdf", ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                            "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"]),
])
def test_robot_arms_agree_with_pinocchio(cache_dir, relative, joints):
    """Panda (7 arm joints, fixed hand merged, two finger sliders, joint damping) and UR5: q̈ at random states."""
    pytest.importorskip("pinocchio")
    path = _robot_file(relative)
    tree = lc.from_urdf(path)
    assert tree.coordinate_names == tuple(joints) and tree.parameters == ()
    assert [float(g) for g in tree.gravity] == [0.0, 0.0, -9.81]
    model = lc.compile(tree, cache_dir=cache_dir)
    assert _agree_with_pinocchio(path, model, 20, np.random.default_rng(39)) <= 1e-12


def test_the_panda_keeps_its_limits_and_merges_its_hand(cache_dir):
    tree = lc.from_urdf(_robot_file("panda_description/urdf/panda.urdf"))
    assert tree.limits["panda_joint4"] == JointLimits(-3.0718, -0.0698, 87.0, 2.175)
    assert tree.limits["panda_finger_joint1"] == JointLimits(0.0, 0.04, 100.0, 0.2)
    link7 = next(link for link in tree.links if link.name == "panda_link7")
    assert link7.mass == pytest.approx(0.735522 + 0.73, rel=1e-15)   # link 7 and the hand fixed to it
    assert [link.joint.damping for link in tree.links][-2:] == [0.3, 0.3]


# -- small URDFs written here ---------------------------------------------------------------------------------------


def _number(draw, low, high):
    return draw(st.floats(low, high, allow_nan=False, allow_infinity=False))


@st.composite
def urdf_texts(draw):
    """A URDF of a root and 2 to 4 more links on revolute, continuous, prismatic and fixed joints (at least one
    moving), each joint's parent a random earlier link, with random origins (xyz, rpy), axes, masses, centres of
    mass, inertial frames and inertias (principal moments satisfying the triangle inequality)."""
    count = draw(st.integers(2, 4))
    kinds = draw(st.lists(st.sampled_from(["revolute", "continuous", "prismatic", "fixed"]), min_size=count,
                          max_size=count).filter(lambda k: any(kind != "fixed" for kind in k)))

    def triple(low, high):
        return " ".join(repr(_number(draw, low, high)) for _ in range(3))

    def inertial():
        a, b = _number(draw, 0.1, 1.0), _number(draw, 0.1, 1.0)
        c = _number(draw, abs(a - b) + 0.01, a + b)
        return (f'<inertial><origin xyz="{triple(-0.5, 0.5)}" rpy="{triple(-3, 3)}"/>'
                f'<mass value="{_number(draw, 0.5, 3.0)!r}"/>'
                f'<inertia ixx="{a!r}" iyy="{b!r}" izz="{c!r}" ixy="0" ixz="0" iyz="0"/></inertial>')

    lines = ['<robot name="random-bot">', f'<link name="base">{inertial()}</link>']
    for i, kind in enumerate(kinds, start=1):
        axis = np.array([_number(draw, -1, 1) for _ in range(3)])
        if np.linalg.norm(axis) < 0.1:
            axis = np.array([0.0, 0.0, 1.0])
        limit = '<limit lower="-1" upper="1.5" effort="10" velocity="2"/>' if kind in ("revolute", "prismatic") else ""
        parent = draw(st.integers(0, i - 1))
        lines += [f'<link name="link{i}">{inertial()}</link>',
                  (f'<joint name="joint-{i}" type="{kind}"><parent link="{f"link{parent}" if parent else "base"}"/>'
                   f'<child link="link{i}"/><origin xyz="{triple(-1, 1)}" rpy="{triple(-3, 3)}"/>'
                   f'<axis xyz="{" ".join(repr(float(x)) for x in axis)}"/>{limit}'
                   f'<dynamics damping="{_number(draw, 0, 0.5)!r}"/></joint>')]
    return "\n".join(lines + ["</robot>"])


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=urdf_texts())
def test_random_urdfs_agree_with_pinocchio(cache_dir, tmp_path, text):
    pytest.importorskip("pinocchio")
    path = tmp_path / "robot.urdf"
    path.write_text(text, encoding="utf-8")
    tree = lc.from_urdf(path)
    assert all(name.startswith("joint_") for name in tree.coordinate_names)   # 'joint-1' made an identifier
    model = lc.compile(tree, cache_dir=cache_dir)
    assert _agree_with_pinocchio(path, model, 5, np.random.default_rng(0)) <= 1e-12


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=urdf_texts())
def test_random_urdfs_on_a_floating_base_agree_with_pinocchio_on_its_free_flyer(cache_dir, tmp_path, text):
    """``floating_base=True``: the root link on an `lc.Free` joint, against ``buildModelFromUrdf(path,
    JointModelFreeFlyer())`` and its ABA at random states (|σ| < 1, off the shadow switch), 1e-12 relative."""
    pin = pytest.importorskip("pinocchio")
    path = tmp_path / "robot.urdf"
    path.write_text(text, encoding="utf-8")
    tree = lc.from_urdf(path, floating_base=True)
    assert tree.coordinate_names[:6] == ("base_x", "base_y", "base_z", "base_mrp1", "base_mrp2", "base_mrp3")
    assert isinstance(tree.links[0].joint, lc.Free) and "floating on its root link 'base'" in tree.description
    model = lc.compile(tree, cache_dir=cache_dir)
    reference = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    data = reference.createData()
    assert reference.nv == model.n
    rng = np.random.default_rng(1)
    for _ in range(5):
        q, v = rng.uniform(-2, 2, model.n), rng.uniform(-2, 2, model.n)
        q[3:6] = rng.uniform(-0.5, 0.5, 3)
        got = model.rhs(0.0, np.concatenate([q, v]))[model.n:]
        expected = free_flyer_accelerations(pin, reference, data, model.coordinates, q, v)
        assert _relative(got, expected) <= 1e-12


def test_merging_fixed_links_follows_the_parallel_axis_theorem():
    """Two point masses m at ±d along x: I = diag(0, 2 m d², 2 m d²) about their middle; a thin rod (m, length L,
    I_G = m L²/12 about y and z) turned 90° about z and put at (0, a, 0) beside a point mass M at the origin: the
    centre of mass at m a / (m + M) along y, and I_zz = m L²/12 + m M a² / (m + M) about it."""
    m, d = 2.0, 0.3
    mass, com, inertia = combined([(m, np.array([d, 0, 0]), np.zeros((3, 3))),
                                   (m, np.array([-d, 0, 0]), np.zeros((3, 3)))])
    assert mass == 2 * m and np.array_equal(com, np.zeros(3))
    np.testing.assert_allclose(inertia, np.diag([0, 2 * m * d ** 2, 2 * m * d ** 2]), rtol=0, atol=1e-15)
    L, a, M = 1.2, 0.5, 3.0
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    rod = turn @ np.diag([0.0, m * L ** 2 / 12, m * L ** 2 / 12]) @ turn.T
    mass, com, inertia = combined([(m, np.array([0, a, 0]), rod), (M, np.zeros(3), np.zeros((3, 3)))])
    reduced = m * M / (m + M)
    np.testing.assert_allclose(com, [0, m * a / (m + M), 0], rtol=0, atol=1e-15)
    expected = np.diag([m * L ** 2 / 12 + reduced * a ** 2, 0.0, m * L ** 2 / 12 + reduced * a ** 2])
    np.testing.assert_allclose(inertia, expected, rtol=0, atol=1e-15)


def _write(tmp_path, body: str, name: str = "bot") -> Path:
    path = tmp_path / f"{name}.urdf"
    path.write_text(f'<robot name="{name}">{body}</robot>', encoding="utf-8")
    return path


INERTIAL = '<inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>'


def _chain(*joints) -> str:
    """Links l0 ... lk, joint i of (name, type) between l(i-1) and li."""
    text = f'<link name="l0">{INERTIAL}</link>'
    for i, (name, kind) in enumerate(joints, start=1):
        text += (f'<link name="l{i}">{INERTIAL}</link><joint name="{name}" type="{kind}"><parent link="l{i - 1}"/>'
                 f'<child link="l{i}"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="5" velocity="3"/>'
                 '</joint>')
    return text


def test_joint_names_become_identifiers_and_the_description_says_so(tmp_path):
    path = _write(tmp_path, _chain(("shoulder-pan", "revolute"), ("2nd", "continuous"), ("class", "prismatic"),
                                   ("shoulder_pan", "revolute"), ("t", "revolute")))
    tree = lc.from_urdf(path, name="arm")
    assert tree.coordinate_names == ("shoulder_pan", "q_2nd", "class_", "shoulder_pan_2", "t_2")
    for before, after in (("shoulder-pan", "shoulder_pan"), ("2nd", "q_2nd"), ("class", "class_"),
                          ("shoulder_pan", "shoulder_pan_2"), ("t", "t_2")):
        assert f"{before!r} -> {after!r}" in tree.description
    assert tree.limits["q_2nd"] == JointLimits(None, None, 5.0, 3.0)   # continuous: no position range
    assert tree.limits["class_"] == JointLimits(-1.0, 1.0, 5.0, 3.0)


def test_damping_is_kept_unless_asked_not_to(tmp_path):
    body = _chain(("hinge", "revolute")).replace("</joint>", '<dynamics damping="0.25" friction="0.1"/></joint>')
    path = _write(tmp_path, body)
    assert lc.from_urdf(path).links[0].joint.damping == 0.25
    assert "friction of ['hinge'] not modelled" in lc.from_urdf(path).description
    assert lc.from_urdf(path, damping=False).links[0].joint.damping == 0


# -- refusals ---------------------------------------------------------------------------------------------------------


def test_files_that_are_not_urdf_trees_are_refused(tmp_path):
    with pytest.raises(lc.ModelError, match="no file"):
        lc.from_urdf(tmp_path / "missing.urdf")
    broken = tmp_path / "broken.urdf"
    broken.write_text("<robot name='x'><link name='a'>", encoding="utf-8")
    with pytest.raises(lc.ModelError, match="broken.urdf is not well-formed XML"):
        lc.from_urdf(broken)
    still = _write(tmp_path, _chain(("weld", "fixed")), "still")
    with pytest.raises(lc.ModelError, match="nothing in 'still' moves"):
        lc.from_urdf(still)
    two_roots = _write(tmp_path, _chain(("hinge", "revolute")) + f'<link name="stray">{INERTIAL}</link>', "roots")
    with pytest.raises(lc.ModelError, match=r"one root link.*'stray'"):
        lc.from_urdf(two_roots)


def test_a_missing_parser_says_which_extra_to_install(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "yourdfpy", None)
    with pytest.raises(ImportError, match=r"lagcomp\[urdf\]"):
        lc.from_urdf(_write(tmp_path, _chain(("hinge", "revolute"))))
