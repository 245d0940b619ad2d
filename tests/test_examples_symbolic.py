"""The bundled examples against equations of motion derived independently.

Pure sympy: Lagrange's equations come from ``sympy.physics.mechanics.LagrangesMethod``
applied to L = T − V, generalized forces are added by hand, and the result is
compared with the equations of motion and closed-form solutions that the
example docstrings state.
"""

from __future__ import annotations

import math

import pytest
import sympy as sp
from sympy.physics.mechanics import LagrangesMethod

from lagcomp import examples
from lagcomp.errors import ModelError
from lagcomp.model import System, t


def lagrange_residual(system: System) -> list[sp.Expr]:
    """d/dt ∂L/∂q̇ − ∂L/∂q − Q for each coordinate, i.e. M q̈ − F − Q."""
    lm = LagrangesMethod(system.T - system.V, list(system.coordinates))
    lm.form_lagranges_equations()
    qdd = sp.Matrix([q.diff(t, 2) for q in system.coordinates])
    residual = lm.mass_matrix * qdd - lm.forcing - sp.Matrix(system.forces)
    return list(residual)


def is_zero(expr) -> bool:
    """Whether a scalar or matrix expression simplifies to zero."""
    if isinstance(expr, sp.MatrixBase):
        return all(is_zero(e) for e in expr)
    expr = sp.expand(sp.expand_trig(expr))
    return expr == 0 or sp.simplify(expr) == 0


def sym(system: System) -> dict[str, sp.Symbol]:
    """The system's parameter symbols by name."""
    return {s.name: s for s in system.parameters}


def speed2(*xyz) -> sp.Expr:
    return sum(c.diff(t) ** 2 for c in xyz)


# -- registry and defaults ------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(examples.EXAMPLES))
def test_every_example_is_complete(name):
    system = examples.get(name)
    assert isinstance(system, System)
    assert system.name.isidentifier()
    assert system.description and "\n" not in system.description
    assert set(system.defaults) == set(system.parameter_names)
    assert all(math.isfinite(v) and v > 0 for v in system.defaults.values())
    assert all(s.is_positive for s in system.parameters)
    assert len(system.q0) == len(system.qd0) == system.n
    assert system.t_end > 0
    assert examples.EXAMPLES[name].__doc__


def test_names_match_registry():
    for name, factory in examples.EXAMPLES.items():
        built = factory()
        assert built.name == (f"{name}_3" if name == "n_link_pendulum" else name)


def test_unknown_name_lists_known_examples():
    with pytest.raises(ModelError) as err:
        examples.get("no_such_pendulum")
    for name in examples.EXAMPLES:
        assert name in str(err.value)


def test_n_link_pendulum_sizes():
    system = examples.get("n_link_pendulum", n=5)
    assert system.n == 5 and len(system.parameters) == 11
    assert system.name == "n_link_pendulum_5"
    assert set(system.parameter_names) == {f"m{i}" for i in range(1, 6)} | {f"l{i}" for i in range(1, 6)} | {"g"}
    assert examples.get("n_link_pendulum_4").n == 4
    for bad in (0, -1, 2.5):
        with pytest.raises(ModelError):
            examples.n_link_pendulum(n=bad)


# -- equations of motion ------------------------------------------------------------------


def test_simple_pendulum():
    s = examples.simple_pendulum()
    (th,) = s.coordinates
    p = sym(s)
    m, l, g = p["m"], p["l"], p["g"]
    (res,) = lagrange_residual(s)
    assert is_zero(res - m * l**2 * (th.diff(t, 2) + g / l * sp.sin(th)))


