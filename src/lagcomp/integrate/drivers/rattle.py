r"""RATTLE: the constrained Störmer-Verlet method, symplectic on the constraint manifold; fixed step; resumable.

The method
----------
For a system that is separable apart from holonomic, scleronomic constraints (`Model.holonomic_separable`:
M constant, F = F(q, t), every constraint Φ(q) = 0 with G = ∂Φ/∂q the constraint matrix Λ and b = 0),
Lagrange's equations in lagcomp's normal form are the constrained Hamiltonian system of
H = ½ pᵀ M⁻¹ p + V(q) (F = −∂V/∂q) with p = M v:

    M q̈ = F(q, t) + G(q)ᵀ λ,      Φ(q) = 0.

A RATTLE step of size h from (q_n, v_n) at t_n, in velocity form (p = M v, M constant, so this is
RATTLE on (q, p) as in Hairer, Lubich & Wanner, *Geometric Numerical Integration*, 2nd ed., sec. VII.1.4,
eq. (1.26); Andersen, J. Comput. Phys. 52 (1983) 24-34; Leimkuhler & Reich, *Simulating Hamiltonian
Dynamics*, sec. 7.2):

    v_½     = v_n + h/2 M⁻¹ (F(q_n, t_n) + G(q_n)ᵀ λ)
    q_{n+1} = q_n + h v_½,                        Φ(q_{n+1}) = 0        (k equations for λ)
    v_{n+1} = v_½ + h/2 M⁻¹ (F(q_{n+1}, t_{n+1}) + G(q_{n+1})ᵀ μ),
                                                  G(q_{n+1}) v_{n+1} = 0  (k linear equations for μ)

It is symmetric, symplectic on the manifold {Φ(q) = 0, G(q) v = 0}, of order 2, and holds both
constraints at every step to the accuracy of the solves (round-off), so the energy error stays bounded
(no drift) over long runs.  Without constraints it is the Störmer-Verlet step of
`lagcomp.integrate.drivers.fixed_step.composition_run`.

How the equations are solved
----------------------------
With a = M⁻¹ F and W = M⁻¹ Gᵀ (n, k) at a position, and the scaled multiplier ν = (h²/2) λ,

    q_{n+1}(ν) = q̃ + W_n ν,     q̃ = q_n + h (v_n + h/2 a_n),

so the position stage is k equations Φ(q̃ + W_n ν) = 0 in ν.  They are solved by simplified Newton:
the Jacobian G(q_{n+1}) W_n is replaced by S_n = G_n W_n = G_n M⁻¹ G_nᵀ (symmetric positive definite
for independent constraints, and independent of h), factored once per position (LU with partial
pivoting), and each iteration is ν ← ν − S_n⁻¹ Φ(q̃ + W_n ν): one ``constraint_residuals`` call and one
k × k substitution.  The contraction factor is O(h) (G changes by O(h) over the step), so a handful of
iterations reach round-off.  Stopping rule, on the change of the coordinates Δq = W_n Δν of an
iteration: converged when max|Δq| ≤ `ROUNDING` max|q| (4 ulps, the rule of the ``project``
kernels), or, once Δq stops shrinking, when it is below `NOISE` max|q| (rounding noise of Φ's
evaluation); relative, so the same in any units (with 1 + max|q| a rod of 1e-12 m stopped at |Δq| ≤ 4 ulps of 1,
one correction early, its length 5e-8 off); a Δq that stops shrinking above that, or `MAX_ITERATIONS` iterations, stop the run with
``CONSTRAINTS_NOT_CONVERGED`` (the step is too large).  Then v_½ = v_n + h/2 a_n + W_n ν / h.

The velocity stage is linear: with w = v_½ + h/2 a_{n+1} and μ' = (h/2) μ, S_{n+1} μ' = −(G_{n+1} w + b)
and v_{n+1} = w + W_{n+1} μ' (b = 0 here; kept so that the stage reads as the velocity constraint).
a, W and the factored S at q_{n+1} are those the next step's position stage needs: one ``forcing`` and
one ``constraint_matrix`` call per step (`_at_position`, also called once at the start of each driver
call; it computes the same bits both times).  M is constant: ``mass_matrix`` is evaluated and factored
once per driver call.

A step of size h runs one RATTLE substep per weight w of a symmetric composition (`composition_run`'s
weights; RATTLE itself: the single weight 1), as `composition_run` does with Störmer-Verlet.

The initial state
-----------------
`simulate` and `sweep` refuse an initial state whose constraint residual exceeds 1e-9, or project it
with ``project_initial=True`` (`lagcomp.integrate.constraints`); the driver does not project it
again.  RATTLE needs no more: the first step's position and velocity stages solve Φ(q_1) = 0 and
G(q_1) v_1 = 0 whatever the small residual of (q_0, v_0), so every state after the first holds the
constraints to round-off.

The driver protocol is `fixed_step`'s (step times from the step index, ``BUFFER_FULL``/``PAUSED``
before a step, continuation bitwise equal to one uninterrupted call).  ``projecting`` is ignored
(`run_options` passes 0 and refuses ``projection=True``): the constraints hold without projection,
which would break the symplectic structure.  ``residual_max[0]`` keeps the largest constraint
residual (position and velocity level) of the accepted states and a second entry, if any, stops the
run with ``RESIDUAL_EXCEEDED`` as in `fixed_step.runge_kutta_run`.
``counters`` = [nfev (``forcing`` calls), nsteps, 0, _, since_save, _]; ``clock`` = [t, _].
A singular M or S (dependent constraints) stops the run with ``RHS_FAILED``, a non-finite state with
``NONFINITE``, ``y`` keeping the last good state.
"""

