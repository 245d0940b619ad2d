"""States to measure kernels at: random ones around a model's start, and close approaches of point pairs."""

from __future__ import annotations

import numpy as np

from lagcomp.errors import ModelError

#: Distances of the close approaches `close_approach_states` makes by default.
CLOSE_DISTANCES = (1e-2, 1e-4, 1e-6)


def random_states(model, n: int = 50, *, seed: int = 0, spread: float = 1.0) -> np.ndarray:
    """n states (q, q̇), shape (n, 2n_q): q = q0 + spread·U(−1, 1), q̇ = q̇0 + spread·N(0, 1).

    q0, q̇0 are the model's defaults (zeros where it has none).
    """
    rng = np.random.default_rng(seed)
    q0 = np.zeros(model.n) if model.q0 is None else np.asarray(model.q0, dtype=float)
    qd0 = np.zeros(model.n) if model.qd0 is None else np.asarray(model.qd0, dtype=float)
    q = q0 + spread * rng.uniform(-1.0, 1.0, size=(n, model.n))
    qd = qd0 + spread * rng.standard_normal(size=(n, model.n))
    return np.hstack([q, qd])


def close_approach_states(model, points, n: int = 30, *, distances=CLOSE_DISTANCES, seed: int = 0,
                          spread: float = 1.0) -> np.ndarray:
    """n states in which two of the `points` are a distance d apart, d cycling through `distances`.

    Parameters
    ----------
    points : sequence of tuples of coordinate names
        The Cartesian coordinates of each point, e.g. ``[("x1", "y1"), ("x2", "y2")]``.
        Every point has the same number of coordinates (2 or 3).
    distances : sequence of float
        Separations of the close pair.

    Each state starts from `random_states`; a random pair (a, b) of points is
    chosen and b is put at a + d·u, u a random unit vector.  Velocities stay random.
    """
    index = {name: i for i, name in enumerate(model.coordinates)}
    try:
        slots = [[index[name] for name in point] for point in points]
    except KeyError as err:
        raise ModelError(f"`points` names {err.args[0]!r}, which is not a coordinate of {model.name!r} "
                         f"(coordinates {list(model.coordinates)}).") from None
    if len(slots) < 2 or len({len(s) for s in slots}) != 1:
        raise ModelError("`points` must list at least two points with the same number of coordinates each.")
    rng = np.random.default_rng(seed)
    states = random_states(model, n, seed=seed + 1, spread=spread)
    for k, state in enumerate(states):
        a, b = rng.choice(len(slots), size=2, replace=False)
        u = rng.standard_normal(len(slots[a]))
        u /= np.linalg.norm(u)
        d = distances[k % len(distances)]
        state[slots[b]] = state[slots[a]] + d * u
    return states
