r"""The energy balance's compiled parts: slopes and power along rows, and a sweep's balance folded row by row.

`lagcomp.integrate.energy_balance` integrates the power P = dh/dt along a run's saved rows (quintic Hermite
interpolant of the state through each interval, 4-point Gauss–Legendre on it).  Its loops over the rows
call the model's kernels; they run here, compiled once per installation, with the kernels passed as
function values (``numba.types.FunctionType``) as the drivers take them (`lagcomp.integrate.drivers.kernel_types`):
a call from Python per row cost a few µs, against tens of ns for the kernel itself.

A sweep keeps no rows: `balance_row_kernel` builds, for one model, a kernel with the signature of the sweep
loops' ``energy`` (``(t, y, p) -> float``) that folds each row it is called with into a running balance kept
in slots appended to the trajectory's parameter row (`slots`; as a contact keeps its modes in ``p``:
every sweep loop passes a ``p`` of the trajectory's own), so the sweep loops compute the balance's residual
without a change (`lagcomp.integrate.sweep`).
"""

from __future__ import annotations

import functools

import numpy as np
from numba import njit, types

from lagcomp.integrate.drivers.kernel_types import (
    ENERGY_FUNCTION,
    FLOAT,
    INT,
    MATRIX,
    RHS,
    VECTOR,
)

#: ``power(t, y, p, lam, out) -> int``: the four terms of dh/dt at y into ``out`` (4,), λ = ``lam`` (k,)
#: (`lagcomp.codegen.power`).
POWER = types.FunctionType(types.int64(FLOAT, VECTOR, VECTOR, VECTOR, VECTOR))
#: ``reactions(t, y, p, out) -> int``: the multipliers λ (k,) at y; 0, or j > 0 where singular.
REACTIONS = types.FunctionType(types.int64(FLOAT, VECTOR, VECTOR, VECTOR))

#: 4-point Gauss–Legendre on [0, 1]: nodes and weights.
NODES = 0.5 + 0.5 * np.polynomial.legendre.leggauss(4)[0]
WEIGHTS = 0.5 * np.polynomial.legendre.leggauss(4)[1]
#: The central differences of f along the motion: ε over the row's interval.
DIFFERENCE = 1e-4
#: The number of power terms (`lagcomp.codegen.power.TERMS`).
N_TERMS = 4


@njit(types.int64(RHS, FLOAT, VECTOR, VECTOR, FLOAT, VECTOR, VECTOR, VECTOR), cache=True, error_model="numpy",
      nogil=True)
def rate_along(rhs, t, y, p, eps, f, g, work):
    """``g`` = f' = ∂f/∂t + ∂f/∂y f at (t, y) by central differences along (1, f) over ±`eps`, ``f`` = rhs(t, y)
    given; ``work`` (3 · 2n,) scratch.  Returns rhs's status (0, or k > 0: a singular mass matrix)."""
    n2 = y.shape[0]
    shifted, ahead, behind = work[:n2], work[n2:2 * n2], work[2 * n2:3 * n2]
    for c in range(n2):
        shifted[c] = y[c] + eps * f[c]
    status = rhs(t + eps, shifted, p, ahead)
    for c in range(n2):
        shifted[c] = y[c] - eps * f[c]
    status = max(status, rhs(t - eps, shifted, p, behind))
    for c in range(n2):
        g[c] = (ahead[c] - behind[c]) / (2 * eps)
    return status


@njit(types.void(RHS, VECTOR, MATRIX, VECTOR, VECTOR, MATRIX, MATRIX), cache=True, error_model="numpy", nogil=True)
def slopes_along(rhs, ts, ys, p, local, f, g):
    """f (the model's ``rhs``) and its rate f' at every row (ts (m,), ys (m, 2n)) into ``f``, ``g`` (m, 2n), the
    differences of row i over ±`DIFFERENCE` · ``local[i]``.  (The rows are states a run accepted: rhs's status
    is not read there, as the run read it.)"""
    work = np.empty(3 * ys.shape[1])
    for i in range(ts.shape[0]):
        rhs(ts[i], ys[i], p, f[i])
        rate_along(rhs, ts[i], ys[i], p, DIFFERENCE * local[i], f[i], g[i], work)


@njit(types.void(POWER, VECTOR, MATRIX, VECTOR, MATRIX, MATRIX), cache=True, error_model="numpy", nogil=True)
def power_along(power, ts, ys, p, lam, out):
    """The power's terms at every row (ts (r,), ys (r, 2n)) into ``out`` (r, 4), the multipliers ``lam`` (r, k)
    there."""
    for i in range(ts.shape[0]):
        power(ts[i], ys[i], p, lam[i], out[i])


@njit(types.void(FLOAT, FLOAT, VECTOR, VECTOR, VECTOR, VECTOR, VECTOR, VECTOR, VECTOR), cache=True,
      error_model="numpy", nogil=True)
def hermite(s, d, y0, y1, f0, f1, g0, g1, out):
    """The quintic Hermite interpolant at the fraction `s` of an interval of length `d` into ``out``: through the
    states y0, y1, their slopes f0, f1 and rates g0, g1 at its ends."""
    h0, h5 = 1 - 10 * s**3 + 15 * s**4 - 6 * s**5, 10 * s**3 - 15 * s**4 + 6 * s**5
    h1, h4 = s - 6 * s**3 + 8 * s**4 - 3 * s**5, -4 * s**3 + 7 * s**4 - 3 * s**5
    h2, h3 = (s**2 - 3 * s**3 + 3 * s**4 - s**5) / 2, (s**3 - 2 * s**4 + s**5) / 2
    for c in range(out.shape[0]):
        out[c] = (h0 * y0[c] + h5 * y1[c] + d * (h1 * f0[c] + h4 * f1[c]) + d * d * (h2 * g0[c] + h3 * g1[c]))


