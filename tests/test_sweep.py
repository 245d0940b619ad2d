"""Sweeps: the same trajectories as separate `simulate` calls, whatever the number of threads."""

from __future__ import annotations

import os
import signal
import threading

import numpy as np
import pytest

from lagcomp.errors import InitialConditionError, OptionError
from lagcomp.integrate.sweep import Sweep


@pytest.fixture(scope="module")
def double_pendulum(compiled):
    return compiled("double_pendulum")


GRID = {"theta1": np.linspace(-3, 3, 12), "theta2": np.linspace(-3, 3, 10)}


def _separately(model, sweep, **options):
    """Final states of one `simulate` call per grid point."""
    finals = np.empty_like(sweep.final)
    for i, a in enumerate(GRID["theta1"]):
        for j, b in enumerate(GRID["theta2"]):
            sol = model.simulate((0, 10), q0=[a, b], qd0=[0.0, 0.0], **options)
            finals[i, j] = np.r_[sol.q[-1], sol.qd[-1]]
    return finals


@pytest.mark.parametrize("options", [dict(method="rk4", dt=0.01), dict(method="dop853", rtol=1e-9, atol=1e-9)],
                         ids=["rk4", "dop853"])
def test_sweep_equals_separate_runs_bitwise_for_any_thread_count(double_pendulum, options):
    one = double_pendulum.sweep((0, 10), GRID, qd0=[0, 0], workers=1, **options)
    two = double_pendulum.sweep((0, 10), GRID, qd0=[0, 0], workers=2, **options)
    assert one.shape == (12, 10) and one.final.shape == (12, 10, 4)
    assert np.all(one.status == 0) and one.done.all()
    np.testing.assert_array_equal(one.final, two.final)
    np.testing.assert_array_equal(one.nsteps, two.nsteps)
    np.testing.assert_array_equal(one.final, _separately(double_pendulum, one, **options))
    np.testing.assert_array_equal(one.t_final, 10.0)


def test_zip_and_explicit_grids_and_swept_parameters(double_pendulum):
    zipped = double_pendulum.sweep((0, 2), {"theta1": [0.1, 0.2, 0.3], "g": [1.0, 9.81, 20.0]}, combine="zip",
                                   method="rk4", dt=0.01)
    explicit = double_pendulum.sweep((0, 2), np.array([[0.1, 1.0], [0.2, 9.81], [0.3, 20.0]]),
                                     names=["theta1", "g"], method="rk4", dt=0.01)
    np.testing.assert_array_equal(zipped.final, explicit.final)
    for k, (theta1, g) in enumerate([(0.1, 1.0), (0.2, 9.81), (0.3, 20.0)]):
        q0 = list(double_pendulum.system.q0)
        q0[0] = theta1
        sol = double_pendulum.simulate((0, 2), q0=q0, params={"g": g}, method="rk4", dt=0.01)
        np.testing.assert_array_equal(zipped.final[k], np.r_[sol.q[-1], sol.qd[-1]])


def test_dense_output_and_energy_match_simulate(double_pendulum):
    t_eval = np.linspace(0, 5, 11)
    sweep = double_pendulum.sweep((0, 5), {"theta1_dot": [0.0, 1.0, 2.0]}, t_eval=t_eval, rtol=1e-10, atol=1e-10,
                                  output=("dense", "energy"))
    assert sweep.dense.shape == (3, 11, 4)
    for k, rate in enumerate([0.0, 1.0, 2.0]):
        qd0 = [rate, double_pendulum.system.qd0[1]]
        sol = double_pendulum.simulate((0, 5), qd0=qd0, t_eval=t_eval, rtol=1e-10, atol=1e-10)
        np.testing.assert_array_equal(sweep.dense[k], np.hstack([sol.q, sol.qd]))
        assert sweep.energy_error[k] == pytest.approx(sol.energy_drift(), rel=1e-12, abs=0)


def test_fixed_step_dense_rows_follow_save_every(double_pendulum):
    sweep = double_pendulum.sweep((0, 1), {"theta1": [0.5, 1.0]}, method="rk4", dt=0.01, save_every=30,
                                  output="dense")
    sol = double_pendulum.simulate((0, 1), q0=[0.5, double_pendulum.system.q0[1]], method="rk4", dt=0.01,
                                   save_every=30)
    np.testing.assert_array_equal(sweep.t_dense, sol.t)
    np.testing.assert_array_equal(sweep.dense[0], np.hstack([sol.q, sol.qd]))


