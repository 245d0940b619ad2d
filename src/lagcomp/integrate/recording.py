"""What a run keeps: every saved row, or only running reductions over them.

The drivers hand back saved rows chunk by chunk.  A `Recorder` either keeps
the rows (``record="trajectory"``) or folds each chunk into a `RunSummary` and
drops it (``record="summary"``), so that a 10⁹-step run needs memory for one
chunk only.  The fold is one compiled call per chunk (`fold_summary_lanes`
with the model's lane kernels where it has them, else `fold_summary`)
calling the kernels for what the summary needs and no more: the
energy, the energy function where it is not the energy itself, the momenta
where a coordinate is cyclic, and at the run's first row and each chunk's
last, whose values the summary's `Observed` holds.  A run keeping its rows
evaluates energies, momenta and summary over all of them when they are first
read (`Observed`, with ``observables`` and `fold_rows`): numba compiles
``observables`` on its first call (0.4 s for a double pendulum, 3.4 s for a
24-link pendulum), which the first trajectory of a new model need not wait
for.  The values are the same either way: the kernels treat each row on its
own, ``observables`` calls the pointwise kernels, and maxima and minima do not
depend on the chunking (`tests/test_solution.py`, `tests/test_recording.py`).

What it costs (DOP853 on the double pendulum over [0, 100] at tol 1e-10, 3 906
rows, 1.1 µs per step; `bench/bench_tiers.py`, table 3): a trajectory copies
its rows, 2 ns a row; a summary evaluates T + V at every row.  Row by row
through a function value (`fold_summary`) that cost 45-48 ns a row and made a
summary 1.05-1.07 times a trajectory's run.  Now a model with lane kernels
(`lagcomp.codegen.energy_lanes`, built on first use) folds a chunk by
`fold_summary_lanes`: its rows copied as columns (1.7 ns a row), E and h of
all of them by the lane kernels (6.6 ns a row with the range check), the
reductions a column at a time (4.8 ns a row, `_extreme`), 14.5 ns a row in all,
plus some 18 µs per compiled call (its function values unboxed: the initial
state is held to fold with the first chunk, `Recorder._hold`).  The lane
kernels are built once a model's summaries have folded `LANES_AFTER_ROWS`
rows without them (or ahead, by ``lagcomp precompile NAME --all``).  A summary
then costs about what a bare trajectory costs; what it saves is memory, and
the energies a trajectory computes when its summary is read.  It is not
cheaper (issue 38; `bench/bench_recording.py`): both have the driver write
every row into the same buffer, then a trajectory copies the rows (joined,
then split into q and q̇: ~2 ns a row) where a summary folds them (T + V at
every row, which a trajectory defers until it is read, and the extremes:
~15 ns a row) in one compiled call per chunk (~15 µs of function values
unboxed).  Through `Model.simulate` with the specialised driver, over the
driver recording nothing: 1.22× for a summary, 1.17× for every step kept,
1.26× for every step kept and its summary read (31 rounds, loaded machine).
Cheaper than a trajectory would need the fold inside the driver, with no
rows written at all.  The values are
bitwise those of the pointwise fold (tests/test_summary_lanes.py).  Folding a
chunk in one compiled call with the first and last rows' values from the
pointwise kernels (rather than calling the ``observables`` kernel for them)
takes the compile of ``observables`` off the path of a new model's first
summary run (1.5-2.1 s before, 0.86-0.98 s after, double pendulum, loaded
machine).
"""

from __future__ import annotations

import contextlib
import weakref
from dataclasses import dataclass

import numpy as np
from numba import njit
from numba.core.dispatcher import Dispatcher

from lagcomp.codegen.kinds import TREE_KIND_OF
from lagcomp.errors import ModelError
from lagcomp.integrate.drivers.kernel_types import (
    ENERGY,
    ENERGY_FUNCTION,
    ENERGY_LANES,
    MOMENTA,
    AddressedKernel,
)
from lagcomp.kernel_support.trig import _TRIG_POLY_MAX

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


