"""Spherical and free joints in kinematic trees (issue 39, item 1): modified Rodrigues parameters (MRPs) and
their shadow switch.

References nobody here wrote: sympy's exact algebra for the MRP kinematics (R(σ), ω = J σ̇, J̇ σ̇, the shadow
set); Pinocchio's ABA (quaternion joints, `JointModelSpherical`, `JointModelFreeFlyer`) at random states; the
closed-form steady precession of a heavy symmetric top; the conservation of energy, angular momentum (world
frame, 3 components) and linear momentum of a free tumbling asymmetric body over 10⁴ turns.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.multibody import mrp

# -- the MRP algebra against sympy ---------------------------------------------------------------------------------

S = sp.symbols("s1:4", real=True)
SD = sp.symbols("sd1:4", real=True)
TAU = sp.Symbol("tau", real=True)


def _exact_rotation(sigma) -> sp.Matrix:
    """R of σ = n tan(θ/4) from the quaternion (cos θ/2, n sin θ/2) = ((1 − s), 2σ) / (1 + s): the textbook
    quaternion rotation matrix (Shuster 1993), not the formula `mrp.rotation` uses."""
    s = sum(x ** 2 for x in sigma)
    w, (x, y, z) = (1 - s) / (1 + s), [2 * c / (1 + s) for c in sigma]
    return sp.Matrix([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                      [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                      [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def test_mrp_kinematics_agree_with_sympy_exactly():
    """R(σ) equals the quaternion's matrix; J σ̇ is the body rate of Rᵀ Ṙ; J̇ σ̇ its time derivative at σ̈ = 0; J⁻¹
    and Jᵀ invert and transpose J; the shadow set has the same R and ω."""
    R = _exact_rotation(S)
    assert sp.simplify(sp.Matrix(mrp.rotation(S)) - R) == sp.zeros(3, 3)
    path = {s: s + TAU * sd for s, sd in zip(S, SD)}     # σ(τ) = σ + τ σ̇: σ̈ = 0
    Rdot = R.xreplace(path).diff(TAU).xreplace({TAU: 0})
    W = sp.simplify(R.T * Rdot)
    omega = sp.Matrix(mrp.angular_velocity(S, SD))
    assert sp.simplify(sp.Matrix([W[2, 1], W[0, 2], W[1, 0]]) - omega) == sp.zeros(3, 1)
    omega_dot = sp.Matrix(mrp.angular_velocity([path[s] for s in S], SD)).diff(TAU).xreplace({TAU: 0})
    assert sp.simplify(omega_dot - sp.Matrix(mrp.rate_product(S, SD))) == sp.zeros(3, 1)
    assert sp.simplify(sp.Matrix(mrp.jacobian_inverse_times(S, list(omega))) - sp.Matrix(SD)) == sp.zeros(3, 1)
    J = sp.Matrix(3, 3, lambda i, j: omega[i].diff(SD[j]))
    assert sp.simplify(sp.Matrix(mrp.jacobian_transpose_times(S, list(SD))) - J.T * sp.Matrix(SD)) == sp.zeros(3, 1)
    shadow, shadow_rates = mrp.shadow(S, SD)
    assert sp.simplify(_exact_rotation(shadow) - R) == sp.zeros(3, 3)
    assert sp.simplify(sp.Matrix(mrp.angular_velocity(shadow, shadow_rates)) - omega) == sp.zeros(3, 1)


@settings(max_examples=50, deadline=None)
@given(axis=st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda a: np.linalg.norm(a) > 1e-3),
       angle=st.floats(-20.0, 20.0))
def test_initial_orientations_from_a_rotation_and_an_axis_angle(axis, angle):
    """`mrp_from_axis_angle` and `mrp_from_rotation` give |σ| ≤ 1 and the rotation asked for (Rodrigues' formula
    for the reference)."""
    n = np.array(axis) / np.linalg.norm(axis)
    K = np.array([[0, -n[2], n[1]], [n[2], 0, -n[0]], [-n[1], n[0], 0]])
    R = np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K
    for sigma in (mrp.mrp_from_axis_angle(axis, angle), mrp.mrp_from_rotation(R)):
        assert np.linalg.norm(sigma) <= 1 + 1e-15
        assert np.max(np.abs(np.array(mrp.rotation(sigma)) - R)) <= 1e-14


# -- against Pinocchio ----------------------------------------------------------------------------------------------


def _chain(n_links: int, free_base: bool) -> lc.Tree:
    """A 3D chain of asymmetric bodies on spherical joints with offset, rotated placements, hanging under
    gravity (on a free-floating base when `free_base`, then a revolute elbow about an unaligned axis); the first
    ball joint has a damper and drives its link with a constant moment."""
    rng = np.random.default_rng(n_links + 10 * free_base)
    links = []
    if free_base:
        tilt = [[0.0, -0.6, 0.8], [1.0, 0.0, 0.0], [0.0, 0.8, 0.6]]
        links.append(lc.Link("base", lc.Free(("x", "y", "z", "b1", "b2", "b3"), origin=(0.1, 0.2, 0.3), rotation=tilt),
                             mass=3.0, com=(0.1, -0.2, 0.05), inertia=(0.3, 0.4, 0.5)))
        links.append(lc.Link("elbow", lc.Revolute("th", axis=(0.3, 0.4, 1.0), origin=(0.5, 0.1, 0.0)),
                             parent="base", mass=1.0, com=(0.2, 0, -0.3), inertia=(0.2, 0.25, 0.1)))
    for i in range(n_links):
        Q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        Q *= np.sign(np.linalg.det(Q))
        moments = rng.uniform(1.0, 1.5, size=3) * 0.1
        loads = {"damping": 0.25, "torque": (0.4, -0.3, 0.2)} if i == 0 else {}
        links.append(lc.Link(f"link{i}", lc.Spherical((f"s{i}x", f"s{i}y", f"s{i}z"), origin=tuple(
            rng.normal(size=3).round(3)), rotation=Q.tolist(), **loads), parent=links[-1].name if links else None,
            mass=float(rng.uniform(0.5, 2)), com=tuple(rng.normal(size=3).round(3)), inertia=tuple(moments)))
    return lc.Tree(links, gravity=(0.3, -0.2, -9.81), name=f"spherical_chain_{n_links}{'_free' if free_base else ''}")


def _pinocchio(tree: lc.Tree):
    """The Pinocchio model of `_chain`'s trees (numeric trees: each link's joint placement, kind and body)."""
    import pinocchio as pin

    model, parent = pin.Model(), 0
    for link in tree.links:
        joint = link.joint
        R = np.eye(3) if joint.rotation is None else np.array(joint.rotation, dtype=float)
        if isinstance(joint, (lc.Free, lc.Spherical)):
            kind = pin.JointModelFreeFlyer() if isinstance(joint, lc.Free) else pin.JointModelSpherical()
        else:
            axis = np.array(joint.axis, dtype=float)
            kind = pin.JointModelRevoluteUnaligned(axis / np.linalg.norm(axis))
        parent = model.addJoint(parent, kind, pin.SE3(R, np.array(joint.origin, dtype=float)), link.name)
        model.appendBodyToJoint(parent, pin.Inertia(float(link.mass), np.array(link.com, dtype=float),
                                                    np.diag(np.array(link.inertia, dtype=float))), pin.SE3.Identity())
    model.gravity = pin.Motion(np.array(tree.gravity, dtype=float), np.zeros(3))
    return model


def _to_pinocchio(tree: lc.Tree, y):
    """Pinocchio's (q, v, τ) of the state y = (q, q̇): quaternions (x, y, z, w) of R(σ), body rates ω = J σ̇, a free
    joint's linear velocity in its body frame Rᵀ ẋ, a ball joint's moment torque − damping ω; and per joint what
    turns its part of Pinocchio's q̈ back."""
    import pinocchio as pin

    n, i = tree.n, 0
    q, v, tau, joints = [], [], [], []
    for link in tree.links:
        if isinstance(link.joint, (lc.Free, lc.Spherical)):
            free = isinstance(link.joint, lc.Free)
            x, xd = y[i:i + 3], y[n + i:n + i + 3]
            k = i + 3 * free
            sigma, rates = y[k:k + 3], y[n + k:n + k + 3]
            R, omega = np.array(mrp.rotation(sigma)), np.array(mrp.angular_velocity(sigma, rates))
            q += [*(x if free else []), *pin.Quaternion(R).coeffs()]
            v += [*(R.T @ xd if free else []), *omega]
            tau += [0.0] * 3 * free + list(np.zeros(3) if free else np.array(link.joint.torque, dtype=float)
                                           - float(link.joint.damping) * omega)
            joints.append((free, sigma, rates, R, omega, R.T @ xd))
            i = k + 3
        else:
            q.append(y[i])
            v.append(y[n + i])
            tau.append(0.0)
            joints.append(None)
            i += 1
    return np.array(q), np.array(v), np.array(tau), joints


