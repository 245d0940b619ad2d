r"""Points of bodies as the outputs of a state-space model: rows of C for positions and velocities.

A body of ``System.bodies`` is at r(q, t) (a particle's position, a rigid body's centre: `lagcomp.codegen.geometry`,
components along the axes of the System's frame, from its origin).  About an equilibrium q₀ (q̇₀ = 0) of
`lagcomp.analysis.linearize`, with x = (δq, δq̇),

    δr = J δq,                      J = ∂r/∂q at (q₀, t),
    δv = (∂/∂q ∂r/∂t) δq + J δq̇,    v = J q̇ + ∂r/∂t,

so the row of C of ``"<body>.x"`` (``.y``, ``.z``: the position's components) is [J_x, 0], and that of
``"<body>.vx"`` (``.vy``, ``.vz``: the velocity's) [∂²r_x/∂q∂t, J_x]; D is 0 (an input inside a position is an
imposed motion, whose derivatives the equations read: `linearize` gives no B then).  The derivatives are
symbolic (sympy, from the System's bodies), evaluated at the point: no finite difference.  A kinematic tree's
outputs are its links' origins (`lagcomp.analysis.tree_points`).
"""

from __future__ import annotations

import numpy as np
from sympy.core.function import AppliedUndef

from lagcomp.errors import ModelError, OptionError
from lagcomp.model.inputs import is_input
from lagcomp.model.system import t as time

#: The components of a point's position and velocity, as output names' suffixes.
POSITION, VELOCITY = ("x", "y", "z"), ("vx", "vy", "vz")


def point_rows(model, q: np.ndarray, t: float, params: dict, names) -> dict:
    """{name: (C row (2n,), D row (U,))} of each body output among `names` (module docstring); other names are
    left to the caller (states).  A ModelError where the model carries no System (`lagcomp.load`), an OptionError
    where a named body is not among those the model places (no position it knows).  A position that reads an
    input u(t) gets no row: its kinetic energy reads u̇, and `Linearization.state_space` refuses the linearization
    (`input_refused`) before it reads the rows."""
    wanted = [name for name in names if isinstance(name, str) and name.rpartition(".")[2] in POSITION + VELOCITY
              and "." in name]
    if not wanted:
        return {}
    from lagcomp.multibody.tree import Tree

    if isinstance(getattr(model, "system", None), Tree):    # a tree's links: their frames' origins
        from lagcomp.analysis.tree_points import tree_point_rows

        return tree_point_rows(model, model.system, q, params, wanted)
    positions = _positions(model)
    unknown = [name for name in wanted if name.rpartition(".")[0] not in positions]
    if unknown:
        raise OptionError(f"Unknown output(s) {unknown}: a body's point is '<body>.x' (.y, .z; .vx, .vy, .vz for its "
                          f"velocity), bodies placed in {model.name!r}: {sorted(positions)}.")
    n, inputs = model.n, len(model.inputs)
    rows = {}
    for name in wanted:
        body, _, part = name.rpartition(".")
        q_symbols, parameters, r = positions[body]
        component = (POSITION + VELOCITY).index(part) % 3
        expression = r[component]
        if any(is_input(f) for f in expression.atoms(AppliedUndef)):
            continue
        values = {**dict(zip(q_symbols, q.tolist(), strict=True)), **_parameter_values(parameters, params), time: t}
        jacobian = np.array([float(expression.diff(s).subs(values)) for s in q_symbols])
        if part in POSITION:
            row = np.concatenate([jacobian, np.zeros(n)])
        else:
            drift = np.array([float(expression.diff(time).diff(s).subs(values)) for s in q_symbols])
            row = np.concatenate([drift, jacobian])
        rows[name] = (row, np.zeros(inputs))
    return rows


def _parameter_values(parameters, params: dict) -> dict:
    """The parameters' symbols to the values the linearization used (by name)."""
    return {s: params[s.name] for s in parameters if s.name in params}


def _positions(model) -> dict:
    """{body name: (q symbols, parameter symbols, r (3,) over them)} of the bodies the model places."""
    from lagcomp.codegen.geometry import body_geometry
    from lagcomp.mechanics.lagrange import derive

    system = getattr(model, "system", None)
    if system is None:
        raise ModelError(f"Outputs at points of bodies read the System's bodies, which a model from lagcomp.load() "
                         f"({model.name!r}) does not carry: linearize lagcomp.compile(system)'s model.")
    eom = _EQUATIONS.get(system.fingerprint())
    if eom is None:
        eom = _EQUATIONS[system.fingerprint()] = derive(system)
    layout, values = body_geometry(eom)
    by_index = dict(values)
    return {name: (tuple(eom.q), tuple(eom.parameters), [by_index[offset + c] for c in range(3)])
            for name, kind, offset in layout if kind != "unplaced"}


#: The equations of the Systems whose points were asked for, by fingerprint (derived once per process).
_EQUATIONS: dict = {}
