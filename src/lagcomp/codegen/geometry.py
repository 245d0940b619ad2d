r"""The ``geometry`` kernel: where each body of a System is and how it is turned, for drawing.

    geometry(t, y, p, out)

writes, for each body of ``System.bodies`` in order, from ``out[offset]`` on:

* its position r, 3 values: a particle's position, a rigid body's centre of mass G, as
  components along the axes of the frame R the system is described in, measured from R's
  origin (`lagcomp.model.bodies`, Conventions);
* for a rigid body whose orientation the model knows, then the rotation matrix C, 9 values
  row-major (C[i, j] at offset + 3 + 3 i + j), whose column j is the body's axis j in R's
  components: r_R = C r_body.

R is the System's `frame`, inertial when it is Galilean.  A `MovingFrame`'s own motion is
given by its acceleration and angular velocity only, never by where it is, so the bodies of
a system in a moving frame are drawn as seen from R.

A body is "unplaced", not drawn, when the model does not know where it is: a sympy Point
located from no origin of the frame (its velocity is all the kinetic energy needs), or a
position with a symbol that is no parameter (the ``d`` of ``x + d``, lost from T).  A rigid
body whose axes have such a symbol is drawn at its centre only.

Which axes are the body's: the ReferenceFrame given as its angular velocity (the body's own
frame, turning with it: the top's spin shows), else its `axes` (a ReferenceFrame, or the
matrix C itself).  A rigid body with neither, its ω given as components, is drawn at its
centre only.

Module constants tell Python callers (`lagcomp.animation`) the layout:
``GEOMETRY`` = ((name, kind, offset), ...) in the order of the bodies, kind one of `KINDS`
(how many values it writes), the names made unique (`unique_names`); ``GEOMETRY_SIZE`` the
length of ``out``.  A system without bodies (T written directly; every Kane model, for now)
has a kernel that writes nothing, ``GEOMETRY = ()`` and ``GEOMETRY_SIZE = 0``.

Positions depend on q, t and the parameters, never on q̇ (`lagcomp.model.bodies` refuses
velocities in them), so the kernel loads no velocity: a caller may pass any q̇.

Cost (``python -m bench.bench_geometry``): lowering it takes 1.5–9 ms for the bundled examples
built from bodies, 0.17–0.40 of their whole `lower` (9–22 ms); a call from Python, once per
frame, about 2 µs, some 4·10⁻⁵ of drawing the frame with matplotlib.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.physics.vector import Point, ReferenceFrame

from lagcomp.ir import Kernel
from lagcomp.mechanics.lagrange import EOM, to_plain
from lagcomp.model.bodies import Particle
from lagcomp.model.frames import MovingFrame, as_frame, column
from lagcomp.model.inputs import is_input
from lagcomp.model.system import t

#: What a body of each kind writes into ``out``: its number of values, and what they are.
KINDS = {
    "particle": (3, "position"),
    "rigid": (12, "centre of mass, then the rotation matrix C row-major (columns: the body axes)"),
    "centre": (3, "centre of mass (a rigid body whose orientation the model does not know)"),
    "unplaced": (0, "nothing: the model does not know where it is"),
}

#: The kernel's signature: `out` has ``GEOMETRY_SIZE`` entries.
ARGS = ("t", "y", "p", "out")


def unique_names(names: list[str]) -> list[str]:
    """`names`, each repeated one as ``<name>[<index>]`` (its position among the bodies), made
    unique by a trailing ``_`` where even that is taken (two bodies are both ``"particle"`` by default)."""
    taken = {name for name in names if names.count(name) == 1}
    unique = []
    for index, name in enumerate(names):
        label = name if names.count(name) == 1 else f"{name}[{index}]"
        while label != name and label in taken:
            label += "_"
        taken.add(label)
        unique.append(label)
    return unique


def position(body, frame: MovingFrame) -> sp.Matrix | None:
    """r (3, 1) of a particle or a rigid body's centre, in the frame's axes from its origin; None for a sympy
    Point when the frame has no origin.  The System checked these when it took the body (`Particle.kinematics`);
    this is the position alone, without the velocities and ω the kinematics derive."""
    point = body.position if isinstance(body, Particle) else body.com
    if isinstance(point, Point):
        return None if frame.origin is None else point.pos_from(frame.origin).to_matrix(frame.axes)
    return column(point, frame.axes, f"{body.name}: position")


def orientation(body, frame: MovingFrame) -> sp.Matrix | None:
    """C (3, 3), columns the body's axes in the frame's components, or None when the model does not say."""
    if isinstance(body, Particle):
        return None
    own = body.angular_velocity if isinstance(body.angular_velocity, ReferenceFrame) else body.axes
    if isinstance(own, sp.MatrixBase):
        return own
    if isinstance(own, ReferenceFrame) and frame.axes is not None:
        try:
            return frame.axes.dcm(own)  # [v]_R = R.dcm(B) [v]_B: its columns are B's axes in R
        except ValueError:  # sympy: no orientation path from the body's axes to the frame's
            return None
    return None


def body_geometry(eom: EOM) -> tuple[tuple[tuple[str, str, int], ...], list[tuple[int, sp.Expr]]]:
    """The layout ``((name, kind, offset), ...)`` and the values ``(index in out, expression)`` over the
    model's plain symbols (`lagcomp.mechanics.lagrange.to_plain`)."""
    system = eom.system
    frame = as_frame(system.frame)
    layout, values, offset = [], [], 0
    names = unique_names([body.name for body in system.bodies])
    for name, body in zip(names, system.bodies, strict=True):
        r = _known(eom, position(body, frame))
        rotation = None if r is None else _known(eom, orientation(body, frame))
        if r is None:
            kind, entries = "unplaced", []
        elif isinstance(body, Particle):
            kind, entries = "particle", list(r)
        elif rotation is None:
            kind, entries = "centre", list(r)
        else:
            kind, entries = "rigid", list(r) + list(rotation)  # a Matrix iterates row-major
        layout.append((name, kind, offset))
        values += list(enumerate(entries, start=offset))
        offset += KINDS[kind][0]
    return tuple(layout), values


