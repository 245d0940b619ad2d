"""A `lagcomp.Tree` as a Pinocchio model, to check lagcomp's recursions against Pinocchio's and to time them side by
side (`bench/bench_multibody.py`, the tests).  Needs ``pin`` (imported when called).
"""

from __future__ import annotations

import numpy as np
import sympy as sp

__all__ = ["fixed_base_accelerations", "free_flyer_accelerations", "pinocchio_model"]


def pinocchio_model(tree, values: dict):
    """A pinocchio.Model of `tree` with the parameters `values` (numbers by name): its joints, placements, mass
    properties and gravity.  The joints' springs, dampers and torques are not in it: Pinocchio's ABA takes the
    generalized forces τ as an argument."""
    import pinocchio as pin

    def num(e):
        return float(sp.sympify(e).subs({s: values[s.name] for s in sp.sympify(e).free_symbols}))

    model = pin.Model()
    ids = []
    for i, node in enumerate(tree.nodes):
        j = node.joint
        axis = np.array([num(a) for a in j.axis])
        joint = _pinocchio_joint(pin, j.kind, axis)
        R = np.array([[num(e) for e in row] for row in j.rotation])
        placement = pin.SE3(R, np.array([num(e) for e in j.origin]))
        parent = 0 if node.parent < 0 else ids[node.parent]
        ids.append(model.addJoint(parent, joint, placement, f"joint{i}"))
        inertia = np.array([[num(node.inertia[a, b]) for b in range(3)] for a in range(3)])
        model.appendBodyToJoint(ids[-1], pin.Inertia(num(node.mass), np.array([num(c) for c in node.com]), inertia),
                                pin.SE3.Identity())
    model.gravity = pin.Motion(np.array([num(g) for g in tree.gravity]), np.zeros(3))
    return model


def _pinocchio_joint(pin, kind: str, axis):
    """Pinocchio's joint model: its axis-aligned kinds (JointModelRZ, ...) for x, y, z, as its own models of such
    chains use, else the unaligned ones."""
    for k, name in enumerate("XYZ"):
        if np.array_equal(axis, np.eye(3)[k]):
            return getattr(pin, f"JointModel{'R' if kind == 'revolute' else 'P'}{name}")()
    return pin.JointModelRevoluteUnaligned(axis) if kind == "revolute" else pin.JointModelPrismaticUnaligned(axis)


def free_flyer_accelerations(pin, model, data, names, q, v) -> np.ndarray:
    """q̈ in lagcomp's coordinates from Pinocchio's ABA of a robot on a free flyer (``buildModelFromUrdf(path,
    JointModelFreeFlyer())``) at lagcomp's state (q, v) of ``lc.from_urdf(path, floating_base=True)``.

    lagcomp's first six coordinates are the root's position x (m, world frame) and MRPs σ; Pinocchio's flyer has
    q = (x, quaternion of R(σ)) and v = (Rᵀ ẋ, ω = J(σ) σ̇) in the root's frame, and back from its v̇:
    ẍ = R (v̇_lin + ω × Rᵀ ẋ), σ̈ = J⁻¹ (ω̇ − J̇ σ̇) (`lagcomp.multibody.mrp`).  The other joints are matched by name
    (URDF names, '-' made '_'), a continuous joint's (cos q, sin q); their generalized force is the joints' viscous
    damping −c q̇ as Pinocchio reads it."""
    from lagcomp.multibody import mrp

    sigma, sigma_dot = q[3:6], v[3:6]
    R, omega = np.array(mrp.rotation(sigma)), np.array(mrp.angular_velocity(sigma, sigma_dot))
    qp, vp = np.empty(model.nq), np.empty(model.nv)
    qp[:3], qp[3:7] = q[:3], pin.Quaternion(R).coeffs()
    vp[:3], vp[3:6] = R.T @ v[:3], omega
    order = _joint_states(model, names, q, v, qp, vp, first=2)
    a = pin.aba(model, data, qp, vp, -model.damping * vp)
    out = np.empty(len(names))
    out[:3] = R @ (a[:3] + np.cross(omega, vp[:3]))
    out[3:6] = mrp.jacobian_inverse_times(sigma, a[3:6] - np.array(mrp.rate_product(sigma, sigma_dot)))
    for index, k in order:
        out[k] = a[index]
    return out


def fixed_base_accelerations(pin, model, data, names, q, v) -> np.ndarray:
    """q̈ in lagcomp's coordinate order `names` from Pinocchio's ABA of a fixed-base robot read from its URDF
    (``buildModelFromUrdf(path)``) at lagcomp's state (q, v), the joints' viscous damping −c q̇ as the torque;
    joints matched by name as in `free_flyer_accelerations`."""
    qp, vp = np.empty(model.nq), np.empty(model.nv)
    order = _joint_states(model, names, q, v, qp, vp, first=1)
    a = pin.aba(model, data, qp, vp, -model.damping * vp)
    out = np.empty(len(names))
    for index, k in order:
        out[k] = a[index]
    return out


def _joint_states(model, names, q, v, qp, vp, first: int) -> list:
    """Fill Pinocchio's `qp`, `vp` for its one-coordinate joints from `first` on with lagcomp's q, v (matched by
    URDF name, '-' made '_'; a continuous joint's q as (cos q, sin q)); [(Pinocchio's velocity index, lagcomp's
    index)]."""
    order = []
    for j in range(first, model.njoints):
        k = list(names).index(model.names[j].replace("-", "_"))
        joint = model.joints[j]
        if joint.nq == 2:
            qp[joint.idx_q:joint.idx_q + 2] = np.cos(q[k]), np.sin(q[k])
        else:
            qp[joint.idx_q] = q[k]
        vp[joint.idx_v] = v[k]
        order.append((joint.idx_v, k))
    return order
