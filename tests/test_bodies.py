"""Bodies, loads and moving frames, symbolically (no numba): against sympy.physics.mechanics and hand derivations."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import sympy as sp
import sympy.physics.mechanics as me
from sympy.physics.vector import ReferenceFrame

import lagcomp as lc
from lagcomp import examples
from lagcomp.errors import ModelError, UndeclaredSymbolError
from lagcomp.mechanics.lagrange import derive
from lagcomp.model import t
from lagcomp.model.bodies import inertia_matrix

import sympy_models


def is_zero(expr) -> bool:
    if isinstance(expr, sp.MatrixBase):
        return all(is_zero(e) for e in expr)
    expr = sp.expand(sp.expand_trig(sp.sympify(expr)))
    return expr == 0 or sp.simplify(expr) == 0


def vanishes(expr, tries: int = 4) -> bool:
    """Zero test for expressions too large for `simplify`: 40-digit evaluation at random points.

    Every function of t (coordinates and their derivatives), t and every symbol
    gets an independent random value in [0.3, 1.7]; a nonzero expression would
    need to vanish at all of them by accident.
    """
    expr = sp.Matrix([expr]) if not isinstance(expr, sp.MatrixBase) else expr
    rng = np.random.default_rng(7)
    derivatives = sorted(expr.atoms(sp.Derivative), key=lambda d: -d.derivative_count)
    for _ in range(tries):
        values = {d: sp.Float(rng.uniform(0.3, 1.7), 40) for d in derivatives}
        e = expr.xreplace(values)
        functions = e.atoms(sp.core.function.AppliedUndef)
        e = e.xreplace({f: sp.Float(rng.uniform(0.3, 1.7), 40) for f in functions})
        e = e.xreplace({s: sp.Float(rng.uniform(0.3, 1.7), 40) for s in e.free_symbols})
        if any(abs(sp.N(x, 40)) > 1e-25 for x in e):
            return False
    return True


def residual(system: lc.System) -> sp.Matrix:
    """M q̈ − F of the derived equations, back in q(t) (so hand-written equations can be subtracted)."""
    eom = derive(system)
    back = {**{s: c for s, c in zip(eom.q, system.coordinates)}, **{v: c.diff(t) for v, c in zip(eom.qd, system.coordinates)}}
    qdd = sp.Matrix([c.diff(t, 2) for c in system.coordinates])
    return (eom.M * qdd - eom.F).xreplace(back)


def lagranges_method_residual(system: lc.System, L, forcelist=None, frame=None) -> sp.Matrix:
    lm = me.LagrangesMethod(L, list(system.coordinates), forcelist=forcelist, frame=frame)
    lm.form_lagranges_equations()
    qdd = sp.Matrix([c.diff(t, 2) for c in system.coordinates])
    return lm.mass_matrix * qdd - lm.forcing


# -- T and Q against sympy.physics.mechanics -----------------------------------------------------


def top_in_sympy():
    """A heavy asymmetric body on a fixed point (Euler angles), built with sympy.physics.mechanics."""
    psi, theta, phi = me.dynamicsymbols("psi theta phi")
    M, a, b, c, g, A, B, C, D = sp.symbols("M a b c g A B C D", positive=True)
    N = ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    body_frame = lc.rotated(N, (psi, "z"), (theta, "x"), (phi, "z"))
    G = O.locatenew("G", a * body_frame.x + b * body_frame.y + c * body_frame.z)
    G.set_vel(N, G.pos_from(O).dt(N))
    inertia = sp.Matrix([[A, D, 0], [D, B, 0], [0, 0, C]])  # A, B > D
    body = me.RigidBody("top", G, body_frame, M, (me.inertia(body_frame, A, B, C, ixy=D), G))
    return (psi, theta, phi), body, inertia, N, O, G, body_frame, g


def test_rigid_body_T_matches_sympy_kinetic_energy():
    q, body, inertia, N, O, G, B, _ = top_in_sympy()
    ours = lc.RigidBody(body.mass, G.pos_from(O).to_matrix(N), inertia, B, name="top").kinetic_energy(lc.MovingFrame(axes=N))
    assert vanishes(ours - body.kinetic_energy(N))
    # components instead of frames: ω from body_rates, position as a Vector
    by_components = lc.RigidBody(body.mass, G.pos_from(O), inertia, lc.body_rates(B, N), axes=B)
    assert vanishes(by_components.kinetic_energy(lc.MovingFrame(axes=N)) - body.kinetic_energy(N))
    assert not vanishes(by_components.kinetic_energy(lc.MovingFrame(axes=N)) - body.kinetic_energy(N) + q[0].diff(t))


def test_bodies_and_loads_give_lagranges_method_equations():
    """Asymmetric top with gravity, a torque and a point force: lagcomp's M, F equal LagrangesMethod's."""
    q, body, inertia, N, O, G, B, g = top_in_sympy()
    k, f = sp.symbols("k f", positive=True)
    P = O.locatenew("P", 2 * B.z)
    P.set_vel(N, P.pos_from(O).dt(N))
    torque = -k * q[2].diff(t) * B.z + f * N.x  # spin damping and a fixed-axis torque
    force = f * sp.sin(t) * N.y
    gravity = (G, -body.mass * g * N.z)
    loads = [gravity, (B, torque), (P, force)]
    ref = lagranges_method_residual(lc.System(q, T=1, name="s"), me.Lagrangian(N, body), loads, N)
    ours = lc.System(
        q,
        bodies=[lc.RigidBody(body.mass, G.pos_from(O), inertia, B, name="top")],
        loads=[lc.Gravity(-g * N.z), lc.Torque(torque, B), lc.Force(force, P.pos_from(O))],
        frame=N, name="top",
    )
    assert vanishes(residual(ours) - ref)
    # the sympy objects themselves (RigidBody, load pairs), with the frame's origin for gravity
    direct = lc.System(q, bodies=[body], loads=[lc.Gravity(-g * N.z)] + loads[1:],
                       frame=lc.MovingFrame(axes=N, origin=O), name="top")
    assert vanishes(residual(direct) - ref)


def test_particles_spring_and_damper_against_hand_derivation():
    x, y = lc.coordinates("x y")
    m, k, c, l0 = sp.symbols("m k c l0", positive=True)
    a, b = lc.Particle(m, (x, 0, 0), name="a"), lc.Particle(m, (0, y, 0), name="b")
    s = lc.System([x, y], bodies=[a, b], loads=[lc.Spring(a, b, k, l0), lc.Damper(a, b, c)], name="s")
    L = sp.sqrt(x**2 + y**2)
    Ldot = L.diff(t)
    assert is_zero(s.T - m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2)
    assert is_zero(s.V - k * (L - l0) ** 2 / 2)
    push = -k * (L - l0) - c * Ldot  # force along the line pushing the ends apart
    expected = [m * x.diff(t, 2) - push * x / L, m * y.diff(t, 2) - push * y / L]
    assert is_zero(residual(s) - sp.Matrix(expected))


def test_force_virtual_work_with_imposed_motion():
    """Q = F·∂r/∂q even when r depends on t (a bead on a rod turned at ω t)."""
    (rho,) = lc.coordinates("rho")
    m, w, F = sp.symbols("m omega F", positive=True)
    r = (rho * sp.cos(w * t), rho * sp.sin(w * t), 0)
    s = lc.System([rho], bodies=[lc.Particle(m, r)], loads=[lc.Force((F, 0, 0), r)], name="s")
    assert is_zero(s.forces[0] - F * sp.cos(w * t))


def test_torque_on_a_body_uses_its_partial_angular_velocities():
    psi, theta = lc.coordinates("psi theta")
    tau1, tau2, tau3 = sp.symbols("tau1:4")
    N = ReferenceFrame("N")
    B = lc.rotated(N, (psi, "z"), (theta, "x"))
    by_frame = lc.RigidBody(1, (0, 0, 0), (1, 1, 1), B, name="b")
    by_components = lc.RigidBody(1, (0, 0, 0), (1, 1, 1), lc.body_rates(B, N), name="c")
    for body in (by_frame, by_components):  # ω = (θ̇, ψ̇ sin θ, ψ̇ cos θ) in body axes
        s = lc.System([psi, theta], bodies=[body], loads=[lc.Torque((tau1, tau2, tau3), body)], frame=N, name="s")
        assert is_zero(sp.Matrix(s.forces) - sp.Matrix([tau2 * sp.sin(theta) + tau3 * sp.cos(theta), tau1]))
    s = lc.System([psi, theta], bodies=[by_frame], loads=[lc.Torque(tau3 * N.z, by_frame)], frame=N, name="s")
    assert is_zero(sp.Matrix(s.forces) - sp.Matrix([tau3, 0]))  # a torque about the fixed z works on ψ only


# -- moving frames -------------------------------------------------------------------------------


def test_moving_frame_equals_virtual_work_of_the_inertial_forces():
    """Particle in a frame with arbitrary a_e(t), ω_e(t): T_R, V_R give T_rel's equations plus the four forces."""
    q1, q2 = lc.coordinates("q1 q2")
    m = sp.Symbol("m", positive=True)
    a_e = sp.Matrix([sp.sin(t), t**2, 1])
    w_e = sp.Matrix([sp.cos(2 * t), sp.Rational(1, 3), t])
    r = sp.Matrix([q1 * sp.cos(q2), q1 * sp.sin(q2) + t, q1 * q2])
    frame = lc.MovingFrame(acceleration=a_e, angular_velocity=w_e)
    s = lc.System([q1, q2], bodies=[lc.Particle(m, r)], frame=frame, name="s")
    v = r.diff(t)
    inertial = -m * (a_e + w_e.diff(t).cross(r) + w_e.cross(w_e.cross(r)) + 2 * w_e.cross(v))
    relative = lc.System([q1, q2], T=m * v.dot(v) / 2, forces=[inertial.dot(r.diff(qi)) for qi in (q1, q2)], name="r")
    assert vanishes(residual(s) - residual(relative))