from __future__ import annotations

import numpy as np
from numba import njit, types

from lagcomp.integrate.drivers.fixed_step import FIXED_STEP_RUN, fixed_step_window
from lagcomp.integrate.drivers.fixed_sweeps import FIXED_SWEEP
from lagcomp.integrate.drivers.kernel_types import (
    CONSTRAINT_MATRIX,
    CONSTRAINT_RESIDUALS,
    ENERGY,
    FLOAT,
    FORCING,
    INDICES,
    INT,
    MASS_MATRIX,
    MATRIX,
    OUTCOME,
    VECTOR,
)
from lagcomp.integrate.drivers.run_state import (
    COUNTER_SLOTS,
    NFEV,
    NSTEPS,
    SINCE_SAVE,
    TIME,
)
from lagcomp.integrate.drivers.sweep_rows import (
    NO_PAUSE,
    SWEEP_ROWS,
    first_row,
    fold_rows,
    record_end,
)
from lagcomp.integrate.status import Status
from lagcomp.kernel_support.linear_solvers import lu_factor, lu_substitute

#: A Newton correction of the coordinates below ROUNDING max|q| has converged (4 ulps).
ROUNDING = 4 * 2.220446049250313e-16
#: A correction that stops shrinking below NOISE max|q| is the rounding noise of Φ: converged too.
NOISE = 1e-10
#: Newton iterations per position stage before the run stops with CONSTRAINTS_NOT_CONVERGED.
MAX_ITERATIONS = 50

#: ``rattle_run(forcing, mass_matrix, constraint_residuals, constraint_matrix, CONSTRAINT_COUNT,
#: <FIXED_STEP_RUN>, weights)``.
RATTLE_RUN = OUTCOME(FORCING, MASS_MATRIX, CONSTRAINT_RESIDUALS, CONSTRAINT_MATRIX, INT, *FIXED_STEP_RUN, VECTOR)
#: ``rattle_sweep(<the same kernels>, CONSTRAINT_COUNT, energy, <FIXED_SWEEP>, weights)``.
RATTLE_SWEEP = types.none(FORCING, MASS_MATRIX, CONSTRAINT_RESIDUALS, CONSTRAINT_MATRIX, INT, ENERGY, *FIXED_SWEEP,
                          VECTOR)

_AT_POSITION = INT(FORCING, CONSTRAINT_MATRIX, FLOAT, VECTOR, VECTOR, MATRIX, INDICES, VECTOR, MATRIX, MATRIX,
                   MATRIX, INDICES)


