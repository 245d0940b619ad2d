"""The constrained examples against independent derivations (sympy and numpy only, no compilation).

Checks: initial conditions on the constraints; the physical meaning and sign
of each multiplier (hoop push, contact reactions, rod tension, knife-edge
force); the free axle's closed-form solution; the rolling disc against
``sympy.physics.mechanics.KanesMethod`` built from frames and bodies.

lagcomp's normal form: M q̈ = F + Λᵀ λ with Λ q̈ = γ, i.e.
[M −Λᵀ; Λ 0] [q̈; λ] = [F; γ].
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
import sympy as sp

from lagcomp.examples import constrained as ex
from lagcomp.examples import unconstrained
from lagcomp.mechanics.lagrange import derive
from lagcomp.model import System, t


@functools.lru_cache(maxsize=None)
def eom_of(name: str):
    return derive(ex.CONSTRAINED_EXAMPLES[name]())


def kkt_symbolic(eom):
    """Symbolic (q̈, λ) solving [M −Λᵀ; Λ 0] [q̈; λ] = [F; γ]."""
    n, k = eom.n, eom.k
    K = sp.BlockMatrix([[eom.M, -eom.C.T], [eom.C, sp.zeros(k, k)]]).as_explicit()
    z = K.LUsolve(sp.Matrix.vstack(eom.F, eom.gamma))
    return z[:n, 0], z[n:, 0]


def kkt_numeric(eom):
    """A function (q, qd, t, p) -> (q̈, λ) evaluating lagcomp's constrained equations with numpy."""
    n, k = eom.n, eom.k
    args = (eom.q, eom.qd, t, eom.parameters)
    fM, fF, fC, fg = (sp.lambdify(args, X, "numpy") for X in (eom.M, eom.F, eom.C, eom.gamma))

    def solve(q, qd, time, p):
        M = np.array(fM(q, qd, time, p), dtype=float)
        C = np.array(fC(q, qd, time, p), dtype=float).reshape(k, n)
        rhs = np.concatenate([np.ravel(fF(q, qd, time, p)), np.ravel(fg(q, qd, time, p))]).astype(float)
        z = np.linalg.solve(np.block([[M, -C.T], [C, np.zeros((k, k))]]), rhs)
        return z[:n], z[n:]

    return solve


def residual_functions(eom):
    """Numeric Φ(q, t, p) and Λ q̇ + b."""
    args = (eom.q, eom.qd, t, eom.parameters)
    fPhi = sp.lambdify(args, eom.Phi, "numpy")
    fCb = sp.lambdify(args, eom.C * sp.Matrix(eom.qd) + eom.b, "numpy")
    return (lambda q, qd, tt, p: np.ravel(np.asarray(fPhi(q, qd, tt, p), dtype=float)),
            lambda q, qd, tt, p: np.ravel(np.asarray(fCb(q, qd, tt, p), dtype=float)))


def values(system: System, overrides=None) -> list[float]:
    d = dict(system.defaults) | dict(overrides or {})
    return [d[name] for name in system.parameter_names]


def is_zero(expr, samples: int = 5) -> bool:
    """Whether `expr` vanishes identically: exact after expansion, else at random points.

    `sympy.simplify` is not used: its running time depends on the state of
    sympy's global cache and can grow to minutes inside a long test session.
    Evaluating at several random points (all symbols uniform in [0.3, 1.7])
    to 1e-9 relative is a sound identity test for these smooth expressions.
    """
    if isinstance(expr, sp.MatrixBase):
        return all(is_zero(e, samples) for e in expr)
    expr = sp.expand(sp.expand_trig(sp.sympify(expr)))
    if expr == 0:
        return True
    symbols = sorted(expr.free_symbols, key=lambda s: s.name)
    terms = sp.Add.make_args(expr)
    rng = np.random.default_rng(7)
    for _ in range(samples):
        point = dict(zip(symbols, rng.uniform(0.3, 1.7, len(symbols))))
        value = complex(expr.evalf(subs=point))
        scale = max(abs(complex(term.evalf(subs=point))) for term in terms)
        if abs(value) > 1e-9 * max(scale, 1e-300):
            return False
    return True


def param(eom, name):
    return next(s for s in eom.parameters if s.name == name)