def test_turn_indicator_in_the_aircraft_frame_equals_the_galilean_description():
    s = examples.get("turn_indicator")
    (theta,) = s.coordinates
    p = {x.name: x for x in s.parameters}
    I_X, I, Om, w, al, k, c = (p[n] for n in ("I_X", "I", "Omega", "omega", "alpha", "k", "c"))
    N = ReferenceFrame("N")
    aircraft = lc.rotated(N, (w * t, "z"))
    gimbal = lc.rotated(aircraft, (al, "x"), (theta, "x"), name="G")
    wheel = lc.rotated(gimbal, (Om * t, "y"), name="W")
    galilean = lc.System(
        [theta], bodies=[lc.RigidBody(1, (0, 0, 0), (I_X, I, I_X), wheel)],
        loads=[lc.Torque(-(k * theta + c * theta.diff(t)) * gimbal.x, gimbal)], frame=N, name="g",
    )
    beta = theta + al
    by_hand = (I_X * theta.diff(t, 2) + (I_X - I) * w**2 * sp.sin(2 * beta) / 2 - I * w * Om * sp.cos(beta)
               + k * theta + c * theta.diff(t))
    assert is_zero(residual(s)[0] - by_hand)
    assert is_zero(residual(galilean)[0] - by_hand)
    assert is_zero(s.T - (I_X * (theta.diff(t) ** 2 + w**2 * sp.cos(beta) ** 2) + I * (Om + w * sp.sin(beta)) ** 2) / 2)