def test_poincare_crossings_per_trajectory(compiled):
    model = compiled("henon_heiles")
    ys = np.array([0.05, 0.1, 0.15])
    energy = 1 / 12
    xdot = np.sqrt(2 * (energy - ys**2 / 2 + ys**3 / 3))
    sweep = model.sweep((0, 300), {"y": ys, "x_dot": xdot}, combine="zip", rtol=1e-11, atol=1e-11,
                        output="events", event_cap=100, events=["section"])
    for k in range(3):
        sol = model.simulate((0, 300), q0=[0, ys[k]], qd0=[xdot[k], 0], rtol=1e-11, atol=1e-11, events=["section"])
        record = sol.events["section"]
        count = sweep.events["section"]["count"][k]
        assert count == len(record) > 40
        np.testing.assert_array_equal(sweep.events["section"]["t"][k, :count], record.t)
        assert np.all(np.isnan(sweep.events["section"]["t"][k, count:]))


def test_memory_estimate_refuses_before_running(double_pendulum):
    grid = {"theta1": np.linspace(0, 1, 1000), "theta2": np.linspace(0, 1, 1000)}
    with pytest.raises(OptionError, match=r"need \d+\.\d MiB .* above the limit of 1\.0 MiB"):
        double_pendulum.sweep((0, 1), grid, method="rk4", dt=0.01, memory_limit=2**20)
    with pytest.raises(OptionError, match="MiB"):
        double_pendulum.sweep((0, 1), {"theta1": [0.0]}, t_eval=np.linspace(0, 1, 10**6), output="dense",
                              memory_limit=2**20)


def test_bad_grids_are_refused(double_pendulum):
    with pytest.raises(OptionError, match="grid names"):
        double_pendulum.sweep((0, 1), {"omega": [1.0]}, method="rk4", dt=0.1)
    with pytest.raises(OptionError, match="one length"):
        double_pendulum.sweep((0, 1), {"theta1": [1.0, 2.0], "g": [1.0]}, combine="zip", method="rk4", dt=0.1)
    with pytest.raises(OptionError, match="non-finite"):
        double_pendulum.sweep((0, 1), {"theta1": [np.nan]}, method="rk4", dt=0.1)
    with pytest.raises(OptionError, match="Unknown sweep output"):
        double_pendulum.sweep((0, 1), {"theta1": [1.0]}, method="rk4", dt=0.1, output="everything")


def test_ctrl_c_keeps_the_finished_chunks(double_pendulum):
    grid = {"theta1": np.linspace(-3, 3, 400), "theta2": np.linspace(-3, 3, 50)}   # 2e7 RK4 steps: far over 1 s
    timer = threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        sweep = double_pendulum.sweep((0, 10), grid, qd0=[0, 0], method="rk4", dt=0.001, progress=False)
    finally:
        timer.cancel()
    assert sweep.interrupted and 0 < sweep.done.sum() < sweep.done.size
    assert np.all(sweep.status[sweep.done] == 0) and np.all(sweep.status[~sweep.done] == 2)
    assert np.all(np.isnan(sweep.final[~sweep.done]))


def test_save_and_load_round_trip(double_pendulum, tmp_path):
    sweep = double_pendulum.sweep((0, 1), {"theta1": [0.1, 0.2], "g": [9.0, 9.81, 10.0]}, method="rk4", dt=0.01,
                                  output="energy")
    sweep.save_npz(tmp_path / "sweep.npz")
    loaded = Sweep.load_npz(tmp_path / "sweep.npz")
    assert loaded.names == sweep.names and loaded.shape == sweep.shape == (2, 3)
    assert loaded.combine == "product" and loaded.method == "rk4"
    np.testing.assert_array_equal(loaded.final, sweep.final)
    np.testing.assert_array_equal(loaded.axes["g"], [9.0, 9.81, 10.0])
    np.testing.assert_array_equal(loaded.energy_error, sweep.energy_error)


def test_kapitza_map_finds_the_stability_boundary_of_the_inverted_pendulum(compiled):
    """Vibrated support h = A cos Ωt: upside down is stable when A²Ω² > 2 g l (the averaged potential
    −(g/l) cos θ + (AΩ/2l)² sin²θ has a minimum at θ = π).  Sweep the amplitude across the boundary,
    start 0.05 rad from upright, and call a run stable when it never leaves by more than 0.5 rad."""
    model = compiled("driven_pendulum")
    g, l, omega = 9.81, 1.0, 200.0
    amplitudes = np.arange(0.016, 0.0285, 0.001)
    t_eval = np.linspace(0, 20, 2001)
    sweep = model.sweep((0, 20), {"A": amplitudes}, q0=[np.pi - 0.05], qd0=[0.0],
                        params={"g": g, "l": l, "Omega": omega}, t_eval=t_eval, rtol=1e-9, atol=1e-9,
                        output="dense")
    assert np.all(sweep.status == 0)
    stable = np.max(np.abs(sweep.dense[:, :, 0] - np.pi), axis=1) < 0.5
    assert not stable[0] and stable[-1]
    first_stable = np.argmax(stable)
    assert np.all(stable[first_stable:]) and not np.any(stable[:first_stable])  # one boundary
    boundary = np.sqrt(2 * g * l) / omega
    assert amplitudes[first_stable - 1] <= boundary + 0.001 and amplitudes[first_stable] >= boundary - 0.001


