"""``atol`` one per state component (issue 36: a position and a velocity do not share a unit).

One number spread over the state gives the bits a number gives (every adaptive driver, their sweeps, the DOP853
lanes, a sensitivity run); the mapping form is the array form; each component's atol is the one its error is
measured against (a loose atol on one component lets its error grow to it while a tight one on the others
holds them); a run in other units, with each atol in its component's units, gives the same trajectory mapped
back (`tests/test_units_invariance.py` does this over every bundled example and method).
"""

import numpy as np
import pytest

import lagcomp as lc

ADAPTIVE = ("dopri5", "dop853", "tsit5", "bs3", "radau", "taylor")


@pytest.fixture(scope="module")
def pendulum(compiled):
    return compiled("double_pendulum")


@pytest.mark.parametrize("method", ADAPTIVE)
def test_one_number_spread_over_the_state_gives_the_same_bits(pendulum, method):
    options = dict(method=method, rtol=1e-8, progress=False)
    number = pendulum.simulate((0.0, 3.0), atol=1e-9, **options)
    spread = pendulum.simulate((0.0, 3.0), atol=np.full(4, 1e-9), **options)
    mapping = pendulum.simulate((0.0, 3.0), atol={"theta1": (1e-9, 1e-9), "theta2": (1e-9, 1e-9)}, **options)
    assert number.status == 0
    for other in (spread, mapping):
        assert np.array_equal(other.t, number.t) and np.array_equal(other.y, number.y)


def test_the_mapping_is_the_array_in_the_state_order(pendulum):
    atol = {"theta2": (3e-9, 4e-7), "theta1": (1e-9, 2e-7)}          # (any order of the coordinates)
    a = pendulum.simulate((0.0, 3.0), atol=atol, rtol=1e-6, progress=False)
    b = pendulum.simulate((0.0, 3.0), atol=[1e-9, 3e-9, 2e-7, 4e-7], rtol=1e-6, progress=False)
    c = pendulum.simulate((0.0, 3.0), atol=[1e-9, 1e-9, 2e-7, 4e-7], rtol=1e-6, progress=False)
    assert np.array_equal(a.y, b.y)
    assert not np.array_equal(a.y, c.y)      # (the entries are read, each where it belongs)


@pytest.mark.parametrize("method", ["dop853", "dopri5", "radau"])
def test_each_component_is_held_to_its_own_atol(pendulum, method):
    """With rtol out of the way (1e-12 of states of size ~1), tightening the rates' atol alone from 1e-6 to 1e-10
    (the angles' kept at 1e-6) takes more steps and shrinks the run's error against a run at rtol 3e-14: the rates'
    entries are read for the rates.  (The Taylor method's order follows min(rtol, min atol), so there tightening
    one component changes the order for all: its per-component atol is tested in tests/test_units_invariance.py.)"""
    span = (0.0, 2.0)
    reference = pendulum.simulate(span, method="dop853", rtol=3e-14, atol=1e-16, progress=False).y[-1]

    def error(rate_atol):
        sol = pendulum.simulate(span, method=method, rtol=1e-12, atol=[1e-6, 1e-6, rate_atol, rate_atol],
                                progress=False)
        assert sol.status == 0
        return np.max(np.abs(sol.y[-1] - reference)), sol.nsteps

    loose, loose_steps = error(1e-6)
    tight, tight_steps = error(1e-10)
    assert tight_steps > loose_steps and tight < loose


@pytest.mark.parametrize("batched", [False, True])
def test_a_sweep_takes_atol_per_component_as_its_runs_do(pendulum, batched):
    atol = [1e-9, 2e-9, 1e-7, 3e-7]
    sweep = pendulum.sweep((0.0, 2.0), {"l1": [1.0, 1.5]}, atol=atol, rtol=1e-7, batched=batched, progress=False)
    for row, l1 in enumerate([1.0, 1.5]):
        run = pendulum.simulate((0.0, 2.0), params={"l1": l1}, atol=atol, rtol=1e-7, progress=False)
        assert np.array_equal(sweep.final[row], run.y[-1])


def test_a_batched_taylor_sweep_takes_equal_atols_as_one_number(pendulum):
    grid = {"l1": [1.0, 1.5]}
    one = pendulum.sweep((0.0, 1.0), grid, method="taylor", batched=True, atol=1e-9, rtol=1e-9, progress=False)
    spread = pendulum.sweep((0.0, 1.0), grid, method="taylor", batched=True, atol=np.full(4, 1e-9), rtol=1e-9,
                            progress=False)
    assert np.array_equal(one.final, spread.final)


def test_a_sensitivity_run_spreads_atol_over_its_columns(pendulum):
    """Each sensitivity S_ij = ∂y_i/∂w_j is held to atol_i, its row's: one number gives the bits it gave."""
    options = dict(rtol=1e-8, sensitivities=["l1"], progress=False)
    number = pendulum.simulate((0.0, 1.0), atol=1e-9, **options)
    spread = pendulum.simulate((0.0, 1.0), atol=np.full(4, 1e-9), **options)
    assert np.array_equal(number.sensitivities, spread.sensitivities) and np.array_equal(number.y, spread.y)
    tighter = pendulum.simulate((0.0, 1.0), atol=[1e-9, 1e-9, 1e-12, 1e-12], **options)
    assert tighter.nsteps >= number.nsteps and not np.array_equal(tighter.y, number.y)


@pytest.mark.parametrize(("atol", "culprit"), [
    ([1e-9, 1e-9], "`atol` has shape (2,)"),
    (np.full((2, 2), 1e-9), "`atol` has shape (2, 2)"),
    ([1e-9, 1e-9, 0.0, 1e-9], "`atol[2]` (theta1_dot)"),
    ([1e-9, np.nan, 1e-9, 1e-9], "`atol[1]` (theta2)"),
    ([1e-9, True, 1e-9, 1e-9], "must hold numbers"),
    (["a", 1e-9, 1e-9, 1e-9], "`atol` must be a number or an array"),
    ({"theta1": (1e-9, 1e-9)}, "missing: ['theta2']"),
    ({"theta1": (1e-9, 1e-9), "theta2": (1e-9, 1e-9), "x": (1, 1)}, "unknown: ['x']"),
    ({"theta1": 1e-9, "theta2": (1e-9, 1e-9)}, "`atol['theta1']` must be a pair"),
    (True, "`atol` must be a number"),
])
def test_a_wrong_atol_is_refused_naming_it(pendulum, atol, culprit):
    with pytest.raises(lc.OptionError) as info:
        pendulum.simulate((0.0, 1.0), atol=atol, progress=False)
    assert culprit in str(info.value)