def coord(eom, name):
    return eom.q[eom.system.coordinate_names.index(name)], eom.qd[eom.system.coordinate_names.index(name)]


# -- every example -------------------------------------------------------------------------------

NAMES = sorted(ex.CONSTRAINED_EXAMPLES)


@pytest.mark.parametrize("name", NAMES)
def test_example_is_complete(name):
    system = ex.CONSTRAINED_EXAMPLES[name]()
    assert isinstance(system, System) and system.name == name
    assert system.description and "\n" not in system.description
    assert set(system.defaults) == set(system.parameter_names)
    assert all(math.isfinite(v) and v > 0 for v in system.defaults.values())
    assert all(s.is_positive for s in system.parameters)
    assert len(system.q0) == len(system.qd0) == system.n and system.t_end > 0
    assert all(c.name.isidentifier() for c in system.constraints)
    assert ex.CONSTRAINED_EXAMPLES[name].__doc__


@pytest.mark.parametrize("name", NAMES)
def test_initial_conditions_satisfy_constraints(name):
    eom = eom_of(name)
    system = eom.system
    phi, cb = residual_functions(eom)
    p = values(system)
    assert np.all(np.abs(phi(system.q0, system.qd0, 0.0, p)) < 1e-15)  # exact up to rounding
    assert np.all(np.abs(cb(system.q0, system.qd0, 0.0, p)) < 1e-15)


# -- bead on the hoop: the hoop's push ---------------------------------------------------------


def test_hoop_reaction_is_the_push_normal_to_the_hoop():
    eom = eom_of("hoop_bead_reaction")
    (th, thd), (_, phd) = coord(eom, "theta"), coord(eom, "phi")
    m, R, g, Om, eps = (param(eom, k) for k in ("m", "R", "g", "Omega", "epsilon"))
    assert eom.constraint_names == ("drive",)
    qdd, lam = kkt_symbolic(eom)
    # the multiplier, with φ̈ the solved one: R sin θ · m R (2 φ̇ θ̇ cos θ + φ̈ sin θ)
    f = m * R * (2 * phd * thd * sp.cos(th) + qdd[1] * sp.sin(th))
    assert is_zero(lam[0] - R * sp.sin(th) * f)
    # on the constraint: φ̈ = −4ε sin 2t, φ̇ = Ω + 2ε cos 2t
    assert is_zero(qdd[1] + 4 * eps * sp.sin(2 * t))
    on = {phd: Om + 2 * eps * sp.cos(2 * t)}
    f_on = m * R * (2 * (Om + 2 * eps * sp.cos(2 * t)) * thd * sp.cos(th) - 4 * eps * sp.sin(2 * t) * sp.sin(th))
    assert is_zero(lam[0].subs(on) - R * sp.sin(th) * f_on)
    # θ obeys the unconstrained hoop_bead equation
    assert is_zero(qdd[0].subs(on) - sp.sin(th) * (g / R + on[phd] ** 2 * sp.cos(th)))
    assert ex.hoop_bead_reaction().defaults == unconstrained.hoop_bead().defaults
    assert ex.hoop_bead_reaction().q0[0] == unconstrained.hoop_bead().q0[0]


# -- badly balanced cylinder: contact reactions ----------------------------------------------------