def _from_pinocchio(joints, a) -> np.ndarray:
    """q̈ of the tree from Pinocchio's a = v̇: σ̈ = J⁻¹ (ω̇ − J̇ σ̇), ẍ = R (v̇ + ω × v) for a free joint."""
    out, k = [], 0
    for joint in joints:
        if joint is None:
            out.append(a[k])
            k += 1
            continue
        free, sigma, rates, R, omega, v = joint
        if free:
            out += list(R @ (a[k:k + 3] + np.cross(omega, v)))
            k += 3
        out += mrp.jacobian_inverse_times(sigma, a[k:k + 3] - np.array(mrp.rate_product(sigma, rates)))
        k += 3
    return np.array(out)


def _relative(a, b) -> float:
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


@pytest.mark.parametrize("n_links, free_base", [(1, False), (3, False), (2, True)])
def test_spherical_chains_agree_with_pinocchio(cache_dir, n_links, free_base):
    """q̈ against Pinocchio's ABA (with the first ball joint's moments), T + V against its energies, and the
    module's own M q̈ = F and p = M q̇, at random states with |σ| up to 2 (past the switch: the equations hold for
    any σ)."""
    pin = pytest.importorskip("pinocchio")
    tree = _chain(n_links, free_base)
    model = lc.compile(tree, cache_dir=cache_dir)
    reference = _pinocchio(tree)
    data = reference.createData()
    rng = np.random.default_rng(n_links)
    n, p = tree.n, model.parameter_vector()
    for _ in range(8):
        y = np.concatenate([rng.uniform(-1.2, 1.2, size=n), rng.normal(size=n)])
        q, v, tau, joints = _to_pinocchio(tree, y)
        qdd = model.rhs(0.0, y)[n:]
        assert _relative(qdd, _from_pinocchio(joints, pin.aba(reference, data, q, v, tau))) <= 1e-12
        energy = pin.computeKineticEnergy(reference, data, q, v) + pin.computePotentialEnergy(reference, data, q)
        assert abs(model.kernels.energy(0.0, y, p) - energy) <= 1e-12 * abs(energy)
        M, F, momenta = np.empty((n, n)), np.empty(n), np.empty(n)
        model.kernels.mass_matrix(0.0, y, p, M)
        model.kernels.forcing(0.0, y, p, F)
        model.kernels.momenta(0.0, y, p, momenta)
        assert np.array_equal(M, M.T) and np.all(np.linalg.eigvalsh(M) > 0)
        assert _relative(M @ qdd, F) <= 1e-12 and _relative(M @ y[n:], momenta) <= 1e-12