def test_compton_disc_equals_the_galilean_description():
    s = examples.get("compton_disc")
    (phi,) = s.coordinates
    p = {x.name: x for x in s.parameters}
    I, I_Y, w, lam, nu = (p[n] for n in ("I", "I_Y", "omega", "lambda", "nu"))
    theta = sp.pi * (1 - sp.cos(nu * t)) / 2
    T = (I * ((theta.diff(t) - w * sp.cos(lam)) ** 2 + w**2 * sp.sin(lam) ** 2 * sp.sin(theta) ** 2)
         + I_Y * (phi.diff(t) + w * sp.sin(lam) * sp.cos(theta)) ** 2) / 2
    assert is_zero(s.T - T)
    # Galilean description: the Earth (carousel) turned by ω t about its axis, which points north and up
    N = ReferenceFrame("N")
    carousel = lc.rotated(N, (w * t, -sp.cos(lam) * N.x + sp.sin(lam) * N.z), name="C")
    disc = lc.rotated(carousel, (theta + sp.pi / 2, "x"), (phi, "y"), name="D")
    galilean = lc.System([phi], bodies=[lc.RigidBody(1, (0, 0, 0), (I, I_Y, I), disc)], frame=N, name="g")
    assert vanishes(residual(galilean) - residual(s))
    assert derive(s).cyclic == ("phi",)


