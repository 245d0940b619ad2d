r"""Statics and steady states: where the generalized forces vanish at rest.

d'Alembert's principle for a system at rest: the virtual work of all the
forces, δW = Σ_i F_i(q, 0, t) δq_i, vanishes for every virtual displacement,
so an equilibrium q* solves

    F(q*, 0, t) = 0

with F the forcing of M q̈ = F(q, q̇, t) (applied, conservative and, with
imposed motions, inertial forces).  When the system is described in a frame
turning steadily (a bead on a hoop spun at Ω, a gyroscope in a turning
aircraft), F(q, 0) does not depend on t and q* is a relative equilibrium: at
rest in the moving description, carried along by the imposed motion.
`Equilibrium.steady` tells whether F(q*, 0, t′) vanishes at other times too.

Numerically q* is found by `scipy.optimize.root` on the compiled F(q, 0, t)
with the compiled Jacobian ∂F/∂q at rest (kernel ``rest_partials``), then
polished by Newton steps to rounding level; a 1-DoF system gets every root in
an interval by bracketing (`find_equilibria`).  Symbolically,
`generalized_forces` gives F(q, 0, t) and `balance` solves F = 0 for chosen
unknowns: the relation between the forces that hold a mechanism in place
(the wheel jack's load and effort).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import optimize

from lagcomp.analysis._common import (RestForces, coordinates_vector, explicit_time, relative_residual, symbolic_system,
                                      tree_of, unconstrained)
from lagcomp.errors import OptionError

#: Times (after t) at which a time-dependent system's equilibrium is checked for steadiness.
STEADY_CHECK_OFFSETS = (0.3183, 1.4142, 2.7183, 9.8696, 31.006)
#: Residuals below this times the force scale count as zero.
RESIDUAL_TOLERANCE = 1e-10


@dataclass(frozen=True)
class Equilibrium:
    """A configuration where the generalized forces vanish at rest.

    Attributes
    ----------
    q : ndarray, shape (n,)
        The equilibrium coordinates q*.
    t : float
        Time at which F(q*, 0, t) was solved.
    residual : float
        max |F(q*, 0, t)|.
    scale : float
        The force scale of the coordinate whose F_i is largest against its own scale
        (`RestForces.force_scale`: Σ_j |∂F_i/∂q_j| |q*_j|, and the parameters' terms where that is not enough, in
        F_i's units).
    success : bool
        Whether every |F_i| is below `RESIDUAL_TOLERANCE` × its scale.
    steady : bool
        Whether F(q*, 0, t′) also vanishes at later times t′: always for
        systems without explicit t, for steady imposed motions in general; an
        instantaneous balance (a time-dependent drive) is not steady.
    message : str
        What the root finder said.
    coordinates : tuple of str
    params : dict
        Parameter values used, by name.
    """

    q: np.ndarray
    t: float
    residual: float
    scale: float
    success: bool
    steady: bool
    message: str
    coordinates: tuple
    params: dict = field(default_factory=dict)

    def __repr__(self) -> str:
        where = ", ".join(f"{c}={v:.12g}" for c, v in zip(self.coordinates, self.q))
        return f"Equilibrium({where}, residual={self.residual:.2g}, success={self.success}, steady={self.steady})"


def _depends_on_time(model) -> bool:
    """Whether F(q, 0, t) may depend on t explicitly (then `Equilibrium.steady` is checked at later times).

    A System's from its T, V, dissipation and forces; a kinematic tree's (`lagcomp.Tree`) from its joints'
    torques, the only part of a tree that may read t (its masses, placements, springs and dampers are constant).
    """
    tree = tree_of(model)
    if tree is not None:
        return explicit_time(*(node.joint.torque for node in tree.nodes), system=tree)
    system = symbolic_system(model, "The statics analysis")
    return explicit_time(system.T, system.V, system.dissipation, *system.forces, system=system)


def _newton_polish(rest: RestForces, q: np.ndarray, iterations: int = 6) -> np.ndarray:
    """A few Newton steps with the compiled Jacobian, kept while they reduce the residual."""
    best, best_r = q, float(np.max(np.abs(rest.force(q))))
    for _ in range(iterations):
        stiffness, _ = rest.partials(best)
        try:
            step = np.linalg.solve(stiffness, rest.force(best))
        except np.linalg.LinAlgError:
            break
        trial = best - step
        r = float(np.max(np.abs(rest.force(trial))))
        if not r < best_r:
            break
        best, best_r = trial, r
    return best


def _equilibrium(rest: RestForces, q: np.ndarray, message: str, time_dependent: bool) -> Equilibrium:
    model = rest.model
    force = rest.force(q)
    scale = rest.force_scale(q, force, RESIDUAL_TOLERANCE)
    ratio, worst = relative_residual(force, scale)
    success = bool(np.all(np.isfinite(q)) and ratio <= RESIDUAL_TOLERANCE)
    steady = success
    if success and time_dependent:
        later = max(relative_residual(rest.force(q, rest.t + dt), scale)[0] for dt in STEADY_CHECK_OFFSETS)
        steady = later <= 1e3 * RESIDUAL_TOLERANCE
    return Equilibrium(q=q, t=rest.t, residual=float(np.max(np.abs(force))), scale=float(scale[worst]), success=success,
                       steady=steady, message=message, coordinates=model.coordinates, params=rest.params)


def find_equilibrium(model, guess, params: dict | None = None, *, t: float = 0.0, method: str = "hybr") -> Equilibrium:
    """The equilibrium F(q*, 0, t) = 0 nearest (in the root finder's sense) to `guess`.

    Parameters
    ----------
    model : Model
        A compiled unconstrained system.
    guess : array_like, shape (n,)
        Starting coordinates.
    params : dict, optional
        Parameter values by name (defaults from the System).
    t : float
        Time at which the forces are balanced (matters only with imposed motions).
    method : str
        `scipy.optimize.root` method; the compiled Jacobian is passed to it.

    Returns
    -------
    Equilibrium
        Check ``success``: a failed search is reported, not raised.
    """
    unconstrained(model, "find_equilibrium")
    rest = RestForces(model, params, t)
    q0 = coordinates_vector(model, guess, "guess")

    def residual_and_jacobian(q):
        return rest.force(q), rest.partials(q)[0]

    found = optimize.root(residual_and_jacobian, q0, jac=True, method=method)
    q = _newton_polish(rest, np.asarray(found.x, dtype=float))
    return _equilibrium(rest, q, str(found.message), _depends_on_time(model))


def find_equilibria(model, bounds, params: dict | None = None, *, t: float = 0.0, samples: int = 2000,
                    starts: int = 7) -> list[Equilibrium]:
    """Every equilibrium in a box, sorted.

    For one coordinate, F(q, 0, t) is sampled at ``samples + 1`` points of
    ``bounds = (a, b)``; each sign change is bracketed and solved by Brent's
    method, and each sampled near-zero minimum of |F| (a double root, which
    does not change sign) is tried by Newton's method.  Roots closer than the
    sampling step can be missed; raise `samples` for finely structured F.

    For n > 1 coordinates, ``bounds`` is a sequence of n pairs and
    `find_equilibrium` is started from a grid of ``starts`` points per axis:
    a multistart, which finds the equilibria whose basins the grid reaches
    (no guarantee of all).

    Returns
    -------
    list of Equilibrium
        Successful, distinct equilibria inside the box, sorted by coordinates.
    """
    unconstrained(model, "find_equilibria")
    box = np.asarray(bounds, dtype=float).reshape(-1, 2)
    if box.shape[0] != model.n or not np.all(box[:, 1] > box[:, 0]):
        raise OptionError(f"`bounds` must give (low, high) with low < high for each of the {model.n} "
                          f"coordinate(s) {list(model.coordinates)}, got {bounds!r}.")
    if model.n == 1:
        candidates = _bracketed_roots(RestForces(model, params, t), box[0], int(samples))
        found = [_equilibrium_at(model, params, t, q) for q in candidates]
    else:
        axes = [np.linspace(lo, hi, int(starts)) for lo, hi in box]
        grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, model.n)
        found = [find_equilibrium(model, q, params, t=t) for q in grid]
    inside = [e for e in found if e.success and np.all((e.q >= box[:, 0] - 1e-12) & (e.q <= box[:, 1] + 1e-12))]
    width = float(np.max(box[:, 1] - box[:, 0]))
    distinct: list[Equilibrium] = []
    for e in sorted(inside, key=lambda e: tuple(e.q)):
        if all(np.max(np.abs(e.q - d.q)) > 1e-9 * width for d in distinct):
            distinct.append(e)
    return distinct


def _equilibrium_at(model, params, t, q: float) -> Equilibrium:
    rest = RestForces(model, params, t)
    return _equilibrium(rest, _newton_polish(rest, np.array([q])), "bracketed", _depends_on_time(model))


def _bracketed_roots(rest: RestForces, interval, samples: int) -> list[float]:
    """Roots of the scalar F(q, 0, t) on `interval`: sign changes (Brent) and near-zero minima of |F| (Newton)."""
    a, b = interval
    grid = np.linspace(a, b, max(samples, 2) + 1)
    f = np.array([rest.force([q])[0] for q in grid])
    scale = max(float(np.max(np.abs(f))), 1e-300)
    roots = [float(q) for q, v in zip(grid, f) if v == 0.0]
    scalar = lambda q: rest.force([q])[0]  # noqa: E731
    for i in np.flatnonzero(f[:-1] * f[1:] < 0):
        roots.append(optimize.brentq(scalar, grid[i], grid[i + 1], xtol=1e-15, rtol=4 * np.finfo(float).eps))
    magnitude = np.abs(f)
    last = len(grid) - 1
    slack = 1e-12 * (b - a)
    for i in range(last + 1):
        lo, hi = max(i - 1, 0), min(i + 1, last)
        local_min = magnitude[i] <= magnitude[lo] and magnitude[i] <= magnitude[hi]
        # an end point has no sign change to bracket; inside, a sign change was handled above
        no_crossing = i in (0, last) or f[lo] * f[hi] > 0
        if local_min and no_crossing and 0 < magnitude[i] < 1e-3 * scale:
            q = float(grid[i])
            for _ in range(50):  # Newton on a double root converges linearly
                slope = rest.partials([q])[0][0, 0]
                if slope == 0.0:
                    break
                q -= scalar(q) / slope
            if grid[lo] - slack <= q <= grid[hi] + slack:
                roots.append(min(max(q, a), b))
    return sorted(roots)


# -- symbolic: virtual work ------------------------------------------------------------


def generalized_forces(system, *, eom=None):
    """F(q, 0, t): the generalized forces at rest, as a sympy column (symbols named after the coordinates).

    By the principle of virtual work these are the coefficients of δq_i in
    the virtual work of every force on the system at rest — applied loads,
    potentials, and the inertial forces of imposed motions.
    """
    from lagcomp.mechanics.lagrange import derive

    eom = derive(system) if eom is None else eom
    return eom.F.xreplace({v: 0 for v in eom.qd})


def balance(system, unknowns, *, eom=None) -> list[dict]:
    """Solve F(q, 0, t) = 0 for `unknowns`: the equilibrium relation between the forces.

    Parameters
    ----------
    system : System
    unknowns : str, Symbol or sequence of them
        Parameter or coordinate names (or symbols) to solve for, e.g. the
        load ``"P"`` a wheel jack holds for a given effort.

    Returns
    -------
    list of dict
        sympy's solutions, each mapping the unknown symbols to expressions of
        the other parameters and the coordinates (plain symbols named after
        the coordinates).
    """
    import sympy as sp

    from lagcomp.mechanics.lagrange import derive

    eom = derive(system) if eom is None else eom
    known = {s.name: s for s in (*eom.parameters, *eom.q)}
    wanted = [unknowns] if isinstance(unknowns, (str, sp.Symbol)) else list(unknowns)
    symbols = []
    for u in wanted:
        name = u.name if isinstance(u, sp.Symbol) else str(u)
        if name not in known:
            raise OptionError(f"Cannot solve for {name!r}: it is neither a parameter nor a coordinate of "
                              f"{system.name!r} ({sorted(known)}).")
        symbols.append(known[name])
    forces = [f for f in generalized_forces(system, eom=eom) if f != 0]
    return sp.solve(forces, symbols, dict=True)
