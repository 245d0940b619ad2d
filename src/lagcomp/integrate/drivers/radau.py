"""Adaptive Radau IIA of order 5 for stiff systems: Hairer & Wanner's RADAU5 scheme, the whole loop compiled.

`radau_run` integrates y' = f(t, y), or the DAE M y' = f(t, y) with a constant diagonal mass M of ones
and zeros (below), with the three-stage Radau IIA method (`lagcomp.integrate.radau`
derives its constants), the model's exact Jacobian J = ∂f/∂y (``rhs_jacobian``), step-size control
and dense output, following Hairer & Wanner, *Solving Ordinary Differential Equations II* (2nd ed.,
1996), sec. IV.8, and scipy's ``Radau`` (``scipy/integrate/_ivp/radau.py``), whose accepted steps it
takes up to round-off (tests/test_radau_driver.py compares them):

1. Stage equations in the transformed variables W = T⁻¹ Z (Z_i = y(t + c_i h) − y), solved by the
   simplified Newton iteration with one real LU of (γ/h M − J) and one complex LU of ((α − iβ)/h M − J)
   (M = I for an ODE; `lagcomp.kernel_support.linear_solvers.lu_factor`, complex for the second);
   at most `NEWTON_MAXITER` iterations, stopped early when the convergence rate θ = ‖ΔWₖ‖/‖ΔWₖ₋₁‖
   is ≥ 1 or predicts no convergence within the budget (θ^(maxiter−k)/(1−θ) ‖ΔW‖ > tol), converged
   when θ/(1−θ) ‖ΔW‖ < tol with tol = max(10 eps/rtol, min(0.03, √rtol)).  Starting values: the
   previous step's collocation polynomial extrapolated to t + c_i h (zero at the first step).
2. Newton failure: with an old Jacobian, evaluate J at (t, y) and retry; with the current one, halve
   the step.  A singular iteration matrix is handled the same way.
3. Error: err = (γ/h M − J)⁻¹ (f(t, y) + M E·Z/h), RMS norm with scale atol_i + max(|y_i|, |y_new,i|) rtol
   (of the differential components: "DAEs");
   on the first step and after a rejection an estimate > 1 is filtered once more,
   err = (γ/h M − J)⁻¹ (f(t, y + err) + M E·Z/h) (HNW IV.8, (8.21); scipy does it after rejections only).
4. Step size: Gustafsson's predictive controller, factor = min(1, h/h_old (err_old/err)^¼) err^(−¼)
   times the safety 0.9 (2 maxiter + 1)/(2 maxiter + iterations), bounded by `MIN_FACTOR` on a
   rejection and `MAX_FACTOR` after an accepted step.  After an accepted step the step is kept
   (and with it the LU factors) when the factor is below 1.2 and J is not re-evaluated; J is
   re-evaluated at the new state when the Newton iteration took more than 2 iterations at a rate
   above `JACOBIAN_RATE` (`DAE_JACOBIAN_RATE` for a DAE), else the old J is kept (and marked not current).
5. Dense output: the collocation polynomial y + Σ_k Q_k x^(k+1), Q = Pᵀ Z (`events.DENSE_POWERS`
   with rows Q/h): ``t_eval`` points, events (located on it by `events.record_events`, as the explicit
   drivers do) and the next step's starting values.

Arguments: the kernels ``rhs``, ``rhs_jacobian`` and ``event_values`` (`kernel_types`), then the driver
protocol of `lagcomp.integrate.drivers` exactly as `lagcomp.integrate.drivers.embedded.embedded_run`
takes it (``y``, ``clock``, ``counters``, ``p``, ``projecting``, ``residual_max``, ``t_end``, ``rtol``,
``atol``, ``max_step``, ``max_steps``, ``pause_at``, ``save_every``, ``t_eval``, ``ts``, ``ys``,
``directions``, ``actions``, ``ev_t``, ``ev_y``, ``ev_i``), so that `lagcomp.integrate.simulate`
calls both alike (``atol`` (N,) per component: only its first ``differential`` entries are read, the algebraic
components' scales come from `_algebraic_scales`); ``projecting`` and ``residual_max`` are unused (constrained
systems are solved as DAEs, not projected: "DAEs" below).  Then
the method's constants (`RadauIIA.driver_arguments`: C, T, TI, MU, ERROR_WEIGHTS, DENSE_WEIGHTS), the
count ``differential`` of differential components (0 ≤ differential ≤ N; N for an ODE; DAEs below) and
its carry, the state a run keeps from call to call besides (y, clock, counters), owned by the caller
(`new_carry`):

* ``jacobian`` (N, N): the last J;
* ``previous`` (4, N): the last step's dense rows Q/h (rows 0-2) and its initial state (row 3);
* ``control`` float64[`CONTROL_SLOTS`]: the last step's proposed size and error norm (the
  controller's memory; 0: none), whether J is current (evaluated at the last accepted state or
  after it) and held at all, the step h of the LU factors held (0: none, refactored at the next
  call's start: the factors are not kept between calls), and the start and size of the last step
  (whose polynomial ``previous`` holds; size 0: none).

Counters: besides `NFEV`, `NSTEPS`, `NREJECTED` (error rejections and Newton failures), `NJEV`
Jacobian evaluations and `NLU` LU factorisations (two per factorisation of the pair, as scipy counts).

It returns ``(status, n_saved)``: DONE; BUFFER_FULL or PAUSED (call again: the continuation takes the
same steps, bit for bit, with one more f evaluation and, if factors were held, one more pair of LU
factorisations per call); TERMINATED; NONFINITE, RHS_FAILED (``rhs`` or ``rhs_jacobian`` reported a
singular mass matrix), STEP_TOO_SMALL, MAX_STEPS, NEWTON_FAILED, ITERATION_MATRIX_SINGULAR, with
``y`` and ``clock[0]`` the last accepted state.  A step that holds more ``t_eval`` points than the
output buffer is committed; the next call first writes its remaining points from ``previous``.

DAEs
----

With ``differential`` = d < N, ``rhs`` gives G(t, z) and ``rhs_jacobian`` ∂G/∂z of the DAE M z' = G(t, z),
M = diag(1 × d, 0 × (N − d)): components [0, d) differential, [d, N) algebraic (of index 2).  The intended
DAE is the stabilised index-2 (Gear–Gupta–Leimkuhler) form of a constrained Lagrange model
(`lagcomp.integrate.dae`): z = (q, v, w, λ, μ), d = 2n, G = (v + Λ_hᵀμ, w, M(q) w − F − Λᵀλ, Λ v + b, Φ),
started consistently (μ = 0, w and λ from the augmented solve).  M enters the iteration matrices, the
Newton right-hand sides T⁻¹F − (shift/h) M W and the error estimate as written above (HNW II, sec. VI.6;
RADAU5 with IMAS = 1).  The initial step is estimated from the differential components alone.
Units.  The algebraic components are in the units of neither the state nor each other (w an acceleration,
λ a force, μ a position over a time), and ``atol`` is in the state's.  RADAU5 scales them by
(atol + |z| rtol)/h (IWORK(6)), which mixes their units with atol's and with the unit of time (the bundled
four-bar linkage scaled to millimetres, or by 1e3, then ended at t = 0 with NEWTON_FAILED).  Here
(`_algebraic_scales`) the scale of z_j is (a_j + rtol |z_j| τ)/h: τ the motion's own time scale
(`_time_scale`: min(‖y‖/‖y'‖, ‖y'‖/‖y''‖) of the differential components, ~1/ω) where RADAU5 has the unit of
time, and a_j the absolute part the differential scales imply: an error δz_j moves the derivatives of the
differential rows i that depend on it by J_ij δz_j, so a_j = min_i scale_i/|J_ij| (λ enters no differential
row: its error is w's, and it is left out).  The same scales in the Newton and the error norms; and the
iteration matrices are factored equilibrated (`lagcomp.kernel_support.linear_solvers.equilibrate`, powers of
two), so that the pivot test does not
depend on the units of their blocks either: a run takes the same steps in any units.  What did not do:
leaving the algebraic components out of the norms (the pendulum's error erratic in rtol: 1.2e-8 at 1e-7,
1.7e-10 at 1e-10), or a_j/h alone (RADAU5's relative part dropped: the spherical pendulum in Cartesian
coordinates at rtol 1e-9, atol 1e-12, whose v_x starts at 0, ended with ITERATION_MATRIX_SINGULAR, its w's
error estimate, O(1/h) as index-2 estimates are, measured against atol/h).  Measured against RADAU5's scales
(errors against a reference at rtol 1e-13, and steps): the pendulum of tests/test_radau_dae.py over 30 s at
rtol 1e-6, 1e-8, 1e-10, 1.1e-6, 7.0e-9, 1.8e-11 in 1827, 5689, 18059 steps against 1.9e-6, 7.2e-9, 2.8e-11 in
1811, 5640, 17900; the four-bar linkage over 10 s, 2.5e-5, 1.2e-7, 8.6e-10 in 2933, 9048, 28865 steps against
9.5e-6, 5.3e-8, 3.0e-10 in 2502, 7894, 25264 (the same steps in millimetres or kilometres, where RADAU5's
failed).
The Newton increments carry the rounding noise of the constraints (Φ and Λ(q) evaluated at a q known to
ulp(|q|)) amplified by ~γ/h through the iteration matrix, and the velocities carry it unamplified (v is
solved from Λ v + b = 0, not integrated); at tight tolerances and large |q| the increments stop shrinking
above the Newton tolerance.  So an iteration whose increment was already below `NEWTON_NOISE` of the error
scale when it stopped shrinking is taken as converged (the ODE path never does).  Measured on the four-bar
linkage over 30 s, whose crank angle reaches 360 rad: without that rule rtol 1e-10 failed at t = 21 s
(with RADAU5's scales), with it the run ends with the constraints at 2.5e-13; below rtol 1e-10 the noise
wins anyway (`lagcomp.integrate.dae.DAE_RTOL_MIN`: rtol 1e-12 ends with NEWTON_FAILED at t = 6.3 s).
Orders (HNW II, sec. VII.4; Hairer, Lubich & Roche 1989): 5 for the differential components, 3 for
the algebraic ones (tests/test_radau_dae.py).  The Newton iteration takes ~3 iterations per step on these problems
however old J is: on the pendulum of tests/test_radau_dae.py at rtol 1e-6, 1e-8, 1e-10 the first increment is 5,
5, 2 error scales (the extrapolated polynomial's error) against Newton tolerances of 1e-3, 1e-4, 1e-5 of them, and
the first rate 0.036, 0.012, 0.004 (geometric means) with J current at ~95% of the steps: J's change across the
stages sets the rate, not J's age.  So a DAE's J is re-evaluated only above the rate `DAE_JACOBIAN_RATE` = 1e-2
(HNW raise RADAU5's THET for an expensive J).  Measured against 1e-3 (same-process A/B, 7 rounds, the pendulum and
bench/bench_loop.py's four-bar linkage): at rtol 1e-10, J evaluations 16,871 → 5,324 and 67,132 → 32,542, steps
+0.6% and +1.1%, iterations per step 2.96 → 3.00 and 3.02 → 3.07, time ×0.67 and ×0.70, error ×1.3 and ×1.6 (at
equal error, interpolated along rtol 1e-8 .. 1e-10: ×0.71 and ×0.77 the time); at 1e-8 time ×0.82 and ×0.77
(×0.84, ×0.82 at equal error); at 1e-6 the same.  What did not pay: rates 2e-2, 3e-2 and 0.1 (more iterations and
error: 0.1 takes 4 per step), the algebraic components started at their values at y (+1 iteration per step,
×1.2-1.4 the time), RADAU5's convergence factor carried from step to step (it never accepts the first iteration
here: that increment is too large), a Newton tolerance 3 times looser for DAEs (error up to ×9 for 1-13% less
time).  Loops over the components are
split at d, so that for d = N (an ODE) every operation and its order are those of the ODE driver before
the DAE form: the same bits, and the same time (same-process A/B against the ODE-only driver on
bench_radau's problems: +1.0% on average over 15 processes, within their ±6% spread).

The output-buffer, step-clamping and non-finite rules are embedded_run's (its docstring): every test
is written so that NaN rejects a step (``not err <= 1``) or ends the run (``not h >= min_step``);
a step whose error estimate is not finite is rejected with h × `MIN_FACTOR` (scipy would accept it).
One deviation from scipy in a degenerate case: an error norm of exactly 0 is not remembered as the
controller's err_old (it would give a factor 0 at the next step).

Measured
--------

Steps: scipy's own at rtol 1e-3 .. 1e-9 on the stiff spring-damper, Robertson and the oscillator (equal
counts of steps, f and J evaluations and LU factorisations; tests/test_radau_driver.py); on the stiff
Van der Pol problem (ε = 1e-6) round-off steers the runs apart (a Newton iteration that converges one
iteration later changes the step), within 1% in steps (e.g. 882 against 874 at rtol 1e-6).  The first
step's re-filtered estimate (HNW's, not scipy's) changes the first step where its first trial fails.

Speed (``python -m bench.bench_radau``: Van der Pol ε = 1e-6 and Robertson, hand-written kernels, the
driver called directly, at equal error against an LSODA reference at rtol 1e-12): scipy's Radau on the
same numba kernels takes 150-290 times as long; numbalsoda's LSODA 1.3-1.6 times (its own
finite-difference Jacobian; these systems have 2 and 3 components); DOP853 on the Van der Pol problem
takes 600 000 steps, 230 ms (radau: 0.18 ms at rtol 1e-3 and a smaller error).  On the bundled stiff
spring pendulum (``python -m bench.bench_stiff``, 4 components) LSODA takes 1.4-1.7 times the driver
call's time at equal error, 0.93-1.09 times ``Model.simulate``'s: simulate's own cost, the same for every
method (0.1-0.2 ms), is as large as a short run.  A driver
call costs ~16 µs besides its steps with `AddressedKernel` kernels (~120 µs with dispatchers: numba
unboxes three kernels).  Where a run's time goes (``python -m bench.bench_radau --parts``, the spring
pendulum at rtol 1e-8): the Newton iterations 67% (~270 ns each: f 3 × 24 ns, the two substitutions
90 ns), the error estimate's substitution 7%, the other per-step work 19%, J and the LU factorisations
4%.  Hence the loop has no row views (``F[s]`` as the rhs output, ``previous[:3]`` for the starting
values cost 25-37% of the run), `_newton` is inlined and the two substitutions interleave
(`_substitute_pair`): those two cut 15-20% of the driver's time, same bits.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from lagcomp.integrate.drivers.events import DENSE_POWERS, dense_state, event_crossings, record_events
from lagcomp.integrate.drivers.kernel_types import (
    EVENTS,
    FLOAT,
    INDICES,
    INT,
    MATRIX,
    OUTCOME,
    RHS,
    RHS_JACOBIAN,
    VECTOR,
)
from lagcomp.integrate.drivers.run_state import (
    EVENT_ROWS,
    NEXT_EVAL,
    NFEV,
    NJEV,
    NLU,
    NREJECTED,
    NSTEPS,
    SINCE_SAVE,
    STEP,
    TIME,
)
from lagcomp.integrate.status import Status
from lagcomp.kernel_support.linear_solvers import equilibrate, lu_factor, lu_substitute

#: Newton iterations per step (HNW's NIT = 7 in radau5.f; scipy's 6, taken here).
NEWTON_MAXITER = 6
#: Bounds of the factor by which one step may change the next (scipy's).
MIN_FACTOR, MAX_FACTOR = 0.2, 10.0
#: After an accepted step the step (and the LU factors) is kept unless it would grow by this factor.
KEEP_STEP_BELOW = 1.2
#: J is evaluated again after a step whose Newton iteration took more than 2 iterations at a rate above this.
JACOBIAN_RATE = 1e-3
#: The same for a DAE (differential < N), whose rate J does not set (module docstring, "DAEs").
DAE_JACOBIAN_RATE = 1e-2
#: A DAE's Newton iteration whose increments stop shrinking below this (in the norm of the error test) has reached
#: the rounding noise of its constraints: its stages are taken as converged (module docstring, "DAEs").
NEWTON_NOISE = 0.03
EPS = 2.220446049250313e-16

#: Slots of ``control``: the last step's proposed size and error norm, J current (1.0) / held (1.0), the
#: step of the LU factors held, the start and size of the last step (the polynomial in ``previous``).
H_PROPOSED, ERR_PREVIOUS, JAC_CURRENT, JAC_HELD, LU_STEP, T_PREVIOUS, H_PREVIOUS = 0, 1, 2, 3, 4, 5, 6
CONTROL_SLOTS = 7

#: Why the last trial step failed: its error, a non-finite value, Newton, a singular iteration matrix.
_ERROR, _NONFINITE, _NEWTON, _SINGULAR = 0, 1, 2, 3

#: The method's constants (`lagcomp.integrate.radau.RadauIIA.driver_arguments`), then the carry.
CONSTANTS = (VECTOR, MATRIX, MATRIX, VECTOR, VECTOR, MATRIX)
CARRY = (MATRIX, MATRIX, VECTOR)

SIGNATURE = OUTCOME(RHS, RHS_JACOBIAN, EVENTS,
                    VECTOR, VECTOR, INDICES, VECTOR, INT, VECTOR, FLOAT, FLOAT, VECTOR, FLOAT, INT, INT, INT,
                    VECTOR, VECTOR, MATRIX, INDICES, INDICES, VECTOR, MATRIX, INDICES,
                    *CONSTANTS, INT, *CARRY)


def new_carry(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The carry of a new run of an N-component system: (jacobian, previous, control), see the module docstring."""
    return np.zeros((n, n)), np.zeros((4, n)), np.zeros(CONTROL_SLOTS)


