"""A `lagcomp.Tree` as a Pinocchio model, to check lagcomp's recursions against Pinocchio's and to time them side by
side (`bench/bench_multibody.py`, the tests).  Needs ``pin`` (imported when called).
"""

from __future__ import annotations

import numpy as np
import sympy as sp

__all__ = ["pinocchio_model"]


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