# -- invariants and closed forms ------------------------------------------------------------------------------------


def _world_momenta(q, qd, mass, com, inertia):
    """Of a free body with state (x, σ; ẋ, σ̇): its linear momentum m v_G, angular momentum about its centre of mass
    R I_G ω and about the world origin, that plus m r_G × v_G, and the scale of the last, |R I_G ω| + m |r_G| |v_G|
    (world axes), and its body rates ω."""
    R = np.array(mrp.rotation(q[3:6]))
    omega = np.array(mrp.angular_velocity(q[3:6], qd[3:6]))
    r_G, v_G = q[:3] + R @ com, qd[:3] + R @ np.cross(omega, com)
    spin = R @ (inertia * omega)
    scale = np.linalg.norm(spin) + mass * np.linalg.norm(r_G) * np.linalg.norm(v_G)
    return mass * v_G, spin, spin + mass * np.cross(r_G, v_G), scale, omega


def test_a_free_tumbling_body_keeps_its_energy_and_momenta_over_ten_thousand_turns(cache_dir):
    """Torque-free asymmetric body (moments 1, 2, 3, centre of mass off the frame's origin) spun about its
    intermediate axis with a 1e-3 perturbation: it flips over and over (Dzhanibekov).  Over 10⁴ turns (10⁴ shadow
    switches, |σ| ≤ 1 throughout), with dop853 at rtol = atol = 3e-14, each invariant's largest drift relative to
    its magnitude: T within 3e-10; the angular momentum about the centre of mass, world axes, all three components
    within 1e-8 of its norm; about the world origin (the body drifts 3 km away) within 1e-8 of the norms of its
    two terms; the linear momentum within 2e-8 of its norm.  Measured 2026-11-28 (3.9e5 steps): 1.1e-11, 8.3e-10,
    6.9e-10, 1.4e-9 (a tenth of the bounds or less)."""
    inertia, mass, com = np.array([1.0, 2.0, 3.0]), 1.5, np.array([0.1, -0.2, 0.3])
    tree = lc.Tree([lc.Link("body", lc.Free(("x", "y", "z", "s1", "s2", "s3")), mass=mass, com=tuple(com),
                            inertia=tuple(inertia))], name="tumbling_body")
    model = lc.compile(tree, cache_dir=cache_dir)
    omega0, sigma0 = np.array([1e-3, 2 * np.pi / 6, 1e-3]), mrp.mrp_from_axis_angle((1, 1, 0), 0.3)
    v0 = np.array([0.05, -0.02, 0.01]) - np.array(mrp.rotation(sigma0)) @ np.cross(omega0, com)
    sol = model.simulate((0.0, 6.3e4), q0=[0, 0, 0, *sigma0], qd0=[*v0, *mrp.mrp_rate(sigma0, omega0)],
                         rtol=3e-14, atol=3e-14, save_every=100)
    assert sol.success and sol.t[-1] == 6.3e4
    switches = sol.events["body_shadow"]
    assert len(switches.t) >= 10_000
    assert np.max(np.linalg.norm(sol.q[:, 3:6], axis=1)) <= 1 + 1e-9
    P, L_G, L_O, scale, omega = map(np.array, zip(*(_world_momenta(q, qd, mass, com, inertia)
                                                    for q, qd in zip(sol.q, sol.qd))))
    assert np.sum(np.diff(np.sign(omega[:, 1])) != 0) >= 20     # the intermediate axis's rate flips sign: tumbling
    energy = sol.energy
    drifts = (np.max(np.abs(energy - energy[0])) / energy[0], np.max(np.abs(L_G - L_G[0])) / np.linalg.norm(L_G[0]),
              np.max(np.abs(L_O - L_O[0]) / scale[:, None]), np.max(np.abs(P - P[0])) / np.linalg.norm(P[0]))
    assert drifts[0] <= 3e-10 and drifts[1] <= 1e-8 and drifts[2] <= 1e-8 and drifts[3] <= 2e-8, drifts


