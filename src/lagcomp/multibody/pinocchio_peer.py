"""A `lagcomp.Tree` as a Pinocchio model, to check lagcomp's recursions against Pinocchio's and to time them side by
side (`bench/bench_multibody.py`, `bench/bench_scale.py`, the tests), with the conversions between lagcomp's state
(q, q̇; ball and free joints on modified Rodrigues parameters) and Pinocchio's (quaternions, body-frame rates).
Needs ``pin`` (imported when called).
"""

from __future__ import annotations

import re

import numpy as np
import sympy as sp

__all__ = ["fixed_base_accelerations", "fixed_base_state", "free_flyer_accelerations", "free_flyer_state",
           "joint_groups", "pinocchio_model", "tree_state", "urdf_accelerations", "urdf_state"]


def pinocchio_model(tree, values: dict):
    """A pinocchio.Model of `tree` with the parameters `values` (numbers by name): its joints, placements, mass
    properties and gravity.  A revolute or prismatic node is a Pinocchio joint of its own (named ``joint<node>``), a
    ball joint a ``JointModelSpherical``, a free joint a ``JointModelFreeFlyer`` (`joint_groups`).  The joints'
    springs, dampers and torques are not in it: Pinocchio's ABA takes the generalized forces τ as an argument
    (`tree_state` gives them)."""
    import pinocchio as pin

    def num(e):
        return _number(e, values)

    model = pin.Model()
    ids = []
    for kind, indices in joint_groups(tree):
        first, last = tree.nodes[indices[0]], tree.nodes[indices[-1]]
        j = first.joint
        if kind == "free":
            joint = pin.JointModelFreeFlyer()
        elif kind == "spherical":
            joint = pin.JointModelSpherical()
        else:
            joint = _pinocchio_joint(pin, kind, np.array([num(a) for a in j.axis]))
        R = np.array([[num(e) for e in row] for row in j.rotation])
        placement = pin.SE3(R, np.array([num(e) for e in j.origin]))
        parent = 0 if first.parent < 0 else ids[first.parent]
        joint_id = model.addJoint(parent, joint, placement, f"joint{indices[0]}")
        ids += [joint_id] * len(indices)
        inertia = np.array([[num(last.inertia[a, b]) for b in range(3)] for a in range(3)])
        model.appendBodyToJoint(joint_id, pin.Inertia(num(last.mass), np.array([num(c) for c in last.com]), inertia),
                                pin.SE3.Identity())
    model.gravity = pin.Motion(np.array([num(g) for g in tree.gravity]), np.zeros(3))
    return model


def joint_groups(tree) -> list:
    """[(kind, node indices)]: the tree's nodes as Pinocchio's joints, in order: a "free" joint's six nodes (three
    translations, then its MRPs), a "spherical" joint's three, each other node alone (its kind).  The mass
    properties of a group are those of its last node (the others are massless frames at the same origin)."""
    from lagcomp.multibody.joints import Free

    links = {link.name: link for link in tree.links}
    groups, i = [], 0
    while i < tree.n:
        node = tree.nodes[i]
        if isinstance(links[node.link].joint, Free):
            groups.append(("free", list(range(i, i + 6))))
        elif node.joint.kind == "spherical":
            groups.append(("spherical", list(range(i, i + 3))))
        else:
            groups.append((node.joint.kind, [i]))
        i += len(groups[-1][1])
    return groups


def tree_state(model, tree, values: dict, y) -> tuple:
    """(q, v, τ, back): Pinocchio's state and generalized forces for `pinocchio_model(tree, values)` at lagcomp's
    state y = (q, q̇), and the function turning Pinocchio's q̈ (v̇) back into lagcomp's q̈ (coordinate order).

    A ball joint's q is the quaternion of R(σ), its v the body rate ω = J(σ) σ̇; a free joint's also has its
    position x and Rᵀ ẋ (its frame's velocity, its own axes).  τ holds each joint's spring, damper and torque as
    lagcomp applies them: −k (q − rest) − c q̇ + torque along a revolute or prismatic axis, torque − c ω on a ball
    joint (torques that are numbers once `values` are in)."""
    import pinocchio as pin

    from lagcomp.multibody import mrp

    n, y = tree.n, np.asarray(y, dtype=float)
    q, v, tau, charts = np.empty(model.nq), np.empty(model.nv), np.zeros(model.nv), []
    for g, (kind, indices) in enumerate(joint_groups(tree)):
        joint = model.joints[g + 1]
        iq, iv, k = joint.idx_q, joint.idx_v, indices[0]
        if kind not in ("free", "spherical"):
            j = tree.nodes[k].joint
            q[iq], v[iv] = y[k], y[n + k]
            tau[iv] = (_number(j.torque, values) - _number(j.stiffness, values) * (y[k] - _number(j.rest, values))
                       - _number(j.damping, values) * y[n + k])
            charts.append((kind, iv, k, None))
            continue
        m = 3 if kind == "free" else 0   # (the free joint's translations come first)
        sigma, rates = y[k + m:k + m + 3], y[n + k + m:n + k + m + 3]
        R, omega = np.array(mrp.rotation(sigma)), np.array(mrp.angular_velocity(sigma, rates))
        q[iq:iq + m], q[iq + m:iq + m + 4] = y[k:k + m], pin.Quaternion(R).coeffs()
        v[iv:iv + m], v[iv + m:iv + m + 3] = (R.T @ y[n + k:n + k + 3])[:m], omega
        j = tree.nodes[k + m].joint
        tau[iv + m:iv + m + 3] = ([_number(tree.nodes[k + m + a].joint.torque, values) for a in range(3)]
                                  - _number(j.damping, values) * omega)
        charts.append((kind, iv, k, (sigma, rates, R, omega, v[iv:iv + m])))
    return q, v, tau, lambda a: _back(np.asarray(a, dtype=float), charts, n)