#: Where a sweep's balance keeps its running state, in slots appended to each trajectory's parameter row from an
#: offset on: these `HEAD` numbers (started flag, previous row's time, h(0), previous h, scale so far, jumps so far,
#: whether the previous row's rate f' is known, the last value returned, the work of each power term), then the
#: previous row's state y, slope f and rate f' (2n each): `slots`.
STARTED, TIME, H0, H_PREVIOUS, SCALE, JUMPS, RATE_KNOWN, LAST, WORK = range(9)
HEAD = WORK + N_TERMS


def slots(n2: int) -> int:
    """The slots the balance of a state of `n2` components keeps in each parameter row."""
    return HEAD + 3 * n2


@njit(FLOAT(RHS, POWER, ENERGY_FUNCTION, REACTIONS, FLOAT, VECTOR, VECTOR, INT, INT, INT), cache=True,
      error_model="numpy", nogil=True)
def balance_row(rhs, power, energy_function, reactions, t, y_in, p, offset, n2, k):
    """Fold the row (t, y) into the running balance in ``p[offset:]`` (`slots`) and return its residual
    r = h − h(0) − ∫P dt − jumps over the scale so far, s = the largest of |h(0)|, |h − h(0)|, each term's |work|
    and |jumps| (`EnergyBalance.scale` up to t).  The first call starts the balance and returns 0.

    Each interval from the previous row is integrated as `lagcomp.integrate.energy_balance` does (quintic Hermite,
    4-point Gauss, f' by differences over ±`DIFFERENCE` times the interval); a row at the previous row's time with
    another state is a reset: the change of h is a jump.  Only ``y[:n2]`` is read (a DAE loop's state is wider).
    NaN where rhs fails."""
    y = y_in[:n2].copy()
    head = p[offset:offset + HEAD]
    y0, f0, g0 = (p[offset + HEAD:offset + HEAD + n2], p[offset + HEAD + n2:offset + HEAD + 2 * n2],
                  p[offset + HEAD + 2 * n2:offset + HEAD + 3 * n2])
    h = energy_function(t, y, p)
    if head[STARTED] == 0.0:
        head[:] = 0.0
        head[STARTED], head[TIME], head[H0], head[H_PREVIOUS] = 1.0, t, h, h
        head[SCALE] = max(abs(h), 1e-300)
        y0[:] = y
        return 0.0 if rhs(t, y, p, f0) == 0 else np.nan
    d = t - head[TIME]
    if d == 0.0 and np.all(y == y0):
        return head[LAST]
    f1, g1, work, node, lam, terms = (np.empty(n2), np.empty(n2), np.empty(3 * n2), np.empty(n2), np.empty(k),
                                      np.empty(N_TERMS))
    if rhs(t, y, p, f1):
        return np.nan
    if d == 0.0:                              # a reset: h jumps; the rate at the new row waits for an interval
        head[JUMPS] += h - head[H_PREVIOUS]
        head[RATE_KNOWN] = 0.0
    else:
        eps = DIFFERENCE * d
        if head[RATE_KNOWN] == 0.0 and rate_along(rhs, head[TIME], y0, p, eps, f0, g0, work):
            return np.nan
        if rate_along(rhs, t, y, p, eps, f1, g1, work):
            return np.nan
        for j in range(NODES.shape[0]):
            hermite(NODES[j], d, y0, y, f0, f1, g0, g1, node)
            time = head[TIME] + d * NODES[j]
            if k and reactions(time, node, p, lam):
                return np.nan
            power(time, node, p, lam, terms)
            for c in range(N_TERMS):
                head[WORK + c] += d * WEIGHTS[j] * terms[c]
        g0[:] = g1
        head[RATE_KNOWN] = 1.0
    y0[:] = y
    f0[:] = f1
    head[TIME], head[H_PREVIOUS] = t, h
    change = h - head[H0]
    residual = change - head[JUMPS]
    scale = max(head[SCALE], abs(change), abs(head[JUMPS]))
    for c in range(N_TERMS):
        residual -= head[WORK + c]
        scale = max(scale, abs(head[WORK + c]))
    head[SCALE] = scale
    head[LAST] = residual / scale
    return head[LAST]


@njit(types.int64(FLOAT, VECTOR, VECTOR, VECTOR), cache=True, nogil=True)
def no_reactions(t, y, p, out):
    """The multipliers of a model without constraints: none."""
    return 0


def balance_row_kernel(kernels, n2: int, k: int, offset: int):
    """The sweep loops' ``energy`` kernel (``(t, y, p) -> float``) that folds each row into the balance of the
    model of `kernels` (`balance_row`; state size `n2`, `k` multipliers, its slots from ``p[offset]``)."""
    return _balance_kernel(kernels.rhs, kernels.power, kernels.energy_function,
                           kernels.reactions if k else no_reactions, n2, k, offset)


@functools.lru_cache(maxsize=64)
def _balance_kernel(rhs, power, energy_function, reactions, n2: int, k: int, offset: int):
    """`balance_row_kernel` for these kernels (dispatchers: one per model and process, whichever namespace holds
    them).  Compiled once per process and model: numba caches no closure on disk; it is a call of the cached
    `balance_row`."""

    @njit(FLOAT(FLOAT, VECTOR, VECTOR), error_model="numpy", nogil=True)
    def balance(t, y, p):
        return balance_row(rhs, power, energy_function, reactions, t, y, p, offset, n2, k)

    return balance
