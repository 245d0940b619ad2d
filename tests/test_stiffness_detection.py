"""Hairer's stiffness test in the explicit embedded pairs, through the public API: a stiff run warns once
(`lagcomp.StiffnessWarning`, advising ``method="radau"``), non-stiff runs never do, and a run cut into
many driver calls decides exactly as one call.

The stiff system is the bundled ``stiff_spring_pendulum`` (k/m = 10⁶, critically damped: eigenvalues
−1000 s⁻¹) at rtol = atol = 1e-6, where the explicit pairs' steps sit at their stability limit (at the
default 1e-8 their steps are set by the accuracy of the fast mode, inside the limit: see "Stiffness
detection" in `lagcomp.integrate.drivers.embedded`).
"""

from __future__ import annotations

import warnings
import weakref

import numpy as np
import pytest

import lagcomp as lc
from lagcomp.integrate import simulate as simulate_module
from lagcomp.integrate import tableaux
from lagcomp.integrate.methods import get_method
from lagcomp.integrate.stiffness import stiffness_advice

STIFF_TOL = dict(rtol=1e-6, atol=1e-6)


def stiffness_warnings(run) -> list[str]:
    """The messages of the StiffnessWarnings `run()` emits, and its result: (messages, result)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = run()
    return [str(w.message) for w in caught if issubclass(w.category, lc.StiffnessWarning)], result


@pytest.mark.parametrize("method", ["dop853", "dopri5", "tsit5"])
def test_stiff_spring_pendulum_warns_once_with_the_advice(compiled, method):
    model = compiled("stiff_spring_pendulum")
    messages, solution = stiffness_warnings(lambda: model.simulate((0, 2), method=method, progress=False, **STIFF_TOL))
    assert solution.status == 0
    assert len(messages) == 1, messages
    (message,) = messages
    assert f"stiff for {method}" in message and 'method="radau"' in message
    assert f"the run took {solution.nsteps:,} steps" in message
    t_stiff = float(message.split("from t = ")[1].split(" ")[0])
    assert 0.0 < t_stiff < 2.0


def test_a_pair_without_the_test_does_not_warn(compiled):
    """BS3's last stage is at t + 3h/4, not beside the FSAL stage at t + h: it has no test."""
    assert tableaux.BS3.stiffness_bound == 0.0
    messages, solution = stiffness_warnings(lambda: compiled("stiff_spring_pendulum").simulate(
        (0, 1), method="bs3", progress=False, **STIFF_TOL))
    assert messages == [] and solution.status == 0


@pytest.mark.parametrize("name, t_end", [("double_pendulum", 100.0), ("henon_heiles", 1000.0)])
@pytest.mark.parametrize("method", ["dop853", "dopri5", "tsit5"])
def test_no_warning_for_non_stiff_runs(compiled, name, t_end, method):
    model = compiled(name)
    for tol in (1e-4, 1e-6, None, 1e-10):
        options = {} if tol is None else dict(rtol=tol, atol=tol)
        messages, solution = stiffness_warnings(lambda options=options: model.simulate(
            (0, t_end), method=method, record="summary", progress=False, **options))
        assert messages == [] and solution.status == 0 and solution.nsteps > 300, (tol, solution.nsteps)


def test_a_chunked_run_decides_as_one_call(compiled, monkeypatch):
    """Many driver calls (16-step budgets, 16-row buffers): the same steps, and the same declaration."""
    model = compiled("stiff_spring_pendulum")

    def run():
        return model.simulate((0, 2), method="dop853", progress=False, **STIFF_TOL)
    whole_messages, whole = stiffness_warnings(run)
    monkeypatch.setattr(simulate_module, "FIRST_BUDGET", 16)
    monkeypatch.setattr(simulate_module, "CALL_SECONDS", 1e-12)     # every later budget: the minimum, 16
    monkeypatch.setattr(simulate_module, "_STEP_RATES", weakref.WeakKeyDictionary())
    monkeypatch.setattr(simulate_module, "FIRST_CHUNK", 16)
    monkeypatch.setattr(simulate_module, "MAX_CHUNK", 16)
    chunked_messages, chunked = stiffness_warnings(run)
    assert len(whole_messages) == len(chunked_messages) == 1

    def decision(message):     # the message up to the f-evaluations, which differ
        return message.split(" steps and ")[0]
    assert decision(chunked_messages[0]) == decision(whole_messages[0])
    np.testing.assert_array_equal(chunked.t, whole.t)
    np.testing.assert_array_equal(chunked.q, whole.q)
    assert chunked.nsteps == whole.nsteps and chunked.nfev > whole.nfev   # one FSAL evaluation more per call


