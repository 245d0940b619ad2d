"""What a run tells its user when its explicit method was found stiff: one `StiffnessWarning`, with advice.

The embedded pairs test their steps for stiffness as they go (Hairer's test: "Stiffness detection" in
`lagcomp.integrate.drivers.embedded`); `lagcomp.integrate.simulate` calls `warn_if_stiff` once the run has
ended, `lagcomp.integrate.sweep` `warn_if_sweep_stiff` once the sweep has.  The advice names the method to
use instead: ``radau``, which takes every model (Lagrange's equations, a constrained one as a DAE, and Kane's),
but not every run: it refuses contacts and friction, events that reset the state, and inputs given as numba
functions (`radau_refusals`).  For those runs the advice says what stands in radau's way and what the model
can do instead.
"""

from __future__ import annotations

import warnings

import numpy as np

from lagcomp.errors import StiffnessWarning
from lagcomp.integrate.status import Status

#: Failures whose message gets the advice when the run was found stiff: a stiff run spends its steps.
ADVISED_FAILURES = (Status.MAX_STEPS, Status.STEP_TOO_SMALL)


def radau_refusals(model) -> tuple[str, ...]:
    """What in a run of `model` radau refuses, each as a phrase with what to do (empty: radau takes it).

    `model` is the run's: a `lagcomp.integrate.function_inputs.DrivenModel` when inputs are numba functions.
    """
    from lagcomp.integrate.contacts import contacts_of, frictions_of

    reasons = []
    functions = getattr(model, "function_inputs", ())
    if functions:
        reasons.append(f"its inputs {list(functions)} are numba functions (give them as laws, "
                       "lc.Input(name, law=...), or as tables, and radau takes them)")
    switching = [name for name, *_ in contacts_of(model) + frictions_of(model)]
    if switching:
        reasons.append(f"its contacts and friction elements {switching} switch and jump within the motion")
    resetting = [e.name for e in getattr(model, "events", ()) if getattr(e, "resets", False)
                 and e.name not in switching]
    if resetting:
        reasons.append(f"its events {resetting} reset the state (leave them out, events=False, to run radau)")
    return tuple(reasons)


def stiffness_advice(model=None) -> str:
    """Which method to use for a stiff system, in one or two sentences: radau, or, when the run of `model` is
    one radau refuses (`radau_refusals`), why not and what helps the explicit methods."""
    reasons = radau_refusals(model) if model is not None else ()
    if not reasons:
        return ('Use method="radau" (Radau IIA, implicit, for stiff systems; constraints are solved with the '
                "motion, without projection): its steps follow the accuracy asked for, not the fast decay.")
    return (f"radau, the implicit method for stiff systems, cannot integrate this run of {model.name!r}: "
            f"{'; '.join(reasons)}. Otherwise the explicit methods it can use keep paying for the fast decay "
            "with small steps: raise max_steps if the run stops short, or make the stiff part less stiff "
            "(a smaller damping or spring constant, or a constraint in place of a stiff spring).")


def warn_if_stiff(method: str, stiff_at, nsteps: int, nfev: int, stacklevel: int, model=None) -> None:
    """Warn once if the run was declared stiff; `stiff_at` is (step number, time) from
    `lagcomp.integrate.drivers.run_state.RunState.stiff_at`, or None; `model` the run's (`stiffness_advice`)."""
    if stiff_at is None:
        return
    step, t = stiff_at
    warnings.warn(
        f"The problem looks stiff for {method}: from t = {t:.6g} (step {step:,}) its steps were limited by the "
        f"method's stability, not by its accuracy (Hairer's stiffness test, an estimate: at rtol of 1e-3 or "
        f"looser an oscillating system that is not stiff can trip it too); the run took {nsteps:,} steps and "
        f"{nfev:,} evaluations of the equations. {stiffness_advice(model)}",
        StiffnessWarning, stacklevel=stacklevel + 1)


def warn_if_sweep_stiff(method: str, stiff_steps: np.ndarray, stacklevel: int, model=None) -> None:
    """Warn once if any trajectory of a sweep was declared stiff; `stiff_steps` holds, per trajectory, the
    step at which it was (0: not); `model` is the sweep's (`stiffness_advice`)."""
    stiff = int(np.count_nonzero(stiff_steps))
    if stiff == 0:
        return
    warnings.warn(
        f"The problem looks stiff for {method} in {stiff:,} of the sweep's {stiff_steps.size:,} trajectories: "
        f"their steps were limited by the method's stability, not by its accuracy (Hairer's stiffness test, an "
        f"estimate). "
        f"{stiffness_advice(model)}",
        StiffnessWarning, stacklevel=stacklevel + 1)
