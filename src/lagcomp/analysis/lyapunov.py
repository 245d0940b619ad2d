r"""Lyapunov exponents: the largest, the spectrum, and the two-trajectory cross-check.

The exponents measure the mean exponential rate at which nearby
trajectories separate, λ = lim (1/t) log |δx(t)|/|δx(0)|.  They do not
depend on the coordinates, so lagcomp computes them in the canonical
variables x = (q, p), where the compiled Jacobian J = ∂f/∂x of ẋ = f(t, x)
lives (`Model.canonical_jacobian`: exact, from the emitted ``canonical_partials``
kernel's symbolic partials, no finite difference; bench/bench_lyapunov.py measures it):

* variational (Benettin et al. 1980): k tangent vectors W obey Ẇ = J W along
  the trajectory; every few steps W is orthonormalized by QR and the logs of
  R's diagonal are summed.  Sum/t converges to the k largest exponents
  (k = 1: the largest; k = 2n: the spectrum — for a Hamiltonian system in
  pairs ±λ_i, with a zero pair per integral such as the energy);
* two trajectories: a shadow started d0 away is advanced with the
  trajectory and pulled back to distance d0 every few steps, summing
  log(d/d0): the same largest exponent, without the Jacobian, as a check.

For a regular (quasi-periodic) orbit the estimate does not settle at a
positive value but falls like log(t)/t: tangent vectors grow only linearly
(shear between neighbouring tori).

Both loops are library code taking the model's kernels
(`lagcomp.integrate.drivers.lyapunov`, RK4 with a fixed step).  On a tree with ball joints they switch each
joint's MRPs to their shadow past |σ| = 1, the tangent vectors (or the shadow trajectory) with them
(`_chart_coordinates`).  They run in chunks: each
chunk's end gives one row of the running estimate (`Lyapunov.history`),
moves the progress bar, and is where Ctrl-C stops the run cleanly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from lagcomp.analysis._common import unconstrained
from lagcomp.errors import IntegrationError, OptionError
from lagcomp.integrate.solution import MESSAGES

#: Seed of the initial tangent directions (reproducible estimates).
SEED = 20261122


@dataclass(frozen=True)
class Lyapunov:
    """Lyapunov exponent estimates along one trajectory.

    Attributes
    ----------
    exponents : ndarray, shape (k,)
        Final estimates (per unit time), in the order of the orthonormalized
        tangent vectors: descending once converged.
    t : ndarray, shape (m,)
        Times (measured from the end of the transient) of the running estimates.
    history : ndarray, shape (m, k)
        Running estimates: the accumulated logs divided by the elapsed time.
    method : str
        "variational" or "two-trajectory".
    status : int
        0, 2 (interrupted by Ctrl-C), or negative (`lagcomp.integrate.solution.MESSAGES`).
    message : str
    final_state : ndarray, shape (2n,)
        The canonical state x = (q, p) at the end.
    dt, renorm_every : float, int
        The RK4 step and how many steps pass between renormalizations.
    params : dict
    """

    exponents: np.ndarray
    t: np.ndarray
    history: np.ndarray
    method: str
    status: int
    message: str
    final_state: np.ndarray
    dt: float
    renorm_every: int
    params: dict = field(default_factory=dict)

    @property
    def largest(self) -> float:
        return float(np.max(self.exponents))


def _setup(model, q0, qd0, params, t_span, dt):
    unconstrained(model, "Lyapunov exponents")
    try:
        t0, t1 = (float(v) for v in t_span)
    except (TypeError, ValueError) as err:
        raise OptionError(f"`t_span` must be a pair (t0, t1), got {t_span!r}.") from err
    if not (math.isfinite(t0) and math.isfinite(t1) and t1 > t0):
        raise OptionError(f"`t_span` = ({t0}, {t1}) must be finite with t1 > t0.")
    dt = float(dt)
    if not (dt > 0 and math.isfinite(dt)):
        raise OptionError(f"`dt` must be positive and finite, got {dt}.")
    p = model.parameter_vector(params)
    y0 = model.initial_state(q0, qd0)
    n = model.n
    x = model.canonical_state(y0[:n], y0[n:], t0, params)
    return p, x, t0, t1, dt


def _chart_coordinates(model) -> np.ndarray:
    """Each ball joint's three coordinates (MRPs σ), int64 (J, 3), whose shadow switches the loops make
    (`lagcomp.integrate.drivers.lyapunov`: past |σ| = 1, tangent vectors through the switch's derivative); (0, 3)
    for a model without."""
    tree = getattr(model, "system", None)
    names = tuple(getattr(tree, "chart_events", ()))
    coordinates = list(getattr(tree, "coordinates", ()))
    rows = [[coordinates.index(sigma) for sigma, _ in event.reset[:3]] for event in tree.events[:len(names)]] \
        if names else []
    return np.array(rows, dtype=np.int64).reshape(len(rows), 3)


def _run(model, advance, t0, t1, dt, transient, renorm_every, samples, progress, sums):
    """Drive `advance(steps, n)` chunk by chunk; returns (status, times, history)."""
    from lagcomp.integrate.run_control import deferred_interrupt, progress_bar

    renorm_every = int(renorm_every)
    if renorm_every < 1:
        raise OptionError(f"`renorm_every` must be a positive number of steps, got {renorm_every}.")
    n_transient = int(round(float(transient) / dt))
    n_total = max(1, math.ceil((t1 - t0) / dt * (1 - 1e-12)))
    if n_transient >= n_total:
        raise OptionError(f"`transient` = {transient} leaves no time of `t_span` to average over.")
    steps = np.zeros(1, dtype=np.int64)
    status = 0
    if n_transient:
        status = advance(steps, n_transient)
        sums[:] = 0.0
    # rows of the running estimate at log-spaced step counts (what a log-log plot of λ(t) wants),
    # each a multiple of renorm_every, the last at the end of the run
    n_avg = n_total - n_transient
    ends = np.geomspace(renorm_every, n_avg, max(2, int(samples)))[-max(1, int(samples)):]
    ends = ends // renorm_every * renorm_every
    ends = np.unique(np.append(ends[ends > 0], n_avg).astype(np.int64)) + n_transient
    times, rows = [], []
    with deferred_interrupt() as interrupted, progress_bar(t0, t1, progress) as bar:
        bar.update(n_transient * dt)
        for end in ends:
            if status != 0:
                break
            todo = int(end - steps[0])
            status = advance(steps, todo)
            elapsed = (int(steps[0]) - n_transient) * dt
            times.append(elapsed)
            rows.append(sums / elapsed)
            bar.update(todo * dt)
            if interrupted[0] and status == 0 and steps[0] < n_total:
                status = 2
                break
    return status, np.asarray(times), np.asarray(rows).reshape(len(rows), sums.size)


def _result(model, method, status, times, history, x, dt, renorm_every, p, throw) -> Lyapunov:
    message = MESSAGES.get(status, f"status {status}")
    if status < 0:
        message = f"{message} (t ≈ {times[-1] if len(times) else 0.0:g} after the transient)"
        if throw:
            raise IntegrationError(f"Lyapunov run of {model.name!r} failed: {message}")
    exponents = history[-1] if len(history) else np.full(history.shape[1], np.nan)
    return Lyapunov(exponents=np.asarray(exponents, dtype=float), t=times, history=history, method=method,
                    status=int(status), message=message, final_state=x.copy(), dt=dt, renorm_every=int(renorm_every),
                    params=dict(zip(model.parameters, p.tolist())))


def lyapunov_exponents(model, t_span, q0=None, qd0=None, params: dict | None = None, *, k: int = 1,
                       dt: float = 0.01, renorm_every: int = 10, transient: float = 0.0, samples: int = 200,
                       progress=None, throw: bool = True) -> Lyapunov:
    """The k largest Lyapunov exponents by the variational equations (Benettin's method).

    Parameters
    ----------
    model : Model
        A compiled unconstrained system.
    t_span : (float, float)
        Time interval; the estimate averages over it after `transient`.
    q0, qd0 : array_like, optional
        Initial coordinates and velocities (default: the System's).
    k : int
        Number of exponents: 1 for the largest, 2n for the full spectrum.
    dt : float
        RK4 step.
    renorm_every : int
        Steps between QR orthonormalizations (keep the growth between two of
        them well below the float range: e^{λ dt renorm_every} ≪ 1e300).
    transient : float
        Time integrated first, whose growth is discarded (the tangent vectors
        align with the unstable directions meanwhile).
    samples : int
        At most how many rows the running estimate `history` gets (at
        log-spaced times, the last at the end).
    progress : bool, optional
        Progress bar (None: for runs over two seconds).
    throw : bool
        Raise `IntegrationError` on failure instead of returning a negative status.
    """
    p, x, t0, t1, dt = _setup(model, q0, qd0, params, t_span, dt)
    m = 2 * model.n
    k = int(k)
    if not 1 <= k <= m:
        raise OptionError(f"`k` must be between 1 and 2n = {m}, got {k}.")
    W = np.linalg.qr(np.random.default_rng(SEED).normal(size=(m, k)))[0]
    W = np.ascontiguousarray(W)
    sums = np.zeros(k)
    from lagcomp.integrate.drivers.lyapunov import lyapunov_run

    kernels, charts = model.kernels, _chart_coordinates(model)

    def advance(steps, n_steps):
        return lyapunov_run(kernels.velocities, kernels.momentum_rate, kernels.canonical_partials, x, W, steps, sums,
                            p, t0, dt, n_steps, renorm_every, charts)

    status, times, history = _run(model, advance, t0, t1, dt, transient, renorm_every, samples, progress, sums)
    return _result(model, "variational", status, times, history, x, dt, renorm_every, p, throw)


def lyapunov_spectrum(model, t_span, q0=None, qd0=None, params: dict | None = None, **options) -> Lyapunov:
    """All 2n exponents (`lyapunov_exponents` with k = 2n); for small systems."""
    return lyapunov_exponents(model, t_span, q0, qd0, params, k=2 * model.n, **options)


def two_trajectory_lyapunov(model, t_span, q0=None, qd0=None, params: dict | None = None, *, d0: float = 1e-8,
                            scale=None, dt: float = 0.01, renorm_every: int = 10, transient: float = 0.0,
                            samples: int = 200, progress=None, throw: bool = True) -> Lyapunov:
    """The largest exponent from a shadow trajectory kept at distance `d0` (in x = (q, p)).

    A cross-check of `lyapunov_exponents` that does not use the Jacobian.
    `d0` must be small enough for the separation to stay linear between
    renormalizations and large enough to stand above rounding.  The distance
    is sqrt(Σ ((xs_i − x_i)/scale_i)²), each component of x = (q, p) in units of
    its `scale_i`: a coordinate and a momentum have different units, so one
    absolute d0 cannot suit both in every unit system.  `scale` (2n,), the size
    of each component in its units (e.g. the coordinates' and momenta's
    typical magnitudes), makes `d0` relative and the estimate the same in any
    units; None (the default) is scale 1 for every component, d0 absolute
    (1e-8 suits states of order one; kept so that earlier results stay bit for
    bit).  Other arguments as for `lyapunov_exponents`.
    """
    p, x, t0, t1, dt = _setup(model, q0, qd0, params, t_span, dt)
    d0 = float(d0)
    if not (d0 > 0 and math.isfinite(d0)):
        raise OptionError(f"`d0` must be positive and finite, got {d0}.")
    scale = _separation_scale(scale, x.size)
    u = np.random.default_rng(SEED).normal(size=x.size)
    xs = x + d0 * (scale * u) / np.linalg.norm(u)
    sums = np.zeros(1)
    from lagcomp.integrate.drivers.lyapunov import divergence_run

    kernels, charts = model.kernels, _chart_coordinates(model)

    def advance(steps, n_steps):
        return divergence_run(kernels.velocities, kernels.momentum_rate, x, xs, steps, sums, p, t0, dt, n_steps,
                              renorm_every, d0, scale, charts)

    status, times, history = _run(model, advance, t0, t1, dt, transient, renorm_every, samples, progress, sums)
    return _result(model, "two-trajectory", status, times, history, x, dt, renorm_every, p, throw)


def _separation_scale(scale, size: int) -> np.ndarray:
    """`two_trajectory_lyapunov`'s `scale` checked: (size,) positive finite floats (None: ones)."""
    if scale is None:
        return np.ones(size)
    try:
        values = np.array(scale, dtype=float)
    except (TypeError, ValueError) as err:
        raise OptionError(f"`scale` must be an array of {size} numbers, got {scale!r}.") from err
    if values.shape != (size,) or not np.all(np.isfinite(values) & (values > 0)):
        raise OptionError(f"`scale` must hold {size} positive finite numbers, one per component of x = (q, p) in its "
                          f"units; got {scale!r}.")
    return values