def _known(eom: EOM, matrix: sp.Matrix | None) -> list[sp.Expr] | None:
    """The entries of `matrix` over the model's plain symbols (`lagcomp.mechanics.lagrange.to_plain`) when they
    are functions of q, t, the parameters and the inputs u(t) (`lagcomp.Input`, read from p like every kernel's) alone;
    else None (no matrix, or a symbol the kinetic energy lost:
    the ``d`` of a constant offset ``x + d`` that no other expression has is no parameter, so the kernel could
    not bind it)."""
    if matrix is None:
        return None
    entries = [to_plain(sp.sympify(e), eom.system, eom.q, eom.qd) for e in matrix]
    known = {*eom.q, *eom.parameters, t}
    if any(e.free_symbols - known or any(not is_input(f) for f in e.atoms(AppliedUndef)) for e in entries):
        return None
    return entries


def geometry_kernel(eom: EOM, build: Callable[..., Kernel]) -> Kernel:
    """The ``geometry`` kernel of `eom`'s bodies, with its ``GEOMETRY`` and ``GEOMETRY_SIZE`` constants.

    `build(name, doc, args, stores)` makes the Kernel with one CSE over the stores, in the module's
    bindings (`lagcomp.codegen.bindings.symbol_bindings`).
    """
    layout, values = body_geometry(eom)
    size = sum(KINDS[kind][0] for _, kind, _ in layout)
    lines = [f"out[{offset}:{offset + KINDS[kind][0]}] {name}: {KINDS[kind][1]}" for name, kind, offset in layout]
    doc = (
        f"Where the bodies are, shape (GEOMETRY_SIZE,) = ({size},), into `out`: positions along the axes of the\n"
        "system's frame from its origin, rotation matrices C (r_frame = C r_body) row-major. Reads no velocity.\n"
        + "\n".join(lines)
    ) if layout else "Where the bodies are: this system has none (T written directly), writes nothing."
    kernel = (build("geometry", doc, ARGS, [(f"out[{i}]", e) for i, e in values]) if values
              else Kernel(name="geometry", doc=doc, args=ARGS, loads=(), temps=(), stores=()))
    return replace(kernel, constants=geometry_constants(layout, size))


def geometry_constants(layout: tuple, size: int) -> tuple[tuple[str, str, object], ...]:
    """``GEOMETRY`` and ``GEOMETRY_SIZE`` as `Kernel.constants`."""
    return (
        ("GEOMETRY", "The bodies `geometry` writes, (name, kind, offset into out); a kind's values: "
         + ", ".join(f"{kind} {count}" for kind, (count, _) in KINDS.items()) + ".", layout),
        ("GEOMETRY_SIZE", "Length of `geometry`'s out.", size),
    )


def no_geometry_kernel() -> Kernel:
    """The ``geometry`` of a module that has no bodies to draw (a Kane model's): writes nothing, size 0."""
    layout: tuple = ()
    return Kernel(name="geometry", doc="Where the bodies are: this model has none to draw, writes nothing.",
                  args=ARGS, loads=(), temps=(), stores=(), constants=geometry_constants(layout, 0))