def _back(a, charts, n) -> np.ndarray:
    """lagcomp's q̈ from Pinocchio's v̇ `a`: a one-coordinate joint's as it is, σ̈ = J⁻¹ (ω̇ − J̇ σ̇), and a free
    joint's ẍ = R (v̇ + ω × v) (v its frame's velocity in its own axes)."""
    from lagcomp.multibody import mrp

    out = np.empty(n)
    for kind, iv, k, chart in charts:
        if chart is None:
            out[k] = a[iv]
            continue
        sigma, rates, R, omega, linear = chart
        m = 3 if kind == "free" else 0
        if m:
            out[k:k + 3] = R @ (a[iv:iv + 3] + np.cross(omega, linear))
        out[k + m:k + m + 3] = mrp.jacobian_inverse_times(sigma, a[iv + m:iv + m + 3]
                                                          - np.array(mrp.rate_product(sigma, rates)))
    return out


def _number(e, values: dict) -> float:
    e = sp.sympify(e)
    return float(e.subs({s: values[s.name] for s in e.free_symbols}))


def _pinocchio_joint(pin, kind: str, axis):
    """Pinocchio's joint model: its axis-aligned kinds (JointModelRZ, ...) for x, y, z, as its own models of such
    chains use, else the unaligned ones."""
    for k, name in enumerate("XYZ"):
        if np.array_equal(axis, np.eye(3)[k]):
            return getattr(pin, f"JointModel{'R' if kind == 'revolute' else 'P'}{name}")()
    return pin.JointModelRevoluteUnaligned(axis) if kind == "revolute" else pin.JointModelPrismaticUnaligned(axis)


def free_flyer_accelerations(pin, model, data, names, q, v) -> np.ndarray:
    """q̈ in lagcomp's coordinates from Pinocchio's ABA of a robot on a free flyer (``buildModelFromUrdf(path,
    JointModelFreeFlyer())``) at lagcomp's state (q, v) of ``lc.from_urdf(path, floating_base=True)``
    (`free_flyer_state`)."""
    qp, vp, tau, back = free_flyer_state(pin, model, names, q, v)
    return back(pin.aba(model, data, qp, vp, tau))


def free_flyer_state(pin, model, names, q, v) -> tuple:
    """(q, v, τ, back) of Pinocchio's free-flyer model of a URDF robot at lagcomp's state (q, v) of
    ``lc.from_urdf(path, floating_base=True)``, and the function turning Pinocchio's v̇ into lagcomp's q̈.

    lagcomp's first six coordinates are the root's position x (m, world frame) and MRPs σ; Pinocchio's flyer has
    q = (x, quaternion of R(σ)) and v = (Rᵀ ẋ, ω = J(σ) σ̇) in the root's frame, and back from its v̇:
    ẍ = R (v̇_lin + ω × Rᵀ ẋ), σ̈ = J⁻¹ (ω̇ − J̇ σ̇) (`lagcomp.multibody.mrp`).  The other joints are matched by name
    (URDF names, '-' made '_'), a continuous joint's (cos q, sin q); their generalized force τ is the joints'
    viscous damping −c q̇ as Pinocchio reads it."""
    from lagcomp.multibody import mrp

    q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
    sigma, sigma_dot = q[3:6], v[3:6]
    R, omega = np.array(mrp.rotation(sigma)), np.array(mrp.angular_velocity(sigma, sigma_dot))
    qp, vp = np.empty(model.nq), np.empty(model.nv)
    qp[:3], qp[3:7] = q[:3], pin.Quaternion(R).coeffs()
    vp[:3], vp[3:6] = R.T @ v[:3], omega
    order = _joint_states(model, names, q, v, qp, vp, first=2)
    charts = [("free", 0, 0, (sigma, sigma_dot, R, omega, vp[:3].copy()))]
    charts += [("revolute", index, k, None) for index, k in order]
    return qp, vp, -model.damping * vp, lambda a: _back(np.asarray(a, dtype=float), charts, len(names))