def test_a_heavy_symmetric_top_precesses_steadily_at_the_closed_form_rate(cache_dir):
    """A top on a ball joint (mass m, centre of mass at l along its symmetry axis, moments A, A, C about the centre
    of mass) tilted by θ and precessing at Ω about the vertical keeps its tilt when its spin about the axis is
    ω₃ = (m g l + A' Ω² cos θ) / (C Ω), A' = A + m l² (θ̈ = 0 of the Euler-angle Lagrangian): the axis then turns
    about the vertical at Ω exactly.  The spin makes σ switch every turn about the axis."""
    m, l, A, C, g = 2.0, 0.3, 0.03, 0.05, 9.81
    tree = lc.Tree([lc.Link("top", lc.Spherical(("s1", "s2", "s3")), mass=m, com=(0, 0, l), inertia=(A, A, C))],
                   gravity=(0, 0, -g), name="symmetric_top")
    model = lc.compile(tree, cache_dir=cache_dir)
    theta, Omega = 0.5, 2.0
    spin = (m * g * l + (A + m * l ** 2) * Omega ** 2 * np.cos(theta)) / (C * Omega)
    R0 = np.array([[1, 0, 0], [0, np.cos(theta), -np.sin(theta)], [0, np.sin(theta), np.cos(theta)]])
    omega = R0.T @ np.array([0, 0, Omega])
    omega[2] = spin                                  # body rate: precession's, with its axial part ω₃
    sigma0 = mrp.mrp_from_rotation(R0)
    t_eval = np.linspace(0, 20, 401)[1:]
    sol = model.simulate((0.0, 20.0), q0=sigma0, qd0=mrp.mrp_rate(sigma0, omega), t_eval=t_eval, rtol=1e-13,
                         atol=1e-13)
    assert sol.success and len(sol.events["top_shadow"].t) >= 20
    assert sol.t[-1] == 20.0 and len(sol.t) >= 400
    axis = np.array([np.array(mrp.rotation(s))[:, 2] for s in sol.q])
    k0, turned = R0[:, 2], Omega * sol.t
    expected = np.column_stack([np.cos(turned) * k0[0] - np.sin(turned) * k0[1],
                                np.sin(turned) * k0[0] + np.cos(turned) * k0[1], np.full_like(turned, k0[2])])
    assert np.max(np.abs(axis - expected)) <= 1e-10