@njit(_AT_POSITION, cache=True, error_model="numpy", nogil=True)
def _at_position(forcing, constraint_matrix, t, y, p, m_lu, m_pivots, a, c, w, s, s_pivots):
    """What both stages need at the coordinates of `y` (n of them) and time t, from M's LU (`m_lu`, `m_pivots`).

    ``a`` (n,) = M⁻¹ F(q, t); ``c`` (k, n + 1) = [G | b]; ``w`` (k, n): row r = M⁻¹ G_rᵀ (the columns of
    W); ``s`` (k, k) = G M⁻¹ Gᵀ, LU-factored with ``s_pivots``.  Returns 0, or j + 1 when pivot j of S
    vanishes (the constraints are dependent at q).
    """
    n = a.shape[0]
    k = c.shape[0]
    forcing(t, y, p, a)
    lu_substitute(m_lu, m_pivots, a)
    constraint_matrix(t, y, p, c)
    for r in range(k):
        for i in range(n):
            w[r, i] = c[r, i]
        lu_substitute(m_lu, m_pivots, w[r])
    for r in range(k):
        for j in range(k):
            total = 0.0
            for i in range(n):
                total += c[r, i] * w[j, i]
            s[r, j] = total
    return lu_factor(s, s_pivots)


@njit(RATTLE_RUN, cache=True, error_model="numpy", nogil=True)
def rattle_run(forcing, mass_matrix, constraint_residuals, constraint_matrix, k, y, clock, counters, p, projecting,
               residual_max, t0, dt, n_steps, pause_at, t_end, save_every, ts, ys, weights):
    """Integrate with RATTLE substeps of sizes w h (module docstring); k constraints; returns ``(status, n_saved)``."""
    n2 = y.shape[0]
    n = n2 // 2
    cap = ts.shape[0]
    m_lu = np.empty((n, n))
    m_pivots = np.empty(n, dtype=np.int64)
    a = np.empty(n)
    c = np.empty((k, n + 1))
    w = np.empty((k, n))
    s = np.empty((k, k))
    s_pivots = np.empty(k, dtype=np.int64)
    y_new = np.empty(n2)
    residuals = np.empty(2 * k)
    nu = np.empty(k)
    correction = np.empty(k)
    n_saved = 0
    residual_bound = residual_max[1] if residual_max.shape[0] > 1 else np.inf
    if counters[NSTEPS] < n_steps:
        mass_matrix(clock[TIME], y, p, m_lu)
        if lu_factor(m_lu, m_pivots) != 0:
            return Status.RHS_FAILED, n_saved
        pivot = _at_position(forcing, constraint_matrix, clock[TIME], y, p, m_lu, m_pivots, a, c, w, s, s_pivots)
        counters[NFEV] += 1
        if pivot != 0:
            return Status.RHS_FAILED, n_saved
    while True:
        step_index = counters[NSTEPS]
        stop, why, t_a, t_b = fixed_step_window(step_index, n_steps, pause_at, counters[SINCE_SAVE], save_every,
                                                n_saved, cap, t0, dt, t_end)
        if stop:
            return why, n_saved
        last = step_index == n_steps - 1
        h = t_b - t_a

        for i in range(n2):
            y_new[i] = y[i]
        elapsed = 0.0
        converged, singular = True, False
        for j in range(weights.shape[0]):
            hw = weights[j] * h
            elapsed += weights[j]
            t_sub = t_b if j == weights.shape[0] - 1 else t_a + elapsed * h
            # position stage: v_½ = v + hw/2 (a + W λ), q ← q + hw v_½ with Φ(q) = 0 (simplified Newton in ν)
            for i in range(n):
                y_new[n + i] += 0.5 * hw * a[i]
                y_new[i] += hw * y_new[n + i]
            for r in range(k):
                nu[r] = 0.0
            previous = np.inf
            converged = False
            for _ in range(MAX_ITERATIONS):
                constraint_residuals(t_sub, y_new, p, residuals)
                for r in range(k):
                    correction[r] = -residuals[r]
                lu_substitute(s, s_pivots, correction)
                change, size = 0.0, 0.0
                for i in range(n):
                    d = 0.0
                    for r in range(k):
                        d += w[r, i] * correction[r]
                    y_new[i] += d
                    change = max(change, abs(d))
                    size = max(size, abs(y_new[i]))
                for r in range(k):
                    nu[r] += correction[r]
                if change <= ROUNDING * size:
                    converged = True
                    break
                if change >= previous:
                    converged = change <= NOISE * size
                    break
                previous = change
            if not converged:
                break
            for i in range(n):
                d = 0.0
                for r in range(k):
                    d += w[r, i] * nu[r]
                y_new[n + i] += d / hw
            # velocity stage at the new position: v = v_½ + hw/2 (a + W μ) with G v + b = 0 (one linear solve)
            if _at_position(forcing, constraint_matrix, t_sub, y_new, p, m_lu, m_pivots, a, c, w, s, s_pivots) != 0:
                singular = True
                break
            counters[NFEV] += 1
            for i in range(n):
                y_new[n + i] += 0.5 * hw * a[i]
            for r in range(k):
                total = c[r, n]
                for i in range(n):
                    total += c[r, i] * y_new[n + i]
                correction[r] = -total
            lu_substitute(s, s_pivots, correction)
            for i in range(n):
                d = 0.0
                for r in range(k):
                    d += w[r, i] * correction[r]
                y_new[n + i] += d
        if not converged:
            return Status.CONSTRAINTS_NOT_CONVERGED, n_saved
        if singular:
            return Status.RHS_FAILED, n_saved
        finite = True
        for i in range(n2):
            if not np.isfinite(y_new[i]):
                finite = False
        if not finite:
            return Status.NONFINITE, n_saved
        constraint_residuals(t_b, y_new, p, residuals)
        residual = 0.0
        for r in range(2 * k):
            residual = max(residual, abs(residuals[r]))
        if residual > residual_max[0]:
            residual_max[0] = residual

        for i in range(n2):
            y[i] = y_new[i]
        clock[TIME] = t_b
        counters[NSTEPS] = step_index + 1
        counters[SINCE_SAVE] += 1
        if last or counters[SINCE_SAVE] >= save_every:
            ts[n_saved] = t_b
            for i in range(n2):
                ys[n_saved, i] = y[i]
            n_saved += 1
            counters[SINCE_SAVE] = 0
        if residual > residual_bound:
            return Status.RESIDUAL_EXCEEDED, n_saved


