"""Gauss-Legendre's stage iteration stops the same way in any units (issue 36, a defect found after it closed).

The fixed-point and simplified-Newton iterations of `lagcomp.integrate.drivers.collocation` are unchanged by a
change of units (a diagonal scaling of x = (q, p) and a unit of time) up to rounding; their stopping test must be
too.  It compared the change of h·K with max(1, max|x|, h max|K|): the 1 is a unit, and one maximum over q (in
L) and p (in M L² T⁻¹) mixes units.  The stiff spring pendulum, whose ṗ carries large spring terms that cancel,
then ended with NOT_CONVERGED in units where those terms' rounding stayed above the test's bounds, while the run
in the original units was DONE; and simplified Newton's iteration matrix I − h A ⊗ J, whose blocks are in the units
of q, p and their rates, was called singular at t = 0 in units of 1000 m, 1000 kg, 1 ms (a pivot test relative to
its largest entry).  The units below are the ones that failed (L, M, T factors; found by
`tests/test_units_invariance.py`'s hypothesis draws and a grid of 10^{-3, -1.5, 0, 0.38, 1.5, 3}); each run
must end as the one in the original units does and agree with it to rounding (the invariance test's bound).

A step too large for the iteration must still fail loudly: `tests/test_symplectic.py`
(``test_gauss_legendre_reports_a_step_too_large``) and `tests/test_integration_failures.py` keep that.
"""

import numpy as np
import pytest

from lagcomp.integrate.status import Status
from tests.test_units_invariance import EXAMPLES, factor

#: (L, M, T) factors in which a gauss run of the stiff spring pendulum ended with NOT_CONVERGED before the fix.
FAILED_UNITS = [
    (10 ** 0.37890625, 10.0, 1.0),
    (2.39, 1000.0, 1.0),
    (2.39, 1.0, 1e-3),
    (1e-3, 10.0, 1e-3),
    (1e-3, 10 ** 1.5, 1e-3),
    (1e-3, 1000.0, 10 ** -1.5),
    (1e-3, 1e-3, 1000.0),
    (1000.0, 1000.0, 1e-3),
]


def run_in_units(model, method, solver, units, name="stiff_spring_pendulum", dt=None, span=None):
    """``name``'s short run (its span and step, or ``span`` and ``dt`` in seconds) in units (L, M, T), mapped back:
    (status, final state (q, q̇), end time in seconds)."""
    coordinates, dimensions, _, default_span, default_dt = EXAMPLES[name]
    span = span or default_span
    position = np.array([factor(units, d) for d in coordinates])
    time = units[2]
    params = {k: v * factor(units, dimensions[k]) for k, v in model.defaults.items()}
    q0, qd0 = np.asarray(model.q0, float), np.asarray(model.qd0, float)
    sol = model.simulate((0.0, span * time), q0 * position, qd0 * position / time, params=params, method=method,
                         dt=(dt or default_dt) * time, implicit_solver=solver, throw=False, progress=False)
    return sol.status, np.concatenate([sol.q[-1] / position, sol.qd[-1] * time / position]), sol.t[-1] / time


@pytest.mark.parametrize("units", FAILED_UNITS, ids=lambda u: "x".join(f"{np.log10(f):+.2f}" for f in u))
@pytest.mark.parametrize("solver", ["fixed_point", "newton"])
@pytest.mark.parametrize("method", ["gauss1", "gauss2", "gauss3"])
def test_the_stage_iteration_converges_in_any_units(compiled, method, solver, units):
    model = compiled("stiff_spring_pendulum")
    status, y, _ = run_in_units(model, method, solver, (1.0, 1.0, 1.0))
    assert status == Status.DONE
    scaled_status, scaled_y, _ = run_in_units(model, method, solver, units)
    assert scaled_status == Status.DONE
    np.testing.assert_allclose(scaled_y, y, rtol=0, atol=1e-10 * np.max(np.abs(y)))


#: A step too large for the iteration, in seconds (in SI units the runs end at t = 0 with NOT_CONVERGED): the
#: fixed point on the stiff spring (h ω ≈ 5 for ω = √(k/m) = 1000/s; it converged at dt = 1e-3), simplified Newton
#: on the pendulum at dt = 20 s over 100 s (`tests/test_symplectic.py`).
TOO_LARGE = [("stiff_spring_pendulum", "fixed_point", 5e-3, 0.05), ("simple_pendulum", "newton", 20.0, 100.0)]


@pytest.mark.parametrize("units", [(1.0, 1.0, 1.0), *FAILED_UNITS],
                         ids=lambda u: "x".join(f"{np.log10(f):+.2f}" for f in u))
@pytest.mark.parametrize(("name", "solver", "dt", "span"), TOO_LARGE)
@pytest.mark.parametrize("method", ["gauss1", "gauss2", "gauss3"])
def test_a_step_too_large_still_fails_in_any_units(compiled, method, name, solver, dt, span, units):
    status, _, t_end = run_in_units(compiled(name), method, solver, units, name=name, dt=dt, span=span)
    assert status == Status.NOT_CONVERGED and t_end == 0.0
