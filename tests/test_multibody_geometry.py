"""The geometry of kinematic trees (issue 39): each link frame's origin and rotation from the ``geometry`` kernel
(`lagcomp.codegen.tree_geometry`), and the animations drawn from it.

References nobody here wrote: Pinocchio's forward kinematics (``pin.forwardKinematics``, ``data.oMi``) on trees
built joint by joint in its own API, and on URDF files read by its own parser (these skip without ``pin``); the
Lagrangian path's ``geometry`` (sympy.physics.vector frames from ``lc.rotated``) on the same chains, whose centres
of mass are at o + C c.  The kernel is read as the animation reads it (`lagcomp.animation_bodies.BodyGeometry`).
"""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from multibody_models import (
    cart_pole,
    lagrangian_system,
    pinocchio_model,
    random_tree,
    universal_chain,
)

import lagcomp as lc
from lagcomp.animation_bodies import BodyGeometry
from lagcomp.examples.trees import ARM5_URDF

#: Positions are O(1) m and rotations O(1): both paths round at a few ulps of that.
TOL = 1e-13


def _frames(model, q, params=None):
    """{link: (origin (3,), C (3, 3))} at coordinates `q`, through the kernel the animation calls."""
    geometry = BodyGeometry.of(model, model.parameter_vector(params))
    frames = geometry.frames(np.zeros(1), np.asarray(q, dtype=float)[None, :])
    return {name: (frames.centres[name][0], frames.rotations[name][0]) for name in frames.centres}


def _pinocchio_frames(pin, model, q) -> list:
    """(translation, rotation) of every joint frame of Pinocchio's `model` at its configuration `q`."""
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    return [(np.array(data.oMi[j].translation), np.array(data.oMi[j].rotation)) for j in range(model.njoints)]


def _agree(got, expected) -> float:
    return max(float(np.max(np.abs(np.asarray(a) - np.asarray(b)))) for a, b in zip(got, expected, strict=True))


# -- against Pinocchio -------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", [1, 7, 39])
def test_link_frames_of_random_trees_are_pinocchios(cache_dir, seed):
    """Random topology, revolute and prismatic joints on unaligned axes, rotated placements: each link's frame is
    Pinocchio's placement of the joint moving it (its node's joint, `pinocchio_model` adds one per node)."""
    pin = pytest.importorskip("pinocchio")
    tree, values = random_tree(seed)
    model = lc.compile(tree, cache_dir=cache_dir)
    reference = pinocchio_model(tree, values)
    last = {node.link: i for i, node in enumerate(tree.nodes)}
    rng = np.random.default_rng(seed)
    for _ in range(10):
        q = rng.uniform(-3, 3, tree.n)
        expected = _pinocchio_frames(pin, reference, q)
        for link, (o, C) in _frames(model, q).items():
            assert _agree((o, C), expected[last[link] + 1]) < TOL, link


def _ball_tree() -> lc.Tree:
    """A floating body carrying a ball joint, a revolute joint and a slider on unaligned axes below it, and a
    universal joint beside them, every joint frame placed with an offset and a rotation."""
    def turn(axis, angle):
        a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
        K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
        return (np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K).tolist()

    body = dict(mass=1.0, com=(0.1, 0.0, -0.2), inertia=(0.1, 0.2, 0.3))
    return lc.Tree([
        lc.Link("base", lc.Free(("x", "y", "z", "s1", "s2", "s3"), origin=(0.1, -0.2, 0.3), rotation=turn((1, 2, 3), 0.4)),
                **body),
        lc.Link("ball", lc.Spherical(("b1", "b2", "b3"), origin=(0.3, 0.1, -0.4), rotation=turn((0, 1, 1), -0.7)),
                parent="base", **body),
        lc.Link("arm", lc.Revolute("q", axis=(0.3, -0.5, 0.8), origin=(0.0, 0.2, -0.5), rotation=turn((1, 0, 0), 1.1)),
                parent="ball", **body),
        lc.Link("slide", lc.Prismatic("d", axis=(1.0, 2.0, -0.5), origin=(0.4, 0.0, 0.1)), parent="arm", **body),
        lc.Link("cardan", lc.Universal(("u1", "u2"), origin=(-0.3, 0.2, 0.0), rotation=turn((2, -1, 1), 0.5)),
                parent="base", **body),
    ], gravity=(0, 0, -9.81), name="ball_tree")


def _quaternion(sigma) -> np.ndarray:
    """Pinocchio's (x, y, z, w) of the rotation with modified Rodrigues parameters σ = n tan(θ/4):
    w = cos(θ/2) = (1 − s)/(1 + s), (x, y, z) = n sin(θ/2) = 2σ/(1 + s), s = σ·σ (tan(θ/4)² = s)."""
    s = float(sigma @ sigma)
    return np.array([*(2 * sigma / (1 + s)), (1 - s) / (1 + s)])


