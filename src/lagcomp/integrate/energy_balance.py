r"""The energy balance of a run: h(t) − h(0) against the work of the non-conservative forces.

Along a motion the energy function h = q̇·∂L/∂q̇ − L changes at the rate (`lagcomp.codegen.power`)

    dh/dt = P = Q·q̇ − 2D − ∂L/∂t − λ·b,

the power of the generalized forces and inputs, of the Rayleigh dissipation, of the explicit time
(imposed motions, inputs in L) and of moving constraints.  So

    r(t) = h(t) − h(0) − ∫₀ᵗ P dt − J(t)

is zero on the exact motion (J: the jumps of h at events that reset the state), and along a computed one
it is the integration error: the drift of a conservative run's energy, generalized to driven and
dissipative systems.  h is T + V when T is homogeneous quadratic in q̇; otherwise (a moving frame, an
imposed motion in T) T + V is not balanced by anything simple and h is the quantity followed.

The integral is taken along the saved rows: on each interval [tᵢ, tᵢ₊₁], the quintic Hermite
interpolant of the state through yᵢ, yᵢ₊₁, the slopes f (the model's ``rhs``) and their rates f' along
the motion (central differences of ``rhs``) at both ends, and 4-point Gauss–Legendre on it.  Its error
is O(Δ⁷) per interval (Δ = tᵢ₊₁ − tᵢ): the rows of an adaptive run's steps are usually enough (a damped
pendulum at rtol = 1e-10: 2e-8 of the energy against 6e-5 with a cubic interpolant); where they are not,
save rows densely (a ``t_eval`` grid).  Rows at the events that reset the state are added where the saved
ones lack them (from `Solution.events`), so that no interval spans a jump.
`EnergyBalance.quadrature_error` estimates this part
(Richardson: the same integrals over every other row).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lagcomp.errors import ModelError
from lagcomp.integrate.balance_kernels import NODES as _NODES
from lagcomp.integrate.balance_kernels import WEIGHTS as _WEIGHTS
from lagcomp.integrate.balance_kernels import power_along, slopes_along
from lagcomp.integrate.contacts import contacts_of, frictions_of

#: The power's terms, in the order of the ``power`` kernel's output (`lagcomp.codegen.power.TERMS`).
TERMS = ("forces", "dissipation", "time", "constraints")


@dataclass(frozen=True)
class EnergyBalance:
    """h(t) − h(0) against the work of each power term, along a run's saved rows (module docstring).

    Attributes
    ----------
    t : ndarray, shape (m,)
        The saved times, and those of the events that reset the state where no row was saved there (a
        ``t_eval`` run): twice, the states just before and after (`_rows`).
    quantity : str
        What is balanced: ``"T + V"`` when the energy function is the mechanical energy, else ``"h"``
        (the Jacobi integral q̇·∂L/∂q̇ − L).
    change : ndarray, shape (m,)
        h(t) − h(0), in the model's units of energy.
    work : dict of str to ndarray, shape (m,)
        ∫₀ᵗ of each power term: ``"forces"`` (Q·q̇, inputs included), ``"dissipation"`` (−2D, ≤ 0),
        ``"time"`` (−∂L/∂t: imposed motions), ``"constraints"`` (−λ·b: moving constraints).
    jumps : ndarray, shape (m,)
        The sum of the changes of h at the events up to t that reset the state (two rows at one time).
    residual : ndarray, shape (m,)
        change − Σ work − jumps: the integration error (plus `quadrature_error`).
    h0 : float
        h at the first row.
    quadrature_error : float
        An estimate of the largest error of the integrals from the rows' spacing alone.
    """

    t: np.ndarray
    quantity: str
    change: np.ndarray
    work: dict
    jumps: np.ndarray
    residual: np.ndarray
    h0: float
    quadrature_error: float

    @property
    def scale(self) -> float:
        """The size the residual is judged against: the largest of |h(0)|, |change| and each |work| (at least
        1e-300)."""
        sizes = [np.max(np.abs(a), initial=0.0) for a in (self.change, self.jumps, *self.work.values())]
        return max(1e-300, *sizes, abs(self.h0))

    @property
    def max_residual(self) -> float:
        """max |residual| over the run, in units of energy."""
        return float(np.max(np.abs(self.residual), initial=0.0))

    @property
    def relative_residual(self) -> float:
        """`max_residual` / `scale`: comparable with the run's relative tolerance."""
        return self.max_residual / self.scale

    def __repr__(self) -> str:
        works = ", ".join(f"{name}={values[-1]:.6g}" for name, values in self.work.items() if np.any(values))
        return (f"EnergyBalance({self.quantity}: change={self.change[-1]:.6g}, work[{works}], "
                f"max_residual={self.max_residual:.3g} (relative {self.relative_residual:.3g}))")


