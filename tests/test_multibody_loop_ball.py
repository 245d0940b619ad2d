r"""Closed loops through ball joints (`lc.Loop` in an `lc.Tree` with `lc.Spherical`), through the public API.

The mechanism is the spatial four-bar RSSR: a crank turning about z at the base origin O (angle θ, radius a), a
coupler of length b on a ball joint at the crank's tip A (the tree's spherical joint, MRPs σ), a rocker of radius c
turning about x at D = (d, 0, h) (angle φ), and the ball joint at B, where the coupler's far end meets the rocker's
tip, cut (`lc.Loop`, xyz).  Five coordinates, three constraints: two degrees of freedom, the crank's and the
coupler's spin about its own axis.

Its input-output relation, derived here: A = a (cos θ, sin θ, 0), B = (d, c cos φ, h + c sin φ), and |B − A| = b
expands to

    P cos φ + Q sin φ = R,   P = −2ac sin θ,   Q = 2hc,   R = b² − a² − c² − d² − h² + 2ad cos θ,

so φ = atan2(Q, P) ± arccos(R / √(P² + Q²)).  The reference is the same mechanism as an `lc.System` (the
Lagrangian path) in the same coordinates, written here by hand: rotations from the unit quaternion of σ
(q₀ = (1 − s)/(1 + s), q_v = 2σ/(1 + s), s = σ·σ), the coupler's body rate from quaternion kinematics
ω = 2 (q₀ q̇_v − q̇₀ q_v − q_v × q̇_v), T = Σ ½ m |Ġ|² + ½ ωᵀ I ω, and the cut joint as three `lc.Holonomic`.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from random_systems import python_kernels
from scipy.spatial.transform import Rotation
from test_multibody_loops import motion

import lagcomp as lc
from lagcomp.multibody import mrp

a, b, c, d, h, g = sp.symbols("a b c d h g", positive=True)
m1, m2, m3, I1, J1, J2, K1 = sp.symbols("m1 m2 m3 I1 J1 J2 K1", positive=True)
#: b² ≈ a² + c² + d² + h² and ad < ch: |R| < √(P² + Q²) at every θ, the crank turns all the way round.
DEFAULTS = {"a": 0.2, "b": 0.81, "c": 0.45, "d": 0.5, "h": 0.4, "g": 9.81, "m1": 1.0, "m2": 0.8, "m3": 0.6,
            "I1": 0.01, "J1": 0.004, "J2": 0.035, "K1": 0.012}


def rssr_tree(q0=None, qd0=None) -> lc.Tree:
    """The RSSR four-bar as a tree plus the cut ball joint at B (module docstring)."""
    return lc.Tree([
        lc.Link("crank", lc.Revolute("theta"), mass=m1, com=(a / 2, 0, 0), inertia=(I1 / 4, I1, I1)),
        lc.Link("coupler", lc.Spherical(("s1", "s2", "s3"), origin=(a, 0, 0)), parent="crank", mass=m2,
                com=(b / 2, 0, 0), inertia=(J1, J2, J2 * 1.1)),
        lc.Link("rocker", lc.Revolute("phi", axis="x", origin=(d, 0, h)), mass=m3, com=(0, c / 2, 0),
                inertia=(K1, K1 / 3, K1)),
    ], gravity=(0, 0, -g), name="rssr", defaults=DEFAULTS, q0=q0, qd0=qd0,
        loops=[lc.Loop("ball", ("coupler", (b, 0, 0)), ("rocker", (0, c, 0)))])


def _quaternion(sigma):
    """(q₀, q_v) of the MRPs σ (sympy)."""
    s = sum(x**2 for x in sigma)
    return (1 - s) / (1 + s), sp.Matrix([2 * x / (1 + s) for x in sigma])


def _turn(q0, qv) -> sp.Matrix:
    """The rotation matrix (x_parent = R x_body) of the unit quaternion (q₀, q_v)."""
    skew = sp.Matrix([[0, -qv[2], qv[1]], [qv[2], 0, -qv[0]], [-qv[1], qv[0], 0]])
    return (q0**2 - (qv.T * qv)[0]) * sp.eye(3) + 2 * qv * qv.T + 2 * q0 * skew


def rssr_system() -> lc.System:
    """The RSSR four-bar on the Lagrangian path, in the tree's coordinates (module docstring)."""
    theta, phi, *sigma = lc.coordinates("theta phi s1 s2 s3")
    q0, qv = _quaternion(sigma)
    q0_dot, qv_dot = q0.diff(lc.t), qv.diff(lc.t)
    crank = sp.Matrix([[sp.cos(theta), -sp.sin(theta), 0], [sp.sin(theta), sp.cos(theta), 0], [0, 0, 1]])
    rocker = sp.Matrix([[1, 0, 0], [0, sp.cos(phi), -sp.sin(phi)], [0, sp.sin(phi), sp.cos(phi)]])
    turn = _turn(q0, qv)
    coupler = crank * turn
    A, D = crank * sp.Matrix([a, 0, 0]), sp.Matrix([d, 0, h])
    centres = [crank * sp.Matrix([a / 2, 0, 0]), A + coupler * sp.Matrix([b / 2, 0, 0]),
               D + rocker * sp.Matrix([0, c / 2, 0])]
    rates = [sp.Matrix([0, 0, theta.diff(lc.t)]),
             turn.T * sp.Matrix([0, 0, theta.diff(lc.t)]) + 2 * (q0 * qv_dot - q0_dot * qv - qv.cross(qv_dot)),
             sp.Matrix([phi.diff(lc.t), 0, 0])]
    inertias = [sp.diag(I1 / 4, I1, I1), sp.diag(J1, J2, J2 * 1.1), sp.diag(K1, K1 / 3, K1)]
    T = sum((m * G.diff(lc.t).dot(G.diff(lc.t)) / 2 + (w.T * I * w)[0] / 2
             for m, G, w, I in zip((m1, m2, m3), centres, rates, inertias)), sp.S.Zero)
    V = sum((m * g * G[2] for m, G in zip((m1, m2, m3), centres)), sp.S.Zero)
    gap = A + coupler * sp.Matrix([b, 0, 0]) - (D + rocker * sp.Matrix([0, c, 0]))
    return lc.System((theta, sigma[0], sigma[1], sigma[2], phi), T=T, V=V, name="rssr_lagrange",
                     defaults=DEFAULTS, parameters=rssr_tree().parameters,
                     constraints=[lc.Holonomic(f"ball_{axis}", gap[k]) for k, axis in enumerate("xyz")])


