"""What a run ended with: one enum for the compiled drivers, `Solution.status` and the sweeps' statuses.

The drivers return these values from compiled code (numba reads an ``IntEnum`` member as its
integer), Python reads them back as `Status` and shows `Status.message`.  Three groups:

* how a run ended well: ``DONE`` (0), ``TERMINATED`` by a terminal event (1), ``INTERRUPTED`` by
  the user (2; set by Python between driver calls, never by a driver);
* failures, negative, with the last good state kept;
* ``BUFFER_FULL`` and ``PAUSED`` (10 and above): the driver stopped between two steps and the
  caller continues the run with another call (a fresh output buffer, a later step budget).  They
  never reach a `Solution`.
"""

from __future__ import annotations

import enum


class Status(enum.IntEnum):
    """The outcome of one driver call, or of a whole run."""

    DONE = 0
    TERMINATED = 1
    INTERRUPTED = 2
    NONFINITE = -1
    RHS_FAILED = -2
    STEP_TOO_SMALL = -3
    MAX_STEPS = -4
    NOT_CONVERGED = -5
    RESIDUAL_EXCEEDED = -6
    MEMORY_FULL = -7
    CONSTRAINTS_NOT_CONVERGED = -8
    NEWTON_FAILED = -9
    ITERATION_MATRIX_SINGULAR = -10
    RESET_FAILED = -11
    EVENTS_ACCUMULATED = -12
    BUFFER_FULL = 10
    PAUSED = 11

    @property
    def message(self) -> str:
        """What the status means to the user, in one or two sentences."""
        return _MESSAGES[self]

    @property
    def call_again(self) -> bool:
        """Whether the driver stopped between steps and the run continues with another call."""
        return self >= Status.BUFFER_FULL


_MESSAGES = {
    Status.DONE: "The integration reached the end of the time span.",
    Status.TERMINATED: "A terminal event stopped the integration.",
    Status.INTERRUPTED: "Interrupted by the user (Ctrl-C); the solution holds what was computed.",
    Status.NONFINITE: "The state or its derivative became non-finite (NaN or inf).",
    Status.RHS_FAILED: "The mass matrix became singular (the kinetic energy is not positive definite at this "
                       "state), or with constraints the augmented matrix [M Λᵀ; Λ 0] did (redundant constraints).",
    Status.STEP_TOO_SMALL: "The step size became too small (the solution may be singular here).",
    Status.MAX_STEPS: "The maximum number of steps was reached.",
    Status.NOT_CONVERGED: "The implicit stage equations did not converge: reduce the step `dt`.",
    Status.RESIDUAL_EXCEEDED: "The constraint residual exceeded `max_residual`: the run drifted off the constraints "
                              "(tighten rtol/atol, or use projection=True or baumgarte=(alpha, beta)).",
    Status.MEMORY_FULL: "The saved rows reached `memory_limit`; the run stopped and kept them (save every K-th step "
                        "with `save_every`, keep only the summary with record=\"summary\", or raise `memory_limit`).",
    Status.CONSTRAINTS_NOT_CONVERGED: "RATTLE's Newton iteration for the constraint multipliers did not converge "
                                      "(the step moved the coordinates too far along the constraints' curvature): "
                                      "reduce the step `dt`.",
    Status.NEWTON_FAILED: "The Newton iteration of the stage equations (radau) did not converge even at the "
                          "smallest step: the Jacobian may not match the right-hand side, or the solution is "
                          "singular here (check the model near this state, or loosen rtol/atol; with constraints, "
                          "their rounding noise at large coordinates can stall it at tight tolerances).",
    Status.ITERATION_MATRIX_SINGULAR: "The iteration matrix γ/h·M − J of radau (M = I; for constraints, the DAE's "
                                      "diag(I, 0)) stayed singular down to the smallest step (a degenerate Jacobian "
                                      "J, or constraints that are dependent here): check the model near this "
                                      "state, or use an explicit method (dop853).",
    Status.RESET_FAILED: "An event's reset gave a non-finite state (or could not be computed): the run stopped at the "
                         "event, with the state just before it (check the reset's expressions at that state; for "
                         "contacts: dependent contacts, or simultaneous impacts that push a contact pressing a "
                         "sliding friction element, whose tangential impulses lagcomp does not solve yet).",
    Status.EVENTS_ACCUMULATED: "An event with a reset fired again within the smallest step after its last reset: "
                               "its occurrences accumulate here (a Zeno point, like a bouncing ball's bounces "
                               "coming to rest); the run stopped at it. Stop the run before, or model the rest "
                               "that follows (e.g. a terminal event on the rebound speed).",
    Status.BUFFER_FULL: "The output buffer is full: call again with a fresh one.",
    Status.PAUSED: "The call's step budget is used up: call again with a later one.",
}

#: Status value -> message, for the statuses a `Solution` or a sweep can hold.
MESSAGES = {int(s): s.message for s in Status if not s.call_again}