def test_cylinder_multipliers_are_the_contact_forces():
    eom = eom_of("unbalanced_cylinder_reactions")
    (x, xd), (z, zd), (th, thd) = (coord(eom, k) for k in ("x", "z", "theta"))
    M, R, a, I, g = (param(eom, k) for k in ("M", "R", "a", "I", "g"))
    assert eom.constraint_names == ("normal", "friction")
    # virtual work of a contact force (F_h, F_v) on the body's material point at the contact.
    # A body point with reference offset d sits at C + d rotated clockwise by θ; the one at the
    # contact now (angle θ0) has d = (R sin θ0, −R cos θ0).  Its virtual displacement, at θ = θ0,
    # gives the generalized force F_v Λ_normal + F_h Λ_friction.
    Fh, Fv, th0 = sp.symbols("F_h F_v theta0")
    d = (R * sp.sin(th0), -R * sp.cos(th0))
    point = sp.Matrix([x + d[0] * sp.cos(th) + d[1] * sp.sin(th), z - d[0] * sp.sin(th) + d[1] * sp.cos(th)])
    assert is_zero(point.subs(th, th0) - sp.Matrix([x, z - R]))
    generalized = (point.jacobian([x, z, th]).T * sp.Matrix([Fh, Fv])).subs(th, th0)
    assert is_zero(generalized - eom.C.T.subs(th, th0) * sp.Matrix([Fv, Fh]))
    # solved on the constraints (x = Rθ, z = R, so ẍ = R θ̈, z̈ = 0):
    # λ_normal = M (g + z̈_G), λ_friction = M ẍ_G
    thdd, ln, lf = sp.symbols("thdd lambda_n lambda_f")
    on = {xd: R * thd, zd: 0}
    qdd = sp.Matrix([R * thdd, 0, thdd])
    equations = (eom.M * qdd - eom.F - eom.C.T * sp.Matrix([ln, lf])).subs(on)
    ((thdd_s, ln_s, lf_s),) = sp.linsolve(list(equations), [thdd, ln, lf])
    xG_dd = R * thdd_s - a * sp.cos(th) * thdd_s + a * sp.sin(th) * thd**2
    zG_dd = a * sp.sin(th) * thdd_s + a * sp.cos(th) * thd**2
    assert is_zero(ln_s - M * (g + zG_dd))
    assert is_zero(lf_s - M * xG_dd)
    # θ̈ is that of the rolling cylinder
    J = M * (R**2 + a**2 - 2 * a * R * sp.cos(th)) + I
    assert is_zero(thdd_s + (M * a * R * sp.sin(th) * thd**2 + M * g * a * sp.sin(th)) / J)
    # and the numerical KKT solve agrees (γ = 0 for these constraints)
    solve = kkt_numeric(eom)
    f = sp.lambdify((th, thd, tuple(eom.parameters)), sp.Matrix([ln_s, lf_s, thdd_s]), "numpy")
    p = values(eom.system)
    for angle, rate in ((1.5, 0.0), (0.3, -2.0), (-2.0, 5.0)):
        qdd_n, lam_n = solve([p[1] * angle, p[1], angle], [p[1] * rate, 0.0, rate], 0.0, p)
        assert np.allclose([*lam_n, qdd_n[2]], np.ravel(f(angle, rate, p)), rtol=1e-12, atol=1e-12)
    s = ex.unbalanced_cylinder_reactions()
    assert s.defaults == unconstrained.unbalanced_cylinder().defaults
    assert s.q0[2] == unconstrained.unbalanced_cylinder().q0[0]


# -- spherical pendulum -----------------------------------------------------------------------------


def test_spherical_pendulum_rod_tension():
    eom = eom_of("spherical_pendulum_cartesian")
    (x, xd), (y, yd), (z, zd) = (coord(eom, k) for k in ("x", "y", "z"))
    m, l, g = (param(eom, k) for k in ("m", "l", "g"))
    assert list(eom.C) == [2 * x, 2 * y, 2 * z]
    qdd, (lam,) = kkt_symbolic(eom)
    v2 = xd**2 + yd**2 + zd**2
    tension = m * (v2 / l - g * z / l)
    rho = sp.sqrt(x**2 + y**2 + z**2)
    assert is_zero((-2 * lam * l - tension).subs(l, rho))  # on the sphere |r| = l
    # hanging straight down at rest: the tension is the weight
    assert sp.simplify((-2 * lam * l).subs({x: 0, y: 0, z: -l, xd: 0, yd: 0, zd: 0}) - m * g) == 0