def rocker_angle(theta: float, p: dict, branch: int = 1) -> float:
    """φ(θ) of the input-output relation (module docstring), on the branch `branch` (±1)."""
    P, Q = -2 * p["a"] * p["c"] * math.sin(theta), 2 * p["h"] * p["c"]
    R = (p["b"]**2 - p["a"]**2 - p["c"]**2 - p["d"]**2 - p["h"]**2 + 2 * p["a"] * p["d"] * math.cos(theta))
    return math.atan2(Q, P) + branch * math.acos(R / math.hypot(P, Q))


def closure_error(theta, phi, p: dict):
    """P cos φ + Q sin φ − R (module docstring), arrays allowed."""
    P, Q = -2 * p["a"] * p["c"] * np.sin(theta), 2 * p["h"] * p["c"]
    R = p["b"]**2 - p["a"]**2 - p["c"]**2 - p["d"]**2 - p["h"]**2 + 2 * p["a"] * p["d"] * np.cos(theta)
    return P * np.cos(phi) + Q * np.sin(phi) - R


def assembled(theta: float, spin: float, p: dict, shadow: bool = False) -> np.ndarray:
    """q = (θ, σ, φ) on the loop: φ from the closed form, the coupler along B − A turned by `spin` about itself,
    σ the MRPs of its rotation relative to the crank (scipy), or their shadow set."""
    phi = rocker_angle(theta, p)
    A = p["a"] * np.array([math.cos(theta), math.sin(theta), 0.0])
    B = np.array([p["d"], p["c"] * math.cos(phi), p["h"] + p["c"] * math.sin(phi)])
    u = (B - A) / p["b"]
    align, _ = Rotation.align_vectors([u], [[1.0, 0.0, 0.0]])
    relative = Rotation.from_euler("z", theta).inv() * align * Rotation.from_euler("x", spin)
    sigma = relative.as_mrp()
    if shadow:
        sigma = -sigma / sigma.dot(sigma)
    return np.array([theta, *sigma, phi])


