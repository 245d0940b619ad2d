r"""Poincaré sections over many initial conditions, from the System's events.

A section is a surface g(t, q, q̇) = 0 crossed in one direction — declared
on the System as ``Event("section", g, direction=+1)``; the adaptive drivers
locate each crossing to a few ulps of t.  `poincare_section` integrates a set
of initial states with `Model.sweep` (every core, ``output="events"``) and
collects each trajectory's crossings; `Section.points` then projects them on
two state components, e.g. (y, ẏ) for the Hénon–Heiles section x = 0.

For a conservative system the initial states of one portrait usually share
an energy: `on_energy_surface` completes states (q, q̇) by the one velocity
component that puts them on h = E.  h is quadratic in the velocities, so with
the others fixed h(v) = a v² + b v + c exactly; three evaluations of the
compiled energy function give a, b, c, and v is the larger root.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from lagcomp.analysis._common import unconstrained
from lagcomp.errors import OptionError


@dataclass(frozen=True)
class Section:
    """Crossings of one event by each of N trajectories.

    Attributes
    ----------
    event : str
    t : ndarray, shape (N, cap)
        Crossing times (NaN beyond each trajectory's count).
    y : ndarray, shape (N, cap, 2n)
        States (q, q̇) at the crossings.
    count : ndarray of int, shape (N,)
        Crossings found per trajectory (at most ``cap`` are kept).
    initial : ndarray, shape (N, 2n)
        The initial states.
    status : ndarray of int, shape (N,)
        Each trajectory's `Solution`-style status.
    state_names : tuple of str
        Names of the 2n state components: coordinates, then ``<name>_dot``.
    params : dict
    """

    event: str
    t: np.ndarray
    y: np.ndarray
    count: np.ndarray
    initial: np.ndarray
    status: np.ndarray
    state_names: tuple
    params: dict = field(default_factory=dict)

    def points(self, x: str, y: str) -> list[np.ndarray]:
        """Per trajectory, its crossings projected on two state components: arrays of shape (k_i, 2)."""
        i, j = (self._index(name) for name in (x, y))
        kept = np.minimum(self.count, self.t.shape[1])
        return [self.y[r, : kept[r]][:, [i, j]] for r in range(self.y.shape[0])]

    def _index(self, name: str) -> int:
        if name not in self.state_names:
            raise OptionError(f"Unknown state component {name!r}; choose from {list(self.state_names)}.")
        return self.state_names.index(name)


def _state_names(model) -> tuple:
    return tuple(model.coordinates) + tuple(f"{c}_dot" for c in model.coordinates)


def on_energy_surface(model, energy: float, states, solve_for: str, params: dict | None = None, *,
                      t: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Complete initial states so that the energy function h equals `energy`.

    Parameters
    ----------
    states : array_like, shape (N, 2n)
        States (q, q̇); the component `solve_for` is overwritten.
    solve_for : str
        A velocity name, ``"<coordinate>_dot"``: the component solved for
        (the larger root of h = E, usually the positive one).

    Returns
    -------
    states : ndarray, shape (N, 2n)
        The completed states (rows where h = E has no real root are NaN).
    valid : ndarray of bool, shape (N,)
        Which rows could be put on the surface.
    """
    names = _state_names(model)
    if solve_for not in names[model.n:]:
        raise OptionError(f"`solve_for` must be a velocity of {model.name!r}: one of {list(names[model.n:])}.")
    j = names.index(solve_for)
    states = np.array(states, dtype=float, ndmin=2)
    if states.shape[1] != 2 * model.n:
        raise OptionError(f"`states` must have {2 * model.n} columns {list(names)}, got shape {states.shape}.")
    p = model.parameter_vector(params)
    out = np.full_like(states, np.nan)
    valid = np.zeros(states.shape[0], dtype=bool)
    h = model.kernels.energy_function
    for r, row in enumerate(states):
        y = row.copy()
        values = []
        for v in (-1.0, 0.0, 1.0):
            y[j] = v
            values.append(h(float(t), y, p))
        a = (values[2] + values[0]) / 2 - values[1]
        b = (values[2] - values[0]) / 2
        c = values[1] - float(energy)
        disc = b * b - 4 * a * c
        if a > 0 and disc >= 0:
            y[j] = (-b + np.sqrt(disc)) / (2 * a)
            out[r], valid[r] = y, True
    return out, valid


def poincare_section(model, t_span, initial_states, params: dict | None = None, *, event: str = "section",
                     max_points: int = 500, rtol: float = 1e-10, atol: float = 1e-12, method: str = "dop853",
                     **sweep_options) -> Section:
    """Integrate each initial state over `t_span` and keep its crossings of `event`.

    Parameters
    ----------
    model : Model
        A compiled unconstrained system declaring `event`.
    t_span : (float, float)
    initial_states : array_like, shape (N, 2n)
        States (q, q̇) to start from (e.g. from `on_energy_surface`).
    event : str
        The System's event defining the section (default ``"section"``).
    max_points : int
        Crossings kept per trajectory (the sweep's ``event_cap``).

    Other keyword arguments go to `Model.sweep` (``workers``, ``max_step``, ``progress``, ...).
    """
    unconstrained(model, "poincare_section")
    if event not in model.event_names:
        raise OptionError(f"{model.name!r} has no event {event!r}; declare it on the System, e.g. "
                          f"Event({event!r}, x, direction=1). Its events: {list(model.event_names)}.")
    states = np.array(initial_states, dtype=float, ndmin=2)
    names = _state_names(model)
    if states.shape[1] != len(names) or not np.all(np.isfinite(states)):
        raise OptionError(f"`initial_states` must be finite rows of {len(names)} values {list(names)}, "
                          f"got shape {states.shape}.")
    sweep = model.sweep(t_span, states, names=names, params=params, output="events", events=[event],
                        event_cap=int(max_points), method=method, rtol=rtol, atol=atol, **sweep_options)
    record = sweep.events[event]
    return Section(event=event, t=record["t"], y=record["y"], count=np.asarray(record["count"]), initial=states,
                   status=np.asarray(sweep.status), state_names=names,
                   params=dict(zip(model.parameters, model.parameter_vector(params).tolist())))