def test_dask_local_cluster_gives_the_local_result_compiling_once_per_worker(double_pendulum):
    """Two worker processes load the module from its source (not pickled numba objects), compile or load it
    once each, and return exactly the local result; a second sweep reuses the loaded kernels.  Radau's Jacobian
    is on demand: the workers load the eager module, then the Jacobians' companion, which imports ``rhs`` from
    it by name."""
    distributed = pytest.importorskip("distributed")
    grid = {"theta1": np.linspace(-2, 2, 9), "g": [9.0, 9.81]}
    local = double_pendulum.sweep((0, 3), grid, method="rk4", dt=0.01, output="energy")
    taylor = dict(method="taylor", rtol=1e-8, atol=1e-8, batched=True)    # a module of its own (taylor_lanes)
    local_taylor = double_pendulum.sweep((0, 3), grid, **taylor)
    radau = dict(method="radau", rtol=1e-8, atol=1e-8)     # an on-demand kernel: the Jacobians' companion module
    local_radau = double_pendulum.sweep((0, 1), grid, **radau)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) \
            as cluster, distributed.Client(cluster) as client:
        remote = double_pendulum.sweep((0, 3), grid, method="rk4", dt=0.01, output="energy", client=client)
        again = double_pendulum.sweep((0, 3), grid, method="rk4", dt=0.01, output="energy", client=client)
        remote_taylor = double_pendulum.sweep((0, 3), grid, client=client, **taylor)
        remote_radau = double_pendulum.sweep((0, 1), grid, client=client, **radau)

        def loaded():   # the eager modules: one per worker that ran a chunk, its rhs compiled once
            from lagcomp.integrate import sweep as module
            return [len(m.rhs.signatures) for m in module._WORKER_MODULES.values()
                    if hasattr(m, "observables") and not hasattr(m, "taylor_lanes")]

        per_worker = client.run(loaded)
    np.testing.assert_array_equal(remote.final, local.final)
    np.testing.assert_array_equal(remote.energy_error, local.energy_error)
    np.testing.assert_array_equal(again.final, local.final)
    np.testing.assert_array_equal(remote_taylor.final, local_taylor.final)
    np.testing.assert_array_equal(remote_radau.final, local_radau.final)
    assert remote.done.all() and remote_taylor.done.all() and remote_radau.done.all()
    assert all(counts in ([], [1]) for counts in per_worker.values()) and [1] in per_worker.values()


def test_to_xarray_names_dimensions_after_the_swept_quantities(double_pendulum):
    pytest.importorskip("xarray")
    sweep = double_pendulum.sweep((0, 1), {"theta1": [0.1, 0.2], "g": [9.0, 9.81, 10.0]}, method="rk4", dt=0.01)
    data = sweep.to_xarray()
    assert data["final"].dims == ("theta1", "g", "state")
    assert data["final"].sel(theta1=0.2, g=9.81, state="theta2_dot").item() == sweep.final[1, 1, 3]
    zipped = double_pendulum.sweep((0, 1), {"theta1": [0.1, 0.2], "g": [9.0, 9.81]}, combine="zip", method="rk4",
                                   dt=0.01).to_xarray()
    assert zipped["final"].dims == ("trajectory", "state") and list(zipped["g"].values) == [9.0, 9.81]


def test_batched_rk4_matches_the_scalar_path(compiled, double_pendulum):
    """SIMD lanes do the scalar arithmetic in the same order, with the same polynomial sin and cos
    (`lagcomp.kernel_support.trig`): bitwise equal, without trigonometry (Hénon–Heiles) and with it."""
    henon = compiled("henon_heiles")
    grid = {"x": np.linspace(-0.3, 0.3, 7), "y": np.linspace(-0.3, 0.3, 11)}   # 77: two blocks, one partial
    scalar = henon.sweep((0, 5), grid, method="rk4", dt=0.01, output=("dense", "energy"), save_every=100)
    lanes = henon.sweep((0, 5), grid, method="rk4", dt=0.01, output=("dense", "energy"), save_every=100,
                        batched=True)
    for key in ("final", "t_final", "status", "nsteps", "dense", "energy_error"):
        np.testing.assert_array_equal(getattr(lanes, key), getattr(scalar, key))
    small = {"theta1": np.linspace(-0.3, 0.3, 9), "theta2": np.linspace(-0.3, 0.3, 5)}
    scalar = double_pendulum.sweep((0, 5), small, method="rk4", dt=0.01, qd0=[0, 0])
    lanes = double_pendulum.sweep((0, 5), small, method="rk4", dt=0.01, qd0=[0, 0], batched=True)
    np.testing.assert_array_equal(lanes.final, scalar.final)
    with pytest.raises(OptionError, match="batched"):
        double_pendulum.sweep((0, 1), small, method="dopri5", batched=True)