def test_double_pendulum():
    s = examples.double_pendulum()
    th1, th2 = s.coordinates
    p = sym(s)
    m1, m2, l1, l2, g = (p[k] for k in ("m1", "m2", "l1", "l2", "g"))
    x1, y1 = l1 * sp.sin(th1), -l1 * sp.cos(th1)
    x2, y2 = x1 + l2 * sp.sin(th2), y1 - l2 * sp.cos(th2)
    assert is_zero(s.T - (m1 * speed2(x1, y1) + m2 * speed2(x2, y2)) / 2)
    assert is_zero(s.V - g * (m1 * y1 + m2 * y2))
    d = th1 - th2
    a1, a2 = th1.diff(t, 2), th2.diff(t, 2)
    w1, w2 = th1.diff(t), th2.diff(t)
    r1, r2 = lagrange_residual(s)
    e1 = (m1 + m2) * l1 * a1 + m2 * l2 * (a2 * sp.cos(d) + w2**2 * sp.sin(d)) + (m1 + m2) * g * sp.sin(th1)
    e2 = l2 * a2 + l1 * (a1 * sp.cos(d) - w1**2 * sp.sin(d)) + g * sp.sin(th2)
    assert is_zero(r1 - l1 * e1)
    assert is_zero(r2 - m2 * l2 * e2)
    assert (s.q0, s.qd0, s.t_end) == ((2.0, 1.0), (0.0, 0.0), 20.0)
    assert s.defaults == {"m1": 1.0, "m2": 1.0, "l1": 1.0, "l2": 1.0, "g": 9.81}


def test_n_link_pendulum_equations():
    n = 3
    s = examples.n_link_pendulum(n=n)
    th = s.coordinates
    p = sym(s)
    m = [p[f"m{i}"] for i in range(1, n + 1)]
    l = [p[f"l{i}"] for i in range(1, n + 1)]
    g = p["g"]
    mu = [sum(m[k:]) for k in range(n)]  # mass carried below rod k
    for j, res in enumerate(lagrange_residual(s)):
        expected = mu[j] * g * l[j] * sp.sin(th[j]) + sum(
            mu[max(j, k)] * l[j] * l[k]
            * (sp.cos(th[j] - th[k]) * th[k].diff(t, 2) + sp.sin(th[j] - th[k]) * th[k].diff(t) ** 2)
            for k in range(n)
        )
        assert is_zero(res - expected)


def test_n_link_pendulum_reduces_to_smaller_examples():
    two, double = examples.n_link_pendulum(n=2), examples.double_pendulum()
    assert two.coordinates == double.coordinates
    assert is_zero(two.T - double.T) and is_zero(two.V - double.V)
    one, simple = examples.n_link_pendulum(n=1), examples.simple_pendulum()
    rename = {one.coordinates[0]: simple.coordinates[0], **{sym(one)[a]: sym(simple)[b] for a, b in
                                                            (("m1", "m"), ("l1", "l"), ("g", "g"))}}
    assert is_zero(one.T.subs(rename) - simple.T) and is_zero(one.V.subs(rename) - simple.V)


def test_sling():
    s = examples.sling()
    (rho,) = s.coordinates
    m, omega = sym(s)["m"], sym(s)["omega"]
    (res,) = lagrange_residual(s)
    assert is_zero(res - m * (rho.diff(t, 2) - omega**2 * rho))
    a = sp.Symbol("a", positive=True)
    sol = a * sp.cosh(omega * t)
    assert is_zero(sol.diff(t, 2) - omega**2 * sol)
    assert sol.subs(t, 0) == a and sol.diff(t).subs(t, 0) == 0
    assert "a" not in s.parameter_names and s.q0[0] > 0 and s.qd0 == (0.0,)


def test_rope():
    s = examples.rope()
    (x,) = s.coordinates
    M, L, g = (sym(s)[k] for k in ("M", "L", "g"))
    (res,) = lagrange_residual(s)
    assert is_zero(res / M - (x.diff(t, 2) - g / L * x))
    x0 = sp.Symbol("x0", positive=True)
    sol = x0 * sp.cosh(t * sp.sqrt(g / L))
    assert is_zero(sol.diff(t, 2) - g / L * sol)
    assert sol.subs(t, 0) == x0 and sol.diff(t).subs(t, 0) == 0
    # the default run ends with the rope still partly on the table
    d = s.defaults
    assert s.q0[0] * math.cosh(s.t_end * math.sqrt(d["g"] / d["L"])) < d["L"]


