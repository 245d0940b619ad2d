r"""Input signals u(t) for the kernels, read from tables packed into the parameter vector p.

Why in p: every driver — fixed-step, adaptive, Radau and its DAE form, the
sweeps — passes p to the kernels untouched, so a model with inputs runs on all
of them unchanged, and a new table (other values, another length) is new data,
never new code: changing an input does not recompile anything.

Layout of p (`lagcomp.integrate.inputs.pack_inputs` writes it)::

    p = (user parameters..., [Baumgarte α, β of a constrained system],
         header_0, ..., header_{J-1},                  # one per input, in name order
         table_0, ..., table_{J-1})

    header_j = s, the index in p where table j starts (a float holding an integer)
    table    = (m, x_0, ..., x_m, a_0, b_0, c_0, d_0, ..., a_{m-1}, b_{m-1}, c_{m-1}, d_{m-1})

m pieces between increasing breakpoints x_i; on piece i,
u(t) = a_i τ³ + b_i τ² + c_i τ + d_i with τ = t − x_i: the coefficients of
`scipy.interpolate.CubicSpline` (its ``c[:, i]``), and for a linear table
those of the piecewise-linear interpolant (a = b = 0).  The kernels bind the
value and the derivatives they need, ``u_x = input_value(t, p, slot, 0)``,
``ud_x = input_value(t, p, slot, 1)``, ...; the generated module lists its
inputs and the highest derivative each needs (``INPUTS``, ``INPUT_ORDERS``).

An input given as a numba function u(t, y, p) (`lagcomp.integrate.function_inputs`) has a
one-piece table with a = b = c = 0 on [0, 1]: its constant d_0 is the value that a wrapper of each
kernel writes there, p[slot] = u(t, y, p), before calling it (NaN until the first call, so that a
kernel reading it unwrapped shows it).

Outside [x_0, x_m] the table is evaluated at the nearest end (t is clamped):
`simulate` refuses a table that does not cover the run, so this only guards
the odd evaluation just past the end (a first-step estimate).

Breakpoints and adaptive steps
------------------------------
The embedded methods do not restart at the table's breakpoints.  At a joint
the cubic pieces meet with continuous u, u̇, ü, but the third derivative jumps,
so a right-hand side holding ü (a support motion in T) has a kink there; the
error estimate of a step that crosses it is large, the step is rejected and
shrunk until the estimate is within the tolerance, and the run's error stays
at the tolerance.  What is left is the interpolant's own error — O(Δ⁴) in u,
O(Δ²) in ü for samples Δ apart of a smooth signal — which bounds how far the
result is from the sampled signal's whatever the tolerance.  Measured by
``python -m bench.bench_inputs`` (a pendulum on a support moved by
x_s = 0.1 sin 3t, 10 s, the table against the expression):

- the difference in θ(10) is 3.4e-3, 2.2e-4, 1.4e-5, 8.5e-7 at Δ = 0.2, 0.1,
  0.05, 0.025 (Δ⁴: the O(Δ²) errors of ẍ_s alternate in sign and cancel in
  the integral), the same at rtol 1e-9 and 1e-12;
- the joints cost steps: DOP853 at rtol 1e-12 takes 1084 steps (1142
  rejected) at Δ = 0.1 against 179 with the expression, 11× the time, and
  3088 (3839) at Δ = 0.025, 30×; at rtol 1e-6, 171 steps against 31 (4×).
  DOPRI5, of lower order, crosses joints at less cost: 2222 steps against
  1652 at rtol 1e-12, Δ = 0.1 (1.8× the time).

- reading the table costs little per evaluation: RK4 over the same 10⁵
  steps takes 1.4× the time with 100 pieces, 1.6× with 10⁴ (a binary search
  of 7 or 14 steps and a cubic, against sin ωt, in a kernel of a dozen
  operations; inlining `input_value` changed nothing measurable).

So a tolerance near the interpolant's error, or DOPRI5, is the economical
choice with tables; restarting at the joints (the issue's other option) would
save the rejected steps and is left for later.
"""

from __future__ import annotations

from numba import njit


@njit(cache=True, error_model="numpy", fastmath=False)
def input_value(t, p, slot, order):
    """The `order`-th derivative (0 to 3) at time t of the input whose table header is p[slot].

    Binary search for the piece (the last breakpoint x_i ≤ t, t clamped to [x_0, x_m]), then
    Horner on that piece's cubic.  Derivatives above the third are zero.
    """
    start = int(p[slot])
    pieces = int(p[start])
    x = start + 1
    tc = min(max(t, p[x]), p[x + pieces])
    lo, hi = 0, pieces - 1
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if p[x + mid] <= tc:
            lo = mid
        else:
            hi = mid - 1
    d = tc - p[x + lo]
    c = x + pieces + 1 + 4 * lo
    if order == 0:
        return ((p[c] * d + p[c + 1]) * d + p[c + 2]) * d + p[c + 3]
    if order == 1:
        return (3.0 * p[c] * d + 2.0 * p[c + 1]) * d + p[c + 2]
    if order == 2:
        return 6.0 * p[c] * d + 2.0 * p[c + 1]
    if order == 3:
        return 6.0 * p[c]
    return 0.0
