"""The Taylor method on a kinematic tree with contacts (issue 39): the mode programs of `lagcomp.codegen.taylor`
(one per set of closed contacts, q̈ = q̈_free + M⁻¹ G_Aᵀ λ_A) built from the tree's articulated-body program and its
``closed_contacts`` kernel (`lagcomp.codegen.tree_taylor`).

The tree: the planar double pendulum of `multibody_models.planar_chain(2)` (hinges about z at the origin and at
(l0, 0, 0) of link 0; gravity −g along y) over a floor at the height of the pivot, met by the tip of link 0 ("knee",
gap l0 sin θ0) and the tip of link 1 ("toe", gap l0 sin θ0 + l1 sin(θ0 + θ1)), restitution e; joint 0 driven by a
torque k t.  Dropped, it bounces on both tips and comes to rest lying flat (θ = 0).  There, with G_knee = (l0, 0)
and G_toe = (l0 + l1, l1), the statics Gᵀ λ = ∂V/∂θ − Q, ∂V/∂θ = g (m0 c0 + m1 (l0 + c1), m1 c1) at θ = 0
(the offsets d_i of the centres of mass enter V as d_i cos, whose slope vanishes there), Q = (k t, 0), give

    λ_toe = g m1 c1 / l1,    λ_knee = (g (m0 c0 + m1 (l0 + c1)) − λ_toe (l0 + l1) − k t) / l0

(link 1's moments about its hinge, then the whole chain's about the pivot), and the knee lifts off where λ_knee = 0.
A friction element pressed by an expression takes the same programs (a sticking element's row held): a block on a
spring carried by a belt, as tests/test_taylor_modes.py's System, switches at the closed form's times.
References: the same tree run with dop853 at rtol 1e-13, and the same system on the Lagrangian path
(`multibody_models.lagrangian_system`, M from T expanded) run with its own Taylor programs.
"""

from dataclasses import replace

import multibody_models as mm
import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_taylor_modes import _belt_switches

import lagcomp as lc
from lagcomp.codegen.taylor import ModePrograms
from lagcomp.codegen.tree_locals import tree_locals
from lagcomp.codegen.tree_taylor import tree_taylor_decomposition
from lagcomp.integrate.status import Status
from lagcomp.multibody import link_point

G = 9.81
CHAIN = {"m0": 1.3, "m1": 0.8, "c0": 0.45, "c1": 0.35, "d0": 0.02, "d1": -0.03, "J0": 0.07, "J1": 0.04,
         "l0": 0.9, "l1": 0.7, "g": G, "e": 0.5, "k": 0.0}
DROP = dict(q0=[0.6, -0.3], qd0=[0.0, 0.0])


def _chain() -> lc.Tree:
    """The floored double pendulum of the module docstring."""
    k, e = sp.symbols("k e")
    links = []
    for i, origin in enumerate([(0, 0, 0), (sp.Symbol("l0"), 0, 0)]):     # (`planar_chain(2)`'s links)
        m, c, d, J = sp.symbols(f"m{i} c{i} d{i} J{i}")
        links.append(lc.Link(f"link{i}", lc.Revolute(f"th{i}", axis="z", origin=origin, torque=k * lc.t if i == 0 else 0),
                             parent=None if i == 0 else "link0", mass=m, com=(c, d, 0), inertia=(J, J, J)))
    knee = link_point(links, "link0", (sp.Symbol("l0"), 0, 0))
    toe = link_point(links, "link1", (sp.Symbol("l1"), 0, 0))
    return lc.Tree(links, gravity=(0, -sp.Symbol("g", positive=True), 0), name="taylor_contacts_chain",
                   events=[lc.Contact("knee", knee[1], restitution=e), lc.Contact("toe", toe[1], restitution=e)],
                   defaults=CHAIN)


@pytest.fixture(scope="module")
def chain(cache_dir):
    """(the tree's model, its Lagrangian twin's with the same contacts)."""
    tree = _chain()
    twin = replace(mm.lagrangian_system(tree), events=tree.user_events, defaults=tree.defaults, parameters=None)
    return lc.compile(tree, cache_dir=cache_dir), lc.compile(twin, cache_dir=cache_dir)