@njit(cache=True, error_model="numpy", nogil=True)
def _factor(jacobian, h, MU, differential, lu_real, pivots_real, lu_complex, pivots_complex, rows, columns):
    """LU factors of γ/h M − J and (α − iβ)/h M − J in place, M = diag(1 × differential, 0 × the rest);
    0, or k > 0 when one is singular (pivot k).

    A DAE's matrices are equilibrated first (`equilibrate`): both factored as R A C, with the powers of two
    R = diag(``rows``), C = diag(``columns``) of the real one; an ODE's are factored as they are (R = C = I:
    the same bits as without).
    """
    n = jacobian.shape[0]
    shift_real = MU[0] / h
    shift_complex = complex(MU[1], MU[2]) / h
    for i in range(n):
        for j in range(n):
            lu_real[i, j] = -jacobian[i, j]
    for i in range(differential):
        lu_real[i, i] += shift_real
    if differential < n:
        equilibrate(lu_real, rows, columns)
    else:
        for i in range(n):
            rows[i] = 1.0
            columns[i] = 1.0
    for i in range(n):
        for j in range(n):
            lu_complex[i, j] = -jacobian[i, j] * rows[i] * columns[j]
    for i in range(differential):
        lu_complex[i, i] += shift_complex * rows[i] * columns[i]
    status = lu_factor(lu_real, pivots_real)
    if status != 0:
        return status
    return lu_factor(lu_complex, pivots_complex)