@pytest.fixture(scope="module")
def models(cache_dir):
    """(the tree's model, the Lagrangian model)."""
    return lc.compile(rssr_tree(), cache_dir=cache_dir), lc.compile(rssr_system(), cache_dir=cache_dir)


def plain_python(model) -> dict:
    """The eager kernels of `model` run as plain Python (`random_systems.python_kernels`): the Lagrangian reference's,
    which numba need not compile (the same emitted code; its compiled kernels are other files' subject)."""
    return python_kernels(model.source_path.read_text(encoding="utf-8"))


def kernel_rows(model, y, params=None, kernels=None):
    """(Φ, Λ q̇, Λ) of `model` at `y`, by its numba kernels or the plain-Python `kernels` (`plain_python`)."""
    p = model.parameter_vector(params)
    residuals, matrix = np.zeros(2 * model.k), np.zeros((model.k, model.n + 1))
    call = (lambda name: getattr(model.kernels, name)) if kernels is None else kernels.__getitem__
    call("constraint_residuals")(0.0, y, p, residuals)
    call("constraint_matrix")(0.0, y, p, matrix)
    return residuals[:model.k], residuals[model.k:], matrix[:, :model.n]


def consistent_state(model, q, rates, params=None, kernels=None) -> np.ndarray:
    """(q, q̇) with q̇ the projection of `rates` onto the null space of Λ(q) (Λ q̇ = 0)."""
    _, _, L = kernel_rows(model, np.concatenate([q, np.zeros(q.size)]), params, kernels)
    null = np.linalg.svd(L)[2][L.shape[0]:]
    return np.concatenate([q, null.T @ (null @ rates)])


def relative(x, reference) -> float:
    return float(np.max(np.abs(x - reference)) / np.max(np.abs(reference)))


def test_assembled_states_close_the_loop(models):
    """Φ of the tree's kernels vanishes (1e-14 m) at the closed form's states, on both MRP sets of the coupler."""
    tree, _ = models
    for theta in np.linspace(0.0, 2 * math.pi, 13):
        for shadow in (False, True):
            q = assembled(theta, 0.7, DEFAULTS, shadow)
            Phi, _, _ = kernel_rows(tree, np.concatenate([q, np.zeros(5)]))
            assert np.max(np.abs(Phi)) <= 1e-14