def _resting_forces(k_t: float = 0.0) -> np.ndarray:
    """(λ_knee, λ_toe) of the chain lying flat, with the torque k t = `k_t` at joint 0 (module docstring)."""
    m0, m1, c0, c1, l0, l1 = (CHAIN[name] for name in ("m0", "m1", "c0", "c1", "l0", "l1"))
    toe = G * m1 * c1 / l1
    return np.array([(G * (m0 * c0 + m1 * (l0 + c1)) - toe * (l0 + l1) - k_t) / l0, toe])


def test_a_tree_with_contacts_has_one_program_per_set_of_closed_contacts():
    """Two contacts: four programs, the held ones with their multipliers' series (rows of W the driver bounds)."""
    tree = _chain()
    programs = tree_taylor_decomposition(tree, tree_locals(tree))
    assert isinstance(programs, ModePrograms) and len(programs.programs) == 4
    assert [len(program.multipliers) for program in programs.programs] == [0, 1, 1, 2]


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(mask=st.integers(0, 3), state=st.lists(st.floats(-1.5, 1.5), min_size=4, max_size=4))
def test_the_series_of_each_mode_equal_the_lagrangian_paths(chain, mask, state):
    """At any state, under each set of closed contacts: the tree's Taylor coefficients to order 20 and its
    multipliers' series equal the Lagrangian twin's (whose M is T's Hessian, factored in the same series LDLᵀ),
    order by order to 1e-11 of order k's largest coefficient (at least 1) up to order 15, growing 1.8× an order
    beyond: the two programs round differently and the recurrences carry each order's rounding into the next
    (measured at y = 0 with the knee closed: 4e-16 at order 1, 1.2e-13 at 11, 1.4e-12 at 15, 2.0e-11 at 19, about
    1.7× an order; a multiplier's order 2 at rest, 0 exactly, 6e-13 from the cancellation of its terms; a wrong
    program is off by O(1))."""
    y = np.array(state)
    found = []
    for model in chain:
        kernels, order = model.kernels, 20
        p = model.parameter_vector({"k": 1.7})
        p[kernels.CONTACT_MODES:kernels.CONTACT_MODES + 2] = [mask & 1, mask >> 1 & 1]
        X, W = np.zeros((4, order + 1)), np.zeros((kernels.TAYLOR_WORK, order + 1))
        status = kernels.taylor_coefficients(0.0, y, p, X, W)
        assert status == -mask.bit_count()      # (−c: rows 0..c−1 of W hold the c multipliers' series)
        found.append(np.vstack([X[:, :order], W[:-status, :order]]))
    scale = np.maximum(np.abs(found[1]).max(axis=0), 1.0) * 1e-11 * 1.8 ** np.maximum(np.arange(order) - 15, 0)
    assert (np.abs(found[0] - found[1]) <= scale).all()


def test_the_dropped_chain_bounces_as_dop853_and_the_lagrangian_taylor_run_say(chain):
    """Every impact of both tips (times, velocities after) and both closings, against dop853 at rtol 1e-13 (to
    1e-11) and against the twin's Taylor run (to 1e-12)."""
    tree, twin = chain
    taylor = tree.simulate((0.0, 3.0), method="taylor", rtol=1e-12, atol=1e-12, **DROP)
    references = (tree.simulate((0.0, 3.0), method="dop853", rtol=1e-13, atol=1e-13, **DROP),
                  twin.simulate((0.0, 3.0), method="taylor", rtol=1e-12, atol=1e-12, **DROP))
    assert taylor.status == Status.DONE, taylor.message
    assert sorted((s.contact, s.closed) for s in taylor.contact_switches) == [("knee", True), ("toe", True)]
    for reference, tolerance in zip(references, (1e-11, 1e-12), strict=True):
        assert [(s.contact, s.closed) for s in reference.contact_switches] == \
            [(s.contact, s.closed) for s in taylor.contact_switches]
        np.testing.assert_allclose([s.t for s in taylor.contact_switches], [s.t for s in reference.contact_switches],
                                   rtol=0, atol=tolerance)
        for contact in ("knee", "toe"):
            impacts, expected = taylor.events[contact], reference.events[contact]
            assert len(impacts) > 10 and len(impacts) == len(expected)
            np.testing.assert_allclose(impacts.t, expected.t, rtol=0, atol=tolerance)
            np.testing.assert_allclose(impacts.qd_after, expected.qd_after, rtol=0, atol=100 * tolerance)