@njit(cache=True, error_model="numpy", nogil=True)
def _substitute_pair(lu_real, pivots_real, d_real, lu_complex, pivots_complex, d_complex, rows, columns, scaled):
    """`lu_substitute` of the real and the complex system at once, in place: the same operations in the same
    order for each, so the same bits, but the two dependency chains of the triangular solves interleave
    (each alone waits on its divisions and subtractions: ~25% less time for N = 4).  With ``scaled`` (a DAE)
    the factors are those of R A C (`_factor`): the right-hand sides are scaled by R first, the solutions by C
    after (powers of two)."""
    n = d_real.shape[0]
    if scaled:
        for i in range(n):
            d_real[i] *= rows[i]
            d_complex[i] *= rows[i]
    for j in range(n):
        d_real[j], d_real[pivots_real[j]] = d_real[pivots_real[j]], d_real[j]
        d_complex[j], d_complex[pivots_complex[j]] = d_complex[pivots_complex[j]], d_complex[j]
    for i in range(n):
        x = d_real[i]
        z = d_complex[i]
        for c in range(i):
            x -= lu_real[i, c] * d_real[c]
            z -= lu_complex[i, c] * d_complex[c]
        d_real[i] = x
        d_complex[i] = z
    for i in range(n - 1, -1, -1):
        x = d_real[i]
        z = d_complex[i]
        for c in range(i + 1, n):
            x -= lu_real[i, c] * d_real[c]
            z -= lu_complex[i, c] * d_complex[c]
        d_real[i] = x / lu_real[i, i]
        d_complex[i] = z / lu_complex[i, i]
    if scaled:
        for i in range(n):
            d_real[i] *= columns[i]
            d_complex[i] *= columns[i]