def test_rope_friction():
    s = examples.rope_friction()
    (x,) = s.coordinates
    M, L, g, f = (sym(s)[k] for k in ("M", "L", "g", "f"))
    mu = M / L
    (Q,) = s.forces
    v = sp.Symbol("v", positive=True)
    xd = x.diff(t)
    # friction opposes the motion, and points to -x at rest (limiting static friction)
    assert is_zero(Q.xreplace({xd: v}) + f * mu * g * (L - x))
    assert is_zero(Q.xreplace({xd: -v}) - f * mu * g * (L - x))
    assert is_zero(Q.xreplace({xd: 0}) + f * mu * g * (L - x))
    l0 = f * L / (1 + f)
    assert is_zero(mu * g * l0 - f * mu * g * (L - l0))  # weight of the hanging part = maximal friction
    # sliding toward +x: ẍ = g(1+f)/L (x − l0)
    (res,) = lagrange_residual(s)
    assert is_zero(res.xreplace({xd: v}) / M - (x.diff(t, 2) - g * (1 + f) / L * (x - l0)))
    # closed form from rest at x0 = l0 + d > l0
    dx = sp.Symbol("d", positive=True)
    k = sp.sqrt(g * (1 + f) / L)
    sol = l0 + dx * sp.cosh(k * t)
    assert is_zero(sol.diff(t, 2) - k**2 * (sol - l0))
    assert is_zero(sol.subs(t, 0) - (l0 + dx)) and sol.diff(t).subs(t, 0) == 0
    tp = sp.Symbol("tau", positive=True)
    assert sol.diff(t).subs(t, tp).is_positive  # keeps sliding toward +x, so s = 1 throughout
    # defaults start above l0 and stop before the rope leaves the table
    dv = s.defaults
    l0v = dv["f"] * dv["L"] / (1 + dv["f"])
    x0 = s.q0[0]
    assert x0 > l0v
    assert l0v + (x0 - l0v) * math.cosh(s.t_end * math.sqrt(dv["g"] * (1 + dv["f"]) / dv["L"])) < dv["L"]


def test_hoop_bead():
    s = examples.hoop_bead()
    (th,) = s.coordinates
    m, R, g, Om, eps = (sym(s)[k] for k in ("m", "R", "g", "Omega", "epsilon"))
    phi = Om * t + eps * sp.sin(2 * t)
    angle = sp.Function("phi")(t)  # simplify with a generic φ(t) first, then impose it
    pos = (R * sp.sin(th) * sp.cos(angle), R * sp.sin(th) * sp.sin(angle), R * sp.cos(th))
    T_cartesian = (m * sp.trigsimp(sp.expand(speed2(*pos))) / 2).subs(angle, phi).doit()
    assert is_zero(s.T - T_cartesian)
    assert is_zero(s.V - m * g * pos[2])
    (res,) = lagrange_residual(s)
    phid = Om + 2 * eps * sp.cos(2 * t)
    assert is_zero(res / (m * R**2) - (th.diff(t, 2) - sp.sin(th) * (g / R + phid**2 * sp.cos(th))))
    # steady relative equilibrium of the uniformly turned hoop
    th_star = sp.acos(-g / (R * Om**2))
    assert is_zero(res.subs(eps, 0).subs(th, th_star).doit())


def test_huygens():
    s = examples.huygens()
    (th,) = s.coordinates
    m, R, g = (sym(s)[k] for k in ("m", "R", "g"))
    x, z = R * (th + sp.sin(th)), R * (1 - sp.cos(th))
    assert is_zero(s.T - m * speed2(x, z) / 2)
    assert is_zero(s.V - m * g * z)
    (res,) = lagrange_residual(s)
    c, sn = sp.cos(th / 2), sp.sin(th / 2)
    assert is_zero(res - 2 * m * R**2 * c * (2 * c * th.diff(t, 2) - sn * th.diff(t) ** 2 + g / R * sn))
    # arc length s = 4R sin(θ/2) is harmonic with ω² = g/(4R)
    arc = 4 * R * sn
    omega2 = g / (4 * R)
    assert is_zero(res - 2 * m * R * c * (arc.diff(t, 2) + omega2 * arc))
    # closed form from rest at θ0: sin(θ/2) = sin(θ0/2) cos ωt, period 4π√(R/g)
    A = sp.Symbol("A", positive=True)  # sin(θ0/2) < 1
    omega = sp.sqrt(omega2)
    sol = 2 * sp.asin(A * sp.cos(omega * t))
    assert is_zero(res.subs(th, sol).doit())
    assert is_zero(2 * sp.pi / omega - 4 * sp.pi * sp.sqrt(R / g))
    assert abs(s.q0[0]) < math.pi