def test_spherical_pendulum_angles_and_cartesian_agree():
    cart, ang = eom_of("spherical_pendulum_cartesian"), eom_of("spherical_pendulum")
    sc, sa = cart.system, ang.system
    assert sc.defaults == sa.defaults
    q, qd = ex.spherical_to_cartesian(*sa.q0, *sa.qd0, sa.defaults["l"])
    assert np.allclose(q, sc.q0, rtol=0, atol=1e-15) and np.allclose(qd, sc.qd0, rtol=0, atol=1e-15)
    # same accelerations at random states: Cartesian KKT vs d²r/dt² of the angular equations
    (th, thd), (ph, phd) = coord(ang, "theta"), coord(ang, "phi")
    l = param(ang, "l")
    r = l * sp.Matrix([sp.sin(th) * sp.cos(ph), sp.sin(th) * sp.sin(ph), -sp.cos(th)])
    J = r.jacobian([th, ph])
    thdd, phdd = sp.symbols("thdd phdd")
    rdd = J * sp.Matrix([thdd, phdd]) + (J * sp.Matrix([thd, phd])).jacobian([th, ph]) * sp.Matrix([thd, phd])
    angular_qdd = ang.M.LUsolve(ang.F)
    args = (th, ph, thd, phd, tuple(ang.parameters))
    f_rdd = sp.lambdify(args, rdd.subs({thdd: angular_qdd[0], phdd: angular_qdd[1]}), "numpy")
    solve = kkt_numeric(cart)
    rng = np.random.default_rng(7)
    for _ in range(5):
        p = [rng.uniform(0.5, 2), rng.uniform(0.5, 2), rng.uniform(5, 15)]
        a, b, ad, bd = rng.uniform(0.3, 2.8), rng.uniform(-3, 3), rng.normal(), rng.normal()
        qc, qdc = ex.spherical_to_cartesian(a, b, ad, bd, p[1])
        qdd, _ = solve(qc, qdc, 0.0, p)
        assert np.allclose(qdd, np.ravel(f_rdd(a, b, ad, bd, p)), rtol=1e-10, atol=1e-10)


# -- free axle ------------------------------------------------------------------------------------


@pytest.mark.parametrize("V0, omega, overrides", [
    (1.0, 1.0, {}),
    (0.7, -1.3, {"alpha": 0.5, "L": 0.8, "I3": 0.05, "m": 2.0}),
    (2.0, 0.0, {}),
])
def test_free_axle_closed_form_solves_the_constrained_equations(V0, omega, overrides):
    eom = eom_of("free_axle")
    s = ex.free_axle(V0=V0, omega=omega)
    names = s.coordinate_names
    p = values(s, overrides)
    params = dict(zip(s.parameter_names, p))
    ts = np.linspace(0.0, 12.0, 61)
    cf = ex.free_axle_closed_form(ts, params, V0, omega)
    args = (eom.q, eom.qd, t, eom.parameters)
    fM, fF, fC = (sp.lambdify(args, X, "numpy") for X in (eom.M, eom.F, eom.C))
    phi, cb = residual_functions(eom)
    for i, tt in enumerate(ts):
        q = [cf[k][i] for k in names]
        qd = [cf[k + "_dot"][i] for k in names]
        qdd = np.array([cf[k + "_ddot"][i] for k in names])
        lam = np.array([cf[c][i] for c in s.constraint_names])
        eq = np.array(fM(q, qd, tt, p), float) @ qdd - np.ravel(fF(q, qd, tt, p)) \
            - np.array(fC(q, qd, tt, p), float).reshape(3, 5).T @ lam
        assert np.abs(eq).max() < 1e-12
        assert np.abs(phi(q, qd, tt, p)).max() < 1e-12 and np.abs(cb(q, qd, tt, p)).max() < 1e-12
    # the rates are the derivatives of the positions (central differences)
    h = 1e-5
    plus, minus = (ex.free_axle_closed_form(ts + d, params, V0, omega) for d in (h, -h))
    for k in names:
        assert np.allclose((plus[k] - minus[k]) / (2 * h), cf[k + "_dot"], atol=1e-7)
        assert np.allclose((plus[k + "_dot"] - minus[k + "_dot"]) / (2 * h), cf[k + "_ddot"], atol=1e-7)
    # the launch: origin, axle along X, V0 down the slope (+Y), spin ω, and λ3 = 0 throughout
    assert [cf[k][0] for k in names] == [0.0] * 5
    if not overrides:  # the factory's default launch is this one
        assert np.allclose([cf[k + "_dot"][0] for k in names], s.qd0, rtol=0, atol=1e-15)
    assert cf["Y_dot"][0] == V0 and cf["theta_dot"][0] == omega and np.all(cf["steer"] == 0)


