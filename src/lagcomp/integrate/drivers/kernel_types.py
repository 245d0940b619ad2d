"""The numba types of the model kernels as the library drivers receive them: the driver protocol's signatures.

A driver of `lagcomp.integrate.drivers` is compiled once per installation from an explicit
signature, ``@njit(SIGNATURE, cache=True)``, whose leading arguments are the model's kernels typed
as ``numba.types.FunctionType``: a first-class function value, called through its address.  The
signature names the kernel's *type*, not the kernel, so numba's on-disk cache of the driver serves
every model (a dispatcher argument without an explicit signature would compile, and cache, one
specialisation per kernel).  Python passes the generated module's dispatchers (``kernels.rhs``);
numba compiles each for the signature below on its first use, from the model's own cache.

Every generated module defines these kernels with these signatures (no-ops where the model has no
constraints or no events), so any driver can take any model.  Arrays are C-contiguous float64:
``t`` is the time, ``y`` the state (2n,), ``p`` the parameter vector, ``out`` the result.
"""

from __future__ import annotations

from numba import types
from numba.experimental import function_type

#: float64[::1], float64[:, ::1], int64[::1]: the array types of every driver argument.
VECTOR = types.float64[::1]
MATRIX = types.float64[:, ::1]
INDICES = types.int64[::1]
FLOAT, INT = types.float64, types.int64
#: What a driver returns: (Status, rows written to the output buffer).
OUTCOME = types.UniTuple(types.int64, 2)