def test_the_tree_matches_the_lagrangian_path(models):
    """q̈ and λ agree to 1e-12 relative with the hand-written Lagrange module, at consistent states (on the loop,
    Λ q̇ = 0) and off the loop with Baumgarte terms, at parameters about the defaults (lengths
    ±3 %: the crank still turns all the way round; the others ±30 %).  The Lagrange module runs as plain Python."""
    tree, lagrange = models
    reference = plain_python(lagrange)
    assert tree.constraints == lagrange.constraints == ("ball_x", "ball_y", "ball_z")
    assert list(tree.coordinates) == list(lagrange.coordinates)   # (θ, σ1, σ2, σ3, φ): the tree's node order
    rng = np.random.default_rng(3)
    for trial in range(16):
        params = {k: v * rng.uniform(0.97, 1.03) if k in "abcdh" else v * rng.uniform(0.7, 1.3)
                  for k, v in DEFAULTS.items()}
        q = assembled(rng.uniform(0, 2 * math.pi), rng.uniform(-math.pi, math.pi), params, shadow=trial % 4 == 3)
        y = consistent_state(lagrange, q, rng.uniform(-3, 3, 5), params, reference)
        gains = (0.0, 0.0)
        if trial % 2:   # off the loop: Φ ≠ 0, Λ q̇ ≠ 0, with Baumgarte gains
            y = y + np.concatenate([rng.uniform(-0.02, 0.02, 5), rng.uniform(-0.5, 0.5, 5)])
            gains = tuple(rng.uniform(0, 4, 2))
        qdd_tree, lam_tree = motion(tree, y, gains, params)
        qdd, lam = motion(lagrange, y, gains, params, reference)
        assert relative(qdd_tree, qdd) <= 1e-12
        assert relative(lam_tree, lam) <= 1e-12


def test_the_shadow_switch_leaves_the_loop_where_it_was(models):
    """The coupler's MRPs and rates replaced by their shadow set (what the ``coupler_shadow`` event's reset does):
    Φ, Λ q̇, λ, θ̈ and φ̈ unchanged (1e-12), and the coupler's angular acceleration J σ̈ + J̇ σ̇ the same from
    either set: the constraints depend on the rotation and the angular velocity only."""
    tree, _ = models
    rng = np.random.default_rng(5)
    for _ in range(6):
        q = assembled(rng.uniform(0, 2 * math.pi), rng.uniform(-math.pi, math.pi), DEFAULTS)
        y = consistent_state(tree, q, rng.uniform(-3, 3, 5))
        y = y + np.concatenate([rng.uniform(-0.01, 0.01, 5), rng.uniform(-0.3, 0.3, 5)])   # (off the loop too)
        sigma, rates = mrp.shadow(y[1:4], y[6:9])
        switched = y.copy()
        switched[1:4], switched[6:9] = sigma, rates
        before, after = kernel_rows(tree, y), kernel_rows(tree, switched)
        for x, x_switched in zip(before[:2], after[:2]):
            assert np.max(np.abs(x - x_switched)) <= 1e-12
        (qdd, lam), (qdd_s, lam_s) = motion(tree, y, (1.0, 2.0)), motion(tree, switched, (1.0, 2.0))
        assert relative(lam_s, lam) <= 1e-12
        assert relative(qdd_s[[0, 4]], qdd[[0, 4]]) <= 1e-12
        turn = [np.add(mrp.jacobian_times(s, x), mrp.rate_product(s, r))
                for s, r, x in ((y[1:4], y[6:9], qdd[1:4]), (switched[1:4], switched[6:9], qdd_s[1:4]))]
        assert relative(turn[1], turn[0]) <= 1e-12


def start(model, spin_rate: float, params=None) -> np.ndarray:
    """A state on the loop (Λ q̇ = 0) with the crank at 1 rad/s and the coupler spinning at about `spin_rate` about
    itself."""
    q = assembled(0.3, 0.2, DEFAULTS if params is None else params)
    _, _, L = kernel_rows(model, np.concatenate([q, np.zeros(5)]), params)
    null = np.linalg.svd(L)[2][L.shape[0]:]
    # the null space's combination with θ̇ = 1 and the coupler's rate along its own x axis = spin_rate
    sigma = q[1:4]
    rows = np.array([[v[0], *np.array(mrp.jacobian_times(sigma, v[1:4]))[[0]]] for v in null])
    coefficients = np.linalg.solve(rows.T, [1.0, spin_rate])
    return np.concatenate([q, null.T @ coefficients])


