"""The same mechanisms as some bundled examples, built with sympy.physics.mechanics (for the interop tests).

Each builder returns the sympy objects and the parameter symbols in the
order of the matching lagcomp example, so parameter vectors line up.
"""

from __future__ import annotations

import sympy as sp
import sympy.physics.mechanics as me

t = me.dynamicsymbols._t


def chain(n: int = 3):
    """Planar chain of n particles on massless rods (example ``n_link_pendulum``), LagrangesMethod."""
    th = me.dynamicsymbols(f"theta1:{n + 1}")
    ms = sp.symbols(f"m1:{n + 1}", positive=True)
    ls = sp.symbols(f"l1:{n + 1}", positive=True)
    g = sp.Symbol("g", positive=True)
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    prev, particles, loads = O, [], []
    for i in range(n):
        P = prev.locatenew(f"P{i + 1}", ls[i] * (sp.sin(th[i]) * N.x - sp.cos(th[i]) * N.y))
        P.set_vel(N, P.pos_from(O).dt(N))
        particles.append(me.Particle(f"bob{i + 1}", P, ms[i]))
        loads.append((P, -ms[i] * g * N.y))
        prev = P
    lm = me.LagrangesMethod(me.Lagrangian(N, *particles), th, forcelist=loads, frame=N)
    return dict(method=lm, bodies=particles, loads=loads, frame=N, origin=O, parameters=ms + ls + (g,))


def kane_chain(n: int = 3):
    """The same chain with KanesMethod, generalized speeds u_i = θ̇_i (absolute rod rates)."""
    th = me.dynamicsymbols(f"theta1:{n + 1}")
    u = me.dynamicsymbols(f"u1:{n + 1}")
    ms = sp.symbols(f"m1:{n + 1}", positive=True)
    ls = sp.symbols(f"l1:{n + 1}", positive=True)
    g = sp.Symbol("g", positive=True)
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    prev, particles, loads = O, [], []
    for i in range(n):
        A = N.orientnew(f"A{i}", "Axis", (th[i], N.z))
        A.set_ang_vel(N, u[i] * N.z)
        P = prev.locatenew(f"P{i + 1}", -ls[i] * A.y)
        P.v2pt_theory(prev, N, A)
        particles.append(me.Particle(f"bob{i + 1}", P, ms[i]))
        loads.append((P, -ms[i] * g * N.y))
        prev = P
    km = me.KanesMethod(N, th, u, kd_eqs=[th[i].diff(t) - u[i] for i in range(n)], bodies=particles, forcelist=loads)
    return dict(method=km, parameters=ms + ls + (g,))


def rolling_disc():
    """Thin disc rolling on a plane (example ``rolling_disc``): sympy RigidBody, LagrangesMethod with
    the two rolling constraints as nonholonomic equations and gravity as a load."""
    x, y, psi, theta, phi = me.dynamicsymbols("x y psi theta phi")
    m, r, I1, I3, g = sp.symbols("m r I1 I3 g", positive=True)
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    A = N.orientnew("A", "Axis", (psi, N.z))
    B = A.orientnew("B", "Axis", (theta, A.x))
    D = B.orientnew("D", "Axis", (phi, B.y))
    G = O.locatenew("G", x * N.x + y * N.y + r * B.z)
    G.set_vel(N, G.pos_from(O).dt(N))
    disc = me.RigidBody("disc", G, D, m, (me.inertia(D, I1, I3, I1), G))
    rolling = [x.diff(t) - r * phi.diff(t) * sp.cos(psi), y.diff(t) - r * phi.diff(t) * sp.sin(psi)]
    loads = [(G, -m * g * N.z)]
    lm = me.LagrangesMethod(me.Lagrangian(N, disc), [x, y, psi, theta, phi], forcelist=loads, frame=N,
                            nonhol_coneqs=rolling)
    return dict(method=lm, bodies=[disc], loads=loads, frame=N, origin=O, parameters=(m, r, I1, I3, g),
                rolling=rolling)


def kane_rolling_disc():
    """The rolling disc with KanesMethod: u_i = q̇_i, the contact-point rates ẋ, ẏ dependent speeds."""
    built = rolling_disc()
    qs = list(built["method"].q)
    us = me.dynamicsymbols("u_x u_y u_psi u_theta u_phi")
    to_u = {q.diff(t): u for q, u in zip(qs, us)}
    N, disc = built["frame"], built["bodies"][0]
    disc.masscenter.set_vel(N, disc.masscenter.vel(N).xreplace(to_u))
    disc.frame.set_ang_vel(N, disc.frame.ang_vel_in(N).xreplace(to_u))
    km = me.KanesMethod(
        N, qs, us[2:], kd_eqs=[q.diff(t) - u for q, u in zip(qs, us)], u_dependent=us[:2],
        velocity_constraints=[c.xreplace(to_u) for c in built["rolling"]], bodies=built["bodies"],
        forcelist=built["loads"],
    )
    return dict(method=km, parameters=built["parameters"])