def test_batched_dop853_takes_the_scalar_steps(compiled, double_pendulum):
    """Each lane runs dop853_run's step control in the same arithmetic order: the same steps and
    bitwise the same states, on Hénon–Heiles and on the double pendulum (the scalar and the batched
    kernels share their sin and cos polynomials)."""
    henon = compiled("henon_heiles")
    grid = {"x": np.linspace(-0.3, 0.3, 7), "y": np.linspace(-0.3, 0.3, 11)}
    scalar = henon.sweep((0, 20), grid, rtol=1e-10, atol=1e-10, output="energy")
    lanes = henon.sweep((0, 20), grid, rtol=1e-10, atol=1e-10, output="energy", batched=True)
    for key in ("final", "t_final", "status", "nsteps", "nrejected", "energy_error"):
        np.testing.assert_array_equal(getattr(lanes, key), getattr(scalar, key))
    small = {"theta1": np.linspace(-0.3, 0.3, 9), "theta2": np.linspace(-0.3, 0.3, 5)}
    scalar = double_pendulum.sweep((0, 5), small, rtol=1e-10, atol=1e-10, qd0=[0, 0])
    lanes = double_pendulum.sweep((0, 5), small, rtol=1e-10, atol=1e-10, qd0=[0, 0], batched=True)
    np.testing.assert_array_equal(lanes.final, scalar.final)
    np.testing.assert_array_equal(lanes.nsteps, scalar.nsteps)
    with pytest.raises(OptionError, match="dense rows or events"):
        double_pendulum.sweep((0, 1), small, t_eval=[0.5, 1.0], output="dense", batched=True)


def test_batched_taylor_takes_the_scalar_steps(compiled, double_pendulum):
    """Each lane of the unrolled Taylor kernel takes taylor_run's steps; its coefficients differ from the
    loop kernel's by rounding only, so the states agree to round-off on a regular part of the plane.
    45 trajectories in 32 lanes: lanes take the next trajectory as theirs end.  The result is the
    same bitwise on 1 and 2 threads (every lane runs the same vector code)."""
    small = {"theta1": np.linspace(-0.5, 0.5, 9), "theta2": np.linspace(-0.5, 0.5, 5)}
    options = dict(method="taylor", rtol=1e-8, atol=1e-8, qd0=[0.3, -0.2], output="energy")
    scalar = double_pendulum.sweep((0, 5), small, **options)
    lanes = double_pendulum.sweep((0, 5), small, batched=True, workers=1, **options)
    assert np.all(lanes.status == 0) and np.all(lanes.t_final == 5.0)
    np.testing.assert_array_equal(lanes.nsteps, scalar.nsteps)
    np.testing.assert_array_equal(lanes.nfev, lanes.nsteps)    # (the scalar sweep recomputes a series per buffer)
    np.testing.assert_allclose(lanes.final, scalar.final, rtol=0, atol=1e-13)
    np.testing.assert_allclose(lanes.energy_error, scalar.energy_error, rtol=0, atol=1e-14)
    two = double_pendulum.sweep((0, 5), small, batched=True, workers=2, **options)
    np.testing.assert_array_equal(two.final, lanes.final)
    capped = double_pendulum.sweep((0, 5), small, batched=True, max_steps=7, **options)
    reference = double_pendulum.sweep((0, 5), small, max_steps=7, **options)
    assert np.all(capped.status == -4)
    np.testing.assert_array_equal(capped.nsteps, reference.nsteps)
    np.testing.assert_allclose(capped.t_final, reference.t_final, rtol=1e-14)   # steps from rounded coefficients


