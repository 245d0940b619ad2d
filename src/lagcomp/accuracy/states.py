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


def close_approach_states(model, points, n: int = 30, *, anchors=(), distances=CLOSE_DISTANCES, seed: int = 0,
                          spread: float = 1.0) -> np.ndarray:
    """n states in which a point comes a distance d from another point or from a fixed anchor.

    Parameters
    ----------
    points : sequence of tuples of coordinate names
        The Cartesian coordinates of each moving point, e.g. ``[("x1", "y1"), ("x2", "y2")]``.
    anchors : sequence of tuples of float
        Fixed positions the points can approach (a primary of the restricted
        three-body problem), each with as many coordinates as a point.
    distances : sequence of float
        Separations of the close pair, used in turn.

    Each state starts from `random_states`; a pair (two points, or a point and
    an anchor) is chosen at random and the point is put at the other's
    position + d·u, u a random unit vector.  Velocities stay random.
    """
    index = {name: i for i, name in enumerate(model.coordinates)}
    try:
        slots = [[index[name] for name in point] for point in points]
    except KeyError as err:
        raise ModelError(f"`points` names {err.args[0]!r}, which is not a coordinate of {model.name!r} "
                         f"(coordinates {list(model.coordinates)}).") from None
    anchors = [np.asarray(a, dtype=float) for a in anchors]
    sizes = {len(s) for s in slots} | {a.size for a in anchors}
    pairs = [(a, b) for a in range(len(slots)) for b in range(len(slots)) if a != b]
    pairs += [(a, -1 - k) for a in range(len(slots)) for k in range(len(anchors))]
    if not pairs or len(sizes) != 1:
        raise ModelError("`points` and `anchors` must give at least one pair, every point and anchor with the "
                         f"same number of coordinates (got sizes {sorted(sizes)}).")
    rng = np.random.default_rng(seed)
    states = random_states(model, n, seed=seed + 1, spread=spread)
    for k, state in enumerate(states):
        moved, other = pairs[rng.integers(len(pairs))]
        target = state[slots[other]] if other >= 0 else anchors[-1 - other]
        u = rng.standard_normal(len(slots[moved]))
        state[slots[moved]] = target + distances[k % len(distances)] * u / np.linalg.norm(u)
    return states