def test_q_ddot_agrees_with_the_lagrangian_path_of_the_same_mrp_kinematics(cache_dir):
    """One body on a ball joint (centre of mass on its z axis, principal moments A, B, C) against the Lagrangian
    path's equations from T = ½ ωᵀ I_G ω + ½ m |ω × c|² and V = m g (R c)_z, with ω = J(σ) σ̇ and R(σ) as
    `test_mrp_kinematics_agree_with_sympy_exactly` checks them: sympy derives q̈ from them, the tree from the
    articulated-body recursion, at random states and parameters."""
    s = lc.coordinates("s1 s2 s3")
    m, g, A, B, C, cz = sp.symbols("m g A B C cz")
    omega = mrp.angular_velocity(list(s), [c.diff(lc.t) for c in s])
    v_G = [omega[1] * cz, -omega[0] * cz, 0]
    T = (A * omega[0] ** 2 + B * omega[1] ** 2 + C * omega[2] ** 2 + m * sum(v ** 2 for v in v_G)) / 2
    system = lc.System(list(s), T=T, V=m * g * mrp.rotation(list(s))[2][2] * cz, name="ball_joint_lagrange")
    tree = lc.Tree([lc.Link("ball", lc.Spherical(s), mass=m, com=(0, 0, cz), inertia=(A, B, C))],
                   gravity=(0, 0, -g), name="ball_joint_tree")
    lagrange, recursive = lc.compile(system, cache_dir=cache_dir), lc.compile(tree, cache_dir=cache_dir)
    assert lagrange.parameters == recursive.parameters
    rng = np.random.default_rng(7)
    for _ in range(20):
        params = dict(zip(recursive.parameters, rng.uniform(0.5, 2.0, size=len(recursive.parameters))))
        y = np.concatenate([rng.uniform(-1.5, 1.5, size=3), rng.normal(size=3)])
        assert _relative(recursive.rhs(0.3, y, params), lagrange.rhs(0.3, y, params)) <= 1e-12
        energies = [model.kernels.energy(0.3, y, model.parameter_vector(params)) for model in (recursive, lagrange)]
        assert abs(energies[0] - energies[1]) <= 1e-12 * abs(energies[1])


# -- the shadow switch as an event, and refusals ---------------------------------------------------------------------


def test_the_shadow_switch_is_an_event_with_a_reset_that_fixed_step_methods_refuse(cache_dir):
    """A spherical joint declares ``<link>_shadow``; rk4 (no event resets) is refused naming it, unless the run
    leaves it out (then σ grows past 1 and the run is still right until the rotation nears a full turn)."""
    tree = lc.Tree([lc.Link("ball", lc.Spherical(("a", "b", "c")), mass=1.0, inertia=(1, 2, 3))], name="ball_only")
    model = lc.compile(tree, cache_dir=cache_dir)
    assert model.event_names == ("ball_shadow",)
    qd0 = mrp.mrp_rate([0, 0, 0], [0, 0, 1.0])
    with pytest.raises(lc.OptionError, match=r"ball_shadow.*rk4"):
        model.simulate((0.0, 1.0), q0=[0, 0, 0], qd0=qd0, method="rk4", dt=1e-3)
    sol = model.simulate((0.0, 4.0), q0=[0, 0, 0], qd0=qd0, method="rk4", dt=1e-3, events=False)
    assert abs(sol.q[-1, 2] - np.tan(4.0 / 4)) <= 1e-12   # σ_z = tan(θ/4), θ = ω t about z: past |σ| = 1 (θ = π)


