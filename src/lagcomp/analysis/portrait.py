r"""Phase portraits of one-degree-of-freedom systems from the energy integral.

For one coordinate q and a Lagrangian without explicit t (steady imposed
motions included), the energy function h = Σ q̇ ∂L/∂q̇ − L = T₂ − T₀ + V is
conserved, and it is quadratic in q̇ with no linear term (T₁ drops out):

    h(q, q̇) = ½ m(q) q̇² + U(q),    m = M (the 1×1 mass matrix),  U(q) = h(q, 0)

(U the effective potential: V − T₀, e.g. the centrifugal term of a spun
hoop).  A level h = E is the pair of curves

    q̇(q, E) = ± √(2 (E − U(q)) / m(q))     where U(q) ≤ E.

The equilibria are the critical points of U; the unstable ones (maxima of U)
carry the separatrices, whose energies E_s = U(q*) divide the regimes: no
motion below min U, oscillation between turning points U(q) = E, and — for an
angle whose range is one period — revolution above every maximum.  Both m and
U are evaluated with the compiled kernels (``mass_matrix``, ``energy_function``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lagcomp.analysis._common import symbolic_system, tree_of, unconstrained
from lagcomp.analysis.oscillations import normal_modes
from lagcomp.analysis.statics import STEADY_CHECK_OFFSETS, Equilibrium, find_equilibria
from lagcomp.errors import ModelError, OptionError

REGIMES = ("no motion", "oscillation", "separatrix", "revolution", "unbounded")


@dataclass(frozen=True)
class Portrait:
    """Level curves of the energy integral of a 1-DoF system.

    Attributes
    ----------
    q : ndarray, shape (k,)
        Sample points of the coordinate.
    energies : ndarray, shape (m,)
        The levels E asked for.
    qd : ndarray, shape (m, k)
        q̇(q, E) ≥ 0 on each level (the other branch is −qd); NaN where U(q) > E.
    potential, inertia : ndarray, shape (k,)
        U(q) = h(q, 0) and m(q) on the samples.
    regimes : tuple of str
        Per energy: "no motion", "oscillation", "separatrix", "revolution"
        (periodic coordinate, every q reached) or "unbounded" (the motion
        leaves the sampled interval of a non-periodic coordinate).
    equilibria : list of Equilibrium
        Equilibria in the interval (critical points of U).
    stable : tuple of bool
        Whether each equilibrium is (linearly) stable.
    separatrices : ndarray, shape (s,)
        Energies U(q*) of the unstable equilibria, ascending, distinct.
    separatrix_qd : ndarray, shape (s, k)
        q̇ ≥ 0 on each separatrix level.
    coordinate : str
    periodic : bool
        Whether the interval is one period of an angle.
    params : dict
    """

    q: np.ndarray
    energies: np.ndarray
    qd: np.ndarray
    potential: np.ndarray
    inertia: np.ndarray
    regimes: tuple
    equilibria: list
    stable: tuple
    separatrices: np.ndarray
    separatrix_qd: np.ndarray
    coordinate: str
    periodic: bool
    turning_points: tuple = ()
    separatrix_turning_points: tuple = ()
    params: dict = field(default_factory=dict)

    def curve(self, j: int, *, separatrix: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """(q, q̇ ≥ 0) of level j (of `separatrices` with ``separatrix=True``), its turning points included.

        The samples of `qd` stop short of the turning points U(q) = E; this
        inserts them (found by Brent's method, q̇ = 0 there) so that drawn
        curves close.  Forbidden stretches stay NaN, which breaks the line.
        """
        qd = (self.separatrix_qd if separatrix else self.qd)[j]
        turning = (self.separatrix_turning_points if separatrix else self.turning_points)[j]
        q = np.concatenate([self.q, turning])
        order = np.argsort(q, kind="stable")
        return q[order], np.concatenate([qd, np.zeros(len(turning))])[order]


def _check_energy_integral(model, p, grid) -> None:
    """Refuse systems whose energy function is not conserved (forces, dissipation, explicit t)."""
    tree = tree_of(model)
    if tree is not None:   # (a kinematic tree: its joints' torques and dampers are its forces and dissipation)
        loaded = any(node.joint.torque != 0 or node.joint.damping != 0 for node in tree.nodes)
    else:
        system = symbolic_system(model, "The energy portrait")
        loaded = any(Q != 0 for Q in system.forces) or system.dissipation != 0
    if loaded:
        raise ModelError(f"{model.name!r} has generalized forces or dissipation: its energy function is not "
                         "conserved, so the phase portrait cannot come from the energy integral; simulate instead.")
    y = np.zeros(2)
    spread, size = 0.0, 0.0
    for q in grid[:: max(1, grid.size // 16)]:
        y[0] = q
        values = [model.kernels.energy_function(t, y, p) for t in (0.0, *STEADY_CHECK_OFFSETS)]
        spread, size = max(spread, max(values) - min(values)), max(size, *(abs(v) for v in values))
    # against the largest energy on the grid, the problem's own scale of energy (was max(1, |E|): one joule)
    if not spread <= 1e-12 * size:
        raise ModelError(f"The energy function of {model.name!r} depends on t at these parameter values "
                         "(an unsteady imposed motion): it is not conserved, so there is no energy integral.")


def phase_portrait(model, energies, bounds, params: dict | None = None, *, periodic: bool = False,
                   samples: int = 801) -> Portrait:
    """The curves q̇(q, E) for each energy E, the separatrix energies and the regimes.

    Parameters
    ----------
    model : Model
        A compiled unconstrained system with one coordinate, no generalized
        forces or dissipation, and no explicit time dependence at `params`.
    energies : array_like
        Levels E of the energy function h.
    bounds : (float, float)
        Interval of the coordinate to sample.
    periodic : bool
        True when `bounds` spans one period of an angle (e.g. (−π, π)): an
        energy above every barrier is then a revolution.
    samples : int
        Number of sample points of q.
    """
    unconstrained(model, "phase_portrait")
    if model.n != 1:
        raise ModelError(f"phase_portrait draws 1-DoF systems; {model.name!r} has {model.n} coordinates "
                         "(use a Poincaré section, lagcomp.analysis.poincare_section).")
    a, b = (float(v) for v in bounds)
    if not b > a:
        raise OptionError(f"`bounds` must be (low, high) with low < high, got {bounds!r}.")
    p = model.parameter_vector(params)
    grid = np.linspace(a, b, int(samples))
    _check_energy_integral(model, p, grid)
    energies = np.atleast_1d(np.asarray(energies, dtype=float))
    U, m = _potential_and_inertia(model, p, grid)
    equilibria: list[Equilibrium] = find_equilibria(model, (a, b), params)
    if periodic and len(equilibria) > 1 and abs((equilibria[-1].q[0] - equilibria[0].q[0]) - (b - a)) < 1e-9 * (b - a):
        equilibria = equilibria[:-1]  # the same point at both ends of a period
    stable = tuple(normal_modes(model, e.q, params).stable for e in equilibria)
    barrier = [_potential_and_inertia(model, p, e.q)[0][0] for e, s in zip(equilibria, stable) if not s]
    separatrices = np.unique(np.round(np.asarray(barrier, dtype=float), 12)) if barrier else np.empty(0)
    scale = max(float(np.max(np.abs(U))), float(np.ptp(U)), 1e-300)
    regimes = tuple(_regime(E, U, separatrices, periodic, scale) for E in energies)
    return Portrait(
        q=grid, energies=energies, qd=_velocity(energies, U, m), potential=U, inertia=m, regimes=regimes,
        equilibria=equilibria, stable=stable, separatrices=separatrices,
        separatrix_qd=_velocity(separatrices, U, m), coordinate=model.coordinates[0], periodic=periodic,
        turning_points=tuple(_turning_points(model, p, grid, U, E) for E in energies),
        separatrix_turning_points=tuple(_turning_points(model, p, grid, U, E) for E in separatrices),
        params=dict(zip(model.parameters, p.tolist())),
    )


def _potential_and_inertia(model, p, q) -> tuple[np.ndarray, np.ndarray]:
    """U(q) = h(q, 0) and m(q) = M(q) at each point of q (time 0)."""
    q = np.atleast_1d(q)
    U, m = np.empty(q.size), np.empty(q.size)
    y, M = np.zeros(2), np.empty((1, 1))
    for i, value in enumerate(q):
        y[0] = value
        U[i] = model.kernels.energy_function(0.0, y, p)
        model.kernels.mass_matrix(0.0, y, p, M)
        m[i] = M[0, 0]
    return U, m


def _turning_points(model, p, grid, U, E: float) -> np.ndarray:
    """The points where U(q) = E between samples (Brent's method on the compiled energy function)."""
    from scipy.optimize import brentq

    excess = E - U
    y = np.zeros(2)

    def g(q):
        y[0] = q
        return E - model.kernels.energy_function(0.0, y, p)

    cells = np.flatnonzero(excess[:-1] * excess[1:] < 0)
    return np.array([brentq(g, grid[i], grid[i + 1], xtol=1e-14) for i in cells])


def _velocity(energies, U, m) -> np.ndarray:
    """√(2 (E − U)/m) on each level, NaN where E < U (a turning point is 0)."""
    excess = np.asarray(energies, dtype=float)[:, None] - U[None, :]
    with np.errstate(invalid="ignore"):
        return np.where(excess >= 0, np.sqrt(np.maximum(excess, 0.0) * 2.0 / m[None, :]), np.nan)


def _regime(E: float, U: np.ndarray, separatrices: np.ndarray, periodic: bool, scale: float) -> str:
    if np.any(np.abs(separatrices - E) <= 1e-12 * scale):
        return "separatrix"
    allowed = E >= U
    if not allowed.any():
        return "no motion"
    if allowed.all() and periodic:
        return "revolution"
    if not periodic and (allowed[0] or allowed[-1]):
        return "unbounded"
    return "oscillation"
