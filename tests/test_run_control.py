"""Run control: summary-only recording, progress display, Ctrl-C returning the partial solution."""

from __future__ import annotations

import os
import signal
import threading

import numpy as np
import pytest

from lagcomp.errors import OptionError


@pytest.fixture(scope="module")
def pendulum(compiled):
    return compiled("simple_pendulum")


def test_summary_mode_reduces_every_row_and_keeps_two(pendulum):
    """record="summary" keeps the first and last rows; its reductions equal those of the full trajectory."""
    options = dict(method="verlet", dt=1e-3, q0=[1.0], qd0=[0.0])
    full = pendulum.simulate((0, 200), **options)
    brief = pendulum.simulate((0, 200), record="summary", **options)
    assert brief.t.tolist() == [0.0, 200.0] and brief.q.shape == (2, 1)
    np.testing.assert_array_equal(brief.q[-1], full.q[-1])
    assert brief.summary.rows == full.summary.rows == full.t.size
    assert brief.summary.energy_error == full.energy_drift() > 0
    assert brief.summary.energy_function_error == full.energy_drift("energy_function")
    np.testing.assert_array_equal(brief.summary.q_max, full.q.max(axis=0))
    np.testing.assert_array_equal(brief.summary.qd_min, full.qd.min(axis=0))
    assert abs(brief.summary.q_max[0] - 1.0) < 1e-6 and abs(brief.summary.q_min[0] + 1.0) < 1e-3


def test_summary_tracks_cyclic_momenta(compiled):
    """The spherical pendulum's φ is cyclic: the summary reports max |p_φ − p_φ0| / |p_φ0|, with
    p_φ = m l² sin²θ φ̇ (the vertical angular momentum), as the full record gives it."""
    model = compiled("spherical_pendulum")
    assert model.cyclic == ("phi",)
    options = dict(rtol=1e-10, atol=1e-12)
    brief = model.simulate((0, 5), record="summary", **options)
    full = model.simulate((0, 5), **options)
    assert set(brief.summary.momentum_errors) == {"phi"}
    d = model.system.defaults
    p_phi = d["m"] * d["l"] ** 2 * np.sin(full.q[:, 0]) ** 2 * full.qd[:, 1]
    by_hand = np.max(np.abs(p_phi - p_phi[0])) / abs(p_phi[0])
    assert brief.summary.momentum_errors["phi"] == pytest.approx(by_hand, rel=1e-6, abs=1e-15)
    assert brief.summary.momentum_errors["phi"] < 1e-9  # measured 1.7e-10 at rtol 1e-10


def test_record_mode_is_checked(pendulum):
    with pytest.raises(OptionError, match="record"):
        pendulum.simulate((0, 1), record="everything")


def test_progress_bar_only_when_asked_or_long(pendulum, capfd):
    pendulum.simulate((0, 1), progress=False)
    pendulum.simulate((0, 1))                   # short: under the display delay
    assert capfd.readouterr().err == ""
    pendulum.simulate((0, 1), progress=True)
    assert "| t = 0/1" in capfd.readouterr().err


def test_progress_bar_appears_once_a_run_is_long(pendulum, capfd, monkeypatch):
    """By default the bar is made at the first update after PROGRESS_DELAY seconds (here 0), not before."""
    from lagcomp.integrate import run_control

    monkeypatch.setattr(run_control, "PROGRESS_DELAY", 0.0)
    pendulum.simulate((0, 1))
    assert "| t = " in capfd.readouterr().err
    pendulum.simulate((0, 1), progress=False)
    assert capfd.readouterr().err == ""


def test_ctrl_c_returns_the_partial_solution(pendulum):
    """SIGINT during a long run: the driver call in progress finishes, then the run stops with status 2,
    keeping every row computed and the state reached (to resume from).  The process's handler is Python's default
    before, as in a user's session (a test run before in the same pytest-xdist worker may have left SIGINT
    ignored: CI saw it once), and must be so again after."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        sol = pendulum.simulate((0, 1e5), method="verlet", dt=1e-4, save_every=10_000, max_steps=10**9 + 1,
                                progress=False)  # 1e9 steps: far longer than the 0.5 s before SIGINT
        handler_after = signal.getsignal(signal.SIGINT)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    assert sol.status == 2 and not sol.success and "Ctrl-C" in sol.message
    assert 0 < sol.t[-1] < 1e5 and sol.nsteps >= 10_000 * (sol.t.size - 2)
    assert np.all(np.diff(sol.t) > 0)
    assert sol.energy_drift() < 1e-5
    assert handler_after is signal.default_int_handler
