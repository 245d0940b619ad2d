"""Random mechanical systems, described once and derived twice: by lagcomp and by sympy.physics.mechanics.

`random_mechanism(seed)` draws a planar or 3-D tree of 1-3 bodies, with at
most four coordinates in all (particles
or rigid bodies with random principal inertias) hung from the ground or from
each other by revolute joints (about a random axis of the parent), sliders
(along a random direction) or, in 3-D, gimbals (two angles), with random
numeric geometry, random masses (symbols with random values), gravity, and
0-2 random holonomic constraints (a body point on a plane, at a fixed
distance from a point, or a smooth relation between two coordinates), each
satisfied at a random configuration q0 and independent there.

The kinematics (frames and position vectors) are built once with
sympy.physics.vector and handed to both sides; everything after that is
derived independently:

* lagcomp: `lc.Particle` / `lc.RigidBody` (T by Koenig's theorem from the
  position and the frame's angular velocity), `lc.Gravity` (a potential),
  `lc.Holonomic`; Lagrange's equations by `lagcomp.mechanics.lagrange`.
* reference: `me.Particle` / `me.RigidBody` kinetic energies in `me.Lagrangian`,
  gravity as point forces by virtual work (`forcelist`), the constraints as
  `hol_coneqs`; `me.LagrangesMethod` forms the equations.

The reference multipliers are the trailing unknowns of sympy's
``mass_matrix_full x = forcing_full`` (the constraint rows being Λ q̈ = γ).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp
import sympy.physics.mechanics as me

import lagcomp as lc

t = me.dynamicsymbols._t


@dataclass
class Mechanism:
    seed: int
    planar: bool
    system: lc.System
    method: me.LagrangesMethod
    coordinates: tuple
    parameters: tuple  # symbols, in the System's order
    values: np.ndarray  # their values
    q0: np.ndarray  # a configuration satisfying the constraints
    qd0: np.ndarray  # velocities satisfying them
    description: str


def _number(rng, low, high):
    return sp.Float(round(float(rng.uniform(low, high)), 3))


def _unit(rng, planar):
    v = rng.normal(size=3)
    if planar:
        v[2] = 0.0
    return v / np.linalg.norm(v)


def _vector(frame, components):
    return sum((sp.Float(round(float(c), 3)) * axis for c, axis in zip(components, (frame.x, frame.y, frame.z))),
               sp.S.Zero * frame.x)


def random_mechanism(seed: int, max_bodies: int = 3, max_coordinates: int = 4) -> Mechanism:
    rng = np.random.default_rng(seed)
    planar = bool(rng.random() < 0.5)
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    up = N.y if planar else N.z
    g = sp.Symbol("g", positive=True)
    n_bodies = int(rng.integers(1, max_bodies + 1))
    frames, origins, coordinates, lc_bodies, me_bodies, loads, masses, words = [N], [O], [], [], [], [], [], []
    for i in range(n_bodies):
        parent = int(rng.integers(0, i + 1))  # 0 = ground
        joint = rng.choice(["revolute", "revolute", "slider"] if planar else ["revolute", "gimbal", "slider"])
        if len(coordinates) + (2 if joint == "gimbal" else 1) > max_coordinates:
            break  # keep the symbolic work of both derivations to seconds
        P = frames[parent]
        where = rng.normal(size=3) * (1, 1, 0 if planar else 1) if parent else np.zeros(3)  # ground joints at O
        J = origins[parent].locatenew(f"J{i}", _vector(P, where))
        if joint == "revolute":
            (q,) = lc.coordinates(f"th{i}")
            axis = P.z if planar else (P.x, P.y, P.z)[int(rng.integers(0, 3))]
            B = P.orientnew(f"B{i}", "Axis", (q, axis))
            new = [q]
        elif joint == "gimbal":
            q, r = lc.coordinates(f"al{i} be{i}")
            A = P.orientnew(f"A{i}", "Axis", (q, P.z))
            B = A.orientnew(f"B{i}", "Axis", (r, A.x))
            new = [q, r]
        else:
            (q,) = lc.coordinates(f"s{i}")
            B = P.orientnew(f"B{i}", "Axis", (sp.S.Zero, P.z))
            J = J.locatenew(f"K{i}", q * _vector(P, _unit(rng, planar)))
            new = [q]
        coordinates += new
        offset = rng.normal(size=3) * (1, 1, 0 if planar else 1)
        offset *= rng.uniform(0.5, 1.5) / max(np.linalg.norm(offset), 1e-3)
        G = J.locatenew(f"G{i}", _vector(B, offset))
        G.set_vel(N, G.pos_from(O).dt(N))
        mass = sp.Symbol(f"m{i}", positive=True)
        masses.append(mass)
        position = G.pos_from(O)
        if rng.random() < 0.5:
            lc_bodies.append(lc.Particle(mass, position, name=f"p{i}"))
            me_bodies.append(me.Particle(f"p{i}", G, mass))
            kind = "particle"
        else:
            moments = sorted(_number(rng, 0.1, 1.0) for _ in range(3))
            moments[2] = min(moments[2], moments[0] + moments[1])  # the triangle inequality of a real body
            lc_bodies.append(lc.RigidBody(mass, position, tuple(moments), B, name=f"b{i}"))
            me_bodies.append(me.RigidBody(f"b{i}", G, B, mass, (me.inertia(B, *moments), G)))
            kind = "body"
        loads.append((G, -mass * g * up))
        frames.append(B)
        origins.append(J)
        words.append(f"{kind}@{joint}<-{parent}")
    coordinates = tuple(coordinates)
    n = len(coordinates)
    q0 = rng.uniform(-1.2, 1.2, size=n)
    positions = [b.masscenter.pos_from(O) for b in me_bodies]
    constraints = _random_constraints(rng, coordinates, positions, N, q0, planar)
    words += [c.name for c in constraints]
    parameters = (*masses, g)
    values = np.array([float(rng.uniform(0.5, 2.0)) for _ in masses] + [9.81])
    system = lc.System(coordinates, bodies=lc_bodies, loads=[lc.Gravity(-g * up)], frame=N, constraints=constraints,
                       parameters=parameters, name=f"random_{seed}", defaults=dict(zip(map(str, parameters), values)))
    method = me.LagrangesMethod(me.Lagrangian(N, *me_bodies), list(coordinates), forcelist=loads, frame=N,
                                hol_coneqs=[c.Phi for c in constraints] or None)
    qd0 = _consistent_velocities(rng, constraints, coordinates, q0)
    return Mechanism(seed, planar, system, method, coordinates, parameters, values, q0, qd0,
                     f"seed {seed}: {'planar' if planar else '3-D'} {', '.join(words)} (n={n})")


def _jacobian(constraints, coordinates, q0) -> np.ndarray:
    if not constraints:
        return np.zeros((0, len(coordinates)))
    Phi = sp.Matrix([c.Phi for c in constraints])
    J = Phi.jacobian(coordinates).xreplace(dict(zip(coordinates, q0)))
    return np.array(J.evalf(), dtype=float)


def _random_constraints(rng, coordinates, positions, N, q0, planar) -> list:
    n = len(coordinates)
    count = int(rng.integers(0, min(2, n - 1) + 1))
    at_q0 = dict(zip(coordinates, q0))
    chosen = []
    for k in range(count):
        for _ in range(10):  # draw until the constraints are independent at q0
            kind = rng.choice(["plane", "distance", "relation"])
            r = positions[int(rng.integers(0, len(positions)))]
            if kind == "plane":
                expr = r.dot(_vector(N, _unit(rng, planar)))
            elif kind == "distance":
                d = r - _vector(N, rng.normal(size=3) * (1, 1, 0 if planar else 1))
                expr = d.dot(d)
            else:
                i, j = rng.choice(n, size=2, replace=False)
                expr = sp.sin(coordinates[i]) + _number(rng, 0.5, 1.5) * coordinates[j] ** 2
            expr = sp.simplify(expr) if sp.count_ops(expr) < 40 else expr
            candidate = lc.Holonomic(f"{kind}{k}", expr - sp.Float(float(expr.xreplace(at_q0).evalf())))
            J = _jacobian([*chosen, candidate], coordinates, q0)
            if np.linalg.svd(J, compute_uv=False)[-1] > 0.05 * max(1.0, np.abs(J).max()):
                chosen.append(candidate)
                break
    return chosen


def _consistent_velocities(rng, constraints, coordinates, q0) -> np.ndarray:
    qd = rng.uniform(-1.0, 1.0, size=len(coordinates))
    J = _jacobian(constraints, coordinates, q0)
    if J.size:
        qd -= np.linalg.pinv(J) @ (J @ qd)  # project onto the null space of Λ(q0)
    return qd


def reference_functions(mech: Mechanism):
    """`f(q, qd) -> (qdd, lam)` from sympy.physics.mechanics (lam: the multipliers of ``mass_matrix_full``)."""
    lm = mech.method
    lm.form_lagranges_equations()
    q = sp.symbols(f"q0:{len(mech.coordinates)}")
    u = sp.symbols(f"u0:{len(mech.coordinates)}")
    plain = {c.diff(t): ui for c, ui in zip(mech.coordinates, u)}
    plain_q = dict(zip(mech.coordinates, q))
    to_numbers = dict(zip(mech.parameters, mech.values))
    lam = list(lm.lam_vec) if lm.lam_vec is not None and len(lm.lam_vec) else []
    M_full = lm.mass_matrix_full.xreplace(plain).xreplace(plain_q).xreplace(to_numbers)
    F_full = lm.forcing_full.xreplace(plain).xreplace(plain_q).xreplace(to_numbers)
    M_fn = sp.lambdify((q, u), M_full, "numpy")
    F_fn = sp.lambdify((q, u), F_full, "numpy")
    n = len(q)

    def accelerations(qv, uv):
        x = np.linalg.solve(np.asarray(M_fn(qv, uv), dtype=float), np.asarray(F_fn(qv, uv), dtype=float).ravel())
        return x[n:2 * n], x[2 * n:2 * n + len(lam)]
    return accelerations


def lagcomp_functions(mech: Mechanism):
    """`f(q, qd) -> (qdd, lam)` from lagcomp's derived equations (lambdified; no numba)."""
    from lagcomp.mechanics.lagrange import derive

    eom = derive(mech.system)
    args = (eom.q, eom.qd, t, eom.parameters)
    parts = [sp.lambdify(args, matrix, "numpy") for matrix in (eom.M, eom.F, eom.C, eom.gamma)]
    n, k = eom.n, eom.k

    def accelerations(qv, uv):
        M, F, C, gamma = (np.asarray(f(qv, uv, 0.0, mech.values), dtype=float).reshape(shape)
                          for f, shape in zip(parts, [(n, n), (n,), (k, n), (k,)]))
        kkt = np.block([[M, -C.T], [C, np.zeros((k, k))]])
        x = np.linalg.solve(kkt, np.concatenate([F, gamma]))
        return x[:n], x[n:]
    return eom, accelerations


def python_kernels(*sources: str) -> dict:
    """The emitted modules executed as plain Python (``njit`` a no-op) into one namespace, in order: the real
    kernels, without numba."""
    def njit(*args, **kwargs):
        return args[0] if args and callable(args[0]) else (lambda f: f)

    namespace = {"njit": njit, "__name__": "lagcomp_python_kernels"}
    for source in sources:
        exec(compile(source.replace("from numba import njit", ""), "<lagcomp kernels>", "exec"), namespace)
    return namespace


def python_model_kernels(model) -> dict:
    """Every kernel of the Lagrange `model` as plain Python (`python_kernels`): its companion modules (every
    on-demand kind, built here), then its eager module.  The eager module comes last, so that the eager kernels
    a companion imports by name (numba's, from the loaded eager module) are replaced by the plain-Python ones."""
    companions = [entry.path.read_text(encoding="utf-8") for entry in model.on_demand_entries.values()]
    return python_kernels(*companions, model.source_path.read_text(encoding="utf-8"))