def test_driven_pendulum_in_the_support_frame():
    support, inertial = examples.get("driven_pendulum_support"), examples.get("driven_pendulum")
    assert support.parameter_names == inertial.parameter_names and support.defaults == inertial.defaults
    (theta,) = support.coordinates
    m, l, g, A, Om = support.parameters
    hdd = (A * sp.cos(Om * t)).diff(t, 2)
    expected = m * l**2 * (theta.diff(t, 2) + (g + hdd) / l * sp.sin(theta))
    assert is_zero(residual(support)[0] - expected)
    assert is_zero(residual(inertial.__class__(inertial.coordinates, T=inertial.T, V=inertial.V, name="i"))[0]
                   - expected.xreplace(dict(zip(support.parameters, inertial.parameters))))


def test_symmetric_top_energy_and_cyclic_angles():
    s = examples.get("symmetric_top")
    psi, theta, phi = s.coordinates
    M, l, g, I1, I3 = s.parameters
    J = I1 + M * l**2
    T = J * (theta.diff(t) ** 2 + psi.diff(t) ** 2 * sp.sin(theta) ** 2) / 2 + I3 * (phi.diff(t) + psi.diff(t) * sp.cos(theta)) ** 2 / 2
    assert is_zero(s.T - T) and is_zero(s.V - M * g * l * sp.cos(theta))
    assert derive(s).cyclic == ("psi", "phi")


def test_free_axle_from_its_wheels_as_rigid_bodies():
    """The example's hand-written T and V, rebuilt from two wheels (rigid bodies) and gravity on the incline."""
    ex = examples.get("free_axle")
    X, Y, theta, phi, phi_p = ex.coordinates
    m, R, L, I1, I3, g, alpha = ex.parameters
    N = ReferenceFrame("N")  # X across the slope, Y down it, z the plane's upward normal
    A = lc.rotated(N, (theta, "z"), name="A")  # A.x = u, along the axle
    centre = sp.Matrix([X, Y, R])
    u = sp.Matrix([sp.cos(theta), sp.sin(theta), 0])
    wheels = [
        lc.RigidBody(m, centre + sign * L / 2 * u, (I3, I1, I1), lc.rotated(A, (angle, "x"), name=f"W{k}"), axes=A,
                     name=f"wheel{k}")
        for k, (sign, angle) in enumerate(((1, phi), (-1, phi_p)))
    ]
    gravity = lc.Gravity((0, g * sp.sin(alpha), -g * sp.cos(alpha)))
    built = lc.System(ex.coordinates, bodies=wheels, loads=[gravity], constraints=ex.constraints, frame=N,
                      parameters=ex.parameters, name="axle")
    assert is_zero(built.T - ex.T)
    assert is_zero(built.V - ex.V - 2 * m * g * R * sp.cos(alpha))  # the constant height of the centres
    assert is_zero(residual(built) - residual(ex))


def test_body_with_components_and_rotation_matrix_in_a_turning_frame():
    """`axes` as a rotation matrix expresses ω_e in body axes like a ReferenceFrame does."""
    (th,) = lc.coordinates("theta")
    I1, I2, I3, w = sp.symbols("I1 I2 I3 omega", positive=True)
    R = ReferenceFrame("R")
    B = lc.rotated(R, (th, "x"))
    frame = lc.MovingFrame(axes=R, angular_velocity=w * R.z)
    with_frame = lc.System([th], bodies=[lc.RigidBody(1, (0, 0, 0), (I1, I2, I3), B)], frame=frame, name="a")
    with_matrix = lc.System([th], bodies=[lc.RigidBody(1, (0, 0, 0), (I1, I2, I3), (th.diff(t), 0, 0), axes=R.dcm(B))],
                            frame=lc.MovingFrame(angular_velocity=(0, 0, w)), name="b")
    assert is_zero(with_frame.T - with_matrix.T)


# -- rotations ---------------------------------------------------------------------------------


def test_rotated_matches_sympy_and_explicit_matrices():
    psi, theta, phi = me.dynamicsymbols("psi theta phi")
    N = ReferenceFrame("N")
    ref = ReferenceFrame("E")
    ref.orient_body_fixed(N, (psi, theta, phi), "zxz")
    assert is_zero(lc.rotated(N, (psi, "z"), (theta, "x"), (phi, "z")).dcm(N) - ref.dcm(N))
    a = sp.Symbol("a")

    def rot(axis, x):
        c, s = sp.cos(x), sp.sin(x)
        return {"x": sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]]),
                "y": sp.Matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
                "z": sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])}[axis]

    # body axes multiply on the right, fixed axes on the left
    B = lc.rotated(N, (theta, "x"), (psi, N.z), (phi, "y"), (a, N.x))
    assert is_zero(N.dcm(B) - rot("x", a) * rot("z", psi) * rot("x", theta) * rot("y", phi))
    w = lc.body_rates(lc.rotated(N, (theta, "x"), (psi * t, N.z)), N)
    assert is_zero(w - sp.Matrix([theta.diff(t), (psi * t).diff(t) * sp.sin(theta), (psi * t).diff(t) * sp.cos(theta)]))
    with pytest.raises(ModelError, match="axis"):
        lc.rotated(N, (theta, "w"))