def test_tray_cylinder():
    s = examples.tray_cylinder()
    (X,) = s.coordinates
    M, R, I, A, Om = (sym(s)[k] for k in ("M", "R", "I", "A", "Omega"))
    a = A * sp.sin(Om * t)
    (res,) = lagrange_residual(s)
    assert is_zero(res * R**2 / (I + M * R**2) - (X.diff(t, 2) - I * a.diff(t, 2) / (I + M * R**2)))
    X0, V0 = sp.symbols("X0 V0", real=True)
    k = I / (I + M * R**2)
    sol = X0 + k * (a - a.subs(t, 0)) + (V0 - k * a.diff(t).subs(t, 0)) * t
    assert is_zero(res.subs(X, sol).doit())
    assert sol.subs(t, 0) == X0 and is_zero(sol.diff(t).subs(t, 0) - V0)


def test_unbalanced_cylinder():
    s = examples.unbalanced_cylinder()
    (th,) = s.coordinates
    M, R, a, I, g = (sym(s)[k] for k in ("M", "R", "a", "I", "g"))
    C = sp.Matrix([R * th, R, 0])
    G = sp.Matrix([R * th - a * sp.sin(th), R - a * sp.cos(th), 0])
    w = sp.Matrix([0, 0, -th.diff(t)])  # clockwise rotation
    assert is_zero((G - C).diff(t) - w.cross(G - C))  # G is carried rigidly by the rotation
    contact = sp.Matrix([R * th, 0, 0])
    assert is_zero(C.diff(t) + w.cross(contact - C))  # rolling without slipping
    assert G.subs(th, 0)[1] == R - a  # lowest at θ = 0
    assert is_zero(s.T - (M * speed2(*G) + I * th.diff(t) ** 2) / 2)
    assert is_zero(s.V - M * g * G[1])
    J = M * (R**2 + a**2 - 2 * a * R * sp.cos(th)) + I
    (res,) = lagrange_residual(s)
    assert is_zero(res - (J * th.diff(t, 2) + M * a * R * sp.sin(th) * th.diff(t) ** 2 + M * g * a * sp.sin(th)))
    assert is_zero((s.T + s.V).diff(t) - th.diff(t) * res)  # E = T + V is a first integral


def test_driven_pendulum():
    s = examples.driven_pendulum()
    (th,) = s.coordinates
    m, l, g, A, Om = (sym(s)[k] for k in ("m", "l", "g", "A", "Omega"))
    h = A * sp.cos(Om * t)
    x, y = l * sp.sin(th), h - l * sp.cos(th)
    assert is_zero(s.T - m * speed2(x, y) / 2)
    assert is_zero(s.V - m * g * y)
    (res,) = lagrange_residual(s)
    assert is_zero(res - m * l * (l * th.diff(t, 2) + (g + h.diff(t, 2)) * sp.sin(th)))
    d = s.defaults
    assert (d["A"] * d["Omega"]) ** 2 > 2 * d["g"] * d["l"]  # Kapitza: inverted position stable
    assert abs(s.q0[0] - math.pi) < 0.5


@pytest.mark.parametrize("name", ["simple_pendulum", "double_pendulum", "n_link_pendulum", "huygens", "rope"])
def test_energy_is_conserved(name):
    s = examples.get(name)
    rate = (s.T + s.V).diff(t) - sum(q.diff(t) * r for q, r in zip(s.coordinates, lagrange_residual(s)))
    assert is_zero(rate)
