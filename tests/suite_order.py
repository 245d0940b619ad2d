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

#: Test files (names under tests/) by the CPU seconds of their tests, heaviest first, at e5082ac (two re-measured
#: where marked, -n 0 with the library's numba cache warm).
HEAVIEST = (
    "test_units_invariance.py",          # 90
    "test_error_table.py",               # 58
    "test_acceptance.py",                # 50
    "test_taylor_sensitivities.py",      # 49
    "test_steady_linearization.py",      # 47
    "test_names.py",                     # 46
    "test_multibody_spherical.py",       # 45 (session 28: Pinocchio's chains' kernels, 10⁴ turns of a free body)
    "test_rhs_jacobian.py",              # 43
    "test_kane_interop.py",              # 42
    "test_resting_contacts.py",          # 40
    "test_directional.py",               # 39 at 615d5a2 (52: kkt_solve linked into each constrained kernel)
    "test_taylor_jacobian.py",           # 33 (103 with the k = 9 case, now marked slow)
    "test_contact_friction.py",          # 32
    "test_driver_staleness.py",          # 28 at 4805bf0 (66: dopri5 compiled twice into an empty numba cache)
    "test_taylor_modes.py",              # 27
    "test_constrained_sensitivities.py",  # 25
    "test_large_systems.py",             # 25
    "test_sweep.py",                     # 23
    "test_on_demand.py",                 # 22
    "test_inputs.py",                    # 22
    "test_animation.py",                 # 20
    "test_geometry.py",                  # 20
    "test_silent_answers.py",            # 19
    "test_friction.py",                  # 18
    "test_parameter_jacobian.py",        # 18
    "test_plots.py",                     # 18
    "test_cli_impacts.py",               # 18
    "test_driver_cache.py",              # 17
    "test_cache_faults.py",              # 16
)

_RANK = {name: rank for rank, name in enumerate(HEAVIEST)}


def order(items: list) -> None:
    """Sort the collected `items` in place: the files of `HEAVIEST` first in its order, then the others as
    collected; the tests of one file keep their order (a stable sort on the file's rank)."""
    items.sort(key=lambda item: _RANK.get(item.path.name, len(HEAVIEST)))