@njit(cache=True, error_model="numpy", nogil=True)
def _substitute_real(lu_real, pivots_real, r, rows, columns, scaled):
    """`lu_substitute` with the real factors (of R A C with ``scaled``, `_factor`): A x = r solved in place."""
    n = r.shape[0]
    if scaled:
        for i in range(n):
            r[i] *= rows[i]
    lu_substitute(lu_real, pivots_real, r)
    if scaled:
        for i in range(n):
            r[i] *= columns[i]


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _newton(rhs, t, y, h, p, C, T, TI, MU, differential, Z, W, F, ytmp, f_stage, d_real, d_complex, lu_real,
            pivots_real, lu_complex, pivots_complex, rows, columns, scale, tol):
    """Simplified Newton iteration for the stages Z (3, N), which hold the starting values on entry.

    The right-hand sides are T⁻¹F − (shift/h) M W with M = diag(1 × differential, 0 × the rest): the
    components from ``differential`` on (algebraic, mass 0) take T⁻¹F alone, in a loop of their own.

    The stage derivatives go to F (3, N) by way of ``f_stage`` (N,): a row view F[s] per rhs call, built
    and reference-counted by numba each time, cost more than the copy.  Inlined into the driver (numba's
    ``inline="always"``): a call passes its 13 arrays as structs and reference-counts them, ~10% of the
    driver's time on a 4-component model (bench/bench_radau.py).

    Returns (status, converged, iterations, rate, f evaluations): status 0, the rhs status (> 0) or −1
    for a non-finite stage derivative; rate < 0 when fewer than two iterations were made.
    """
    n = y.shape[0]
    shift_real = MU[0] / h
    shift_complex = complex(MU[1], MU[2]) / h
    for s in range(3):
        for i in range(n):
            W[s, i] = TI[s, 0] * Z[0, i] + TI[s, 1] * Z[1, i] + TI[s, 2] * Z[2, i]
    norm_old = -1.0
    rate = -1.0
    nfev = 0
    iterations = 0
    for k in range(NEWTON_MAXITER):
        iterations = k + 1
        for s in range(3):
            for i in range(n):
                ytmp[i] = y[i] + Z[s, i]
            status = rhs(t + C[s] * h, ytmp, p, f_stage)
            nfev += 1
            if status != 0:
                return status, False, iterations, rate, nfev
            for i in range(n):
                F[s, i] = f_stage[i]
                if not np.isfinite(f_stage[i]):
                    status = -1
            if status != 0:
                return status, False, iterations, rate, nfev
        for i in range(differential):
            f0, f1, f2 = F[0, i], F[1, i], F[2, i]
            d_real[i] = TI[0, 0] * f0 + TI[0, 1] * f1 + TI[0, 2] * f2 - shift_real * W[0, i]
            g = complex(TI[1, 0] * f0 + TI[1, 1] * f1 + TI[1, 2] * f2, TI[2, 0] * f0 + TI[2, 1] * f1 + TI[2, 2] * f2)
            d_complex[i] = g - shift_complex * complex(W[1, i], W[2, i])
        for i in range(differential, n):
            f0, f1, f2 = F[0, i], F[1, i], F[2, i]
            d_real[i] = TI[0, 0] * f0 + TI[0, 1] * f1 + TI[0, 2] * f2
            d_complex[i] = complex(TI[1, 0] * f0 + TI[1, 1] * f1 + TI[1, 2] * f2,
                                   TI[2, 0] * f0 + TI[2, 1] * f1 + TI[2, 2] * f2)
        _substitute_pair(lu_real, pivots_real, d_real, lu_complex, pivots_complex, d_complex, rows, columns,
                         differential < n)
        acc = 0.0
        for i in range(n):
            a = d_real[i] / scale[i]
            b = d_complex[i].real / scale[i]
            c = d_complex[i].imag / scale[i]
            acc += a * a + b * b + c * c
        norm = np.sqrt(acc / (3 * n)) if n > 0 else 0.0
        if not np.isfinite(norm):
            return 0, False, iterations, rate, nfev
        if norm_old >= 0.0:
            rate = norm / norm_old
            if rate >= 1.0 or rate ** (NEWTON_MAXITER - k) / (1.0 - rate) * norm > tol:
                # a DAE's increments stop shrinking at the rounding noise of its constraints (module docstring)
                return 0, differential < n and norm_old <= NEWTON_NOISE, iterations, rate, nfev
        for i in range(n):
            W[0, i] += d_real[i]
            W[1, i] += d_complex[i].real
            W[2, i] += d_complex[i].imag
        for s in range(3):
            for i in range(n):
                Z[s, i] = T[s, 0] * W[0, i] + T[s, 1] * W[1, i] + T[s, 2] * W[2, i]
        if norm == 0.0 or (rate >= 0.0 and rate / (1.0 - rate) * norm < tol):
            return 0, True, iterations, rate, nfev
        norm_old = norm
    return 0, False, iterations, rate, nfev


