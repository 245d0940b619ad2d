"""Reactions of the constrained examples, compiled and run, against Newton's laws and closed forms."""

from __future__ import annotations

import numpy as np
import pytest
from test_examples_constrained_symbolic import _disc_state, disc_qdd_reference

from lagcomp.examples.constrained import free_axle_closed_form, spherical_to_cartesian

TIGHT = dict(method="dop853", rtol=1e-12, atol=1e-12)


def test_hoop_push_from_the_released_drive_angle(compiled):
    model = compiled("hoop_bead_reaction")
    d = model.system.defaults
    m, R, W, eps = d["m"], d["R"], d["Omega"], d["epsilon"]
    ts = np.linspace(0, 10, 201)
    sol = model.simulate((0, 10), t_eval=ts, **TIGHT)
    assert sol.success and sol.constraint_residual < 1e-8
    theta, phi = sol.q.T
    theta_dot, phi_dot = sol.qd.T
    np.testing.assert_allclose(phi, W * ts + eps * np.sin(2 * ts), rtol=0, atol=1e-9)
    phi_ddot = -4 * eps * np.sin(2 * ts)
    push = m * R * (2 * phi_dot * theta_dot * np.cos(theta) + phi_ddot * np.sin(theta))
    expected = R * np.sin(theta) * push  # λ is the generalized force along φ: the torque R sin θ · f
    lam = sol.reactions["drive"]
    away_from_zeros = np.abs(expected) > 1e-3 * np.max(np.abs(expected))
    np.testing.assert_allclose(lam[away_from_zeros], expected[away_from_zeros], rtol=1e-8)
    # θ(t) is that of the model where φ(t) is imposed directly
    plain = compiled("hoop_bead").simulate((0, 10), q0=[theta[0]], qd0=[theta_dot[0]], t_eval=ts, **TIGHT)
    np.testing.assert_allclose(theta, plain.q[:, 0], rtol=0, atol=1e-8)


def test_unbalanced_cylinder_reactions_obey_newton_for_the_centre_of_mass(compiled):
    model = compiled("unbalanced_cylinder_reactions")
    d = model.system.defaults
    M, a, g = d["M"], d["a"], d["g"]
    ts = np.linspace(0, 10, 401)
    sol = model.simulate((0, 10), t_eval=ts, **TIGHT)
    assert sol.success and sol.constraint_residual < 1e-9
    theta, theta_dot = sol.q[:, 2], sol.qd[:, 2]
    qdd = np.array([model.rhs(t, y)[model.n:] for t, y in zip(sol.t, sol.y)])
    x_dd, z_dd, theta_dd = qdd.T
    # G = (x − a sin θ, z − a cos θ): differentiate twice
    xG_dd = x_dd - a * np.cos(theta) * theta_dd + a * np.sin(theta) * theta_dot**2
    zG_dd = z_dd + a * np.sin(theta) * theta_dd + a * np.cos(theta) * theta_dot**2
    np.testing.assert_allclose(sol.reactions["normal"], M * (g + zG_dd), rtol=1e-8)
    F_h = sol.reactions["friction"]
    np.testing.assert_allclose(F_h, M * xG_dd, rtol=1e-8, atol=1e-8 * np.max(np.abs(F_h)))
    assert sol.energy_drift() < 1e-9
    # and θ(t) is that of the model with the rolling constraint eliminated by hand
    rolled = compiled("unbalanced_cylinder").simulate((0, 10), t_eval=ts, **TIGHT)
    np.testing.assert_allclose(theta, rolled.q[:, 0], rtol=0, atol=1e-8)


@pytest.mark.parametrize("V0, omega", [(1.0, 1.0), (0.5, -2.0)])
def test_free_axle_follows_its_closed_form(compiled, V0, omega):
    model = compiled("free_axle", V0=V0, omega=omega)
    ts = np.linspace(0, 20, 201)
    sol = model.simulate((0, 20), t_eval=ts, **TIGHT)
    assert sol.success
    exact = free_axle_closed_form(ts, model.system.defaults, V0, omega)
    for j, name in enumerate(model.coordinates):
        # measured: 2.8e-12 (Y, relative to 1 + max|Y|)
        np.testing.assert_allclose(sol.q[:, j], exact[name], rtol=0, atol=1e-11 * (1 + np.max(np.abs(exact[name]))))
    np.testing.assert_allclose(sol.q[:, 2], omega * ts, rtol=1e-12, atol=1e-10)  # θ = ωt
    for name in ("roll_X", "roll_Y"):
        np.testing.assert_allclose(sol.reactions[name], exact[name], rtol=0, atol=2e-13)  # measured 5.2e-14
    np.testing.assert_allclose(sol.reactions["steer"], 0.0, atol=1e-15)  # measured 0.0


@pytest.mark.parametrize("name, t_end", [("rolling_disc", 50.0), ("chaplygin_sleigh", 200.0)])
def test_nonholonomic_examples_conserve_energy_and_keep_their_constraints(compiled, name, t_end):
    model = compiled(name)
    sol = model.simulate((0, t_end), save_every=10, **TIGHT)
    assert sol.success
    assert sol.energy_drift() < 1e-9
    assert sol.constraint_residual < 1e-9


def test_rolling_disc_accelerations_equal_kanes_method(compiled, rng):
    model = compiled("rolling_disc")
    params = model.system.defaults
    for _ in range(8):
        q, qd = _disc_state(rng, params["r"])
        ours = model.rhs(0.0, np.concatenate([q, qd]))[model.n:]
        np.testing.assert_allclose(ours, disc_qdd_reference(params, q, qd), rtol=1e-10, atol=1e-10)


def test_spherical_pendulum_rod_tension(compiled):
    cartesian, angles = compiled("spherical_pendulum_cartesian"), compiled("spherical_pendulum")
    d = cartesian.system.defaults
    m, l, g = d["m"], d["l"], d["g"]
    ts = np.linspace(0, 10, 201)
    ref = angles.simulate((0, 10), t_eval=ts, **TIGHT)
    sol = cartesian.simulate((0, 10), t_eval=ts, **TIGHT)
    expected = np.array([np.concatenate(spherical_to_cartesian(*row[[0, 1]], *row[[2, 3]], l))
                         for row in np.hstack([ref.q, ref.qd])])
    np.testing.assert_allclose(sol.y, expected, rtol=0, atol=1e-8)
    # Φ = x² + y² + z² − l²: Λ = 2r, the rod pulls the bob with 2λ r, tension N = −2λ l
    speed2 = np.sum(sol.qd**2, axis=1)
    newton = m * (speed2 / l - g * sol.q[:, 2] / l)
    np.testing.assert_allclose(-2 * l * sol.reactions["rod"], newton, rtol=1e-9)


def test_constrained_examples_run_from_the_command_line(capsys, cache_dir):
    from lagcomp.cli import main

    code = main(["--cache-dir", str(cache_dir), "run", "free_axle", "--t-end", "2"])
    out = capsys.readouterr().out
    assert code == 0 and "status 0" in out
    for name in ("roll_X", "roll_Y", "steer"):
        assert f"reaction    {name}:" in out
    assert "largest constraint residual" in out