#: The drift of h beyond which `lagcomp run` and `lagcomp.plots.plot_run` show the energy balance instead: h is
#: then no first integral (forces, dissipation, imposed motions), and its drift measures them, not the error.
BALANCE_ABOVE = 1e-6


def balance_or_none(solution) -> EnergyBalance | None:
    """`solution`'s energy balance where h drifts by more than `BALANCE_ABOVE`; None where it does not, or where
    the balance is refused (contacts, friction, Kane models, a summary run, no kernels kept)."""
    if solution.summary.energy_function_error <= BALANCE_ABOVE:
        return None
    try:
        return energy_balance(solution)
    except ModelError:
        return None


def sweep_balances(model) -> bool:
    """Whether a sweep of `model` reports the energy balance's residual as its energy error (`lagcomp.integrate.
    sweep`): where the balance is available (`PowerSource.of`) and some term of dh/dt is not identically zero
    (``power_terms`` of the ``power`` kind's entry); else h is a first integral and the drift of T + V is kept."""
    if PowerSource.of(model, np.empty(0)).refused:
        return False
    try:
        entry = model.on_demand_entry("power")
    except ModelError:          # (a kinematic tree: its on-demand kinds are refused, naming the issue)
        return False
    return entry is not None and bool(entry.metadata["power_terms"])


class PowerSource:
    """A run's model kernels and parameter vector, for `Solution.energy_balance` (None for a Solution built by
    hand or pickled: the kernels are not kept), or why the balance is refused."""

    def __init__(self, kernels, p: np.ndarray, n: int, k: int, refused: str | None = None):
        self.kernels, self.p, self.n, self.k, self.refused = kernels, p, n, k, refused

    @classmethod
    def of(cls, model, p: np.ndarray) -> PowerSource:
        """The source of `model`'s runs with parameters `p`: refused for Kane models and models with contacts
        or friction elements (their forces are not among Q, D and λ: the balance would not close)."""
        refused = None
        if getattr(model, "speeds", None) is not None:
            refused = "a Kane model (its equations are not Lagrange's: no energy function h is derived)"
        elif contacts_of(model) or frictions_of(model):
            refused = ("contacts or friction elements (their normal and friction forces are not generalized "
                       "forces of the System: the balance would not close)")
        return cls(model.kernels, p, model.n, model.k, refused)

    def __reduce__(self):
        return _unpickled, ()


def _unpickled():
    return None


def energy_balance(solution) -> EnergyBalance:
    """The `EnergyBalance` of `solution` (module docstring); a ModelError where it is refused."""
    source = solution.power_source
    if source is None:
        raise ModelError("This Solution keeps no model kernels (built by hand, pickled or loaded): its energy "
                         "balance needs the run's model; simulate again in this process.")
    if source.refused:
        raise ModelError(f"The energy balance of {solution.model_name!r} is not available for {source.refused}.")
    if solution.summary.rows != solution.t.size:
        raise ModelError("The energy balance integrates the power along the saved rows; a record='summary' run "
                         "keeps only two: run with record='trajectory'.")
    ts, ys, h = _rows(solution, source)
    slopes = _slopes(source, ts, ys)
    work = _work(source, ts, ys, slopes)
    flat = np.diff(ts) == 0                                   # an event's reset: two rows at one time
    jumps = np.concatenate([[0.0], np.cumsum(np.where(flat, np.diff(h), 0.0))])
    change = h - h[0]
    return EnergyBalance(
        t=ts, quantity="T + V" if np.array_equal(solution.energy_function, solution.energy) else "h", change=change,
        work={name: work[:, j] for j, name in enumerate(TERMS)}, jumps=jumps,
        residual=change - work.sum(axis=1) - jumps, h0=float(h[0]),
        quadrature_error=_quadrature_error(source, ts, ys, slopes, work, flat))