#: ``rhs(t, y, p, out) -> int``: ``out = y'``; 0, or k > 0 when the mass matrix was singular at pivot k.
RHS = types.FunctionType(types.int64(FLOAT, VECTOR, VECTOR, VECTOR))
#: ``rhs_jacobian(t, y, p, out) -> int``: ``out`` (N, N) = ∂f/∂y of y' = f(t, y), row i the component f_i,
#: column j the variable y_j, exact (emitted from the symbolic equations); 0, or k > 0 as ``rhs`` returns, or
#: ``lagcomp.ir.NO_JACOBIAN`` (-1) where the module has none (its ``RHS_JACOBIAN_REFUSED`` says why).
RHS_JACOBIAN = types.FunctionType(types.int64(FLOAT, VECTOR, VECTOR, MATRIX))
#: ``rhs_with_jacobian(t, y, p, ydot, out) -> int``: ``ydot`` = f and ``out`` = ∂f/∂y at once, bitwise what ``rhs``
#: and ``rhs_jacobian`` write (one call: f is computed once); their statuses.
RHS_WITH_JACOBIAN = types.FunctionType(types.int64(FLOAT, VECTOR, VECTOR, VECTOR, MATRIX))
#: ``rhs_parameter_jacobian(t, y, p, out) -> int``: ``out`` (N, P) = ∂f/∂p of y' = f(t, y, p), P the model's
#: parameters (the first P entries of p: not the Baumgarte gains nor the inputs' tables after them), exact; 0,
#: or k > 0 as ``rhs`` returns, or ``lagcomp.ir.NO_JACOBIAN`` (-1) where the module has none (its
#: ``RHS_PARAMETER_JACOBIAN_REFUSED`` says why).
RHS_PARAMETER_JACOBIAN = types.FunctionType(types.int64(FLOAT, VECTOR, VECTOR, MATRIX))
#: ``project(t, y, p) -> int``: moves ``y`` onto the constraints in place; 0, or k > 0 when impossible.
PROJECT = types.FunctionType(types.int64(FLOAT, VECTOR, VECTOR))
#: ``constraint_residual(t, y, p) -> float``: the largest constraint residual at ``y`` (0.0 without constraints).
RESIDUAL = types.FunctionType(types.float64(FLOAT, VECTOR, VECTOR))
#: ``event_values(t, y, p, out)``: the event functions' values at ``y`` (writes nothing without events).
EVENTS = types.FunctionType(types.none(FLOAT, VECTOR, VECTOR, VECTOR))
#: ``event_reset(t, y, p, e, out) -> int``: ``out`` = the state just after event ``e`` (its reset applied to ``y``, the
#: state just before; ``y`` itself for an event without one); 0, or k > 0 when it cannot be computed.  A contact's
#: reset writes its mode slots of ``p``: the drivers pass a ``p`` of their own run (a sweep's row, not shared).
EVENT_RESET = types.FunctionType(types.int64(FLOAT, VECTOR, VECTOR, INT, VECTOR))
#: ``event_gradients(t, y, p, out) -> int``: ``out`` (E, N + 1 + P) = ∂g/∂y, ∂g/∂t, ∂g/∂p of the event functions,
#: exact (writes nothing without events); 0, or ``lagcomp.ir.NO_JACOBIAN`` where the module has none (its
#: ``EVENT_GRADIENTS_REFUSED`` says why).  Read by `lagcomp.integrate.sensitivities.event_sensitivities`, no driver.
EVENT_GRADIENTS = types.FunctionType(types.int64(FLOAT, VECTOR, VECTOR, MATRIX))
#: ``energy(t, y, p) -> float``: T + V at ``y`` (the sweeps' energy drift).
ENERGY = types.FunctionType(types.float64(FLOAT, VECTOR, VECTOR))
#: ``energy_function(t, y, p) -> float``: the energy function h = Σ q̇ ∂L/∂q̇ − L at ``y`` (the Hamiltonian's value).
ENERGY_FUNCTION = types.FunctionType(types.float64(FLOAT, VECTOR, VECTOR))
#: ``velocities(t, x, p, out) -> int`` (unconstrained models): ``out = q̇`` (n,) at x = (q, p) from M q̇ = p − b; 0, or k > 0.
VELOCITIES = types.FunctionType(types.int64(FLOAT, VECTOR, VECTOR, VECTOR))
#: ``energy_lanes(T, Y, p, out, reach)`` (and ``energy_function_lanes``): ``out[l]`` = ``energy`` of row l of a run,
#: ``reach[l]`` the sum of |x| over its sin and cos arguments; T, out, reach (B,), Y (2n, B) the rows as columns, p
#: the run's (`lagcomp.codegen.energy_lanes`: a summary's energies).
ENERGY_LANES = types.FunctionType(types.none(VECTOR, MATRIX, VECTOR, VECTOR, VECTOR))
#: ``momenta(t, y, p, out)``: ``out = ∂L/∂q̇`` (n,), the conjugate momenta at y = (q, q̇).
MOMENTA = types.FunctionType(types.none(FLOAT, VECTOR, VECTOR, VECTOR))
#: ``momentum_rate(t, y, p, out)``: ``out = ṗ = ∂L/∂q + Q − ∂D/∂q̇`` (n,) at y = (q, q̇).
MOMENTUM_RATE = types.FunctionType(types.none(FLOAT, VECTOR, VECTOR, VECTOR))
#: ``canonical_partials(t, y, p, out)`` (unconstrained models): ``out`` (4, n, n) = M, ∂P/∂q, ∂ṗ/∂q, ∂ṗ/∂q̇ at y = (q, q̇).
CANONICAL_PARTIALS = types.FunctionType(types.none(FLOAT, VECTOR, VECTOR, types.float64[:, :, ::1]))
#: ``taylor_coefficients(t, y, p, X, W) -> int``: the normalized Taylor coefficients X[i, k] = y_i⁽ᵏ⁾(t)/k!,
#: k = 0..order (order = X.shape[1] − 1, any), of the solution through y at t; W (rows, order + 1) is work
#: space of the model's ``TAYLOR_WORK`` rows.  0; −c when rows 0..c−1 of W hold held rows' multipliers (modes:
#: `lagcomp.codegen.taylor.ModePrograms`); or j > 0 when pivot j of M is not positive at t.
TAYLOR = types.FunctionType(types.int64(FLOAT, VECTOR, VECTOR, MATRIX, MATRIX))
#: ``taylor_lanes(T, Y, P, X)``: the batched Taylor kernel of one order over L lanes (flat arrays, lane
#: last; `lagcomp.codegen.taylor_lanes` gives the layout): every lane's coefficients, norms and pivot test.
TAYLOR_LANES = types.FunctionType(types.none(VECTOR, VECTOR, VECTOR, VECTOR))
#: ``taylor_lanes_advance(H, X, S, S_new)``: every lane's state and carry after its step H[l] (Horner's rule
#: and compensated sums, as the scalar Taylor driver's).
TAYLOR_ADVANCE = types.FunctionType(types.none(VECTOR, VECTOR, VECTOR, VECTOR))
#: bool[::1]: a flag per lane of a batch.
FLAGS = types.boolean[::1]
#: ``rhs_lanes(T, Y, P, out, bad)``: out[:, l] = y' of lane l; T, bad (B,), Y, out (2n, B), P (n_p, B); bad: M singular.
RHS_LANES = types.FunctionType(types.none(VECTOR, MATRIX, MATRIX, MATRIX, FLAGS))


