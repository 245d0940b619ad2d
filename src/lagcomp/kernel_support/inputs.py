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

Outside [x_0, x_m] the table is evaluated at the nearest end (t is clamped):
`simulate` refuses a table that does not cover the run, so this only guards
the odd evaluation just past the end (a first-step estimate).

Breakpoints and adaptive steps
------------------------------
The embedded methods do not restart at the breakpoints: a step that straddles
one integrates a right-hand side whose derivative of the order the equations
read plus one jumps there (ẍ_s of a cubic spline is continuous, its slope is
not), and the error estimate sees that as a local loss of smoothness.  It
rejects and shrinks the step where the estimate exceeds the tolerance and
accepts it otherwise, so the error of the run stays at the tolerance, plus the
interpolant's own error, which is what the result differs from the sampled
signal by: for a cubic spline of spacing Δ, O(Δ⁴) in u, O(Δ³) in u̇, O(Δ²)
in ü.  What this costs was measured (`tests/test_inputs.py`, the pendulum on a
support driven by x_s = A sin ωt, DOP853 at rtol 1e-10; README, "Inputs"):
more steps than with the expression x_s(t) written out, because a step may
not straddle too many joints; and the difference from the expression scales
with Δ² as the interpolant of ẍ_s does.
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
