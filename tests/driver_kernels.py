"""Hand-written model kernels for the driver tests (tests/test_drivers.py): the four every driver takes.

Compiled with ``error_model="numpy"``, as the generated kernels are, so that a division by zero gives
inf/NaN for the drivers to detect.  Test problems, selected by p[0]:

0. harmonic oscillator ``y0' = y1, y1' = -y0`` (N = 2);
1. Kepler problem ``q'' = -q / |q|^3``, y = (q, q') (N = 4);
2. the oscillator, with a NaN derivative for t > p[1];
3. the oscillator, whose rhs returns status 3 (singular) for t > p[1];
4. ``y0' = 1 / (1 - t), y1' = 0``: a division by zero at t = 1 (N = 2);
5. at rest: y' = 0, so that every norm of f vanishes (N = 2).

Events: g0 = y[0] (the oscillator's position), g1 = t - p[1].

`project` and `constraint_residual` are the no-op hooks of an unconstrained model; the fixed-step
tests (tests/test_fixed_step_drivers.py) use `circle_projection` and `circle_residual` instead, the
unit circle being the oscillator's orbit from (1, 0), and `oscillator_energy`.
"""

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def rhs(t, y, p, out):
    kind = int(p[0])
    if kind == 4:
        out[0] = 1.0 / (1.0 - t)
        out[1] = 0.0
        return 0
    if kind == 5:
        out[0] = 0.0
        out[1] = 0.0
        return 0
    if kind == 1:
        r2 = y[0] * y[0] + y[1] * y[1]
        r3 = r2 * np.sqrt(r2)
        out[0] = y[2]
        out[1] = y[3]
        out[2] = -y[0] / r3
        out[3] = -y[1] / r3
        return 0
    out[0] = y[1]
    out[1] = -y[0]
    if kind == 2 and t > p[1]:
        out[1] = np.nan
    if kind == 3 and t > p[1]:
        return 3
    return 0


@njit(cache=True, error_model="numpy")
def project(t, y, p):
    return 0


@njit(cache=True, error_model="numpy")
def constraint_residual(t, y, p):
    return 0.0


@njit(cache=True, error_model="numpy")
def event_values(t, y, p, out):
    if out.shape[0] > 0:
        out[0] = y[0]
    if out.shape[0] > 1:
        out[1] = t - p[1]


@njit(cache=True, error_model="numpy")
def event_reset(t, y, p, e, out):
    """No event resets the state: out = y."""
    for i in range(y.shape[0]):
        out[i] = y[i]
    return 0


@njit(cache=True, error_model="numpy")
def circle_projection(t, y, p):
    """Onto the unit circle y0² + y1² = 1 (the oscillator's orbit from (1, 0))."""
    r = np.sqrt(y[0] * y[0] + y[1] * y[1])
    y[0] /= r
    y[1] /= r
    return 0


@njit(cache=True, error_model="numpy")
def circle_residual(t, y, p):
    return abs(y[0] * y[0] + y[1] * y[1] - 1.0)


@njit(cache=True, error_model="numpy")
def oscillator_energy(t, y, p):
    return 0.5 * (y[0] * y[0] + y[1] * y[1])