def fixed_base_accelerations(pin, model, data, names, q, v) -> np.ndarray:
    """q̈ in lagcomp's coordinate order `names` from Pinocchio's ABA of a fixed-base robot read from its URDF
    (``buildModelFromUrdf(path)``) at lagcomp's state (q, v) (`fixed_base_state`)."""
    qp, vp, tau, back = fixed_base_state(model, names, q, v)
    return back(pin.aba(model, data, qp, vp, tau))


def fixed_base_state(model, names, q, v) -> tuple:
    """(q, v, τ, back) of Pinocchio's model of a fixed-base URDF robot at lagcomp's state (q, v): joints matched by
    name as in `free_flyer_state`, τ the joints' viscous damping −c q̇; back turns Pinocchio's v̇ into lagcomp's q̈."""
    qp, vp = np.empty(model.nq), np.empty(model.nv)
    order = _joint_states(model, names, q, v, qp, vp, first=1)
    charts = [("revolute", index, k, None) for index, k in order]
    return qp, vp, -model.damping * vp, lambda a: _back(np.asarray(a, dtype=float), charts, len(names))


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


def urdf_accelerations(pin, model, data, names, q, v) -> np.ndarray:
    """q̈ in lagcomp's coordinates `names` from Pinocchio's ABA of a URDF robot read by its own reader, whatever its
    joints (`urdf_state`)."""
    qp, vp, tau, back = urdf_state(pin, model, names, q, v)
    return back(pin.aba(model, data, qp, vp, tau))


def urdf_state(pin, model, names, q, v) -> tuple:
    """(q, v, τ, back) of Pinocchio's model of a URDF robot at lagcomp's state (q, v) of ``lc.from_urdf(path)``
    (with ``floating_base=True`` if the model has Pinocchio's ``root_joint`` free flyer), joints matched by name
    (URDF names made identifiers as lagcomp makes them: every character outside letters, digits and ``_`` becomes
    ``_``):

    * a one-coordinate joint as in `fixed_base_state` (a continuous joint's q as (cos q, sin q));
    * a ``JointModelFreeFlyer`` named J (``<J>_x`` … ``<J>_mrp3``; the root's first six coordinates) as in
      `free_flyer_state`;
    * a ``JointModelPlanar`` named J (``<J>_x``, ``<J>_y``, ``<J>_theta``): q = (x, y, cos θ, sin θ) and v = (Rᵀ (ẋ,
      ẏ), θ̇), its linear velocity in the child's axes (R = Rz(θ)); back: (ẍ, ÿ) = R (v̇_lin + θ̇ ẑ × v_lin), θ̈ = v̇_θ.

    τ is the joints' viscous damping −c v as Pinocchio reads it; back turns Pinocchio's v̇ into lagcomp's q̈."""
    from lagcomp.multibody import mrp

    names = [str(name) for name in names]
    q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
    qp, vp, charts = np.empty(model.nq), np.empty(model.nv), []
    for j in range(1, model.njoints):
        joint, name = model.joints[j], _identifier(model.names[j])
        iq, iv, kind = joint.idx_q, joint.idx_v, joint.shortname()
        if kind == "JointModelFreeFlyer":
            k = 0 if model.names[j] == "root_joint" else names.index(f"{name}_x")
            sigma, sigma_dot = q[k + 3:k + 6], v[k + 3:k + 6]
            R, omega = np.array(mrp.rotation(sigma)), np.array(mrp.angular_velocity(sigma, sigma_dot))
            qp[iq:iq + 3], qp[iq + 3:iq + 7] = q[k:k + 3], pin.Quaternion(R).coeffs()
            vp[iv:iv + 3], vp[iv + 3:iv + 6] = R.T @ v[k:k + 3], omega
            charts.append(("free", iv, k, (sigma, sigma_dot, R, omega, vp[iv:iv + 3].copy())))
        elif kind == "JointModelPlanar":
            k = names.index(f"{name}_x")
            c, s = np.cos(q[k + 2]), np.sin(q[k + 2])
            qp[iq:iq + 4] = q[k], q[k + 1], c, s
            vp[iv:iv + 3] = c * v[k] + s * v[k + 1], -s * v[k] + c * v[k + 1], v[k + 2]
            charts.append(("planar", iv, k, (c, s, vp[iv:iv + 3].copy())))
        else:
            k = names.index(name)
            if joint.nq == 2:
                qp[iq:iq + 2] = np.cos(q[k]), np.sin(q[k])
            else:
                qp[iq] = q[k]
            vp[iv] = v[k]
            charts.append(("revolute", iv, k, None))
    planar = [chart for chart in charts if chart[0] == "planar"]
    rest = [chart for chart in charts if chart[0] != "planar"]

    def back(a):
        a = np.asarray(a, dtype=float)
        out = _back(a, rest, len(names))
        for _, iv, k, (c, s, linear) in planar:
            w = linear[2]
            lx, ly = a[iv] - w * linear[1], a[iv + 1] + w * linear[0]
            out[k:k + 3] = c * lx - s * ly, s * lx + c * ly, a[iv + 2]
        return out

    return qp, vp, -model.damping * vp, back


def _identifier(name: str) -> str:
    return re.sub(r"\W", "_", name, flags=re.ASCII)