@njit(cache=True, error_model="numpy", nogil=True)
def _error_norm(err, y, y_new, rtol, atol, differential, h, jacobian, time_scale, scale):
    """RMS norm of err scaled by atol + max(|y|, |y_new|) rtol for the differential components, and for the
    algebraic ones (from ``differential`` on) by the scales `_algebraic_scales` gives (with ``jacobian`` and
    ``time_scale``); ``scale`` (N,) is work space.  0 for N = 0."""
    n = y.shape[0]
    for i in range(differential):
        scale[i] = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol
    _algebraic_scales(jacobian, differential, h, rtol, y, y_new, time_scale, scale)
    acc = 0.0
    for i in range(n):
        e = err[i] / scale[i]
        acc += e * e
    return np.sqrt(acc / n) if n > 0 else 0.0


@njit(cache=True, error_model="numpy", nogil=True)
def _algebraic_scales(jacobian, differential, h, rtol, y, y_new, time_scale, scale):
    """The algebraic components' scales (from ``differential`` on), RADAU5's (atol + rtol |z_j|)/h in units of
    z_j: (a_j + rtol max(|z_j|, |z_new,j|) τ)/h, τ = ``time_scale`` (`_time_scale`), a_j the absolute part the
    differential scales in ``scale`` imply, min over the differential rows i that depend on z_j of
    scale_i/|J_ij| (∞ when none does: then z_j is left out of the norms).

    An error δz_j moves the differential derivatives by J_ij δz_j, their values over a time τ by τ J_ij δz_j,
    so a_j measures it in their units; RADAU5's time is the unit of time (module docstring, "DAEs")."""
    n = scale.shape[0]
    for j in range(differential, n):
        implied = np.inf
        for i in range(differential):
            coupling = abs(jacobian[i, j])
            if coupling > 0.0:
                implied = min(implied, scale[i] / coupling)
        scale[j] = (implied + rtol * max(abs(y[j]), abs(y_new[j])) * time_scale) / h


@njit(cache=True, error_model="numpy", nogil=True)
def _time_scale(y, f, previous, h_previous, rtol, atol, differential, interval):
    """How long the differential components take to change by their own size, or their rates by theirs, whichever
    is shorter: min(‖y‖/‖f‖, ‖f‖/‖y''‖) in the RMS norm of the scales atol + |y| rtol, y'' at the end of the last
    step from its polynomial (``previous``, ``h_previous`` > 0; none at a run's first step); ``interval`` when
    nothing moves.  A time the problem defines, in its units: the motion's time scale (~1/ω for an oscillator)."""
    d0 = 0.0
    d1 = 0.0
    d2 = 0.0
    for i in range(differential):
        sc = atol[i] + abs(y[i]) * rtol
        d0 += (y[i] / sc) ** 2
        d1 += (f[i] / sc) ** 2
        if h_previous > 0.0:
            d2 += ((2.0 * previous[1, i] + 6.0 * previous[2, i]) / h_previous / sc) ** 2
    scale = interval
    if d1 > 0.0:
        scale = min(scale, np.sqrt(d0 / d1))
    if d2 > 0.0:
        scale = min(scale, np.sqrt(d1 / d2))
    return scale