def test_radau_runs_the_loop_as_a_dae(models):
    """radau (the DAE, no projection, rtol 1e-10) against dop853 at 1e-13: states to 1e-8 of their largest entry,
    the loop closed (residual ≤ 1e-9, the closed form's P cos φ + Q sin φ − R ≤ 1e-9 m²), the energy kept (1e-8
    relative).  radau's events cannot reset: both runs keep the one MRP set, past |σ| = 1 (a half turn of the
    coupler relative to the crank; the set is singular at a full turn only)."""
    tree, _ = models
    y0 = start(tree, 2.0)
    ts = np.linspace(0.0, 2.0, 41)
    options = {"q0": y0[:5], "qd0": y0[5:], "t_eval": ts, "events": False}
    run = tree.simulate((0.0, 2.0), method="radau", rtol=1e-10, atol=1e-10, **options)
    tight = tree.simulate((0.0, 2.0), method="dop853", rtol=1e-13, atol=1e-13, **options)
    assert run.success and tight.success, (run.message, tight.message)
    assert run.q[-1, 0] - run.q[0, 0] > math.pi   # (the crank turns: not a trivial run)
    assert 1 < np.max(np.linalg.norm(run.q[:, 1:4], axis=1)) < 3
    assert np.max(np.abs(run.y - tight.y)) <= 1e-8 * np.max(np.abs(tight.y))
    assert run.constraint_residual <= 1e-9
    assert np.max(np.abs(closure_error(run.q[:, 0], run.q[:, 4], DEFAULTS))) <= 1e-9
    energy = run.energy
    assert np.max(np.abs(energy - energy[0])) <= 1e-8 * np.max(np.abs(energy))
    for name in tree.constraints:
        assert relative(run.reactions[name], tight.reactions[name]) <= 1e-7


def test_a_spinning_coupler_switches_its_mrps_and_the_loop_stays_closed(models):
    """dop853 with the shadow switches (the coupler spinning at ~12 rad/s passes a half turn every ~¼ s): every
    switch keeps |σ| ≤ 1, the loop stays closed (residual and the closed form ≤ 1e-9) and the energy is kept
    (1e-9 relative) without projection."""
    tree, _ = models
    y0 = start(tree, 12.0)
    run = tree.simulate((0.0, 3.0), q0=y0[:5], qd0=y0[5:], method="dop853", rtol=1e-12, atol=1e-12,
                        t_eval=np.linspace(0.0, 3.0, 301))
    assert run.success, run.message
    assert len(run.events["coupler_shadow"].t) >= 6
    assert np.max(np.linalg.norm(run.q[:, 1:4], axis=1)) <= 1 + 1e-9
    assert run.constraint_residual <= 1e-9
    assert np.max(np.abs(closure_error(run.q[:, 0], run.q[:, 4], DEFAULTS))) <= 1e-9
    energy = run.energy
    assert np.max(np.abs(energy - energy[0])) <= 1e-9 * np.max(np.abs(energy))