def test_max_steps_message_gives_the_advice(compiled):
    model = compiled("stiff_spring_pendulum")
    messages, solution = stiffness_warnings(lambda: model.simulate((0, 2), method="dopri5", max_steps=300,
                                                                   progress=False, **STIFF_TOL))
    assert solution.status == -4 and len(messages) == 1
    assert "maximum number of steps" in solution.message and 'method="radau"' in solution.message
    with pytest.raises(lc.IntegrationError, match='method="radau"'), warnings.catch_warnings():
        warnings.simplefilter("ignore", lc.StiffnessWarning)
        model.simulate((0, 2), method="dopri5", max_steps=300, throw=True, progress=False, **STIFF_TOL)


def test_the_advice_names_what_exists():
    """radau, which takes every model: Lagrange's equations, constrained or not, and Kane's
    (tests/test_radau_kane.py: a stiff Kane model warned by dop853 and integrated by radau)."""
    assert stiffness_advice().startswith('Use method="radau"')
    assert get_method("radau").any_state


def test_a_sweep_warns_once_for_its_stiff_trajectories(compiled):
    """One warning for the sweep, counting its stiff trajectories (k/m = 10⁶, not 100); each as its own run."""
    model = compiled("stiff_spring_pendulum")
    messages, sweep = stiffness_warnings(lambda: model.sweep(
        (0, 0.5), {"k": [1e2, 1e6], "c": [20.0, 2e3]}, combine="zip", method="dopri5", progress=False, **STIFF_TOL))
    assert np.all(sweep.status == 0)
    assert len(messages) == 1 and "in 1 of the sweep's 2 trajectories" in messages[0], messages
    assert 'method="radau"' in messages[0]
    stiff_messages, single = stiffness_warnings(lambda: model.simulate((0, 0.5), method="dopri5", progress=False,
                                                                       **STIFF_TOL))
    assert len(stiff_messages) == 1
    np.testing.assert_array_equal(sweep.final[1], np.concatenate([single.q[-1], single.qd[-1]]))


def test_each_bound_lies_just_inside_the_stability_interval():
    """R(z) = 1 + z bᵀ(I − zA)⁻¹1 on the negative real axis: |R| <= 1 from 0 to −bound, and the interval's
    end within 5% beyond it."""
    for tab in (tableaux.DOPRI5, tableaux.DOP853, tableaux.TSIT5):
        s = tab.n_stages

        def stability(z, tab=tab, s=s):
            return abs(1.0 + z * tab.B @ np.linalg.solve(np.eye(s) - z * tab.A, np.ones(s)))
        inside = [stability(-x) for x in np.linspace(0.0, tab.stiffness_bound, 400)[1:]]
        assert max(inside) < 1.0, tab.name
        assert stability(-1.05 * tab.stiffness_bound) > 1.0, tab.name


def test_a_bound_needs_the_last_stage_beside_the_fsal_stage():
    with pytest.raises(ValueError, match="C\\[-1\\] = 1"):
        tableaux.Tableau(name="bs3_with_bound", order=3, error_order=2, A=tableaux.BS3.A, B=tableaux.BS3.B,
                         C=tableaux.BS3.C, E=tableaux.BS3.E, P=tableaux.BS3.P, stiffness_bound=2.0)
