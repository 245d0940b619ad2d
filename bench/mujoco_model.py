"""A `lagcomp.Tree` as a MuJoCo model, and lagcomp's state in MuJoCo's coordinates: the MuJoCo column of
`bench.bench_scale`.

The MJCF has a body per link (placed by its joint's origin and rotation), its hinges and slides in order (MuJoCo
composes the joints of one body as the tree's massless frames do), a ``ball`` joint for a `lagcomp.Spherical`, a
``freejoint`` for a `lagcomp.Free` root, inertial properties about the centre of mass, gravity, and contacts and
every constraint disabled.  MuJoCo's conventions (its documentation, "Floating objects" and ``qvel``): a ball
joint's qpos is the unit quaternion (w, x, y, z) of the body's rotation from its joint frame and its qvel the
angular velocity ω in the body's own axes; a free joint's qpos is the body origin's world position then the
quaternion, its qvel the origin's world velocity then ω (body axes).  lagcomp's ball and free joints are on
modified Rodrigues parameters σ (`lagcomp.multibody.mrp`): ω = J(σ) σ̇, and back from MuJoCo's q̈ (qacc):
σ̈ = J⁻¹ (ω̇ − J̇ σ̇), ẍ = R₀ᵀ a₀ (R₀, the free joint's placement; lagcomp's x is in that frame).
"""

from __future__ import annotations

import numpy as np
import sympy as sp

from lagcomp.multibody import mrp
from lagcomp.multibody.pinocchio_peer import joint_groups


def numeric(expr, values: dict) -> float:
    """`expr` (a number or an expression of the parameters) at the parameter `values` (numbers by name)."""
    expr = sp.sympify(expr)
    return float(expr.subs({s: values[s.name] for s in expr.free_symbols}))


def _floats(entries, values) -> str:
    return " ".join(repr(numeric(e, values)) for e in entries)


def _joint_name(tree, kind: str, indices) -> str:
    """MuJoCo's name of a group of `joint_groups`: the coordinate's name for a hinge or slide, the link's with
    ``_ball`` or ``_free`` for the others."""
    node = tree.nodes[indices[0]]
    return node.joint.coordinate.func.__name__ if len(indices) == 1 else f"{node.link}_{kind[:4]}"


def _joint_xml(tree, kind: str, indices, values) -> str:
    j, name = tree.nodes[indices[0]].joint, _joint_name(tree, kind, indices)
    if kind == "free":
        return f'<freejoint name="{name}"/>'
    if kind == "spherical":
        return f'<joint name="{name}" type="ball" damping="{numeric(j.damping, values)!r}"/>'
    return (f'<joint name="{name}" type="{"hinge" if kind == "revolute" else "slide"}" '
            f'axis="{_floats(j.axis, values)}" damping="{numeric(j.damping, values)!r}" '
            f'stiffness="{numeric(j.stiffness, values)!r}" springref="{numeric(j.rest, values)!r}"/>')


def mjcf(tree, values: dict) -> str:
    """The MJCF text of `tree` at the parameter `values` (module docstring)."""
    import mujoco

    children, groups = {}, {}
    for link in tree.links:
        children.setdefault(link.parent, []).append(link)
    for kind, indices in joint_groups(tree):
        groups.setdefault(tree.nodes[indices[0]].link, []).append((kind, indices))

    def body(link) -> str:
        mine = groups[link.name]
        first = tree.nodes[mine[0][1][0]].joint
        quat = np.empty(4)
        mujoco.mju_mat2Quat(quat, np.array([[numeric(e, values) for e in row] for row in first.rotation]).ravel())
        text = (f'<body name="{link.name}" pos="{_floats(first.origin, values)}" '
                f'quat="{" ".join(repr(float(x)) for x in quat)}">')
        text += "".join(_joint_xml(tree, kind, indices, values) for kind, indices in mine)
        last = tree.nodes[mine[-1][1][-1]]
        I = last.inertia
        full = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]
        text += (f'<inertial pos="{_floats(last.com, values)}" mass="{numeric(last.mass, values)!r}" '
                 f'fullinertia="{_floats(full, values)}"/>')
        return text + "".join(body(child) for child in children.get(link.name, [])) + "</body>"

    return (f'<mujoco model="{tree.name}"><compiler angle="radian" inertiafromgeom="false"/>'
            f'<option gravity="{_floats(tree.gravity, values)}"><flag contact="disable" constraint="disable"/></option>'
            f'<worldbody>{"".join(body(link) for link in children[None])}</worldbody></mujoco>')


def set_state(m, d, tree, values: dict, y) -> None:
    """MuJoCo's qpos and qvel (of `d`, for the model `m` of `mjcf(tree, values)`) at lagcomp's state y = (q, q̇),
    and in qfrc_applied the joints' torques (numbers once `values` are in; a ball joint's along its body axes, as
    MuJoCo's generalized forces of its three rotational DOFs are)."""
    import mujoco

    n, quat = tree.n, np.empty(4)
    for kind, indices in joint_groups(tree):
        joint, k = m.joint(_joint_name(tree, kind, indices)), indices[0]
        a, b = joint.qposadr[0], joint.dofadr[0]
        d.qfrc_applied[b:b + len(indices)] = [numeric(tree.nodes[i].joint.torque, values) for i in indices]
        if kind not in ("free", "spherical"):
            d.qpos[a], d.qvel[b] = y[k], y[n + k]
            continue
        m3 = 3 if kind == "free" else 0
        sigma, rates = y[k + m3:k + m3 + 3], y[n + k + m3:n + k + m3 + 3]
        R = np.array(mrp.rotation(sigma))
        if kind == "free":
            R0, origin = _placement(tree.nodes[k].joint, values)
            d.qpos[a:a + 3], d.qvel[b:b + 3] = origin + R0 @ y[k:k + 3], R0 @ y[n + k:n + k + 3]
            R = R0 @ R
        mujoco.mju_mat2Quat(quat, R.ravel())
        d.qpos[a + m3:a + m3 + 4] = quat
        d.qvel[b + m3:b + m3 + 3] = mrp.angular_velocity(sigma, rates)


def accelerations(m, d, tree, values: dict, y) -> np.ndarray:
    """lagcomp's q̈ from MuJoCo's qacc (after ``mj_forward`` at `set_state`'s state y)."""
    n, out = tree.n, np.empty(tree.n)
    for kind, indices in joint_groups(tree):
        joint, k = m.joint(_joint_name(tree, kind, indices)), indices[0]
        b = joint.dofadr[0]
        if kind not in ("free", "spherical"):
            out[k] = d.qacc[b]
            continue
        m3 = 3 if kind == "free" else 0
        if kind == "free":
            out[k:k + 3] = _placement(tree.nodes[k].joint, values)[0].T @ d.qacc[b:b + 3]
        sigma, rates = y[k + m3:k + m3 + 3], y[n + k + m3:n + k + m3 + 3]
        out[k + m3:k + m3 + 3] = mrp.jacobian_inverse_times(
            sigma, d.qacc[b + m3:b + m3 + 3] - np.array(mrp.rate_product(sigma, rates)))
    return out


def _placement(joint, values) -> tuple:
    """(rotation, origin) of a joint's frame in its parent's, as numbers."""
    return (np.array([[numeric(e, values) for e in row] for row in joint.rotation]),
            np.array([numeric(e, values) for e in joint.origin]))
