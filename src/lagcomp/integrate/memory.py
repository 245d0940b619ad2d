"""What a run or a sweep will hold in memory, estimated before it starts, and the refusal when it is too much.

A run that runs out of memory fails late (after the integration, when its
rows are joined) or is killed outright, and loses its work; the estimate
costs nothing.  Both estimates count float64 values (8 bytes each).
"""

from __future__ import annotations

from lagcomp.errors import OptionError

#: Default ceiling on the memory of a run's or a sweep's outputs, in bytes (raise it with `memory_limit`).
MEMORY_LIMIT = 2 * 2**30


def run_bytes(rows: int, n: int, k: int) -> int:
    """Peak bytes of a run keeping `rows` rows of an n-coordinate model with k constraints.

    Each row is kept as t, y = (q, q̇), T + V, h and the momenta (3 + 3n
    values), twice while the chunks are joined, then copied into q and q̇
    (2n) and evaluated for k reactions and k residuals.
    """
    return 8 * rows * (2 * (3 + 3 * n) + 2 * n + 2 * k)


def sweep_bytes(n_traj: int, n2: int, rows: int, n_events: int, cap: int) -> int:
    """Bytes of a sweep's outputs (state, times, status and counters; `rows` dense rows; energy; the first
    `cap` occurrences of `n_events` events) and its inputs Y0 and P, for `n_traj` trajectories of size n2."""
    per = 8 * (n2 + 1 + 1 + 3 + 2) + 8 * rows * n2 + 8 * n_events * (1 + cap * (1 + n2))
    return n_traj * per + 8 * n_traj * (n2 + 8)


def checked_limit(limit) -> float:
    """`memory_limit` checked: a positive number of bytes."""
    if isinstance(limit, bool) or not isinstance(limit, (int, float)) or not limit > 0:
        raise OptionError(f"`memory_limit` must be a positive number of bytes, got {limit!r}.")
    return limit


def check(needed: int, limit, what: str, detail: str, remedies: str) -> None:
    """Raise OptionError when `needed` bytes exceed `limit`: `what` needs the figure for `detail`; `remedies`."""
    if needed > checked_limit(limit):
        raise OptionError(f"{what} need {needed / 2**20:.1f} MiB for {detail}, above the limit of "
                          f"{limit / 2**20:.1f} MiB: {remedies}, or raise `memory_limit`.")
