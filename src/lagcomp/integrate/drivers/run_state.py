"""The state of a resumable run: what a driver call reads and leaves for the next call.

A run is a sequence of driver calls (Python shows progress, honours Ctrl-C and swaps output buffers
between them).  Three arrays carry it from call to call, owned by the caller and updated in place
by the compiled drivers:

* ``y`` (N,): the state, the last accepted one on return;
* ``clock`` float64[3], indexed by `TIME` and `STEP`: the time of ``y``, and the next step size to
  try (adaptive drivers; h <= 0 asks for an initial step) or the last step taken (Taylor); and
  `STIFF_AT_TIME`, below;
* ``counters`` int64[11], indexed by `NFEV` (right-hand-side evaluations), `NSTEPS` (accepted steps
  since the run's start, which ``pause_at`` and ``max_steps`` count against), `NREJECTED`,
  `NEXT_EVAL` (index of the next ``t_eval`` point to fill), `SINCE_SAVE` (steps since the last
  saved row, for ``save_every``), `EVENT_ROWS` (event rows this call wrote: the caller resets it
  with each fresh event buffer), and for the implicit adaptive method (Radau) `NJEV` (Jacobian
  evaluations) and `NLU` (LU factorisations); the other drivers leave these two at 0;
* the stiffness detection of the explicit embedded pairs (`lagcomp.integrate.drivers.embedded`,
  Hairer's test): `STIFF_TESTS` (tests that found the step at the stability limit in the current
  series, Hairer's IASTI; six others in a row end the series), `NONSTIFF_TESTS` (tests since the
  last such one, NONSTI), and once `STIFF_TESTS` reached
  `lagcomp.integrate.drivers.embedded.STIFF_TESTS_TO_DECLARE`, `STIFF_AT_STEP` (the step number
  at which the run was declared stiff; 0: not declared) and ``clock[STIFF_AT_TIME]`` (its time).
  Carried from call to call, so that a chunked run decides as an uninterrupted one.

The slot names are module constants, which numba compiles as literals: ``counters[NSTEPS]`` costs
what ``counters[1]`` does.  `RunState` is the Python side: the three arrays of a new run, with
the counts by name.
"""

from __future__ import annotations

import numpy as np

#: Slots of ``clock``.
TIME, STEP, STIFF_AT_TIME = 0, 1, 2
#: Slots of ``counters``.
NFEV, NSTEPS, NREJECTED, NEXT_EVAL, SINCE_SAVE, EVENT_ROWS, NJEV, NLU = 0, 1, 2, 3, 4, 5, 6, 7
STIFF_TESTS, NONSTIFF_TESTS, STIFF_AT_STEP = 8, 9, 10
CLOCK_SLOTS, COUNTER_SLOTS = 3, 11


class RunState:
    """``y``, ``clock`` and ``counters`` of a run starting at (t0, y0), as the drivers take them."""

    def __init__(self, y0: np.ndarray, t0: float, step: float = 0.0):
        self.y = np.array(y0, dtype=np.float64)
        self.clock = np.zeros(CLOCK_SLOTS)
        self.clock[TIME], self.clock[STEP] = t0, step
        self.counters = np.zeros(COUNTER_SLOTS, dtype=np.int64)

    @property
    def t(self) -> float:
        return float(self.clock[TIME])

    @property
    def nfev(self) -> int:
        return int(self.counters[NFEV])

    @property
    def nsteps(self) -> int:
        return int(self.counters[NSTEPS])

    @property
    def nrejected(self) -> int:
        return int(self.counters[NREJECTED])

    @property
    def njev(self) -> int:
        return int(self.counters[NJEV])

    @property
    def nlu(self) -> int:
        return int(self.counters[NLU])

    @property
    def stiff_at(self) -> tuple[int, float] | None:
        """(step number, time) at which the stiffness detection declared the run stiff, or None."""
        step = int(self.counters[STIFF_AT_STEP])
        return (step, float(self.clock[STIFF_AT_TIME])) if step > 0 else None

    @property
    def event_rows(self) -> int:
        """Event rows the last driver call wrote."""
        return int(self.counters[EVENT_ROWS])

    def new_event_buffer(self) -> None:
        """Before a call with fresh event buffers: the driver writes its event rows from row 0."""
        self.counters[EVENT_ROWS] = 0
