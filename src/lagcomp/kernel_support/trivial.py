"""The kernels that every model without constraints, or without events, has alike: the drivers' constraint
hooks ``project`` and ``constraint_residual`` (nothing to do) and ``event_values`` (no events).

The eager module of such a model imports them from here (`lagcomp.codegen.emit`) instead of defining its own,
so that numba compiles them once into its cache (beside this file), not once per model: a new model's first
run compiles only its own kernels.  Their signatures are those of the drivers' kernel types
(`lagcomp.integrate.drivers.kernel_types`).
"""

from __future__ import annotations

from numba import njit


@njit(cache=True, error_model="numpy")
def constraint_residual(t, y, p):
    """Largest constraint residual: always 0.0, this system has no constraints."""
    return 0.0


@njit(cache=True, error_model="numpy")
def project(t, y, p):
    """Projection onto the constraints: nothing to do, this system has none."""
    return 0


@njit(cache=True, error_model="numpy")
def event_values(t, y, p, out):
    """Event functions g, shape (0,): this system has no events."""

