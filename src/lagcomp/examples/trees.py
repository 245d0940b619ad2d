"""Kinematic trees (`lagcomp.Tree`) as examples and for the benchmarks: chains of n links to measure how the
multibody path scales (`bench/bench_multibody.py`, `bench/bench_scale.py`, issue 39), a cart-pole, and a five-joint
robot arm read from the URDF file shipped with lagcomp (`ARM5_URDF`, `arm5`).

These factories are not in `lagcomp.examples.EXAMPLES`, which holds Systems; each returns a Tree whose
parameters are free symbols (no defaults): the tests draw them at random.  Every joint frame is placed without
rotation; the planar and universal chains' joints turn about x, y or z, so that the same system can also be written
with `lagcomp.rotated` (`tests/multibody_models.py` does, for the Lagrangian path); the ball chain's turn about any
axis (modified Rodrigues parameters, `lagcomp.Spherical`).
"""

from __future__ import annotations

from pathlib import Path

import sympy as sp

from lagcomp.model import coordinates, t
from lagcomp.multibody import Link, Prismatic, Revolute, Spherical, Tree, Universal

__all__ = ["ARM5_URDF", "arm5", "cart_pole", "planar_chain", "spherical_chain", "universal_chain"]

#: A five-joint arm's URDF, shipped with lagcomp: a turntable (``shoulder_pan`` about z), three pitch joints about y
#: (``shoulder_lift``, ``elbow``, ``wrist_pitch``), a wrist roll (``wrist_roll`` about z) and a tool fixed to the hand;
#: uniform cylinders of 0.25 to 1.5 kg, 0.75 m reach, viscous joint damping (the file's comment has the numbers).
ARM5_URDF = Path(__file__).resolve().parent / "urdf" / "arm5.urdf"


def planar_chain(n: int, name: str | None = None) -> Tree:
    """n rigid links hinged about z, each hinge at the end of the previous link (length l_i along its x), centre
    of mass at (c_i, d_i, 0), inertia about it (J_i, J_i, J_i); gravity −g along y."""
    g = sp.Symbol("g", positive=True)
    links = []
    for i in range(n):
        m, c, d, J = sp.symbols(f"m{i} c{i} d{i} J{i}")
        origin = (0, 0, 0) if i == 0 else (sp.Symbol(f"l{i - 1}"), 0, 0)
        links.append(Link(f"link{i}", Revolute(f"th{i}", axis="z", origin=origin),
                          parent=None if i == 0 else f"link{i - 1}", mass=m, com=(c, d, 0), inertia=(J, J, J)))
    return Tree(links, gravity=(0, -g, 0), name=name or f"planar_chain_{n}")


def universal_chain(n: int) -> Tree:
    """n rigid links hanging from universal joints (x, then y), the next joint at (0, 0, −l_i) of link i, centre
    of mass at (0, 0, −c_i), principal moments (A_i, B_i, C_i); gravity −g along z."""
    g = sp.Symbol("g", positive=True)
    links = []
    for i in range(n):
        m, c, A, B, C = sp.symbols(f"m{i} c{i} A{i} B{i} C{i}")
        origin = (0, 0, 0) if i == 0 else (0, 0, -sp.Symbol(f"l{i - 1}"))
        links.append(Link(f"link{i}", Universal((f"a{i}", f"b{i}"), origin=origin),
                          parent=None if i == 0 else f"link{i - 1}", mass=m, com=(0, 0, -c), inertia=(A, B, C)))
    return Tree(links, gravity=(0, 0, -g), name=f"universal_chain_{n}")


def spherical_chain(n: int) -> Tree:
    """n rigid links hanging from ball joints (`Spherical`: three MRPs each), the next joint at (0, 0, −l_i) of
    link i, centre of mass at (0, 0, −c_i), principal moments (A_i, B_i, C_i); gravity −g along z."""
    g = sp.Symbol("g", positive=True)
    links = []
    for i in range(n):
        m, c, A, B, C = sp.symbols(f"m{i} c{i} A{i} B{i} C{i}")
        origin = (0, 0, 0) if i == 0 else (0, 0, -sp.Symbol(f"l{i - 1}"))
        links.append(Link(f"link{i}", Spherical((f"s{i}x", f"s{i}y", f"s{i}z"), origin=origin),
                          parent=None if i == 0 else f"link{i - 1}", mass=m, com=(0, 0, -c), inertia=(A, B, C)))
    return Tree(links, gravity=(0, 0, -g), name=f"spherical_chain_{n}")


def cart_pole() -> Tree:
    """A cart sliding along x (spring k to x = 0, damper b, force F sin(w t)) carrying a pendulum about z (damper
    e); gravity −g along y."""
    M, m, c, J, g, k, b, F, w, e = sp.symbols("M m c J g k b F w e")
    x, th = coordinates("x th")
    cart = Link("cart", Prismatic(x, axis="x", stiffness=k, damping=b, torque=F * sp.sin(w * t)), mass=M)
    pole = Link("pole", Revolute(th, axis="z", damping=e), parent="cart", mass=m, com=(0, -c, 0),
                inertia=(J, J, J))
    return Tree([cart, pole], gravity=(0, -g, 0), name="cart_pole_tree")


def arm5(**options) -> Tree:
    """The five-joint arm of `ARM5_URDF` as a Tree (`lagcomp.from_urdf` with `options`: ``floating_base``,
    ``damping``, ``q0``, ...); needs yourdfpy (the ``urdf`` extra)."""
    from lagcomp.multibody.urdf import from_urdf

    return from_urdf(ARM5_URDF, **options)
