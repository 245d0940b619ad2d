"""What a run keeps: every saved row, or only running reductions over them.

The drivers hand back saved rows chunk by chunk.  A `Recorder` evaluates the
energies and momenta of each chunk with the compiled ``observables`` kernel
and either keeps the rows (``record="trajectory"``) or folds them into a
`RunSummary` and drops them (``record="summary"``), so that a 10⁹-step run
needs memory for one chunk only.  The summary is computed in both modes.
"""

from __future__ import annotations

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


class Recorder:
    """Collect the chunks of one run (see the module docstring)."""

    def __init__(self, model, p: np.ndarray, record: str):
        self.model, self.p, self.keep = model, p, record == "trajectory"
        self.parts: list[tuple] = []
        self.first: tuple | None = None
        self.last: tuple | None = None
        self.rows = 0
        n = model.n
        self.cyclic = [model.coordinates.index(c) for c in model.cyclic]
        size = model.state_size
        self.extremes = np.array([np.full(size, np.inf), np.full(size, -np.inf)])
        self.deviation = np.zeros(2 + len(self.cyclic))

    def add(self, ts: np.ndarray, ys: np.ndarray) -> None:
        """Take the rows ``ts`` (m,), ``ys`` (m, 2n) (copied: the caller reuses its buffers)."""
        m = ts.shape[0]
        if m == 0:
            return
        ts, ys = ts.copy(), ys.copy()
        energy, energy_function, momenta = np.empty(m), np.empty(m), np.empty((m, self.model.n))
        self.model.kernels.observables(ts, ys, self.p, energy, energy_function, momenta)
        rows = (ts, ys, energy, energy_function, momenta)
        if self.first is None:
            self.first = tuple(a[:1] for a in rows)
        self.last = tuple(a[-1:] for a in rows)
        self.rows += m
        self.extremes[0] = np.minimum(self.extremes[0], ys.min(axis=0))
        self.extremes[1] = np.maximum(self.extremes[1], ys.max(axis=0))
        tracked = np.column_stack([energy, energy_function, momenta[:, self.cyclic]])
        start = np.concatenate([self.first[2], self.first[3], self.first[4][0, self.cyclic]])
        self.deviation = np.maximum(self.deviation, np.max(np.abs(tracked - start), axis=0))
        if self.keep:
            self.parts.append(rows)

    def rows_kept(self) -> tuple[np.ndarray, ...]:
        """(t, y, energy, energy_function, momenta): all rows, or the first and last in summary mode."""
        if self.keep:
            return tuple(np.concatenate(columns) for columns in zip(*self.parts))
        if self.rows == 1:
            return self.first
        return tuple(np.concatenate(pair) for pair in zip(self.first, self.last))

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