def _pinocchio_ball_tree(pin, tree):
    """`_ball_tree` in Pinocchio's own joints (free flyer, spherical on a quaternion, unaligned revolute and
    prismatic, RX then RY), and the Pinocchio joint id of each link's frame."""
    model, ids = pin.Model(), {}

    def add(link, parent, joint, placement_of):
        j = placement_of.joint
        rotation = np.eye(3) if j.rotation is None else np.array(j.rotation, dtype=float)
        placement = pin.SE3(rotation, np.array(j.origin, dtype=float))
        ids[link] = model.addJoint(parent, joint, placement, link)
        return ids[link]

    links = {link.name: link for link in tree.links}
    base = add("base", 0, pin.JointModelFreeFlyer(), links["base"])
    ball = add("ball", base, pin.JointModelSpherical(), links["ball"])
    arm = add("arm", ball, pin.JointModelRevoluteUnaligned(np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])),
              links["arm"])
    add("slide", arm, pin.JointModelPrismaticUnaligned(np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])),
        links["slide"])
    first = add("cardan", base, pin.JointModelRX(), links["cardan"])
    ids["cardan"] = model.addJoint(first, pin.JointModelRY(), pin.SE3.Identity(), "cardan_y")
    return model, ids


@pytest.fixture(scope="module")
def ball_tree(cache_dir):
    tree = _ball_tree()
    return tree, lc.compile(tree, cache_dir=cache_dir)


finite = st.floats(-3, 3, allow_nan=False)
mrp = st.tuples(*[st.floats(-1.5, 1.5, allow_nan=False)] * 3)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(position=st.tuples(finite, finite, finite), sigma=mrp, ball=mrp, q=finite, d=finite, u=st.tuples(finite, finite))
def test_free_and_ball_joints_on_mrps_place_links_as_pinocchio(ball_tree, position, sigma, ball, q, d, u):
    """MRPs of either set (|σ| up to 1.5 √3: the shadow set too) against Pinocchio's quaternions."""
    pin = pytest.importorskip("pinocchio")
    tree, model = ball_tree
    reference, ids = _pinocchio_ball_tree(pin, tree)
    sigma, ball = np.array(sigma), np.array(ball)
    ours = np.array([*position, *sigma, *ball, q, d, *u])
    theirs = np.array([*position, *_quaternion(sigma), *_quaternion(ball), q, d, *u])
    expected = _pinocchio_frames(pin, reference, theirs)
    for link, frame in _frames(model, ours).items():
        assert _agree(frame, expected[ids[link]]) < TOL * 10, link   # (positions up to ~10 m here)


@pytest.mark.parametrize("floating_base", [False, True])
def test_the_bundled_arm_urdf_places_its_links_as_pinocchio_reads_it(cache_dir, floating_base):
    """`lc.from_urdf` of the shipped arm (its tool's fixed joint merged into the hand: the hand keeps its own frame)
    against Pinocchio's URDF parser, joints matched by name, the root on Pinocchio's free flyer when it floats."""
    pin = pytest.importorskip("pinocchio")
    pytest.importorskip("yourdfpy")
    from lagcomp.multibody import mrp as mrps

    tree = lc.from_urdf(ARM5_URDF, floating_base=floating_base)
    model = lc.compile(tree, cache_dir=cache_dir)
    reference = pin.buildModelFromUrdf(str(ARM5_URDF), *([pin.JointModelFreeFlyer()] if floating_base else []))
    names = tree.coordinate_names
    rng = np.random.default_rng(5)
    for _ in range(10):
        q = rng.uniform(-2.5, 2.5, tree.n)
        qp = np.empty(reference.nq)
        first = 1
        if floating_base:
            q[3:6] = rng.uniform(-1, 1, 3)
            qp[:3], qp[3:7] = q[:3], pin.Quaternion(np.array(mrps.rotation(q[3:6]), dtype=float)).coeffs()
            first = 2
        for j in range(first, reference.njoints):
            joint, k = reference.joints[j], names.index(reference.names[j])
            qp[joint.idx_q:joint.idx_q + joint.nq] = (np.cos(q[k]), np.sin(q[k])) if joint.nq == 2 else q[k]
        expected = _pinocchio_frames(pin, reference, qp)
        frames = _frames(model, q)
        assert sorted(frames) == sorted(link.name for link in tree.links)
        for j in range(1, reference.njoints):
            link = tree.links[j - 1].name if floating_base else tree.nodes[names.index(reference.names[j])].link
            assert _agree(frames[link], expected[j]) < TOL, link


