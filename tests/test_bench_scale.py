"""The scale bench's pieces (bench/bench_scale.py, bench/mujoco_model.py, lagcomp.multibody.pinocchio_peer): what
it times is what it says, and its peers' state conversions give the peers' q̈ back in lagcomp's coordinates.

References nobody here wrote: Pinocchio's ABA (``JointModelSpherical``, ``JointModelFreeFlyer``) and MuJoCo's
``mj_forward`` (ball and free joints, quaternions and body-frame rates) at random states; each skips cleanly when
its package is not installed.
"""

from __future__ import annotations

import numpy as np
import pytest

import lagcomp as lc
from bench import bench_scale
from lagcomp.examples import trees


def _values(tree: lc.Tree, seed: int) -> dict:
    rng = np.random.default_rng(seed)
    return {name: (9.81 if name == "g" else float(rng.uniform(1.0, 1.5))) for name in tree.parameter_names}


def _floating_tree() -> lc.Tree:
    """A free-floating base carrying a ball-jointed arm (damped, driven by a constant moment) and a hinged link on
    an unaligned axis, every placement rotated: each kind of joint group the conversions handle."""
    c, s = np.cos(0.4), np.sin(0.4)
    tilt = [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
    return lc.Tree([
        lc.Link("base", lc.Free(("x", "y", "z", "b1", "b2", "b3")), mass=3.0, com=(0.1, -0.2, 0.05),
                inertia=(0.3, 0.4, 0.5)),
        lc.Link("arm", lc.Spherical(("s1", "s2", "s3"), origin=(0.3, 0.1, -0.2), rotation=tilt, damping=0.3,
                                    torque=(0.4, -0.3, 0.2)), parent="base", mass=1.2, com=(0.0, 0.1, -0.4),
                inertia=(0.2, 0.15, 0.1)),
        lc.Link("hand", lc.Revolute("th", axis=(0.3, 0.4, 1.0), origin=(0.0, 0.0, -0.6), damping=0.2),
                parent="arm", mass=0.7, com=(0.1, 0.0, -0.1), inertia=(0.05, 0.06, 0.04)),
    ], gravity=(0.3, -0.2, -9.81), name="bench_floating_tree")


def test_the_cold_compile_builds_no_kernel_on_demand(tmp_path):
    """The "cold compile + first rhs" figure is lc.compile and the first rhs only: reading the operations must not
    build the Jacobians' companion modules (``Model.operations`` does; the bench counted them in until
    2026-11-29: Solo12's figure 50.9 s instead of ~10 s)."""
    tree = trees.planar_chain(2)
    _, y, figures = bench_scale.cold_compile(tree, _values(tree, 2), cache_dir=tmp_path)
    assert not [f.name for f in (tmp_path / "modules").iterdir() if "on_demand" in f.name]
    assert figures["ops"] == figures["evaluated"] > 0 and figures["n"] == 2 and y.shape == (4,)


@pytest.mark.parametrize("build", [lambda: trees.spherical_chain(3), _floating_tree])
def test_pinocchio_and_mujoco_accelerations_in_lagcomps_coordinates(tmp_path, build):
    """Pinocchio's q̈ (its ABA, and its M⁻¹ (τ − h) from CRBA and RNEA: `bench_scale.pinocchio_solved`) and
    MuJoCo's, converted back to the MRP coordinates, equal lagcomp's rhs to 1e-12 relative at random states with
    |σ| up to 2 (past the shadow switch: the equations hold for any σ)."""
    pin = pytest.importorskip("pinocchio")
    mujoco = pytest.importorskip("mujoco")
    from bench import mujoco_model
    from lagcomp.multibody.pinocchio_peer import pinocchio_model, tree_state

    tree = build()
    values = _values(tree, 3)
    model = lc.compile(tree, cache_dir=tmp_path)
    reference = pinocchio_model(tree, values)
    data = reference.createData()
    m = mujoco.MjModel.from_xml_string(mujoco_model.mjcf(tree, values))
    d = mujoco.MjData(m)
    rng, n = np.random.default_rng(5), tree.n
    for _ in range(4):
        y = np.concatenate([rng.uniform(-1.2, 1.2, n), rng.normal(size=n)])
        expected = model.rhs(0.0, y, values)[n:]
        q, v, tau, back = tree_state(reference, tree, values, y)
        pinocchio = back(pin.aba(reference, data, q, v, tau))
        solved, condition = bench_scale.pinocchio_solved(pin, reference, data, q, v, tau)
        mujoco_model.set_state(m, d, tree, values, y)
        mujoco.mj_forward(m, d)
        scale = np.max(np.abs(expected))
        assert np.max(np.abs(pinocchio - expected)) <= 1e-12 * scale
        assert np.max(np.abs(back(solved) - expected)) <= 1e-12 * scale
        assert 1.0 <= condition < 1e6
        assert np.max(np.abs(mujoco_model.accelerations(m, d, tree, values, y) - expected)) <= 1e-12 * scale