@pytest.fixture(scope="module")
def heavy_ball(cache_dir):
    """An asymmetric body on a ball joint under gravity, its centre of mass off the joint."""
    tree = lc.Tree([lc.Link("ball", lc.Spherical(("a", "b", "c")), mass=1.3, com=(0.2, -0.1, 0.5),
                            inertia=(0.2, 0.3, 0.4))], gravity=(0.5, 0.0, -9.81), name="heavy_ball")
    return lc.compile(tree, cache_dir=cache_dir)


@settings(max_examples=60, deadline=None)
@given(sigma=st.tuples(*[st.floats(-3.0, 3.0)] * 3).filter(lambda v: 0.25 <= np.dot(v, v) <= 9.0),
       rates=st.tuples(*[st.floats(-5.0, 5.0)] * 3))
def test_the_emitted_shadow_reset_keeps_the_orientation_the_angular_velocity_and_the_energy(heavy_ball, sigma,
                                                                                         rates):
    """The module's ``event_reset`` at any state: R(σ) and ω unchanged, so T + V too; |σ| becomes 1/|σ|."""
    y, after, p = np.array([*sigma, *rates]), np.empty(6), heavy_ball.parameter_vector()
    assert heavy_ball.kernels.event_reset(0.0, y, p, 0, after) == 0
    assert abs(np.linalg.norm(after[:3]) * np.linalg.norm(sigma) - 1) <= 1e-15
    assert np.max(np.abs(np.array(mrp.rotation(after[:3])) - np.array(mrp.rotation(sigma)))) <= 1e-15
    omega = np.array(mrp.angular_velocity(sigma, rates))
    assert np.max(np.abs(np.array(mrp.angular_velocity(after[:3], after[3:])) - omega)) <= 1e-14 * max(
        np.linalg.norm(omega), 1.0)
    energies = [heavy_ball.kernels.energy(0.0, state, p) for state in (y, after)]
    scale = abs(energies[0]) + 1.3 * np.hypot(0.5, 9.81) * np.linalg.norm([0.2, -0.1, 0.5])   # |T + V| + max |V|
    assert abs(energies[1] - energies[0]) <= 1e-14 * scale


@pytest.mark.parametrize("joint, count", [(lc.Spherical(("a", "b")), 3), (lc.Free(("x", "y", "z", "a", "b")), 6)])
def test_a_joint_with_the_wrong_number_of_coordinates_is_refused(joint, count):
    with pytest.raises(lc.ModelError, match=f"needs {count} coordinates"):
        lc.Tree([lc.Link("body", joint, mass=1.0, inertia=(1, 1, 1))])


def test_the_jacobian_of_a_ball_joint_is_that_of_its_coordinates_rhs(heavy_ball):
    """The on-demand Jacobian (forward mode over the recursion, `lagcomp.codegen.tree_companion`) differentiates
    the σ̈ that ``rhs`` returns, through the MRP chart (σ̈ = J⁻¹ψ), not the body-axis accelerations ψ: against
    fourth-order central differences of ``rhs`` (truncation ~h⁴, rounding ~1e-16/h: 1e-9 relative), and its f
    is ``rhs``'s bitwise."""
    rng = np.random.default_rng(5)
    p, k = heavy_ball.parameter_vector(), heavy_ball.kernels
    for _ in range(4):
        y = np.concatenate([rng.uniform(-0.6, 0.6, 3), rng.normal(size=3)])
        f, ydot, J = np.empty(6), np.empty(6), np.empty((6, 6))
        k.rhs(0.0, y, p, f)
        assert k.rhs_with_jacobian(0.0, y, p, ydot, J) == 0 and np.array_equal(ydot, f)

        def rhs(state):
            out = np.empty(6)
            k.rhs(0.0, state, p, out)
            return out

        h, columns = 1e-3, []
        for j in range(6):
            e = np.zeros(6)
            e[j] = h
            columns.append((8 * (rhs(y + e) - rhs(y - e)) - (rhs(y + 2 * e) - rhs(y - 2 * e))) / (12 * h))
        assert _relative(J, np.array(columns).T) <= 1e-9