# -- against the Lagrangian path ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("build", [lambda: universal_chain(2), cart_pole], ids=["universal_chain_2", "cart_pole"])
def test_centres_and_axes_are_the_lagrangian_paths(cache_dir, build):
    """The same chain as lc.RigidBody on lc.rotated frames (`lagrangian_system`: body<i> for node i): its bodies'
    centres are the links' o + C c, its rotation matrices the links' C, at random parameters and coordinates."""
    tree = build()
    twin = lagrangian_system(tree)
    model, lagrangian = lc.compile(tree, cache_dir=cache_dir), lc.compile(twin, cache_dir=cache_dir)
    rng = np.random.default_rng(3)
    last = {node.link: i for i, node in enumerate(tree.nodes)}
    for _ in range(5):
        params = {name: float(rng.uniform(0.5, 2.0)) for name in tree.parameter_names}
        q = rng.uniform(-3, 3, tree.n)
        values = {s: params[s.name] for s in tree.parameters}
        bodies = BodyGeometry.of(lagrangian, lagrangian.parameter_vector(params)).frames(np.zeros(1), q[None, :])
        for link, (o, C) in _frames(model, q, params).items():
            com = np.array([float(c.subs(values)) for c in tree.nodes[last[link]].com])
            name = f"body{last[link]}"
            assert np.max(np.abs(o + C @ com - bodies.centres[name][0])) < TOL, link
            assert np.max(np.abs(C - bodies.rotations[name][0])) < TOL, link


# -- the kernel's layout, and drawing ----------------------------------------------------------------------------------


def test_the_layout_names_every_link_with_its_parent(cache_dir):
    tree = _ball_tree()
    kernels = lc.compile(tree, cache_dir=cache_dir).kernels
    assert kernels.GEOMETRY == tuple((link.name, "link", 12 * k) for k, link in enumerate(tree.links))
    assert kernels.GEOMETRY_SIZE == 12 * len(tree.links)
    assert kernels.GEOMETRY_PARENTS == tuple((link.name, link.parent) for link in tree.links)


@pytest.fixture(scope="module")
def arm_run(cache_dir):
    pytest.importorskip("yourdfpy")
    model = lc.compile(lc.from_urdf(ARM5_URDF), cache_dir=cache_dir)
    return model, model.simulate((0, 1), q0=[0.3, 0.9, 0.6, 0.4, 0.0], qd0=[1.0, 0, 0, 0, 2.0],
                                 t_eval=np.linspace(0, 1, 51), progress=False)


@pytest.mark.usefixtures("animations_freed_quietly")
def test_an_arm_animation_draws_its_links_where_the_kernel_puts_them_and_saves(arm_run, tmp_path):
    """Markers at the links' origins, a rod from each link's origin to its children's (the first from the base's
    origin), the links' axes; 3-D; the clip is written."""
    pytest.importorskip("matplotlib")
    model, sol = arm_run
    path = tmp_path / "arm.html"
    anim = sol.animate(fps=5, dpi=30, size=(3, 3), axes_length=0.05, save=path)
    assert path.stat().st_size > 0 and "lagcomp-player" in path.read_text(encoding="utf-8")
    names = ["shoulder_link", "upper_arm", "forearm", "wrist", "hand"]
    assert set(anim.markers) == set(names) and anim.markers["hand"].axes.name == "3d"
    assert set(anim.segments) == {("origin", "shoulder_link"), *zip(names[:-1], names[1:])}
    for k in (0, len(anim.frame_times) - 1):
        anim.draw(k)
        q = np.array([np.interp(anim.frame_times[k], sol.t, sol.q[:, i]) for i in range(5)])
        frames = _frames(model, q)
        for a, b in zip(names[:-1], names[1:]):
            x, y, z = anim.segments[(a, b)].get_data_3d()
            assert np.max(np.abs(np.array([x, y, z]).T - [frames[a][0], frames[b][0]])) < 1e-12
        tip = np.array([d[0] for d in anim.body_axes[("hand", "z")].get_data_3d()][:3])
        assert np.max(np.abs(tip - frames["hand"][0])) < 1e-12   # (the axis starts at the origin)


def test_a_pickled_run_keeps_the_skeleton(arm_run):
    """Unpickled, the run's geometry has no kernel (it names the fix) but keeps its layout and the links' parents."""
    sol = arm_run[1]
    restored = pickle.loads(pickle.dumps(sol))
    assert restored.geometry.parents == sol.geometry.parents == (
        ("shoulder_link", None), ("upper_arm", "shoulder_link"), ("forearm", "upper_arm"), ("wrist", "forearm"),
        ("hand", "wrist"))
    with pytest.raises(lc.errors.OptionError, match="no model geometry"):
        restored.animate()