def _rows(solution, source: PowerSource) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rows the balance integrates along, (ts (m,), ys (m, 2n), h (m,)): the saved ones, with the states just
    before and just after each located event that reset the state, where the saved rows lack them (a ``t_eval``
    run saves none at events), so that no interval spans a jump."""
    ts, ys, h = solution.t, np.hstack([solution.q, solution.qd]), solution.energy_function
    extra = [(time, 2 if after else 0, np.concatenate(state))    # before the saved rows at that time, or after
             for record in solution.events.values() if record.q_after is not None
             for time, *states in zip(record.t, record.q, record.qd, record.q_after, record.qd_after)
             if not (np.array_equal(states[0], states[2]) and np.array_equal(states[1], states[3]))
             for after, state in ((False, states[:2]), (True, states[2:]))
             if not np.any((ts == time) & np.all(ys == np.concatenate(state), axis=1))]
    if not extra:
        return ts, ys, h
    times = np.concatenate([ts, [time for time, _, _ in extra]])
    ranks = np.concatenate([np.ones(ts.size), [rank for _, rank, _ in extra]])
    order = np.lexsort((ranks, times))
    states = np.vstack([ys, [state for _, _, state in extra]])[order]
    energy = np.array([source.kernels.energy_function(float(time), state, source.p)
                       for time, state in zip(times[order], states)])
    return times[order], states, energy


def _work(source: PowerSource, ts: np.ndarray, ys: np.ndarray, slopes: tuple) -> np.ndarray:
    """∫ from ts[0] to each row of each power term, (m, 4): Gauss–Legendre on the Hermite interpolant of each
    interval (module docstring); nothing across an interval of length 0 (an event's reset)."""
    steps = np.diff(ts)
    nodes_t = ts[:-1, None] + steps[:, None] * _NODES[None, :]
    nodes_y = np.stack([_hermite(s, ys, slopes, steps) for s in _NODES], axis=1)
    power = _power(source, nodes_t.ravel(), nodes_y.reshape(-1, ys.shape[1])).reshape(*nodes_t.shape, -1)
    increments = steps[:, None] * np.einsum("g,igk->ik", _WEIGHTS, power)
    increments[steps == 0] = 0.0
    return np.vstack([np.zeros(len(TERMS)), np.cumsum(increments, axis=0)])


def _hermite(s: float, ys, slopes: tuple, steps) -> np.ndarray:
    """The quintic Hermite interpolant of every interval at its fraction `s`, (m − 1, 2n): through the rows'
    states, slopes f and their rates f' (`_slopes`)."""
    f, g = slopes
    d = steps[:, None]
    h0, h5 = 1 - 10 * s**3 + 15 * s**4 - 6 * s**5, 10 * s**3 - 15 * s**4 + 6 * s**5
    h1, h4 = s - 6 * s**3 + 8 * s**4 - 3 * s**5, -4 * s**3 + 7 * s**4 - 3 * s**5
    h2, h3 = (s**2 - 3 * s**3 + 3 * s**4 - s**5) / 2, (s**3 - 2 * s**4 + s**5) / 2
    return h0 * ys[:-1] + h5 * ys[1:] + d * (h1 * f[:-1] + h4 * f[1:]) + d * d * (h2 * g[:-1] + h3 * g[1:])


def _slopes(source: PowerSource, ts: np.ndarray, ys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """f(tᵢ, yᵢ) (the model's ``rhs``) and its rate along the motion f' = ∂f/∂t + ∂f/∂y f, by central differences
    along (1, f) over ±ε, ε = `balance_kernels.DIFFERENCE` times the row's longer interval; both (m, 2n).  (With ε
    that small the differences' truncation, ε² times the third derivative, and their rounding, 1e-16 |f|/ε, stay
    far below what the interpolant leaves.)  One compiled loop over the rows (`balance_kernels.slopes_along`)."""
    f, g = np.empty_like(ys), np.empty_like(ys)
    steps = np.diff(ts)
    local = np.maximum(np.concatenate([steps, [0.0]]), np.concatenate([[0.0], steps]))
    # (a row between two zero-length intervals, at a reset: the run's span, a time of the problem's own; a single
    # row has no interval that reads its slopes)
    local[local <= 0] = (ts[-1] - ts[0]) or 1.0
    slopes_along(source.kernels.rhs, np.ascontiguousarray(ts), np.ascontiguousarray(ys), source.p, local, f, g)
    return f, g


def _power(source: PowerSource, ts: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """The power's terms at the states `ys` (r, 2n), (r, 4): the multipliers there from ``reactions_along``; one
    compiled loop over the rows (`balance_kernels.power_along`)."""
    ts, ys = np.ascontiguousarray(ts, dtype=float), np.ascontiguousarray(ys, dtype=float)
    lam = np.zeros((ts.size, source.k))
    if source.k:
        residual = np.empty(ts.size)
        source.kernels.reactions_along(ts, ys, source.p, lam, residual)
    out = np.empty((ts.size, len(TERMS)))
    power_along(source.kernels.power, ts, ys, source.p, lam, out)
    return out


def _quadrature_error(source, ts, ys, slopes, work, flat) -> float:
    """The rows' spacing's share of the residual, estimated by Richardson: the same integrals over every other
    row differ from these by about 2⁶ − 1 = 63 times their error (O(Δ⁷) per interval).  Pairs of intervals
    with an event's reset inside keep the fine values (no difference).  0 with fewer than three rows."""
    if ts.size < 3:
        return 0.0
    even = np.arange(0, ts.size, 2)
    coarse = _work(source, ts[even], ys[even], (slopes[0][even], slopes[1][even])).sum(axis=1)
    fine = work[even].sum(axis=1)
    pairs = np.diff(fine - coarse)
    crossing = flat[even[:-1]] | flat[even[:-1] + 1]
    return float(np.max(np.abs(np.cumsum(np.where(crossing, 0.0, pairs))), initial=0.0) / 63)
