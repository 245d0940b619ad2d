r"""Refuse sympy models whose stated velocities are not the time derivatives of their positions.

Paths that re-derive the equations from the kinetic energy (LagrangesMethod,
`from_kanes_method`, sympy bodies in `System(bodies=...)`) read T from the
velocities sympy holds for points and frames.  Those may have been set by
hand — ``v2pt_theory`` from a rolling contact whose velocity is set to zero,
``set_vel``, ``set_ang_vel`` with generalized speeds — and then encode
nonholonomic rolling conditions.  Lagrange's equations of such a T are wrong
(the Whipple bicycle's eigenvalues at 5 m/s came out −19.83, −0.738,
2.53 ± 12.74i instead of −14.08, −0.32, −0.78 ± 4.46i), while Kane's
equations of the same model are right.  So these paths check, before
deriving anything:

- each point P: v_P − v_O = d/dt r_{P/O} in the inertial frame, with O a point
  of P's position tree (one whose velocity is set to zero if there is one);
- each frame F oriented relative to the inertial frame N: its stated ω_F
  equals the ω of its direction cosine matrix C (the axial vector of Ċ Cᵀ).

Speeds are replaced through the kinematic differential equations, and both
sides are evaluated at random states and parameter values (exact symbolic
comparison of a bicycle's velocities is too slow); a relative difference
above 1e-8 at any sample is a stated velocity.  Points whose position tree
holds no point with a known velocity, and frames with no orientation
relative to N (a wheel spun by ``set_ang_vel`` alone), cannot be checked and
are taken as stated.
"""

from __future__ import annotations

import random

import sympy as sp
from sympy.physics import mechanics as me
from sympy.physics.mechanics import dynamicsymbols

from lagcomp.errors import ModelError

__all__ = ["check_stated_velocities"]

t = dynamicsymbols._t
#: Random samples per check, and the relative difference that counts as a mismatch.
SAMPLES, TOLERANCE = 2, 1e-8


def check_stated_velocities(points, frames, inertial: me.ReferenceFrame, kindiff: dict | None = None) -> None:
    """Raise ModelError naming the first point or frame whose velocity in `inertial` is stated, not derived.

    `kindiff` maps q̇ to the speeds (``KanesMethod.kindiffdict()``), so that
    velocities stated in speeds compare with derivatives of positions.
    """
    kindiff = kindiff or {}
    for point in _unique(points):
        mismatch = _point_mismatch(point, inertial, kindiff)
        if mismatch is not None:
            origin, size = mismatch
            raise ModelError(
                f"point {point.name}: its velocity in {inertial.name} was set by hand (v2pt_theory / set_vel) and is "
                f"not d/dt of its position from {origin.name} (they differ by {size:.3g} at a random state): the "
                "kinetic energy re-derived from it would give Lagrange's equations of a different system (a rolling "
                "constraint written into the velocities). Compile the KanesMethod instead (lagcomp.compile(km) uses "
                "Kane's equations as stated), or set the velocity from the position "
                f"({point.name}.set_vel({inertial.name}, {point.name}.pos_from({origin.name}).dt({inertial.name})))."
            )
    for frame in _unique(frames):
        size = _frame_mismatch(frame, inertial, kindiff)
        if size is not None:
            raise ModelError(
                f"frame {frame.name}: its angular velocity in {inertial.name} was set by hand (set_ang_vel) and is not "
                f"the rate of its orientation (they differ by {size:.3g} at a random state). Compile the KanesMethod "
                "instead (lagcomp.compile(km)), or let sympy derive it from the orientation (orientnew / orient)."
            )


def _unique(items) -> list:
    seen, kept = set(), []
    for item in items:
        if item is not None and id(item) not in seen:
            seen.add(id(item))
            kept.append(item)
    return kept


def _origin(point: me.Point, frame) -> me.Point | None:
    """A point of `point`'s position tree other than itself with a velocity in `frame`, zero ones first."""
    seen, todo, known = {point}, [point], []
    while todo:
        current = todo.pop(0)
        stated = current._vel_dict.get(frame)
        if current is not point and stated is not None:
            if stated == 0:
                return current
            known.append(current)
        for other in current._pos_dict:
            if other not in seen:
                seen.add(other)
                todo.append(other)
    return known[0] if known else None


def _point_mismatch(point: me.Point, frame, kindiff: dict):
    origin = _origin(point, frame)
    if origin is None:
        return None
    try:
        stated = (point.vel(frame) - origin.vel(frame)).to_matrix(frame)
        derived = point.pos_from(origin).to_matrix(frame).diff(t)
    except ValueError:
        return None
    size = _difference(stated, derived.xreplace(kindiff))
    return None if size is None else (origin, size)


def _frame_mismatch(frame: me.ReferenceFrame, inertial, kindiff: dict):
    try:
        C = inertial.dcm(frame)
        stated = frame.ang_vel_in(inertial).to_matrix(inertial)
    except ValueError:
        return None
    W = C.diff(t) * C.T
    derived = sp.Matrix([W[2, 1], W[0, 2], W[1, 0]])
    return _difference(stated, derived.xreplace(kindiff))


def _difference(stated: sp.Matrix, derived: sp.Matrix) -> float | None:
    """The largest |stated − derived| at random values, when above TOLERANCE relative; else None."""
    rng = random.Random(18)
    for _ in range(SAMPLES):
        values = _random_values(stated, derived, rng=rng)
        a = [complex(sp.N(e.xreplace(values[0]).xreplace(values[1]), 20)) for e in stated]
        b = [complex(sp.N(e.xreplace(values[0]).xreplace(values[1]), 20)) for e in derived]
        size = max(abs(x - y) for x, y in zip(a, b))
        scale = max(1.0, *(abs(x) for x in a + b))
        if size > TOLERANCE * scale:
            return size
    return None


def _random_values(*matrices, rng) -> tuple[dict, dict]:
    """(derivatives and functions of t, then symbols) -> random floats in [0.3, 1.3]."""
    exprs = [e for m in matrices for e in m]
    derivatives = set().union(*(e.atoms(sp.Derivative) for e in exprs))
    functions = set().union(*(e.atoms(sp.core.function.AppliedUndef) for e in exprs))
    symbols = set().union(*(e.free_symbols for e in exprs)) - {t}
    draw = lambda items: {x: sp.Float(rng.uniform(0.3, 1.3)) for x in sorted(items, key=str)}  # noqa: E731
    first = draw(derivatives) | draw(functions)
    return first, draw(symbols) | {t: sp.Float(0.7)}