def test_a_taylor_sweep_over_the_restitution_ends_where_dop853s_does(chain):
    """`sweep(..., method="taylor")` (the driver per trajectory, its modes in each trajectory's p): final states
    against a dop853 sweep at rtol 1e-13, through the bounces (e = 0.8, 0.5) and to rest (e = 0.3)."""
    grid = {"e": [0.3, 0.5, 0.8]}
    taylor, dop853 = (chain[0].sweep((0.0, 1.0), grid, method=method, rtol=tol, atol=tol, progress=False, **DROP)
                      for method, tol in (("taylor", 1e-12), ("dop853", 1e-13)))
    assert not taylor.status.any() and not dop853.status.any()
    np.testing.assert_allclose(taylor.final, dop853.final, rtol=0, atol=1e-10)
    assert np.abs(taylor.final[0]).max() < 1e-13        # (at rest by t = 1 s)


def test_the_chain_at_rest_is_held_by_the_static_forces(chain):
    """After both contacts close the chain lies flat (to 1e-13 rad) and the floor pushes with the statics' forces."""
    sol = chain[0].simulate((0.0, 3.0), method="taylor", rtol=1e-12, atol=1e-12, t_eval=np.linspace(0.0, 3.0, 301),
                            **DROP)
    rest = sol.t > max(s.t for s in sol.contact_switches)
    assert rest.sum() > 10
    assert np.abs(sol.q[rest]).max() < 1e-13 and np.abs(sol.qd[rest]).max() < 1e-13
    np.testing.assert_allclose(sol.contact_forces[rest], np.broadcast_to(_resting_forces(), (rest.sum(), 2)),
                               rtol=1e-13)
    assert not sol.contact_forces[sol.t < min(s.t for s in sol.contact_switches)].any()


def test_the_knee_lifts_off_where_the_torque_takes_its_force_to_zero(chain):
    """Started at rest lying flat, both contacts closed, joint 0 driven by k t: λ_knee falls linearly and the knee
    lifts off at λ_knee = 0 (the event of the held program's multiplier, located on its series), λ_toe constant."""
    k = 4.0
    t_off = _resting_forces()[0] * CHAIN["l0"] / k
    sol = chain[0].simulate((0.0, t_off + 0.2), q0=[0.0, 0.0], qd0=[0.0, 0.0], params={"k": k}, method="taylor",
                            rtol=1e-12, atol=1e-12, t_eval=np.linspace(0.0, t_off + 0.2, 201))
    assert sol.status == Status.DONE, sol.message
    first = sol.contact_switches[0]
    assert (first.contact, first.closed) == ("knee", False)
    assert first.t == pytest.approx(t_off, abs=1e-10)
    held = sol.t < t_off
    assert held.sum() > 10 and np.abs(sol.q[held]).max() < 1e-13 and np.abs(sol.qd[held]).max() < 1e-13
    expected = np.array([_resting_forces(k * t) for t in sol.t[held]])
    np.testing.assert_allclose(sol.contact_forces[held], expected, rtol=1e-12, atol=1e-12 * expected.max())
    assert sol.q[sol.t > t_off + 0.1, 0].min() > 0.0


def test_a_tree_block_on_a_belt_switches_at_the_closed_form_times(cache_dir):
    """A block (m) on a prismatic joint with a spring (k), friction μs, μk against a belt at v_b, pressed by m g:
    stick and slip alternate at the closed form's times (`test_taylor_modes._belt_switches`)."""
    x, = lc.coordinates("x")
    m, k, g, v_b, mu_s, mu_k = sp.symbols("m k g v_b mu_s mu_k", positive=True)
    tree = lc.Tree([lc.Link("block", lc.Prismatic(x, axis="x", stiffness=k), mass=m)], gravity=(0, 0, 0),
                   events=[lc.Friction("belt", x.diff(lc.t) - v_b, normal=m * g, static=mu_s, kinetic=mu_k)],
                   name="taylor_contacts_belt", defaults={"m": 1.0, "k": 4.0, "g": G, "v_b": 0.5, "mu_s": 0.6,
                                                          "mu_k": 0.4})
    expected, period = _belt_switches(0.6, 0.4, periods=4)
    sol = lc.compile(tree, cache_dir=cache_dir).simulate((0.0, expected[-1] + period / 4), [0.0], [0.5],
                                                          method="taylor", rtol=1e-12, atol=1e-12)
    assert sol.status == Status.DONE, sol.message
    assert [s.mode for s in sol.friction_switches] == [-1, 0] * 4
    np.testing.assert_allclose([s.t for s in sol.friction_switches], expected, rtol=0, atol=1e-10)
