"""What a run keeps: every saved row, or only running reductions over them.

The drivers hand back saved rows chunk by chunk.  A `Recorder` either keeps
the rows (``record="trajectory"``) or evaluates the energies and momenta of
each chunk with the compiled ``observables`` kernel, folds them into a
`RunSummary` and drops them (``record="summary"``), so that a 10⁹-step run
needs memory for one chunk only.  A run keeping its rows evaluates energies,
momenta and summary over all of them when they are first read (`Observed`):
numba compiles ``observables`` on its first call (0.4 s for a double pendulum,
3.4 s for a 24-link pendulum), which the first trajectory of a new model need
not wait for.  The values are the same either way: the kernel treats each row
on its own, and maxima and minima do not depend on the chunking.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass

import numpy as np

RECORD_MODES = ("trajectory", "summary")


@dataclass(frozen=True)
class RunSummary:
    """Running reductions over every saved row of a run (with ``save_every=k``, every k-th step).

    Attributes
    ----------
    rows : int
        Number of states reduced (the initial one included).
    energy_error, energy_function_error : float
        Largest relative deviation max |E − E₀| / |E₀| of T + V and of the
        energy function h from their initial values (absolute when the
        initial value is 0).
    momentum_errors : dict of str to float
        The same for the momentum of each cyclic coordinate.
    q_min, q_max, qd_min, qd_max : ndarray, shape (n,)
        Smallest and largest value of each coordinate and velocity.
    """

    rows: int
    energy_error: float
    energy_function_error: float
    momentum_errors: dict
    q_min: np.ndarray
    q_max: np.ndarray
    qd_min: np.ndarray
    qd_max: np.ndarray


def _relative(deviation: float, reference: float) -> float:
    return deviation / abs(reference) if reference != 0 else deviation


class Observed:
    """T + V, h and the momenta along a run's kept rows, and its `RunSummary`: evaluated on first read, once.

    `values()` is (energy (m,), energy_function (m,), momenta (m, n), summary).  Pickling or copying
    evaluates them and keeps the values only (not the model the evaluation needs).
    """

    def __init__(self, evaluate=None, values: tuple | None = None):
        self._evaluate, self._values = evaluate, values

    def values(self) -> tuple:
        if self._values is None:
            self._values, self._evaluate = self._evaluate(), None
        return self._values

    def __reduce__(self):
        return Observed, (None, self.values())


class Recorder:
    """Collect the chunks of one run (see the module docstring)."""

    def __init__(self, model, p: np.ndarray, record: str, progress=None):
        self.model, self.p, self.keep, self.progress = model, p, record == "trajectory", progress
        self.parts: list[tuple] = []
        self.first: tuple | None = None  # rows (t, y) and, in summary mode, (energy, energy_function, momenta)
        self.last: tuple | None = None
        self.rows = 0
        if not self.keep:  # the running reductions (a run keeping its rows folds them in a new Recorder)
            self.cyclic = [model.coordinates.index(c) for c in model.cyclic]
            size = model.state_size
            self.extremes = np.array([np.full(size, np.inf), np.full(size, -np.inf)])
            self.deviation = np.zeros(2 + len(self.cyclic))

    def add(self, ts: np.ndarray, ys: np.ndarray) -> None:
        """Take the rows ``ts`` (m,), ``ys`` (m, 2n) (copied: the caller reuses its buffers)."""
        if ts.shape[0] == 0:
            return
        ts, ys = ts.copy(), ys.copy()
        if self.keep:
            self._note((ts, ys))
            self.parts.append((ts, ys))
        else:
            self._fold(ts, ys)

    def _note(self, rows: tuple) -> None:
        if self.first is None:
            self.first = tuple(a[:1] for a in rows)
        self.last = tuple(a[-1:] for a in rows)
        self.rows += rows[0].shape[0]

    def _fold(self, ts: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, ...]:
        """Evaluate the observables of rows ts, ys into the running reductions; returns them."""
        m = ts.shape[0]
        energy, energy_function, momenta = np.empty(m), np.empty(m), np.empty((m, self.model.n))
        self.model.kernels.observables(ts, ys, self.p, energy, energy_function, momenta)
        self._note((ts, ys, energy, energy_function, momenta))
        self.extremes[0] = np.minimum(self.extremes[0], ys.min(axis=0))
        self.extremes[1] = np.maximum(self.extremes[1], ys.max(axis=0))
        tracked = np.column_stack([energy, energy_function, momenta[:, self.cyclic]])
        start = np.concatenate([self.first[2], self.first[3], self.first[4][0, self.cyclic]])
        self.deviation = np.maximum(self.deviation, np.max(np.abs(tracked - start), axis=0))
        return energy, energy_function, momenta

    def result(self) -> tuple[np.ndarray, np.ndarray, Observed]:
        """(t (m,), y (m, 2n), Observed): all rows, or the first and last in summary mode."""
        if self.keep:
            ts, ys = (np.concatenate(columns) for columns in zip(*self.parts))
            model, p, progress = self.model, self.p, self.progress
            return ts, ys, Observed(lambda: _observed_along(model, p, ts, ys, progress))
        rows = self.first if self.rows == 1 else tuple(np.concatenate(pair) for pair in zip(self.first, self.last))
        return rows[0], rows[1], Observed(values=(*rows[2:], self.summary()))

    def summary(self) -> RunSummary:
        n = self.model.n
        e0, h0, p0 = self.first[2][0], self.first[3][0], self.first[4][0, self.cyclic]
        return RunSummary(
            rows=self.rows,
            energy_error=float(_relative(self.deviation[0], e0)),
            energy_function_error=float(_relative(self.deviation[1], h0)),
            momentum_errors={
                self.model.coordinates[i]: float(_relative(d, ref))
                for i, d, ref in zip(self.cyclic, self.deviation[2:], p0)
            },
            q_min=self.extremes[0, :n].copy(), q_max=self.extremes[1, :n].copy(),
            qd_min=self.extremes[0, n:].copy(), qd_max=self.extremes[1, n:].copy(),
        )


def _observed_along(model, p: np.ndarray, ts: np.ndarray, ys: np.ndarray, progress) -> tuple:
    """What a summary-mode `Recorder` computes chunk by chunk, over all the rows ts, ys at once."""
    from lagcomp.stages import numba_stage

    folding = Recorder(model, p, "summary")
    stage = numba_stage(model.kernels.observables, "the energies and momenta", f"{model.name}: energies", progress)
    with stage or contextlib.nullcontext() as stages:
        if stages is not None:
            stages.start(stages.names[0])
        energies = folding._fold(ts, ys)
    return (*energies, folding.summary())