@njit(cache=True, error_model="numpy", nogil=True)
def _predicted_factor(h_abs, h_proposed_old, err, err_old):
    """Gustafsson's predictive step-size factor (HNW IV.8, (8.25)); the one-step formula without a history."""
    multiplier = 1.0
    if err_old > 0.0 and h_proposed_old > 0.0 and err != 0.0:
        multiplier = h_abs / h_proposed_old * (err_old / err) ** 0.25
    if err == 0.0:
        return np.inf
    return min(1.0, multiplier) * err ** -0.25


@njit(cache=True, error_model="numpy", nogil=True)
def _initial_step(rhs, t, y, f, p, t_end, rtol, atol, max_step, differential, probe_y, probe_f):
    """HNW I, sec. II.4's starting step for an estimate of order 3 (as scipy's Radau), from the differential
    components [0, differential) alone (the others' f is a residual, not a derivative, and the probe
    leaves them unchanged); (h, rhs status)."""
    n = differential
    interval = t_end - t
    if n == 0:
        return min(interval, max_step), 0
    d0 = 0.0
    d1 = 0.0
    for i in range(n):
        sc = atol[i] + abs(y[i]) * rtol
        d0 += (y[i] / sc) ** 2
        d1 += (f[i] / sc) ** 2
    d0 = np.sqrt(d0 / n)
    d1 = np.sqrt(d1 / n)
    h0 = 0.01 * d0 / d1 if (d0 >= 1e-5 and d1 >= 1e-5) else 1e-6
    h0 = min(h0, interval)
    for i in range(n):
        probe_y[i] = y[i] + h0 * f[i]
    for i in range(n, y.shape[0]):
        probe_y[i] = y[i]
    status = rhs(t + h0, probe_y, p, probe_f)
    if status != 0:
        return 0.0, status
    d2 = 0.0
    for i in range(n):
        if not np.isfinite(probe_f[i]):
            return min(h0, max_step), 0
        sc = atol[i] + abs(y[i]) * rtol
        d2 += ((probe_f[i] - f[i]) / sc) ** 2
    d2 = np.sqrt(d2 / n) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** 0.25
    return min(100.0 * h0, h1, interval, max_step), 0


@njit(cache=True, error_model="numpy", nogil=True)
def _jacobian(rhs_jacobian, t, y, p, jacobian):
    """J at (t, y) into ``jacobian``: 0, the kernel's status (> 0), or −1 when an entry is not finite."""
    status = rhs_jacobian(t, y, p, jacobian)
    if status != 0:
        return status
    n = y.shape[0]
    for i in range(n):
        for j in range(n):
            if not np.isfinite(jacobian[i, j]):
                return -1
    return 0


