"""The runs whose trajectories must stay bitwise equal when the drivers change (tests/data/driver_golden.npz).

Stored from the template drivers at 40e7228, before the integrator layer became library code (#19):

    python -m tests.golden_runs   # rewrites tests/data/driver_golden.npz (only when a change is meant)
"""

from __future__ import annotations

import pathlib

import numpy as np

import lagcomp as lc
from lagcomp.examples import get

GOLDEN = pathlib.Path(__file__).parent / "data" / "driver_golden.npz"

#: (example, initial coordinates, initial velocities)
STATES = {
    "double_pendulum": ([1.2, -0.4], [0.3, 0.8]),
    "rolling_disc": (None, None),
}

#: run label -> simulate options (t_span first)
RUNS = {
    "rk4": dict(t_span=(0.0, 5.0), method="rk4", dt=1e-3, save_every=7),
    "dop853": dict(t_span=(0.0, 10.0), method="dop853", rtol=1e-10, atol=1e-10),
    "dop853_dense": dict(t_span=(0.0, 10.0), method="dop853", rtol=1e-9, atol=1e-9,
                         t_eval=np.linspace(0.0, 10.0, 101)),
    "dopri5": dict(t_span=(0.0, 10.0), method="dopri5", rtol=1e-8, atol=1e-8),
    "dopri5_dense": dict(t_span=(0.0, 10.0), method="dopri5", rtol=1e-8, atol=1e-8,
                         t_eval=np.linspace(0.0, 10.0, 101)),
}


def runs(cache_dir=None):
    """label -> (t, y) of every golden run, computed now."""
    out = {}
    for example, (q0, qd0) in STATES.items():
        model = lc.compile(get(example), cache_dir=cache_dir)
        for label, options in RUNS.items():
            options = dict(options)
            sol = model.simulate(options.pop("t_span"), q0, qd0, **options)
            out[f"{example}/{label}/t"] = sol.t
            out[f"{example}/{label}/y"] = sol.y
    return out


if __name__ == "__main__":
    np.savez_compressed(GOLDEN, **runs())
    print(f"wrote {GOLDEN}")
