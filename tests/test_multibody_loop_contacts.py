"""Contacts on a tree with loops (issue 39): the four-bar as a tree with its pin at B cut (`lc.Loop`), its rocker's
tip B stopped by a floor at height h (gap c sin θ3 − h), against the four-bar `lc.System` with the same contact
(`four_bar_linkage`, its loop written by hand; contacts on a System with constraints:
tests/test_contacts_constrained.py).

Both are one mechanism in two sets of coordinates, the tree's (θ1, φ2 = θ2 − θ1, θ3) = T (θ1, θ2, θ3), so the
impacts come at the same times, the states map by T, the normal impulses and forces are the same (the same gap
function of θ3) and so are the loop's multipliers (both the force the rocker exerts on the coupler at B).  The
linkage has one degree of freedom: a plastic impact of B on the floor (e = 0) stops it, and it stays at rest on the
floor when gravity presses B down (closed form: the velocities after the impact are 0, then q̇ = 0 to the end).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import sympy as sp
from test_multibody_loops import TO_TREE, a, b, c, d, g, m1, m2, m3, rod

import lagcomp as lc
from lagcomp.examples.constrained import four_bar_linkage
from lagcomp.integrate.status import Status

h, e = sp.symbols("h e", positive=True)
EPS = np.finfo(float).eps


@pytest.fixture(scope="module")
def stopped(tmp_path_factory):
    """(the tree's model, the System's model), each with the floor under B."""
    cache = tmp_path_factory.mktemp("cache")
    example = four_bar_linkage()
    defaults = {**example.defaults, "h": 0.36, "e": 0.8}
    theta3 = example.coordinates[2]
    system = dataclasses.replace(example, events=[lc.Contact("stop", c * sp.sin(theta3) - h, restitution=e)],
                                 name="four_bar_stop", defaults=defaults, parameters=[*example.parameters, h, e])
    rocker, = lc.coordinates("theta3")
    tree = lc.Tree([
        lc.Link("crank", lc.Revolute("theta1"), **rod(m1, a)),
        lc.Link("coupler", lc.Revolute("phi2", origin=(a, 0, 0)), parent="crank", **rod(m2, b)),
        lc.Link("rocker", lc.Revolute(rocker, origin=(d, 0, 0)), **rod(m3, c)),
    ], gravity=(0, -g, 0), name="four_bar_tree_stop", defaults=defaults, q0=TO_TREE @ example.q0,
        qd0=TO_TREE @ example.qd0,
        loops=[lc.Loop("loop", ("coupler", (b, 0, 0)), ("rocker", (c, 0, 0)), directions="xy")],
        events=[lc.Contact("stop", c * sp.sin(rocker) - h, restitution=e)])
    return lc.compile(tree, cache_dir=cache), lc.compile(system, cache_dir=cache)


def _runs(stopped, restitution, span=(0.0, 1.0)):
    runs = [model.simulate(span, params={"e": restitution}, rtol=1e-12, atol=1e-12) for model in stopped]
    assert all(run.status == Status.DONE for run in runs), [run.message for run in runs]
    return runs


def _velocity_rows(model, t, q, qd):
    """Λ q̇ at each row (r, k), from the model's ``constraint_residuals`` (Φ, then Λ q̇)."""
    p, out = model.parameter_vector(), np.empty(2 * model.k)
    rows = []
    for ti, qi, qdi in zip(t, q, qd, strict=True):
        model.kernels.constraint_residuals(float(ti), np.concatenate([qi, qdi]), p, out)
        rows.append(out[model.k:].copy())
    return np.array(rows)


@pytest.mark.parametrize("restitution", [1.0, 0.8])
def test_the_rocker_bounces_on_its_stop_as_the_system_does(stopped, restitution):
    on_tree, on_system = _runs(stopped, restitution)
    hits, reference = on_tree.events["stop"], on_system.events["stop"]
    assert len(hits) == len(reference) >= 1
    np.testing.assert_allclose(hits.t, reference.t, rtol=0, atol=1e-11)
    np.testing.assert_allclose(hits.q, reference.q @ TO_TREE.T, rtol=0, atol=1e-11)
    np.testing.assert_allclose(hits.qd_after, reference.qd_after @ TO_TREE.T, rtol=0, atol=1e-9)
    np.testing.assert_allclose(hits.impulses, reference.impulses, rtol=1e-9)
    # the impact keeps the loop's velocity rows Λ q̇ to rounding
    jump = _velocity_rows(stopped[0], hits.t, hits.q, hits.qd_after) - _velocity_rows(stopped[0], hits.t, hits.q,
                                                                                      hits.qd)
    scale = np.abs(hits.qd).sum(axis=1) + np.abs(hits.qd_after).sum(axis=1)
    assert np.all(np.abs(jump) <= 16 * EPS * scale[:, None])
    # e = 1: the kinetic energy is kept up to the drift term Λc Λ q̇⁻ (1e-12 here)
    if restitution == 1.0:
        energy = on_tree.energy
        np.testing.assert_allclose(energy, energy[0], rtol=1e-9)
    np.testing.assert_allclose(on_tree.q[-1], on_system.q[-1] @ TO_TREE.T, rtol=0, atol=1e-9)


def test_a_plastic_stop_holds_the_linkage_with_the_systems_forces(stopped):
    on_tree, on_system = _runs(stopped, 0.0)
    assert [(s.contact, s.closed) for s in on_tree.contact_switches] == [("stop", True)]
    assert [(s.contact, s.closed) for s in on_system.contact_switches] == [("stop", True)]
    t_stop = on_tree.contact_switches[0].t
    assert t_stop == pytest.approx(on_system.contact_switches[0].t, abs=1e-11)
    resting = on_tree.t > t_stop
    assert resting.sum() >= 2
    # one degree of freedom: stopped by the floor, up to what the impact keeps, the run's drift off the loop's
    # velocity rows before it (Λ q̇⁻ ~ 1e-13 of the speed at rtol = 1e-12)
    speed = np.abs(on_tree.events["stop"].qd).max()
    assert np.all(np.abs(on_tree.qd[resting]) <= 1e-12 * speed)
    assert np.all(on_tree.contact_forces[resting, 0] > 0)
    at_rest = on_system.t > on_system.contact_switches[0].t
    np.testing.assert_allclose(on_tree.contact_forces[resting, 0], on_system.contact_forces[at_rest, 0][0],
                               rtol=1e-9)
    for name in ("loop_x", "loop_y"):
        np.testing.assert_allclose(on_tree.reactions[name][resting], on_system.reactions[name][at_rest][0],
                                   rtol=1e-9, atol=1e-9)