def test_free_axle_closed_form_formulas():
    """The printed closed forms, against the function, for the default launch."""
    s = ex.free_axle()
    d = s.defaults
    V0, w = 1.0, 1.0
    ts = np.linspace(0, 20, 41)
    cf = ex.free_axle_closed_form(ts, d, V0, w)
    A = d["m"] * d["g"] * d["R"] ** 2 * math.sin(d["alpha"]) / (d["I3"] + d["m"] * d["R"] ** 2)
    wt = w * ts
    gs = d["g"] * math.sin(d["alpha"])
    printed = {"X": V0 / w * (np.cos(wt) - 1) - A / (4 * w**2) * (2 * wt - np.sin(2 * wt)),
               "Y": V0 / w * np.sin(wt) + A / (4 * w**2) * (1 - np.cos(2 * wt)),
               "roll_X": -d["m"] * (V0 * w * np.cos(wt) + A * np.sin(2 * wt)),
               "roll_Y": -d["m"] * (V0 * w * np.sin(wt) - A * np.cos(2 * wt) + gs)}
    for k, formula in printed.items():   # the same formulas evaluated twice: equal to a few roundings of their terms
        np.testing.assert_allclose(cf[k], formula, rtol=1e-13, atol=1e-13 * np.abs(formula).max(), err_msg=k)
    # drift along −X at mean speed A/(2ω) after whole turns
    period = 2 * math.pi / w
    one = ex.free_axle_closed_form(np.array([period, 2 * period]), d, V0, w)
    np.testing.assert_allclose(np.diff(one["X"]) / period, -A / (2 * w), rtol=1e-12, atol=0)
    assert np.allclose(one["Y"], 0, atol=1e-12)


def test_free_axle_heading_turns_uniformly_and_steer_multiplier_vanishes():
    """For any state on the constraints: θ̈ = 0 and λ_steer = 0 (not only for the launch)."""
    eom = eom_of("free_axle")
    s = eom.system
    solve = kkt_numeric(eom)
    rng = np.random.default_rng(3)
    p = values(s)
    R, L = s.defaults["R"], s.defaults["L"]
    for _ in range(5):
        X, Y, th, ph = rng.normal(size=4)
        php = ph + L * th / R  # on Φ = L θ + R (φ − φ′) = 0
        thd, sig_d = rng.normal(size=2)
        phd, phpd = sig_d - L * thd / (2 * R), sig_d + L * thd / (2 * R)
        Xd, Yd = R * sig_d * math.sin(th), -R * sig_d * math.cos(th)
        qdd, lam = solve([X, Y, th, ph, php], [Xd, Yd, thd, phd, phpd], 0.0, p)
        assert abs(qdd[2]) < 1e-12 and abs(lam[2]) < 1e-12


# -- Chaplygin sleigh -----------------------------------------------------------------------------


def test_chaplygin_sleigh_knife_force_and_reduced_equations():
    eom = eom_of("chaplygin_sleigh")
    (x, xd), (y, yd), (th, w) = (coord(eom, k) for k in ("x", "y", "theta"))
    m, I, a = (param(eom, k) for k in ("m", "I", "a"))
    e1 = sp.Matrix([sp.cos(th), sp.sin(th)])
    e2 = sp.Matrix([-sp.sin(th), sp.cos(th)])
    # a sideways force F e2 at K = G + a e1 has generalized components F (e2·δG + a δθ) = F Λ
    K = sp.Matrix([x, y]) + a * e1
    F = sp.Symbol("F")
    assert is_zero((K.jacobian([x, y, th]).T * (F * e2)) - F * eom.C.T)
    qdd, (lam,) = kkt_symbolic(eom)
    v = sp.Symbol("v")
    on = {xd: v * sp.cos(th) + a * w * sp.sin(th), yd: v * sp.sin(th) - a * w * sp.cos(th)}  # v_G = v e1 − a ω e2
    aG = sp.Matrix(qdd[:2]).subs(on)
    J = I + m * a**2
    vdot = (aG.T * e1)[0] + (-a * w) * w  # d/dt (v_G·e1) = a_G·e1 + v_G·(ω e2)
    wdot = qdd[2].subs(on)
    assert is_zero(vdot + a * w**2)
    assert is_zero(wdot - m * a * v * w / J)
    assert is_zero(lam.subs(on) - m * (v * w - a * wdot))
    # closed form v = −V tanh(k(t − t0)), ω = W sech(k(t − t0)), W² = V² m/J, k = a m V/J
    V, t0 = sp.symbols("V t0", positive=True)
    k = a * m * V / J
    vs, ws = -V * sp.tanh(k * (t - t0)), V * sp.sqrt(m / J) / sp.cosh(k * (t - t0))
    assert is_zero((vs.diff(t) + a * ws**2).rewrite(sp.exp))
    assert is_zero((ws.diff(t) - m * a * vs * ws / J).rewrite(sp.exp))
    assert is_zero((m * vs**2 / 2 + J * ws**2 / 2 - m * V**2 / 2).rewrite(sp.exp))
    gd = lambda u: 2 * sp.atan(sp.tanh(u / 2))  # noqa: E731  (Gudermann's function, gd' = sech)
    heading = sp.sqrt(J / m) / a * (gd(k * (t - t0)) + gd(k * t0))
    assert heading.subs(t, 0) == 0
    gap = sp.lambdify((t, t0, V, m, I, a), heading.diff(t) - ws, "numpy")
    assert np.abs(gap(np.linspace(-3, 5, 17), 0.7, 1.3, 1.1, 0.2, 0.4)).max() < 1e-12