class AddressedKernel:
    """A kernel as a driver argument that numba unboxes cheaply: its function type, and its address looked up once.

    A dispatcher passed for a ``FunctionType`` argument costs, at every call of the driver from Python,
    numba's compile-result and address look-ups in Python (`numba.experimental.function_type`): ~35 µs
    of CPU time per kernel, 70 µs per call of the Taylor driver (~3 µs for the template driver with its
    kernel as a global: `bench/taylor_library_vs_template.py`).  numba types an object by its
    ``_numba_type_`` and takes its address from ``__wrapper_address__`` (its wrapper address protocol);
    this one costs ~5 µs.  The driver then calls the kernel's cfunc wrapper, the C-ABI entry around the
    same compiled function, one call deeper than the native entry it calls for a dispatcher: no
    measurable cost per step around the Taylor kernel, 1.5% per step of DOP853 around the simple
    pendulum's rhs (which is why `lagcomp.integrate.simulate` uses it for a run's short first call
    only; `python -m bench.bench_call_cost` measures both costs).

    The address is looked up when numba first asks for it, at the first call of the driver, as for a
    dispatcher, so the kernel compiles where a dispatcher's would (under the run's compile stage).
    """

    def __init__(self, kernel, kind: types.FunctionType):
        self._numba_type_ = kind
        self.kernel = kernel                # keeps the compiled code at the address alive
        self._address = None

    def __wrapper_address__(self) -> int:
        if self._address is None:
            self._address = function_type._get_wrapper_address(self.kernel, self._numba_type_.signature)
        return self._address


# -- the kernels of M q̈ = F + Λᵀ λ one by one (the RATTLE driver, `lagcomp.integrate.drivers.rattle`) --------------
# Constrained modules only: an unconstrained module has no ``constraint_residuals`` or ``constraint_matrix``.

#: ``forcing(t, y, p, out)``: ``out = F(q, q̇, t)`` (n,), the right-hand side of M q̈ = F + Λᵀ λ.
FORCING = types.FunctionType(types.none(FLOAT, VECTOR, VECTOR, VECTOR))
#: ``mass_matrix(t, y, p, out)``: ``out = M(q, t)`` (n, n), symmetric.
MASS_MATRIX = types.FunctionType(types.none(FLOAT, VECTOR, VECTOR, MATRIX))
#: ``constraint_residuals(t, y, p, out)``: ``out`` (k_h + k,) = Φ of the holonomic constraints, then Λ q̇ + b of all k.
CONSTRAINT_RESIDUALS = types.FunctionType(types.none(FLOAT, VECTOR, VECTOR, VECTOR))
#: ``constraint_matrix(t, y, p, out)``: ``out`` (k, n + 1) = [Λ | b] at y's coordinates.
CONSTRAINT_MATRIX = types.FunctionType(types.none(FLOAT, VECTOR, VECTOR, MATRIX))