# -- System bookkeeping --------------------------------------------------------------------------


def test_replace_does_not_count_bodies_twice():
    s = examples.get("symmetric_top")
    again = dataclasses.replace(s, name="top2")
    assert again.T == s.T and again.V == s.V and again.forces == s.forces
    psi = s.coordinates[0]
    without_gravity = dataclasses.replace(s, loads=())
    assert is_zero(without_gravity.V)
    extra = dataclasses.replace(s, T=psi.diff(t) ** 2)
    assert is_zero(extra.T - s.T - psi.diff(t) ** 2)


def test_fingerprint_follows_bodies():
    (x,) = lc.coordinates("x")
    m = sp.Symbol("m", positive=True)
    a = lc.System([x], bodies=[lc.RigidBody(m, (x, 0, 0), (1, 2, 2), (0, x.diff(t), 0))], name="s")
    b = lc.System([x], bodies=[lc.RigidBody(m, (x, 0, 0), (1, 3, 3), (0, x.diff(t), 0))], name="s")
    assert a.fingerprint() != b.fingerprint()


def test_undeclared_symbol_names_the_body():
    (x,) = lc.coordinates("x")
    u = me.dynamicsymbols("u")
    with pytest.raises(UndeclaredSymbolError, match="wheel"):
        lc.System([x], bodies=[lc.Particle(1, (x, u, 0), name="wheel")], name="s")
    with pytest.raises(UndeclaredSymbolError, match="spring"):
        lc.System([x], bodies=[lc.Particle(1, (x, 0, 0))], loads=[lc.Spring((0, 0, 0), (x, 0, 0), sp.Symbol("k"))],
                  parameters=(), name="s")


def test_system_needs_a_kinetic_energy():
    (x,) = lc.coordinates("x")
    with pytest.raises(ModelError, match="kinetic energy"):
        lc.System([x], V=x**2, name="s")


# -- rejected input ------------------------------------------------------------------------------


@pytest.mark.parametrize("inertia, match", [
    ([[1, 0.1, 0], [0, 1, 0], [0, 0, 1]], "not symmetric"),
    ([[1, 2, 0], [2, 1, 0], [0, 0, 1]], "not positive semidefinite"),
    ((1, 1, -1), "not positive semidefinite"),
    ((1, 1, 3), "triangle inequality"),
    ((1, 2), "3 principal moments"),
])
def test_bad_inertia_is_rejected(inertia, match):
    (x,) = lc.coordinates("x")
    with pytest.raises(ModelError, match=match):
        lc.RigidBody(1, (x, 0, 0), inertia, (0, 0, x.diff(t)), name="wheel")


def test_bad_symbolic_inertia_is_rejected():
    A, B, D = sp.symbols("A B D", positive=True)
    with pytest.raises(ModelError, match="not symmetric"):
        inertia_matrix([[A, D, 0], [2 * D, B, 0], [0, 0, A]], None, "wheel")
    with pytest.raises(ModelError, match="not positive semidefinite"):
        inertia_matrix((A, B, -A), None, "wheel")
    assert inertia_matrix((A, B, A + B), None, "plate") == sp.diag(A, B, A + B)  # a flat plate is allowed


def test_angular_velocity_with_accelerations_is_rejected():
    (x,) = lc.coordinates("x")
    with pytest.raises(ModelError, match="acceleration"):
        lc.RigidBody(1, (x, 0, 0), (1, 1, 1), (0, 0, x.diff(t, 2)), name="wheel")
    with pytest.raises(ModelError, match="velocities"):
        lc.Particle(1, (x.diff(t), 0, 0))
    with pytest.raises(ModelError, match="imposed"):
        lc.MovingFrame(angular_velocity=(0, 0, x))
    with pytest.raises(ModelError, match="3 components"):
        lc.Particle(1, (x, 0))