# -- rolling disc: Kane's method as the reference ---------------------------------------------------

DISC_PARAMS = ("m", "r", "I1", "I3", "g")


@functools.lru_cache(maxsize=None)
def _disc_reference():
    """Kane's equations of the rolling disc, built from frames, points and a rigid body.

    Coordinates as in `lagcomp.examples.constrained.rolling_disc`: x, y of the
    contact point, heading ψ about z, lean θ about A_x, spin φ about B_y.
    Generalized speeds u_i = q̇_i; u_x, u_y are dependent, fixed by the
    vanishing velocity of the disc's material point at the contact.
    """
    from sympy.physics.mechanics import KanesMethod, Point, ReferenceFrame, RigidBody, dynamicsymbols, inertia

    q = dynamicsymbols("q1:6")
    u = dynamicsymbols("u1:6")
    m, r, I1, I3, g = sp.symbols(DISC_PARAMS, positive=True)
    N = ReferenceFrame("N")
    A = N.orientnew("A", "Axis", [q[2], N.z])
    B = A.orientnew("B", "Axis", [q[3], A.x])
    D = B.orientnew("D", "Axis", [q[4], B.y])
    to_u = {qi.diff(t): ui for qi, ui in zip(q, u)}  # kinematic equations q̇ = u
    O = Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", q[0] * N.x + q[1] * N.y)
    G = P.locatenew("G", r * B.z)
    D.set_ang_vel(N, D.ang_vel_in(N).subs(to_u))
    G.set_vel(N, G.pos_from(O).dt(N).subs(to_u))
    contact = G.vel(N) + D.ang_vel_in(N).cross(P.pos_from(G))
    assert sp.simplify(contact.dot(N.z)) == 0
    constraints = [contact.dot(N.x), contact.dot(N.y)]
    disc = RigidBody("disc", G, D, m, (inertia(B, I1, I3, I1), G))
    kane = KanesMethod(
        N, q_ind=list(q), u_ind=[u[2], u[3], u[4]], u_dependent=[u[0], u[1]],
        kd_eqs=[qi.diff(t) - ui for qi, ui in zip(q, u)], velocity_constraints=constraints,
    )
    kane.kanes_equations([disc], [(G, -m * g * N.z)])
    order = [u[2], u[3], u[4], u[0], u[1]]  # Kane's speeds: independent, then dependent
    qs, us = sp.symbols("q1:6"), sp.symbols("u1:6")
    plain = {**dict(zip(u, us)), **dict(zip(q, qs))}
    Mk = kane.mass_matrix.xreplace(plain)
    Fk = kane.forcing.xreplace(plain)
    cons = sp.Matrix(constraints).xreplace(plain)
    args = (qs, us, (m, r, I1, I3, g))
    perm = [order.index(ui) for ui in u]
    return sp.lambdify(args, Mk, "numpy"), sp.lambdify(args, Fk, "numpy"), sp.lambdify(args, cons, "numpy"), perm