def test_batched_taylor_of_a_time_dependent_system(compiled):
    """The driven pendulum's equations hold t: its series (t, 1, 0, ...) in every lane.  This pendulum
    swings hard enough for rounding to grow: lanes and scalar kernel differ by no more than the
    scalar method's own spread under a 1-ulp change of the start (measured: 2e-11 and 1e-11)."""
    driven = compiled("driven_pendulum")
    angles = np.linspace(-2.0, 2.0, 7)
    options = dict(method="taylor", rtol=1e-8, atol=1e-8)
    scalar = driven.sweep((0, 3), {"theta": angles}, **options)
    nudged = driven.sweep((0, 3), {"theta": np.nextafter(angles, np.inf)}, **options)
    lanes = driven.sweep((0, 3), {"theta": angles}, batched=True, **options)
    np.testing.assert_array_equal(lanes.nsteps, scalar.nsteps)
    spread = np.abs(nudged.final - scalar.final).max()
    assert 0 < spread < 1e-10
    assert np.abs(lanes.final - scalar.final).max() <= 5 * spread


def test_batched_taylor_refuses_a_program_too_large_to_unroll(double_pendulum, monkeypatch):
    from lagcomp.codegen import taylor_lanes

    monkeypatch.setattr(taylor_lanes, "TERMS_MAX", 100)
    with pytest.raises(OptionError, match=r"order 11 .* about 1,1\d\d terms, above .*TERMS_MAX = 100"):
        double_pendulum.sweep((0, 1), {"theta1": [0.1]}, method="taylor", rtol=1e-8, atol=1e-8, batched=True)


def test_sweep_checks_tolerances_like_simulate(double_pendulum):
    with pytest.raises(OptionError, match="rtol"):
        double_pendulum.sweep((0, 1), {"theta1": [0.1]}, rtol=1e-17)


@pytest.mark.parametrize("options", [dict(method="rk4", dt=0.005), dict(method="dop853", rtol=1e-10, atol=1e-10)],
                         ids=["rk4-projected", "dop853"])
def test_constrained_sweep_equals_separate_runs_and_keeps_the_rod_length(compiled, options):
    """Spherical pendulum in Cartesian coordinates (rod as a multiplier): initial x swept and projected onto
    the sphere, g swept; each trajectory is bitwise the `simulate` run from the same projected state."""
    model = compiled("spherical_pendulum_cartesian")
    grid = {"x": [0.3, 0.6, 0.9], "g": [4.0, 9.81]}
    sweep = model.sweep((0, 2), grid, project_initial=True, output="energy", **options)
    assert np.all(sweep.status == 0)
    for i, x in enumerate(grid["x"]):
        for j, g in enumerate(grid["g"]):
            q0 = [x, *model.q0[1:]]
            sol = model.simulate((0, 2), q0=q0, params={"g": g}, project_initial=True, progress=False, **options)
            np.testing.assert_array_equal(sweep.final[i, j], np.r_[sol.q[-1], sol.qd[-1]])
    x, y, z = np.moveaxis(sweep.final[..., :3], -1, 0)
    np.testing.assert_allclose(x**2 + y**2 + z**2, 1.0, atol=1e-8)  # l = 1: the rod held its length
    assert np.max(sweep.energy_error) < 1e-6  # the rod's tension does no work


def test_constrained_sweep_refuses_an_inconsistent_start_naming_the_trajectory(compiled):
    model = compiled("spherical_pendulum_cartesian")
    with pytest.raises(InitialConditionError, match=r"Trajectory 1 of the sweep \(x=0.6\).*constraint `rod`"):
        model.sweep((0, 1), {"x": [model.q0[0], 0.6]}, method="rk4", dt=0.01)


def test_sweep_against_scipy_on_lagranges_method_equations(double_pendulum):
    """An independent reference for sweeps: each trajectory (swept initial angle and swept g) against
    scipy's DOP853 at rtol 1e-12 on the equations sympy.physics.mechanics' LagrangesMethod derives.

    Measured: max |Δy| = 8.6e-13 over 3 s (the wildest start, θ1 = 2.5, g = 20; 2e-15 for the others).
    """
    import dataclasses

    from reference import lagranges_method_rhs
    from scipy.integrate import solve_ivp

    points = [(0.3, 9.81), (1.5, 1.0), (2.5, 20.0)]
    sweep = double_pendulum.sweep((0, 3), np.array(points), names=["theta1", "g"], method="dop853", rtol=1e-12,
                                  atol=1e-12)
    assert np.all(sweep.status == 0)
    system = double_pendulum.system
    for k, (theta1, g) in enumerate(points):
        rhs = lagranges_method_rhs(dataclasses.replace(system, defaults={**system.defaults, "g": g}))
        y0 = np.r_[theta1, system.q0[1], system.qd0]
        theirs = solve_ivp(rhs, (0, 3), y0, method="DOP853", rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(sweep.final[k], theirs.y[:, -1], rtol=0, atol=4e-12)
