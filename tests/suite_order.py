"""The order pytest-xdist hands the test files to its workers: the heaviest first.

The default run (pyproject.toml) spreads whole files over one worker per core (``--dist loadfile``) in the
order of the collection (``--no-loadscope-reorder``: xdist's own reorder puts the files with the most tests
first, which left the few-test files that compile the largest kernels, most of them late in the alphabet, to
run last on one worker while the other idled).  `HEAVIEST` lists the files whose tests take the most CPU,
heaviest first (numba compiling their models' kernels, mostly); `order` moves them ahead of the others, which
keep their collection order.  Longest-first is what keeps both workers busy to the end.

The figures (CPU seconds of each file's tests, ``-p no:randomly``, a cold cache, measured with a per-test
``time.process_time`` and the children's ``getrusage``) are from issue 35's measurement; a file that grows past
about 15 s of CPU belongs in the list (docs/testing.md says how to measure).
"""

from __future__ import annotations

#: Test files (names under tests/) by the CPU seconds of their tests, heaviest first: unmarked figures from one run
#: at 8a988cb (session 29: -n 2, a cold cache, Pinocchio installed, ``tests/cpu_profile.py``), test_multibody.py's
#: -n 0 at 8a988cb, the others at e5082ac or where noted.  Without Pinocchio (the ``test`` extra has no ``pin``:
#: CI's run) the tests against it skip and the multibody files weigh less; ranked by their weight with it, they run
#: early where they are heavy, and cost nothing by going first where they are light.
HEAVIEST = (
    "test_multibody.py",                 # 122 (-n 0; without Pinocchio 47: its random trees took 72; 4 less since
                                         # session 30: the repeated-steps test's 4-link chain)
    "test_units_invariance.py",          # 81 (-n 0 with every driver cold, session 30: 119, of which radau's
                                         # driver 16 and the collocation one 8)
    "test_multibody_jacobians.py",       # 107 (-n 0 after test_multibody.py, whose models it shares: conftest's
                                         # tree_pair; radau's driver 19 of it): third, so that it starts once the
                                         # first has compiled them, not on the other worker at the same time;
                                         # 25 less since session 30 (its Lagrangian references run as Python)
    "test_error_table.py",               # 74 (29 at -n 0 with the library drivers already compiled, session 30)
    "test_multibody_taylor.py",          # 58 (-n 0, session 30, with the Taylor, dop853 and sweep drivers cold: 18
                                         # of it; the top's Taylor kernel 11, the pairs' Taylor kernels 16)
    "test_taylor_sensitivities.py",      # 58 (-n 0 with dop853's and Taylor's drivers cold, session 30: 73, then
                                         # 66 with one variational module fewer)
    "test_multibody_names.py",           # 58 (-n 0, session 30; 79 before its plain-named ∂f/∂y ran as Python)
    "test_multibody_loop_names.py",      # 54 (-n 0, session 30: the risky-named loop tree's numba 33, the drawn
                                         # trees' builds 18; 88 before the plain-named probe ran as Python)
    "test_multibody_spherical.py",       # 54 (without Pinocchio 21; -n 0 70, with the dop853 driver's compile)
    "test_taylor_jacobian.py",           # 52 (its k = 9 case marked slow)
    "test_steady_linearization.py",      # 52 (-n 0, session 30: 50, of which 27 the Whipple bicycle's sympy)
    "test_rhs_jacobian.py",              # 50
    "test_names.py",                     # 46
    "test_kane_interop.py",              # 46
    "test_urdf.py",                      # not measured yet (5-9 min of wall under load, session 29; 18 random
                                         # URDFs against Pinocchio)
    "test_multibody_loops.py",           # not measured yet
    "test_multibody_gauss.py",           # 41 (-n 0, session 30, the gauss drivers cold: 17 of it)
    "test_directional.py",               # 41
    "test_acceptance.py",                # 38
    "test_multibody_friction_expr.py",   # 37 (-n 0, session 30; the contact-and-expression tree's kernels 15)
    "test_multibody_loop_ball.py",       # 31 (-n 0, session 30; 35 before its Lagrange module ran as Python)
    "test_driver_staleness.py",          # 28 at 4805bf0 (66: dopri5 compiled twice into an empty numba cache)
    "test_taylor_modes.py",              # 27 (e5082ac)
    "test_constrained_sensitivities.py",  # 25 (e5082ac)
    "test_large_systems.py",             # 25 (e5082ac)
    "test_sweep.py",                     # 23 (e5082ac)
    "test_on_demand.py",                 # 22 (e5082ac)
    "test_inputs.py",                    # 22 (e5082ac)
    "test_animation.py",                 # 20 (e5082ac)
    "test_geometry.py",                  # 20 (e5082ac)
    "test_silent_answers.py",            # 19 (e5082ac)
    "test_friction.py",                  # 18 (e5082ac)
    "test_parameter_jacobian.py",        # 18 (e5082ac)
    "test_plots.py",                     # 18 (e5082ac)
    "test_cli_impacts.py",               # 18 (e5082ac)
    "test_urdf_joints.py",               # 18 (-n 0, session 30; 25 before the hand-built trees ran as Python)
    "test_driver_cache.py",              # 17 (e5082ac)
    "test_cache_faults.py",              # 16 (e5082ac)
)
# (Out of the list at 8a988cb: test_resting_contacts.py 13 s, test_contact_friction.py 9 s.)

_RANK = {name: rank for rank, name in enumerate(HEAVIEST)}


def order(items: list) -> None:
    """Sort the collected `items` in place: the files of `HEAVIEST` first in its order, then the others as
    collected; the tests of one file keep their order (a stable sort on the file's rank)."""
    items.sort(key=lambda item: _RANK.get(item.path.name, len(HEAVIEST)))