def test_turning_frame_needs_body_axes():
    (x,) = lc.coordinates("x")
    body = lc.RigidBody(1, (x, 0, 0), (1, 1, 1), (0, 0, x.diff(t)))
    with pytest.raises(ModelError, match="body's axes"):
        lc.System([x], bodies=[body], frame=lc.MovingFrame(angular_velocity=(0, 0, 1)), name="s")
    N = ReferenceFrame("N")
    with pytest.raises(ModelError, match="frame="):
        lc.System([x], bodies=[lc.Particle(1, x * N.x)], name="s")


# -- interop (symbolic and numerical through the derivation; the compiled comparison is in test_bodies_runs) --


def _qdd(system: lc.System):
    """q̈(q, q̇, t, p) by solving the augmented system numerically from the derived equations."""
    eom = derive(system)
    args = (*eom.q, *eom.qd, t, *eom.parameters)
    M, F, C, G = (sp.lambdify(args, X, "numpy") for X in (eom.M, eom.F, eom.C, eom.gamma))

    def qdd(*values):
        m, f, c, g = (np.array(X(*values), dtype=float) for X in (M, F, C, G))
        n, k = m.shape[0], c.shape[0]
        K = np.block([[m, c.T], [c, np.zeros((k, k))]]) if k else m
        rhs = np.concatenate([f.ravel(), g.ravel()]) if k else f.ravel()
        return np.linalg.solve(K, rhs)[:n]

    return qdd


def test_kanes_method_chain_gives_the_native_accelerations(rng):
    built = sympy_models.kane_chain(3)
    km, params = built["method"], built["parameters"]
    native = examples.get("n_link_pendulum", n=3)
    ours = lc.from_kanes_method(km, name="kane_chain", parameters=params)
    assert [s.name for s in ours.parameters] == list(native.parameter_names)
    a, b = _qdd(ours), _qdd(native)
    for _ in range(5):
        values = (*rng.uniform(-2, 2, 6), 0.0, *rng.uniform(0.5, 1.5, 7))
        np.testing.assert_allclose(a(*values), b(*values), rtol=1e-12, atol=1e-12)


def test_kanes_method_without_speeds_from_qdot_is_refused():
    q, u1, u2 = me.dynamicsymbols("q u1 u2")
    N = ReferenceFrame("N")
    P = me.Point("P")
    P.set_vel(N, u1 * N.x)
    km = me.KanesMethod(N, [q], [u1], kd_eqs=[q.diff(t) - u1], bodies=[me.Particle("p", P, 1)], forcelist=[])
    assert lc.from_kanes_method(km, name="ok").T == q.diff(t) ** 2 / 2
    with pytest.raises(ModelError):
        lc.from_lagranges_method(km)
    u_only = me.KanesMethod(N, [q], [u1, u2], kd_eqs=[q.diff(t) - u1 - u2], bodies=[me.Particle("p", P, 1)],
                            forcelist=[])
    with pytest.raises(ModelError, match="do not determine the speeds"):
        lc.from_kanes_method(u_only, name="bad")


def test_sympy_bodies_in_a_system_give_the_native_rolling_disc(rng):
    """sympy RigidBody + (Point, Vector) load passed straight to System, and from_lagranges_method."""
    built = sympy_models.rolling_disc()
    native = examples.get("rolling_disc")
    direct = lc.System(
        native.coordinates, bodies=built["bodies"], loads=built["loads"],
        frame=lc.MovingFrame(axes=built["frame"], origin=built["origin"]),
        constraints=[lc.Nonholonomic(c.name, c.expr) for c in native.constraints],
        parameters=built["parameters"], name="disc",
    )
    via_lm = lc.from_lagranges_method(built["method"], name="disc", parameters=built["parameters"])
    assert [c.name for c in via_lm.constraints] == ["nonholonomic_0", "nonholonomic_1"]
    kane = sympy_models.kane_rolling_disc()
    via_km = lc.from_kanes_method(kane["method"], name="disc", parameters=kane["parameters"])
    assert [c.name for c in via_km.constraints] == ["velocity_0", "velocity_1"]
    reference = _qdd(native)
    for system in (direct, via_lm, via_km):
        ours = _qdd(system)
        for _ in range(4):
            values = (*rng.uniform(-1, 1, 10), 0.0, *rng.uniform(0.5, 1.5, 5))
            np.testing.assert_allclose(ours(*values), reference(*values), rtol=1e-12, atol=1e-12)