@njit(RATTLE_SWEEP, cache=True, error_model="numpy", nogil=True)
def rattle_sweep(forcing, mass_matrix, constraint_residuals, constraint_matrix, k, energy, Y0, P, projecting, t0,
                 dt, n_steps, t_end, save_every, final, t_final, status, counts, dense, energy_stats, weights):
    """Trajectory j from (t0, Y0[j]) with parameters P[j]: ``n_steps`` steps of `rattle_run`
    (`lagcomp.integrate.drivers.fixed_sweeps` describes the outputs)."""
    n2 = Y0.shape[1]
    for j in range(Y0.shape[0]):
        y, p = Y0[j].copy(), P[j]
        clock, counters, residual = np.array([t0, 0.0]), np.zeros(COUNTER_SLOTS, dtype=np.int64), np.zeros(1)
        ts, ys = np.empty(SWEEP_ROWS), np.empty((SWEEP_ROWS, n2))
        e0, deviation, row = energy(t0, y, p), 0.0, first_row(Y0, dense, j)
        while True:
            code, n_saved = rattle_run(forcing, mass_matrix, constraint_residuals, constraint_matrix, k, y, clock,
                                       counters, p, projecting, residual, t0, dt, n_steps, NO_PAUSE, t_end,
                                       save_every, ts, ys, weights)
            deviation, row = fold_rows(energy, ts, ys, n_saved, p, e0, deviation, dense, j, row)
            if code != Status.BUFFER_FULL:
                break
        record_end(j, y, clock, counters, code, e0, deviation, final, t_final, status, counts, energy_stats)