#: {model kernels: `pointwise_kernels`}: their function values made (and their addresses looked up) once.
_POINTWISE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def pointwise_kernels(kernels):
    """(energy, energy_function or None when it is the energy kernel itself, momenta) of a model's `kernels` as
    function values for `fold_summary`, once per kernels; None when they are not numba functions (a stand-in)."""
    try:
        return _POINTWISE[kernels]
    except (KeyError, TypeError):
        pass
    found = [getattr(kernels, name, None) for name in ("energy", "energy_function", "momenta")]
    pointwise = None
    if all(isinstance(kernel, Dispatcher) for kernel in found):
        energy, energy_function, momenta = (AddressedKernel(kernel, kind) for kernel, kind in
                                            zip(found, (ENERGY, ENERGY_FUNCTION, MOMENTA), strict=True))
        pointwise = (energy, None if found[1] is found[0] else energy_function, momenta)
    with contextlib.suppress(TypeError):   # (not weakly referenceable: made again at each run)
        _POINTWISE[kernels] = pointwise
    return pointwise


#: {model kernels: `lane_kernels`}, once per kernels.
_LANES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
#: {model kernels: rows its summaries folded by the pointwise kernels in this process}.
_FOLDED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
#: Rows a model's summaries fold by the pointwise kernels before they build its lane kernels, when those are not
#: in the cache yet.  Building them (lowering, emitting, numba's compile) costs some 0.5 s of CPU, what the
#: pointwise fold spends over the lanes' in ~15 million rows (35 ns a row, double pendulum): built at once, they
#: would double a new model's first summary run (0.5 -> 1.1 s); built when the rows folded without them have cost
#: about as much, they cost at most twice what they save (ski rental).  ``lagcomp precompile NAME --all`` builds them.
LANES_AFTER_ROWS = 10_000_000


def lane_kernels(kernels):
    """(energy_lanes, energy_function_lanes) of a model's `kernels` as function values for `fold_summary_lanes`
    (`lagcomp.codegen.energy_lanes`), once per kernels: an on-demand kind, built once the model's summaries have
    folded `LANES_AFTER_ROWS` rows without it (None until then).  None for a model without them: a kinematic tree
    (its energy is `lagcomp.multibody.energy`'s), a Kane model or a stand-in (no companion modules), a model with
    inputs or more than ``UNROLL_MAX`` coordinates (the kind is empty), or one whose companion cannot be built here
    (loaded without its equations, no sympy): their summaries call the pointwise kernels, with the same values."""
    try:
        return _LANES[kernels]
    except (KeyError, TypeError):
        pass
    companion = getattr(kernels, "companion", None)
    lanes = None
    if companion is not None and companion.kind_of is not TREE_KIND_OF:
        if _FOLDED.get(kernels, 0) < LANES_AFTER_ROWS and not _lanes_built(kernels, companion):
            return None         # (not yet: asked again at the next chunk)
        try:
            found = (kernels.energy_lanes, kernels.energy_function_lanes)
        except (AttributeError, ModelError):     # (an empty kind, or no equations to build it from)
            found = ()
        if found and all(isinstance(kernel, Dispatcher) for kernel in found):
            energy, energy_function = (AddressedKernel(kernel, ENERGY_LANES) for kernel in found)
            lanes = (energy, None if found[1] is found[0] else energy_function)
    with contextlib.suppress(TypeError):   # (not weakly referenceable: looked up again at each run)
        _LANES[kernels] = lanes
    return lanes


#: {model kernels} whose lane kernels the cache on disk did not hold when a summary first asked in this process.
_LOOKED_UP: weakref.WeakSet = weakref.WeakSet()


