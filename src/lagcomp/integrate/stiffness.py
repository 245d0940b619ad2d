"""What a run tells its user when its explicit method was found stiff: one `StiffnessWarning`, with advice.

The embedded pairs test their steps for stiffness as they go (Hairer's test: "Stiffness detection" in
`lagcomp.integrate.drivers.embedded`); `lagcomp.integrate.simulate` calls `warn_if_stiff` once the run has
ended, `lagcomp.integrate.sweep` `warn_if_sweep_stiff` once the sweep has.  The advice names the method to
use instead: ``radau``, which takes every model (Lagrange's equations, a constrained one as a DAE, and Kane's).
"""

from __future__ import annotations

import warnings

import numpy as np

from lagcomp.errors import StiffnessWarning
from lagcomp.integrate.status import Status

#: Failures whose message gets the advice when the run was found stiff: a stiff run spends its steps.
ADVISED_FAILURES = (Status.MAX_STEPS, Status.STEP_TOO_SMALL)


def stiffness_advice() -> str:
    """Which method to use for a stiff system, in one sentence."""
    return ('Use method="radau" (Radau IIA, implicit, for stiff systems; constraints are solved with the '
            "motion, without projection): its steps follow the accuracy asked for, not the fast decay.")


def warn_if_stiff(method: str, stiff_at, nsteps: int, nfev: int, stacklevel: int) -> None:
    """Warn once if the run was declared stiff; `stiff_at` is (step number, time) from
    `lagcomp.integrate.drivers.run_state.RunState.stiff_at`, or None."""
    if stiff_at is None:
        return
    step, t = stiff_at
    warnings.warn(
        f"The problem looks stiff for {method}: from t = {t:.6g} (step {step:,}) its steps were limited by the "
        f"method's stability, not by its accuracy (Hairer's stiffness test, an estimate: at rtol of 1e-3 or "
        f"looser an oscillating system that is not stiff can trip it too); the run took {nsteps:,} steps and "
        f"{nfev:,} evaluations of the equations. {stiffness_advice()}",
        StiffnessWarning, stacklevel=stacklevel + 1)


def warn_if_sweep_stiff(method: str, stiff_steps: np.ndarray, stacklevel: int) -> None:
    """Warn once if any trajectory of a sweep was declared stiff; `stiff_steps` holds, per trajectory, the
    step at which it was (0: not)."""
    stiff = int(np.count_nonzero(stiff_steps))
    if stiff == 0:
        return
    warnings.warn(
        f"The problem looks stiff for {method} in {stiff:,} of the sweep's {stiff_steps.size:,} trajectories: "
        f"their steps were limited by the method's stability, not by its accuracy (Hairer's stiffness test, an "
        f"estimate). "
        f"{stiffness_advice()}",
        StiffnessWarning, stacklevel=stacklevel + 1)