def disc_qdd_reference(params, q, qd):
    """q̈ of the rolling disc (order x, y, ψ, θ, φ) from Kane's method, at a state on the rolling constraints.

    `params` maps m, r, I1, I3, g to values.  Independent of lagcomp's
    derivation: kinematics from sympy frames and points, the constraint from
    the contact point's velocity, dynamics from Kane's equations.
    """
    fM, fF, fcons, perm = _disc_reference()
    p = [params[k] for k in DISC_PARAMS]
    rates = np.linalg.solve(np.array(fM(q, qd, p), dtype=float), np.ravel(fF(q, qd, p)).astype(float))
    return rates[perm]


def disc_constraint_reference(params, q, qd):
    """The reference's contact-point velocity (x and y components) at a state."""
    _, _, fcons, _ = _disc_reference()
    return np.ravel(fcons(q, qd, [params[k] for k in DISC_PARAMS])).astype(float)


def _disc_state(rng, r):
    q = [rng.normal(), rng.normal(), rng.uniform(-3, 3), rng.uniform(-1.2, 1.2), rng.uniform(-3, 3)]
    psid, thd, phd = rng.normal(scale=3, size=3)
    return q, [r * phd * math.cos(q[2]), r * phd * math.sin(q[2]), psid, thd, phd]


def test_rolling_disc_matches_kanes_method():
    eom = eom_of("rolling_disc")
    s = eom.system
    assert s.parameter_names == DISC_PARAMS and eom.constraint_names == ("roll_x", "roll_y")
    solve = kkt_numeric(eom)
    _, cb = residual_functions(eom)
    rng = np.random.default_rng(2024)
    for i in range(6):
        params = dict(s.defaults) if i == 0 else {
            "m": rng.uniform(0.5, 2), "r": rng.uniform(0.05, 0.5), "I1": rng.uniform(0.01, 0.1),
            "I3": rng.uniform(0.01, 0.1), "g": rng.uniform(5, 15)}
        p = [params[k] for k in s.parameter_names]
        q, qd = _disc_state(rng, params["r"])
        assert np.abs(cb(q, qd, 0.0, p)).max() < 1e-12
        assert np.abs(disc_constraint_reference(params, q, qd)).max() < 1e-12  # the same rolling manifold
        qdd, _ = solve(q, qd, 0.0, p)
        ref = disc_qdd_reference(params, q, qd)
        assert np.allclose(qdd, ref, rtol=1e-10, atol=1e-10), (qdd, ref)


def test_rolling_disc_defaults_are_a_steady_turn():
    eom = eom_of("rolling_disc")
    s = eom.system
    qdd, lam = kkt_numeric(eom)(s.q0, s.qd0, 0.0, values(s))
    # θ̈ = ψ̈ = φ̈ = 0; the contact point accelerates toward the centre of its circle
    assert np.abs(qdd[2:]).max() < 1e-12
    psid, spin, r = s.qd0[2], s.qd0[4], s.defaults["r"]
    assert np.allclose(qdd[:2], [0.0, r * spin * psid], atol=1e-12)
    assert psid < 0 < s.q0[3] and abs(r * spin / abs(psid) - 1.68) < 0.01
    # the friction on the disc is horizontal, toward the turn (−y here): the multipliers
    assert abs(lam[0]) < 1e-12 and lam[1] < 0
    # the docstring's steady-turn condition, at other leans, spins and parameters
    solve = kkt_numeric(eom)
    rng = np.random.default_rng(11)
    for _ in range(4):
        params = {"m": rng.uniform(0.5, 2), "r": rng.uniform(0.05, 0.3), "g": 9.81}
        params |= {"I1": params["m"] * params["r"] ** 2 / 4, "I3": params["m"] * params["r"] ** 2 / 2}
        lean, spin, psi = rng.uniform(-0.5, 0.5), rng.uniform(10, 40), rng.uniform(-3, 3)
        turn = ex._disc_steady_turn_rate(params, lean, spin)
        r = params["r"]
        q, qd = [0.3, -0.2, psi, lean, 1.0], [r * spin * math.cos(psi), r * spin * math.sin(psi), turn, 0.0, spin]
        qdd, _ = solve(q, qd, 0.0, [params[k] for k in s.parameter_names])
        assert np.abs(qdd[2:]).max() < 1e-10