def _lanes_built(kernels, companion) -> bool:
    """Whether the model's lane kernels are built: looked up in the cache on disk at a model's first summary chunk in
    this process, in the process only after (a summary of a model without them asked the disk at every chunk: a
    read of the cache's index, 10 µs, milliseconds on a busy machine, for a run of 0.2 ms).  Lanes built meanwhile
    by another process are found once `LANES_AFTER_ROWS` rows are folded; the values are the same either way."""
    looked_up = kernels in _LOOKED_UP
    if companion.built("energy_lanes", on_disk=not looked_up):
        return True
    with contextlib.suppress(TypeError):   # (not weakly referenceable: looked up at each chunk)
        _LOOKED_UP.add(kernels)
    return False


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
        self.held: tuple | None = None   # summary mode: the first row, not folded yet (`_hold`)
        if not self.keep:  # the running reductions (a run keeping its rows folds them in a new Recorder)
            self.cyclic = np.array([model.coordinates.index(c) for c in model.cyclic], dtype=np.int64)
            size = model.state_size
            self.extremes = np.array([np.full(size, np.inf), np.full(size, -np.inf)])
            self.deviation = np.zeros(2 + len(self.cyclic))
            self.start: np.ndarray | None = None    # (E, h, cyclic momenta) of the first row
            self._kernels = False                   # `_pointwise`, looked up at the first chunk
            self._lanes = False                     # `lane_kernels`, looked up at each chunk until found

    def add(self, ts: np.ndarray, ys: np.ndarray, reused: bool = True) -> None:
        """Take the rows ``ts`` (m,), ``ys`` (m, 2n): copied when kept and the caller `reused` its buffers (kept as
        they are when it does not: a run's last driver call, whose rows `result` copies once, a 3,906-row copy
        fewer for a run of one call), read at once and dropped in summary mode (their first and last rows
        copied)."""
        if ts.shape[0] == 0:
            return
        if self.keep:
            rows = (ts.copy(), ys.copy()) if reused else (ts, ys)
            self._note(rows, copy=False)    # (views of rows no one writes again)
            self.parts.append(rows)
            return
        if self._pointwise() is None:
            if self.first is None:      # the first row's observables start the deviations
                self._fold(ts[:1], ys[:1])
                ts, ys = ts[1:], ys[1:]
            if ts.shape[0]:
                self._fold(ts, ys)
        elif self.first is None and self.held is None and ts.shape[0] == 1:
            self._hold(ts, ys)
        else:
            self._reduce(*self._after_held(ts, ys))

    def _hold(self, ts: np.ndarray, ys: np.ndarray) -> None:
        """Keep the run's first row when it comes alone (`lagcomp.integrate.simulate` adds the initial state on its
        own) to fold with the next chunk: one compiled call fewer, whose unboxing of five function values costs
        some 18 µs, more than the fold of a 3,906-row chunk's energies by lanes (`fold_summary_lanes`)."""
        self.held = (ts.copy(), ys.copy())
        self.last, self.rows = self.held, 1   # (what a caller reads of them meanwhile: the last time, the rows)

    def _after_held(self, ts: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The rows ts, ys after the held first row, if any, which is no longer held (nor counted)."""
        if self.held is None:
            return ts, ys
        (t0, y0), self.held, self.rows = self.held, None, 0
        return np.concatenate([t0, ts]), np.concatenate([y0, ys])

    def _pointwise(self):
        """`pointwise_kernels` of the model; None: call the observables kernel on every row."""
        if self._kernels is False:
            self._kernels = pointwise_kernels(self.model.kernels)
        return self._kernels

    def _reduce(self, ts: np.ndarray, ys: np.ndarray) -> None:
        """Summary mode: fold rows ts, ys into the running reductions by the pointwise kernels in one compiled call
        (`fold_summary`), which also evaluates the observables of the run's first row (they start the deviations)
        and of the chunk's last row (`Observed` of a summary holds the first and last rows')."""
        energy, energy_function, momenta = self._pointwise()
        n, first = self.model.n, self.first is None
        ys = np.ascontiguousarray(ys)       # (each row goes to the kernels as a C-contiguous vector)
        if first:
            self.start = np.empty(2 + self.cyclic.size)
        ends = np.empty((2, 2 + n))         # (E, h, momenta) of the first and the last row
        rest = (energy, energy_function or energy, momenta, energy_function is not None, self.cyclic.size > 0, first,
                ts, ys, self.p, self.cyclic, self.start, self.extremes, self.deviation, ends)
        if not self._lanes:
            self._lanes = lane_kernels(self.model.kernels)
        if self._lanes is None:
            fold_summary(*rest)
            with contextlib.suppress(TypeError):    # (rows toward `LANES_AFTER_ROWS`)
                _FOLDED[self.model.kernels] = _FOLDED.get(self.model.kernels, 0) + ts.shape[0]
        else:
            fold_summary_lanes(self._lanes[0], self._lanes[1] or self._lanes[0], *rest)
        if first:
            self.first = (ts[:1].copy(), ys[:1].copy(), ends[0, :1], ends[0, 1:2], ends[0, 2:][None, :])
        self.last = (ts[-1:].copy(), ys[-1:].copy(), ends[1, :1], ends[1, 1:2], ends[1, 2:][None, :])
        self.rows += ts.shape[0]

    def _note(self, rows: tuple, copy: bool = True) -> None:
        """Count `rows` (arrays along the rows: t, y, ...) and keep their first (the run's first) and last; copied
        unless `copy` is False (rows kept as they are)."""
        if self.first is None:
            self.first = tuple(a[:1].copy() if copy else a[:1] for a in rows)
        self.last = tuple(a[-1:].copy() if copy else a[-1:] for a in rows)
        self.rows += rows[0].shape[0]

    def _fold(self, ts: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, ...]:
        """Evaluate the observables of rows ts, ys into the running reductions; returns them."""
        m = ts.shape[0]
        energy, energy_function, momenta = np.empty(m), np.empty(m), np.empty((m, self.model.n))
        self.model.kernels.observables(ts, ys, self.p, energy, energy_function, momenta)
        self._note((ts, ys, energy, energy_function, momenta))
        if self.start is None:
            self.start = np.concatenate([self.first[2], self.first[3], self.first[4][0, self.cyclic]])
        fold_rows(ys, energy, energy_function, momenta, self.cyclic, self.start, self.extremes, self.deviation)
        return energy, energy_function, momenta

    def result(self) -> tuple[np.ndarray, np.ndarray, Observed]:
        """(t (m,), y (m, 2n), Observed): all rows, or the first and last in summary mode."""
        if self.keep:
            ts, ys = (np.concatenate(columns) for columns in zip(*self.parts))
            model, p, progress = self.model, self.p, self.progress
            return ts, ys, Observed(lambda: _observed_along(model, p, ts, ys, progress))
        if self.held is not None:   # (a run of one row)
            self._reduce(*self._after_held(self.held[0][:0], self.held[1][:0]))
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


@njit(cache=True, error_model="numpy", nogil=True)
def fold_rows(ys, energy, energy_function, momenta, cyclic, start, extremes, deviation):
    """Fold rows into the running reductions, in place, in one pass over them (no temporary arrays).

    ``extremes`` (2, N): the smallest and largest value of each column of ``ys`` (m, N); ``deviation``
    (2 + c,): the largest |energy − start[0]|, |energy_function − start[1]| and |momenta[:, cyclic[k]] −
    start[2 + k]|.  A NaN sticks, as in ``np.minimum``/``np.maximum`` of the rows' ``min``/``max``.
    The chain of numpy calls this replaces cost 0.1 ms per chunk of rows, more than the observables
    kernel itself on a double pendulum (`bench/bench_tiers.py`, the ``record="summary"`` row).
    """
    m, size = ys.shape
    for r in range(m):
        for i in range(size):
            v = ys[r, i]
            low, high = extremes[0, i], extremes[1, i]
            if not np.isnan(low) and (v < low or np.isnan(v)):      # (a NaN, once there, stays)
                extremes[0, i] = v
            if not np.isnan(high) and (v > high or np.isnan(v)):
                extremes[1, i] = v
        _raise_to(deviation, 0, abs(energy[r] - start[0]))
        _raise_to(deviation, 1, abs(energy_function[r] - start[1]))
        for k in range(cyclic.shape[0]):
            _raise_to(deviation, 2 + k, abs(momenta[r, cyclic[k]] - start[2 + k]))


@njit(cache=True, error_model="numpy", nogil=True)
def fold_summary(energy, energy_function, momenta, own_h, cyclic_rows, first, ts, ys, p, cyclic, start, extremes,
                 deviation, ends):
    """`fold_rows` with the values computed row by row by the pointwise kernels (function values).

    ``energy`` at every row, ``energy_function`` too if ``own_h`` (else h is the energy: a model whose T is
    quadratic in q̇ and time-free, whose module binds one kernel to both names), ``momenta`` at the rows of a model
    with a cyclic coordinate (``cyclic_rows``) and at the first and last rows only otherwise.  ``first``: ``ys[0]`` is
    the run's first row, whose E, h and cyclic momenta are written into ``start`` before the fold.  ``ends`` (2, 2 + n)
    gets (E, h, momenta) of the first row (when ``first``) and of the last.  The values are those of the
    ``observables`` kernel, which calls the same kernels on each row; a summary of the double pendulum evaluates
    three cosines per row instead of seven, and calls no kernel of its own (numba compiles ``observables`` for a
    trajectory's energies, on first read: 0.4 s for a double pendulum).  A model with lane kernels folds by
    `fold_summary_lanes`, to the same values.
    """
    m = ys.shape[0]
    e, h = np.empty(m), np.empty(m if own_h else 0)
    for r in range(m):
        e[r] = energy(ts[r], ys[r], p)
        if own_h:
            h[r] = energy_function(ts[r], ys[r], p)
    _fold_energies(e, h if own_h else e, momenta, cyclic_rows, first, ts, ys, np.ascontiguousarray(ys.T), p, cyclic,
                   start, extremes, deviation, ends)


@njit(cache=True, error_model="numpy", nogil=True)
def fold_summary_lanes(energy_lanes, energy_function_lanes, energy, energy_function, momenta, own_h, cyclic_rows,
                       first, ts, ys, p, cyclic, start, extremes, deviation, ends):
    """`fold_summary` with E and h of all the rows from the lane kernels ``energy_lanes`` and
    ``energy_function_lanes`` (`lagcomp.codegen.energy_lanes`), on the rows copied as columns (the layout their loop
    vectorizes on): bitwise the scalar kernels' values, the rows whose sin and cos arguments leave the polynomials'
    range evaluated again by the scalar ``energy`` and ``energy_function``, as `fold_summary` would.
    """
    columns = np.ascontiguousarray(ys.T)
    e = _by_lanes(energy_lanes, energy, ts, ys, columns, p)
    h = _by_lanes(energy_function_lanes, energy_function, ts, ys, columns, p) if own_h else e
    _fold_energies(e, h, momenta, cyclic_rows, first, ts, ys, columns, p, cyclic, start, extremes, deviation, ends)


@njit(cache=True, error_model="numpy", nogil=True)
def _by_lanes(lanes, scalar, ts, ys, columns, p):
    """The values (m,) of a scalar kernel at rows ys (m, N) by its lane kernel on ``columns`` = ysᵀ, rows whose
    trigonometric arguments are not all within `_TRIG_POLY_MAX` (NaN included) by the scalar kernel itself."""
    m = ys.shape[0]
    values, reach = np.empty(m), np.empty(m)
    lanes(ts, columns, p, values, reach)
    for r in range(m):
        if not reach[r] <= _TRIG_POLY_MAX:
            values[r] = scalar(ts[r], ys[r], p)
    return values


@njit(cache=True, error_model="numpy", nogil=True)
def _fold_energies(e, h, momenta, cyclic_rows, first, ts, ys, columns, p, cyclic, start, extremes, deviation, ends):
    """Fold rows ys (m, N), also given as ``columns`` = ysᵀ, with their E and h, e and h (m,), into the running
    reductions (see `fold_summary` for the other arguments): to the values `fold_rows` leaves, each reduction over
    a column at a time (`_extreme`, `_largest_deviation`: 2-3 ns a row on the double pendulum, against 12 ns for
    `fold_rows`'s pass over the rows, which carries each bound through memory from row to row)."""
    m, size = ys.shape
    n = ends.shape[1] - 2
    work = np.empty(n)
    if first:
        momenta(ts[0], ys[0], p, work)
        start[0], start[1] = e[0], h[0]
        for k in range(cyclic.shape[0]):
            start[2 + k] = work[cyclic[k]]
        _ends_row(ends, 0, e[0], h[0], work)
    for i in range(size):
        extremes[0, i] = _extreme(columns[i], extremes[0, i], True)
        extremes[1, i] = _extreme(columns[i], extremes[1, i], False)
    deviation[0] = _largest_deviation(e, start[0], deviation[0])
    deviation[1] = _largest_deviation(h, start[1], deviation[1])
    if cyclic_rows:
        for r in range(m):
            momenta(ts[r], ys[r], p, work)
            for k in range(cyclic.shape[0]):
                _raise_to(deviation, 2 + k, abs(work[cyclic[k]] - start[2 + k]))
    momenta(ts[m - 1], ys[m - 1], p, work)
    _ends_row(ends, 1, e[m - 1], h[m - 1], work)


@njit(cache=True, error_model="numpy", nogil=True)
def _extreme(values, bound, lowest):
    """What `fold_rows` leaves in a running bound after ``values`` (m,), in order: NaN once there (the bound's own,
    else the first NaN met), else the smallest (`lowest`) or the largest of the bound and the values, the first met
    of two that compare equal (+0 and −0, the only equal values whose bits differ).  Four running bounds over
    alternate values, whose chains of comparisons overlap; a zero result is found again in order."""
    if np.isnan(bound):
        return bound
    m = values.shape[0]
    nan = False
    for r in range(m):
        nan |= np.isnan(values[r])
    if nan:
        for r in range(m):
            if np.isnan(values[r]):
                return values[r]
    a0 = a1 = a2 = a3 = bound
    r = 0
    while r + 4 <= m:
        a0 = _better(values[r], a0, lowest)
        a1 = _better(values[r + 1], a1, lowest)
        a2 = _better(values[r + 2], a2, lowest)
        a3 = _better(values[r + 3], a3, lowest)
        r += 4
    for k in range(r, m):
        a0 = _better(values[k], a0, lowest)
    result = _better(a3, _better(a2, _better(a1, a0, lowest), lowest), lowest)
    if result == 0.0:           # (which zero: the first met)
        result = bound
        for k in range(m):
            result = _better(values[k], result, lowest)
    return result


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _better(value, bound, lowest):
    """value if it is below (`lowest`) or above the bound, else the bound (a NaN value never is)."""
    return value if (value < bound if lowest else value > bound) else bound


@njit(cache=True, error_model="numpy", nogil=True)
def _largest_deviation(values, reference, largest):
    """What `_raise_to` leaves in ``largest`` after |values[r] − reference| for each r in order: NaN once there
    (``largest``'s own, else the first NaN met), else the largest (all are ≥ +0: no tie of two zeros)."""
    if np.isnan(largest):
        return largest
    m = values.shape[0]
    a0 = a1 = a2 = a3 = largest
    nan = False
    r = 0
    while r + 4 <= m:
        d0, d1 = abs(values[r] - reference), abs(values[r + 1] - reference)
        d2, d3 = abs(values[r + 2] - reference), abs(values[r + 3] - reference)
        nan |= np.isnan(d0) | np.isnan(d1) | np.isnan(d2) | np.isnan(d3)
        a0, a1 = _better(d0, a0, False), _better(d1, a1, False)
        a2, a3 = _better(d2, a2, False), _better(d3, a3, False)
        r += 4
    for k in range(r, m):
        d = abs(values[k] - reference)
        nan |= np.isnan(d)
        a0 = _better(d, a0, False)
    if nan:
        for k in range(m):
            d = abs(values[k] - reference)
            if np.isnan(d):
                return d
    return _better(a3, _better(a2, _better(a1, a0, False), False), False)


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _ends_row(ends, row, e, h, momenta):
    """ends[row] = (e, h, momenta...)."""
    ends[row, 0], ends[row, 1] = e, h
    for i in range(momenta.shape[0]):
        ends[row, 2 + i] = momenta[i]


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _raise_to(values, i, value):
    """values[i] = max(values[i], value), a NaN on either side giving (and keeping) NaN."""
    if not np.isnan(values[i]) and (value > values[i] or np.isnan(value)):
        values[i] = value


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