def test_a_ball_joint_beside_a_loop_moves_as_without_it(cache_dir):
    """A ball-jointed pendulum beside an arm held on a rail (the loop): nothing couples them, so the pendulum's
    σ̈ is the open tree's (the pendulum alone, the articulated-body algorithm) to 1e-12 at random states, and the
    arm's θ̈ and the rail's force those of the arm alone.  (Before the loops' augmented system was written in the
    coordinates, the pendulum's σ̈ here was its body-rate acceleration, not σ̈: the case was refused.)"""
    ball = lc.Link("ball", lc.Spherical(("s1", "s2", "s3")), mass=1.0, com=(0.1, 0.2, -0.5),
                   inertia=(0.02, 0.03, 0.04))
    arm = lc.Link("arm", lc.Revolute("th", origin=(2, 0, 0)), mass=1.0, com=(0.5, 0, 0), inertia=(0.01, 0.1, 0.1))
    rail = [lc.Loop("rail", ("arm", (1, 0, 0)), (None, (0, -0.5, 0)), directions="y")]
    both = lc.compile(lc.Tree([ball, arm], gravity=(0, -9.81, 0), name="ball_beside_a_loop", loops=rail),
                      cache_dir=cache_dir)
    alone = lc.compile(lc.Tree([ball], gravity=(0, -9.81, 0), name="ball_alone"), cache_dir=cache_dir)
    arm_alone = lc.compile(lc.Tree([arm], gravity=(0, -9.81, 0), name="arm_on_its_rail", loops=rail),
                           cache_dir=cache_dir)
    rng = np.random.default_rng(9)
    for _ in range(10):
        y = np.concatenate([rng.uniform(-0.8, 0.8, 3), rng.uniform(-1, 1, 1), rng.uniform(-2, 2, 4)])
        qdd, lam = motion(both, y, (1.0, 2.0))
        ball_state = y[[0, 1, 2, 4, 5, 6]]
        out = np.zeros(6)
        assert alone.kernels.rhs(0.0, ball_state, alone.parameter_vector(), out) == 0
        assert relative(qdd[:3], out[3:]) <= 1e-12
        qdd_arm, lam_arm = motion(arm_alone, y[[3, 7]], (1.0, 2.0))
        assert abs(qdd[3] - qdd_arm[0]) <= 1e-12 * abs(qdd_arm[0]) and abs(lam[0] - lam_arm[0]) <= 1e-12 * abs(lam_arm[0])


def test_a_free_body_held_at_a_point_moves_as_on_a_ball_joint(cache_dir):
    """A free body (`lc.Free`: three slides, then a ball joint) whose point p_b is held at the base point P0 by a
    loop (xyz) is the body on a ball joint at P0 (the open tree, the articulated-body algorithm): at the states
    where the loop is closed (x = P0 − R p_b, ẋ = −R (ω × p_b)) its σ̈ is the ball joint's to 1e-12, and λ, the
    force the base exerts on the body at the pivot, is Newton's m (a_G − g) of the ball joint's motion."""
    mass, com, inertia = 1.3, np.array([0.1, -0.2, 0.4]), (0.05, 0.07, 0.04)
    pivot, hold = np.array([0.3, -0.1, 0.2]), np.array([0.05, 0.1, -0.15])
    gravity = np.array([0.0, 0.0, -9.81])
    free = lc.compile(lc.Tree([lc.Link("body", lc.Free(("x", "y", "z", "s1", "s2", "s3")), mass=mass,
                                       com=tuple(com), inertia=inertia)], gravity=tuple(gravity), name="held_free_body",
                              loops=[lc.Loop("pivot", ("body", tuple(hold)), (None, tuple(pivot)))]),
                      cache_dir=cache_dir)
    ball = lc.compile(lc.Tree([lc.Link("body", lc.Spherical(("s1", "s2", "s3"), origin=tuple(pivot)), mass=mass,
                                       com=tuple(com - hold), inertia=inertia)], gravity=tuple(gravity),
                              name="ball_jointed_body"), cache_dir=cache_dir)
    rng = np.random.default_rng(13)
    for _ in range(10):
        sigma, rates = rng.uniform(-0.6, 0.6, 3), rng.uniform(-2, 2, 3)
        R = Rotation.from_mrp(sigma).as_matrix()
        omega = np.array(mrp.jacobian_times(sigma, rates))
        y = np.concatenate([pivot - R @ hold, sigma, -R @ np.cross(omega, hold), rates])
        qdd, lam = motion(free, y)
        out = np.zeros(6)
        assert ball.kernels.rhs(0.0, np.concatenate([sigma, rates]), ball.parameter_vector(), out) == 0
        assert relative(qdd[3:], out[3:]) <= 1e-12
        alpha = np.add(mrp.jacobian_times(sigma, out[3:]), mrp.rate_product(sigma, rates))
        r = com - hold
        a_G = R @ (np.cross(alpha, r) + np.cross(omega, np.cross(omega, r)))
        assert relative(lam, mass * (a_G - gravity)) <= 1e-12