def test_a_tree_with_a_closed_loop_has_its_geometry(cache_dir):
    """Loops refuse the Jacobians for now, not the geometry: a four-bar's coupler end meets the rocker's."""
    import sympy as sp

    a, b, c, d = sp.symbols("a b c d", positive=True)
    rod = dict(mass=1, com=(0, 0, 0), inertia=(1, 1, 1))
    tree = lc.Tree([
        lc.Link("crank", lc.Revolute("th1", axis="z"), **rod),
        lc.Link("coupler", lc.Revolute("th2", axis="z", origin=(a, 0, 0)), parent="crank", **rod),
        lc.Link("rocker", lc.Revolute("th3", axis="z", origin=(d, 0, 0)), **rod),
    ], loops=[lc.Loop("pin", ("coupler", (b, 0, 0)), ("rocker", (c, 0, 0)), directions="xy")],
        defaults=dict(a=1.0, b=2.0, c=1.5, d=2.5), name="four_bar_geometry")
    model = lc.compile(tree, cache_dir=cache_dir)
    frames = _frames(model, [0.4, 0.2, -0.3])
    th1, th2, th3 = 0.4, 0.2, -0.3
    assert np.max(np.abs(frames["coupler"][0] - [np.cos(th1), np.sin(th1), 0])) < TOL
    assert np.max(np.abs(frames["rocker"][0] - [2.5, 0, 0])) < TOL
    assert np.max(np.abs(frames["coupler"][1][:2, 0] - [np.cos(th1 + th2), np.sin(th1 + th2)])) < TOL
    assert np.max(np.abs(frames["rocker"][1][:2, 0] - [np.cos(th3), np.sin(th3)])) < TOL


def test_lagcomp_animate_draws_a_tree_from_a_file(cache_dir, tmp_path, capsys):
    """``lagcomp animate FILE:FUNCTION`` takes a function returning a Tree, and writes the clip of its links."""
    pytest.importorskip("matplotlib")
    pytest.importorskip("yourdfpy")
    from PIL import Image

    from lagcomp.cli import main

    (tmp_path / "robot.py").write_text("from lagcomp.examples.trees import arm5\n\n\ndef arm():\n"
                                       "    return arm5(q0=[0.3, 0.9, 0.6, 0.4, 0.0], t_end=0.6)\n", encoding="utf-8")
    out = tmp_path / "arm.gif"
    argv = ["--cache-dir", str(cache_dir), "animate", f"{tmp_path / 'robot.py'}:arm", "-o", str(out), "--fps", "5",
            "--quiet"]
    assert main(argv) == 0
    assert "animated" in capsys.readouterr().out
    with Image.open(out) as clip:
        assert clip.n_frames == 4      # t = 0, 0.2, 0.4, 0.6


# -- link points as outputs of a state-space model ----------------------------------------------------------------------


@pytest.mark.parametrize("seed", [7, 39])
def test_link_points_as_outputs_are_pinocchios_joint_jacobians(cache_dir, seed):
    """``linearize(..., outputs=["<link>.x", ..., "<link>.vz"])``: rows [J, 0] and [0, J] with J = ∂o/∂q the linear
    part of Pinocchio's joint Jacobian in world-aligned axes (a revolute or prismatic joint's velocity is q̇)."""
    pin = pytest.importorskip("pinocchio")
    tree, values = random_tree(seed)
    model = lc.compile(tree, cache_dir=cache_dir)
    reference = pinocchio_model(tree, values)
    data = reference.createData()
    q = np.random.default_rng(seed).uniform(-3, 3, tree.n)
    names = [f"{link.name}.{part}" for link in tree.links for part in ("x", "y", "z", "vx", "vy", "vz")]
    space = lc.analysis.linearize(model, q, outputs=names).state_space()
    assert space.outputs == tuple(names) and not space.D.any()
    pin.computeJointJacobians(reference, data, q)
    last = {node.link: i for i, node in enumerate(tree.nodes)}
    n = tree.n
    for row, name in zip(space.C, names, strict=True):
        link, _, part = name.partition(".")
        J = pin.getJointJacobian(reference, data, last[link] + 1, pin.LOCAL_WORLD_ALIGNED)[:3]
        expected = J["xyz".index(part[-1])]
        position, velocity = (row[:n], row[n:]) if len(part) == 1 else (row[n:], row[:n])
        assert np.max(np.abs(position - expected)) < TOL and not velocity.any(), name


def test_an_unknown_link_point_names_the_links(cache_dir):
    model = lc.compile(cart_pole(), cache_dir=cache_dir)
    params = {name: 1.0 for name in model.parameters}
    with pytest.raises(lc.OptionError, match=r"Unknown output.*\['arm\.vx'\].*\['cart', 'pole'\]"):
        lc.analysis.linearize(model, [0.0, 0.0], params=params, outputs=["pole.x", "arm.vx"]).state_space()