@njit(SIGNATURE, cache=True, error_model="numpy", nogil=True)
def radau_run(rhs, rhs_jacobian, event_values,
              y, clock, counters, p, projecting, residual_max, t_end, rtol, atol, max_step, max_steps, pause_at,
              save_every, t_eval, ts, ys, directions, actions, ev_t, ev_y, ev_i,
              C, T, TI, MU, ERROR_WEIGHTS, DENSE_WEIGHTS, differential, jacobian, previous, control):
    """Integrate from (clock[0], y) towards t_end with Radau IIA of order 5.

    See the module docstring for the arguments, the return value and the algorithm.
    """
    n = y.shape[0]
    cap = ts.shape[0]
    n_eval = t_eval.shape[0]
    use_t_eval = n_eval > 0

    f = np.empty(n)
    y_new = np.empty(n)
    ytmp = np.empty(n)
    ftmp = np.empty(n)
    err = np.empty(n)
    z_error = np.empty(n)
    scale = np.empty(n)
    err_scale = np.empty(n)
    Z = np.empty((3, n))
    W = np.empty((3, n))
    F = np.empty((3, n))
    dense = np.empty((3, n))
    d_real = np.empty(n)
    d_complex = np.empty(n, dtype=np.complex128)
    lu_real = np.empty((n, n))
    lu_complex = np.empty((n, n), dtype=np.complex128)
    pivots_real = np.empty(n, dtype=np.int64)
    pivots_complex = np.empty(n, dtype=np.int64)
    rows = np.ones(n)
    columns = np.ones(n)
    n_events = directions.shape[0]
    g_old = np.empty(n_events)
    g_new = np.empty(n_events)
    g_work = np.empty(n_events)
    crossed = np.zeros(n_events, dtype=np.bool_)
    crossing_times = np.empty(n_events)

    n_saved = 0
    t = clock[TIME]
    # t_eval points up to t: those after the last step's start come from its polynomial (a step that held
    # more points than the last call's buffer), the others were written or precede the run.
    j = counters[NEXT_EVAL]
    has_previous = control[H_PREVIOUS] > 0.0
    while j < n_eval and t_eval[j] <= t:
        if has_previous and t_eval[j] > control[T_PREVIOUS]:
            if n_saved >= cap:
                counters[NEXT_EVAL] = j
                return Status.BUFFER_FULL, n_saved
            ts[n_saved] = t_eval[j]
            if t_eval[j] == t:
                for i in range(n):
                    ys[n_saved, i] = y[i]
            else:
                dense_state(DENSE_POWERS, previous[:3], previous[3], control[T_PREVIOUS], control[H_PREVIOUS],
                            t_eval[j], ys[n_saved])
            n_saved += 1
        j += 1
    counters[NEXT_EVAL] = j
    if t >= t_end:
        return Status.DONE, n_saved

    status = rhs(t, y, p, f)
    counters[NFEV] += 1
    if n_events > 0:
        event_values(t, y, p, g_old)
    if status == 0:
        for i in range(n):
            if not (np.isfinite(y[i]) and np.isfinite(f[i])):
                status = -1
    h_abs = clock[STEP]
    if status == 0 and h_abs <= 0.0:
        h_abs, status = _initial_step(rhs, t, y, f, p, t_end, rtol, atol, max_step, differential, ytmp, ftmp)
        counters[NFEV] += 1
        if status == 0:
            clock[STEP] = h_abs
    if status == 0 and control[JAC_HELD] == 0.0:
        status = _jacobian(rhs_jacobian, t, y, p, jacobian)
        counters[NJEV] += 1
        control[JAC_HELD] = 1.0
        control[JAC_CURRENT] = 1.0
    if status != 0:
        return (Status.RHS_FAILED if status > 0 else Status.NONFINITE), n_saved
    lu_step = control[LU_STEP]
    if lu_step != 0.0:
        counters[NLU] += 2
        if _factor(jacobian, lu_step, MU, differential, lu_real, pivots_real, lu_complex, pivots_complex, rows,
                   columns) != 0:
            lu_step = 0.0       # (not after a successful factorisation of the same matrices)
    jac_current = control[JAC_CURRENT] != 0.0
    newton_tol = max(10.0 * EPS / rtol, min(0.03, np.sqrt(rtol)))

    while True:
        if t >= t_end:
            return Status.DONE, n_saved
        if counters[NSTEPS] >= max_steps:
            return Status.MAX_STEPS, n_saved
        if counters[NSTEPS] >= pause_at:
            return Status.PAUSED, n_saved

        min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
        h_proposed = h_abs
        h_proposed_old = control[H_PROPOSED]
        err_old = control[ERR_PREVIOUS]
        if h_abs > max_step:
            h_abs = max_step
            h_proposed_old = 0.0
            err_old = 0.0
        elif h_abs < min_step:
            h_abs = min_step
            h_proposed_old = 0.0
            err_old = 0.0

        # Stop before a step whose outputs would not fit (embedded_run's rule).
        room = cap - n_saved
        t_reach = min(t + h_abs, t_end)
        need = 0
        if use_t_eval:
            j = counters[NEXT_EVAL]
            while j < n_eval and t_eval[j] <= t_reach and need <= room:
                need += 1
                j += 1
        elif counters[SINCE_SAVE] + 1 >= save_every or t_reach >= t_end:
            need = 1
        if need > room and (n_saved > 0 or not use_t_eval):
            return Status.BUFFER_FULL, n_saved
        if counters[EVENT_ROWS] + n_events > ev_t.shape[0]:
            return Status.BUFFER_FULL, n_saved
        if n_events > 0 and not use_t_eval and n_saved >= cap:
            return Status.BUFFER_FULL, n_saved

        # Trial loop.
        time_scale = 0.0
        if differential < n:
            time_scale = _time_scale(y, f, previous, control[H_PREVIOUS], rtol, atol, differential, t_end - t)
        rejected = False
        trouble = _ERROR
        newton_failed = False   # a DAE's iteration matrix turns singular to working precision at tiny h (pivots ~h²):
        while True:             # after a Newton failure that is the failure to report, not the matrix
            t_new = t + h_abs
            if t_new > t_end:  # noqa: PLR1730 (a NaN t_new stays NaN: the test below ends the run)
                t_new = t_end
            if not (h_abs >= min_step and t_new < np.inf):
                if trouble == _NEWTON or (trouble == _SINGULAR and newton_failed):
                    return Status.NEWTON_FAILED, n_saved
                if trouble == _SINGULAR:
                    return Status.ITERATION_MATRIX_SINGULAR, n_saved
                if trouble == _ERROR and h_abs < min_step:
                    return Status.STEP_TOO_SMALL, n_saved
                return Status.NONFINITE, n_saved
            h = t_new - t
            h_abs = h

            # Starting values: the last step's polynomial at t + c_i h, less y (`dense_state`'s arithmetic,
            # inline: its row views of ``previous`` cost more than the sums).
            h_previous = control[H_PREVIOUS]
            if h_previous > 0.0:
                for s in range(3):
                    x = (t + h * C[s] - control[T_PREVIOUS]) / h_previous
                    for i in range(n):
                        acc = ((previous[2, i] * x + previous[1, i]) * x + previous[0, i]) * x
                        Z[s, i] = (previous[3, i] + h_previous * acc) - y[i]
            else:
                for s in range(3):
                    for i in range(n):
                        Z[s, i] = 0.0
            for i in range(differential):
                scale[i] = atol[i] + abs(y[i]) * rtol
            _algebraic_scales(jacobian, differential, h, rtol, y, y, time_scale, scale)

            converged = False
            iterations = 0
            rate = -1.0
            while True:
                singular = False
                if lu_step == 0.0:
                    counters[NLU] += 2
                    if _factor(jacobian, h, MU, differential, lu_real, pivots_real, lu_complex, pivots_complex,
                               rows, columns) != 0:
                        singular = True
                        trouble = _SINGULAR
                    else:
                        lu_step = h
                if not singular:
                    status, converged, iterations, rate, nfev = _newton(
                        rhs, t, y, h, p, C, T, TI, MU, differential, Z, W, F, ytmp, ftmp, d_real, d_complex, lu_real,
                        pivots_real, lu_complex, pivots_complex, rows, columns, scale, newton_tol)
                    counters[NFEV] += nfev
                    if status > 0:
                        return Status.RHS_FAILED, n_saved
                    trouble = _NONFINITE if status < 0 else _NEWTON
                    newton_failed = newton_failed or (trouble == _NEWTON and not converged)
                if converged or jac_current:
                    break
                status = _jacobian(rhs_jacobian, t, y, p, jacobian)
                counters[NJEV] += 1
                if status != 0:
                    return (Status.RHS_FAILED if status > 0 else Status.NONFINITE), n_saved
                jac_current = True
                control[JAC_CURRENT] = 1.0
                lu_step = 0.0
            if not converged:
                h_abs *= 0.5
                lu_step = 0.0
                counters[NREJECTED] += 1
                continue

            # Error estimate, filtered through the real LU (and once more on the first step or a retry).
            for i in range(differential):
                y_new[i] = y[i] + Z[2, i]
                z_error[i] = (ERROR_WEIGHTS[0] * Z[0, i] + ERROR_WEIGHTS[1] * Z[1, i]
                              + ERROR_WEIGHTS[2] * Z[2, i]) / h
                err[i] = f[i] + z_error[i]
            for i in range(differential, n):
                y_new[i] = y[i] + Z[2, i]
                z_error[i] = 0.0        # M E·Z/h: mass 0
                err[i] = f[i]
            _substitute_real(lu_real, pivots_real, err, rows, columns, differential < n)
            err_norm = _error_norm(err, y, y_new, rtol, atol, differential, h, jacobian, time_scale,
                                       err_scale)
            safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + iterations)
            if (rejected or counters[NSTEPS] == 0) and err_norm > 1.0 and np.isfinite(err_norm):
                for i in range(n):
                    ytmp[i] = y[i] + err[i]
                status = rhs(t, ytmp, p, ftmp)
                counters[NFEV] += 1
                if status > 0:
                    return Status.RHS_FAILED, n_saved
                for i in range(n):
                    err[i] = ftmp[i] + z_error[i]
                _substitute_real(lu_real, pivots_real, err, rows, columns, differential < n)
                err_norm = _error_norm(err, y, y_new, rtol, atol, differential, h, jacobian, time_scale,
                                       err_scale)
            for i in range(n):
                if not np.isfinite(y_new[i]):
                    err_norm = np.nan
            if err_norm <= 1.0:
                break
            if np.isfinite(err_norm):
                factor = _predicted_factor(h_abs, h_proposed_old, err_norm, err_old)
                h_abs *= max(MIN_FACTOR, safety * factor)
                trouble = _ERROR
            else:
                h_abs *= MIN_FACTOR
                trouble = _NONFINITE
            lu_step = 0.0
            rejected = True
            counters[NREJECTED] += 1

        # The next step size; the LU factors are kept with an unchanged step.
        recompute_jacobian = iterations > 2 and rate > (JACOBIAN_RATE if differential == n else DAE_JACOBIAN_RATE)
        factor = min(MAX_FACTOR, safety * _predicted_factor(h_abs, h_proposed_old, err_norm, err_old))
        if not recompute_jacobian and factor < KEEP_STEP_BELOW:
            factor = 1.0
        else:
            lu_step = 0.0

        # Dense rows Q/h of the step, events and outputs.
        for k in range(3):
            for i in range(n):
                dense[k, i] = (DENSE_WEIGHTS[0, k] * Z[0, i] + DENSE_WEIGHTS[1, k] * Z[1, i]
                               + DENSE_WEIGHTS[2, k] * Z[2, i]) / h
        n_crossed = 0
        if n_events > 0:
            event_values(t_new, y_new, p, g_new)
            n_crossed = event_crossings(g_old, g_new, directions, actions, crossed)
        stop = False
        if n_crossed > 0:
            n_recorded, t_stop = record_events(event_values, DENSE_POWERS, dense, y, t, h, p, g_old, g_new, crossed,
                                               actions, crossing_times, ev_t, ev_y, ev_i, counters[EVENT_ROWS],
                                               ytmp, g_work)
            counters[EVENT_ROWS] = n_recorded
            if t_stop < np.inf:
                stop = True
                t_new = t_stop
                dense_state(DENSE_POWERS, dense, y, t, h, t_stop, y_new)
        if use_t_eval:
            j = counters[NEXT_EVAL]
            while j < n_eval and t_eval[j] <= t_new and n_saved < cap:
                te = t_eval[j]
                ts[n_saved] = te
                if te == t_new:
                    for i in range(n):
                        ys[n_saved, i] = y_new[i]
                else:
                    dense_state(DENSE_POWERS, dense, y, t, h, te, ys[n_saved])
                n_saved += 1
                j += 1
            counters[NEXT_EVAL] = j
        else:
            counters[SINCE_SAVE] += 1
            if counters[SINCE_SAVE] >= save_every or t_new >= t_end or stop:
                ts[n_saved] = t_new
                for i in range(n):
                    ys[n_saved, i] = y_new[i]
                n_saved += 1
                counters[SINCE_SAVE] = 0

        # Commit: f and, if due, J at the new state, then the carry.
        if not stop:
            status = rhs(t_new, y_new, p, ftmp)
            counters[NFEV] += 1
            if status == 0:
                for i in range(n):
                    if not np.isfinite(ftmp[i]):
                        status = -1
            if status == 0 and recompute_jacobian:
                status = _jacobian(rhs_jacobian, t_new, y_new, p, jacobian)
                counters[NJEV] += 1
            if status != 0:
                return (Status.RHS_FAILED if status > 0 else Status.NONFINITE), n_saved
            jac_current = recompute_jacobian
        for i in range(n):
            previous[3, i] = y[i]
            for k in range(3):
                previous[k, i] = dense[k, i]
            y[i] = y_new[i]
            f[i] = ftmp[i]
        control[T_PREVIOUS] = t
        control[H_PREVIOUS] = h
        control[H_PROPOSED] = h_proposed
        control[ERR_PREVIOUS] = err_norm
        control[JAC_CURRENT] = 1.0 if jac_current else 0.0
        control[LU_STEP] = lu_step
        t = t_new
        h_abs *= factor
        clock[TIME] = t
        clock[STEP] = h_abs
        counters[NSTEPS] += 1
        if stop:
            return Status.TERMINATED, n_saved
        if use_t_eval and counters[NEXT_EVAL] < n_eval and t_eval[counters[NEXT_EVAL]] <= t:
            return Status.BUFFER_FULL, n_saved     # the rest of this step's points: at the next call's start
        for ev in range(n_events):
            g_old[ev] = g_new[ev]
