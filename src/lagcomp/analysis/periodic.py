r"""Periodic orbits by shooting: Newton (Gauss-Newton) on φ_T(y0) − y0 with the monodromy matrix.

An orbit of ẏ = f(y) is periodic with period T when the flow φ brings its initial state back:

    R(y0, T) = φ_T(y0) − y0 = 0       (N equations, N = 2n),

each component divided by its size s_i over the guess's motion (`component_scale`), so that the least-squares
sum weighs the coordinates and their rates alike in any units (unscaled, a run in hours weighted the rates
3600² times less than the angles, and the solve stalled).

The unknowns z = (y0, T) are found by `scipy.optimize.least_squares` (trust-region, below) with the exact
Jacobian ∂R/∂(y0, T) = [Φ − I | f(φ_T(y0))]: the monodromy matrix Φ = ∂φ_T/∂y0 comes from
``simulate(..., sensitivities=("q0", "qd0"))`` (the variational equations with the emitted ``rhs_jacobian``),
in the same run as φ_T(y0), and f from the model's ``rhs`` kernel.  Two equations more make the solution unique:

* the phase condition Σ_i f_i(y_g) (y0 − y_g)_i / s_i² = 0 (y_g the guess, s_i the component's size over the
  guess's motion, so that every term is in 1/time): any point of a periodic orbit is a solution, so
  y0 is pinned to the hyperplane through the guess across the flow there (the Poincaré phase condition;
  its row of the Jacobian is f(y_g)/s², exact);
* which member of the family: the periodic orbits of an autonomous conservative system come in one-parameter
  families (by energy, or by amplitude).  ``fix="period"`` holds T at `period`, the energy then being whatever
  the orbit of that period has; ``fix=<a state component's name>`` (default: the first coordinate) holds that
  component of y0 at its value in the guess, an amplitude: the period then comes out of the solve (`period`
  is only its starting value), as the energy does.  Both rows are exact (unit vectors).

That makes N + 2 equations for N + 1 unknowns, consistent: energy conservation makes one component of R
redundant (Φ − I has the flow direction f and the family's direction in its kernel, and the two conditions
remove both).  Gauss-Newton on a consistent overdetermined system converges quadratically like Newton, so no
equation has to be dropped by hand (which one would be a choice per system).
A system with more symmetries keeps more directions in that kernel (the three bodies' translations and
rotation); the trust-region step (from the SVD of the scaled J) has no component along it (in scipy's
scaled norm), and the solve ends on one of the symmetric copies of the orbit (the figure eight of
tests/test_periodic.py, translated and shifted in phase).

The Floquet multipliers are the eigenvalues of Φ at the solution (they do not depend on the coordinates: Φ in
(q, q̇) is similar to the symplectic one in (q, p) since φ_T(y0) = y0).  For an autonomous Hamiltonian system two
equal 1 (the flow direction and the energy), and the others come in pairs μ, 1/μ: on the unit circle when the
orbit is linearly stable.  The trivial pair is a Jordan block, so an error δ of Φ splits it by ~√δ about 1
(the double pendulum's normal mode at rtol 1e-12: 1 ± 3e-8, their mean 1 to 1e-14), while the other
multipliers move by ~δ (|μ| = 1 to ~1e-13 there).  Each further symmetry brings its own trivial multipliers
(the planar three bodies: 8, within 6e-6 of 1; the figure eight's other four on the unit circle to 3e-12).
Φ is integrated with ``sensitivity_control="both"``.

The solver is scipy's trust-region reflective ``least_squares(method="trf")`` with the same scaling
(``x_scale="jac"``).  Levenberg-Marquardt (``method="lm"``, scipy's MINPACK) was used before: scipy 1.17's MINPACK
reads memory it has not written (with the same residuals and Jacobians, the first step differed with the garbage
left on the heap before the call: 60 of 200 calls one way, 140 the other), so the orbit found from a guess that
is not close — Simó's figure eight with positions and velocities both 10 % too large — depended on the process.

Refused (`OptionError`, docs/errors.md): models with Lagrange multipliers (Newton's steps on the whole state
would leave their constraints), a guess of the wrong size or not finite, an unknown `fix`, a period that is not
positive, no convergence (the residual reached is in the message), and a degenerate solution: a state that over
the period moves by at most `DEGENERATE` times what the guess's does (an equilibrium, bodies escaping: periodic
with any period, no orbit).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from lagcomp.errors import OptionError

#: A solution whose state moves by at most this fraction of what the guess's moves over the period is refused
#: (`_refuse_degenerate`): an equilibrium or an escape, not an orbit.
DEGENERATE = 1e-6


@dataclass(frozen=True)
class PeriodicOrbit:
    """A periodic orbit found by `periodic_orbit`.

    Attributes
    ----------
    y0 : ndarray, shape (N,)
        The initial state (q, q̇) on the orbit.
    period : float
    multipliers : ndarray of complex, shape (N,)
        Floquet multipliers: the eigenvalues of `monodromy` (``numpy.linalg.eigvals``), by decreasing modulus.
    monodromy : ndarray, shape (N, N)
        Φ = ∂φ_T(y0)/∂y0, columns in state order.
    residual : float
        max_i |φ_T(y0) − y0|_i / s_i at the solution, s_i the component's size over the guess's motion
        (`component_scale`).
    iterations : int
        Jacobian evaluations (each one integration with sensitivities).
    evaluations : int
        Residual evaluations (integrations).
    fix : str
        What held the family's member: "period" or a state component's name.
    solution : Solution
        The orbit over one period (dense rows as `simulate` records them, with its sensitivities).
    """

    y0: np.ndarray
    period: float
    multipliers: np.ndarray
    monodromy: np.ndarray
    residual: float
    iterations: int
    evaluations: int
    fix: str
    solution: object

    @property
    def stable(self) -> bool:
        """Linear stability: no multiplier outside the unit circle by more than 1e-6 (the margin lets the trivial
        pair at 1 through, split by ~√(error of Φ); a Hamiltonian orbit's unstable pair μ, 1/μ has |μ| > 1)."""
        return bool(np.max(np.abs(self.multipliers)) <= 1.0 + 1e-6)


def periodic_orbit(model, guess, period: float, *, fix: str | None = None, params: dict | None = None,
                   rtol: float = 1e-12, atol=1e-12, tol: float = 1e-10, max_iterations: int = 50,
                   method: str = "dop853") -> PeriodicOrbit:
    """The periodic orbit of an autonomous model near `guess` by shooting (see the module docstring).

    Parameters
    ----------
    model : Model
        A compiled model whose sensitivities `simulate` integrates (unconstrained; no events are located).
    guess : array_like, shape (N,)
        A state (q, q̇) near the orbit, e.g. a linear normal mode's shape times an amplitude, at rest.
    period : float
        The period: held when ``fix="period"``, else the starting value (e.g. 2π/ω of the linear mode).
    fix : str, optional
        "period", or the name of a state component (`Model.state_names`) held at its value in `guess`
        (default: the first coordinate; an amplitude when the guess is at rest).
    params : dict, optional
    rtol, atol : float or array_like
        Tolerances of every integration; `atol` one number or one per state component in its units
        (`lagcomp.integrate.tolerances`: positions and velocities differ by a unit of time).
    tol : float
        The largest max_i |φ_T(y0) − y0|_i / s_i accepted, s_i = max_t |y_i(t)| over the guess's motion (at least
        `atol`): relative to each component's own size, so the same in any units; `OptionError` above it.
    max_iterations : int
        Residual evaluations at most (scipy's ``max_nfev``; each iteration takes one, and one Jacobian).
    method : str
        An embedded pair (dop853, dopri5, tsit5, bs3): the methods that integrate sensitivities.
    """
    if model.k:
        raise OptionError(f"`periodic_orbit` shoots on the whole state (q, q̇) of {model.name!r}, whose constraints "
                          f"{list(model.constraints)} its Newton steps would leave (and `simulate` refuses an "
                          "inconsistent start).")
    names = tuple(model.state_names)
    size = len(names)
    try:
        y_guess = np.asarray(guess, dtype=float).ravel()
    except (TypeError, ValueError) as err:
        raise OptionError(f"`guess` must be a state of {size} numbers {list(names)}, got {guess!r}.") from err
    if y_guess.shape != (size,) or not np.all(np.isfinite(y_guess)):
        raise OptionError(f"`guess` must be a finite state of {size} numbers {list(names)} of {model.name!r}, "
                          f"got {y_guess.tolist()}.")
    period = float(period)
    if not (period > 0 and math.isfinite(period)):
        raise OptionError(f"`period` must be positive and finite, got {period}.")
    fix = names[0] if fix is None else fix
    if fix != "period" and fix not in names:
        raise OptionError(f"`fix` must be 'period' or a state component {list(names)}, got {fix!r}.")
    shooting = _Shooting(model, y_guess, params, rtol, atol, method)
    guess_run = shooting.plain_run(y_guess, period)
    scale = component_scale(guess_run, atol)
    fixed_row = np.zeros(size + 1)
    fixed_row[size if fix == "period" else names.index(fix)] = 1.0 / (period if fix == "period" else
                                                                       scale[names.index(fix)])
    fixed_value = fixed_row @ np.append(y_guess, period)
    phase_row = np.append(shooting.field(y_guess) / scale**2, 0.0)

    def residual(z):
        end = shooting.run(z).y[-1]
        conditions = [phase_row @ (z - np.append(y_guess, 0.0)), z @ fixed_row - fixed_value]
        return np.concatenate([(end - z[:size]) / scale, conditions])

    def jacobian(z):
        sol = shooting.run(z)
        block = np.hstack([sol.sensitivities[-1] - np.eye(size), shooting.field(sol.y[-1])[:, None]])
        return np.vstack([block / scale[:, None], phase_row, fixed_row])

    start = np.append(y_guess, period)
    result = least_squares(residual, start, jac=jacobian, method="trf", xtol=1e-15, ftol=1e-15, gtol=1e-15,
                           max_nfev=max(1, int(max_iterations)), x_scale="jac")  # (not "lm": see the module docstring)
    z = result.x
    sol = shooting.run(z)
    closing = float(np.max(np.abs(sol.y[-1] - z[:size]) / scale))
    if not (closing <= tol) or not (z[size] > 0):
        raise OptionError(f"`periodic_orbit` of {model.name!r} did not converge: max |φ_T(y0) − y0| / scale "
                          f"reached {closing:.3g} (tol {tol:g}) at T = {z[size]:.6g} after {result.njev} iterations "
                          f"({result.message}); start from a closer guess or period.")
    _refuse_degenerate(shooting, sol, guess_run)
    monodromy = sol.sensitivities[-1].copy()
    multipliers = np.linalg.eigvals(monodromy)
    multipliers = multipliers[np.argsort(-np.abs(multipliers), kind="stable")]
    return PeriodicOrbit(y0=z[:size].copy(), period=float(z[size]), multipliers=multipliers, monodromy=monodromy,
                         residual=closing, iterations=int(result.njev or 0), evaluations=int(result.nfev), fix=fix,
                         solution=sol)


def _extent(sol) -> float:
    """How far a run's state moves from its start: max over its rows of max_i |y_i(t) − y_i(0)|."""
    return float(np.max(np.abs(sol.y - sol.y[0])))


def component_scale(run, atol) -> np.ndarray:
    """Each state component's size over a run, max_t |y_i(t)| (at least `atol`, a number or (N,)), shape (N,): in its
    own units, so
    that the shooting residual φ_T(y0) − y0, the phase condition and the closing test over it are the same in any
    units (an angle's rate is in 1/time, a length in metres or millimetres)."""
    return np.maximum(np.max(np.abs(run.y), axis=0), atol)


def _refuse_degenerate(shooting, sol, guess_run) -> None:
    """Refuse a solution of the shooting equations that is no orbit: nothing moving, on the scale of the motion
    the guess makes over the period (`DEGENERATE`: an equilibrium, or bodies so far apart that they hardly move,
    both "periodic" with any period)."""
    moved, sought = _extent(sol), _extent(guess_run)
    if not moved > DEGENERATE * sought:
        state = ", ".join(f"{name}={value:.6g}" for name, value in zip(shooting.model.state_names, sol.y[0]))
        raise OptionError(
            f"`periodic_orbit` of {shooting.model.name!r} converged to a motion that is no orbit: over the period "
            f"T = {sol.t[-1]:.6g} its state moves by {moved:.3g}, {moved / sought if sought else 0.0:.3g} times what "
            f"the guess's moves ({sought:.3g}), from ({state}): an equilibrium, or bodies escaping so far apart that "
            "they hardly move, which repeat with any period. Start from a closer guess or period (or hold an "
            "amplitude, `fix=`, rather than the period).")


class _Shooting:
    """φ_T(y0) with its monodromy matrix, one integration per distinct z = (y0, T) (the last one kept: scipy
    asks for the residual and the Jacobian at the same point)."""

    def __init__(self, model, y_guess, params, rtol, atol, method):
        self.model, self.n = model, model.n
        self.p = model.parameter_vector(params)
        self.params = dict(zip(model.parameters, self.p.tolist(), strict=True))
        # the step control covers the sensitivities too: Φ is what the multipliers are read from, and with the
        # state-only control an orbit of small amplitude (small state, O(1) sensitivities) gets Φ to ~1e-8 only
        self.options = dict(rtol=rtol, atol=atol, method=method, sensitivity_control="both")
        self._last = (None, None)
        if model.events:
            self.options["events"] = False  # the shooting needs no crossings: not locating them saves their work
        self.field(y_guess)  # the model's own refusals (singular M) before any integration

    def run(self, z):
        if self._last[0] is not None and np.array_equal(self._last[0], z):
            return self._last[1]
        T = float(z[-1])
        if not (T > 0 and math.isfinite(T)):
            raise OptionError(f"`periodic_orbit` of {self.model.name!r} reached a period T = {T:g} ≤ 0: start "
                              "from a closer guess or period.")
        sol = self.model.simulate((0.0, T), z[:self.n], z[self.n:-1], self.params, sensitivities=("q0", "qd0"),
                                  progress=False, throw=True, **self.options)
        self._last = (z.copy(), sol)
        return sol

    def plain_run(self, y, T: float):
        """φ_t(y) over [0, T], without sensitivities (the guess's motion, `_refuse_degenerate`)."""
        options = {key: value for key, value in self.options.items() if key != "sensitivity_control"}
        return self.model.simulate((0.0, T), y[:self.n], y[self.n:], self.params, progress=False, throw=True,
                                   **options)

    def field(self, y) -> np.ndarray:
        """f(y) at t = 0 (the model is autonomous: any t), shape (N,)."""
        return self.model.rhs(0.0, y, self.params)
