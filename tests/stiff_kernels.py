"""Hand-written kernels with exact Jacobians for the Radau driver's tests (tests/test_radau_driver.py) and bench.

``rhs(t, y, p, out)`` and ``rhs_jacobian(t, y, p, out)`` (out (N, N) = ∂f/∂y) as the generated modules
define them (`lagcomp.integrate.drivers.kernel_types`), compiled with ``error_model="numpy"``.  Problems,
selected by p[0]:

0. harmonic oscillator ``y0' = y1, y1' = -y0`` (N = 2), exact solution (cos t, -sin t) from (1, 0);
1. Van der Pol in Hairer's scaling, ``y0' = y1, y1' = ((1 - y0²) y1 - y0) / ε`` with ε = p[1]
   (1e-3 .. 1e-6: stiff; HNW II, sec. IV.10) (N = 2);
2. Robertson's chemical kinetics (HNW II, sec. IV.10; N = 3);
3. a stiff spring-damper ``x'' = -k x - c x'`` with k = p[1], c = p[2], y = (x, x') (N = 2): linear,
   y(t) = expm(A t) y0 in closed form;
4. the oscillator with a NaN derivative for t > p[1];
5. the oscillator whose rhs returns 3 (a singular mass matrix) for t > p[1];
6. the oscillator whose Jacobian kernel returns 3 for t > p[1].
"""

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def rhs(t, y, p, out):
    kind = int(p[0])
    if kind == 1:
        out[0] = y[1]
        out[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) / p[1]
        return 0
    if kind == 2:
        out[0] = -0.04 * y[0] + 1e4 * y[1] * y[2]
        out[2] = 3e7 * y[1] * y[1]
        out[1] = -out[0] - out[2]
        return 0
    if kind == 3:
        out[0] = y[1]
        out[1] = -p[1] * y[0] - p[2] * y[1]
        return 0
    out[0] = y[1]
    out[1] = -y[0]
    if kind == 4 and t > p[1]:
        out[1] = np.nan
    if kind == 5 and t > p[1]:
        return 3
    return 0


@njit(cache=True, error_model="numpy")
def rhs_jacobian(t, y, p, out):
    kind = int(p[0])
    if kind == 1:
        out[0, 0] = 0.0
        out[0, 1] = 1.0
        out[1, 0] = (-2.0 * y[0] * y[1] - 1.0) / p[1]
        out[1, 1] = (1.0 - y[0] * y[0]) / p[1]
        return 0
    if kind == 2:
        out[0, 0] = -0.04
        out[0, 1] = 1e4 * y[2]
        out[0, 2] = 1e4 * y[1]
        out[2, 0] = 0.0
        out[2, 1] = 6e7 * y[1]
        out[2, 2] = 0.0
        for j in range(3):
            out[1, j] = -out[0, j] - out[2, j]
        return 0
    if kind == 3:
        out[0, 0] = 0.0
        out[0, 1] = 1.0
        out[1, 0] = -p[1]
        out[1, 1] = -p[2]
        return 0
    out[0, 0] = 0.0
    out[0, 1] = 1.0
    out[1, 0] = -1.0
    out[1, 1] = 0.0
    if kind == 6 and t > p[1]:
        return 3
    return 0


def scipy_functions(p):
    """``fun(t, y)`` and ``jac(t, y)`` for scipy's ``solve_ivp`` around `rhs` and `rhs_jacobian` at parameters `p`."""
    p = np.asarray(p, dtype=float)

    def fun(t, y):
        out = np.empty(y.size)
        rhs(t, y, p, out)
        return out

    def jac(t, y):
        out = np.empty((y.size, y.size))
        rhs_jacobian(t, y, p, out)
        return out
    return fun, jac
