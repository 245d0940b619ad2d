"""The runs whose trajectories must stay bitwise equal when the drivers change (tests/data/driver_golden*.npz).

Stored from the template drivers before the integrator layer became library code (#19): the
general drivers' runs at 40e7228, the symplectic compositions' at d18c60c.

    python -m tests.golden_runs [set ...]   # rewrites the sets' files (only when a change is meant)
"""

from __future__ import annotations

import pathlib
import sys

import numpy as np

import lagcomp as lc
from lagcomp.examples import get

DATA = pathlib.Path(__file__).parent / "data"
GOLDEN = DATA / "driver_golden.npz"

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

#: The explicit symplectic compositions take separable systems only, hence examples of their own.
SEPARABLE_STATES = {
    "henon_heiles": (None, None),
    "pythagorean_three_body": (None, None),
}
COMPOSITION_RUNS = {
    "verlet": dict(t_span=(0.0, 10.0), method="verlet", dt=1e-3, save_every=7),
    "yoshida4": dict(t_span=(0.0, 10.0), method="yoshida4", dt=3e-3, save_every=5),
    "yoshida6": dict(t_span=(0.0, 10.0), method="yoshida6", dt=1e-2),
}

#: set name -> (file, examples, runs)
SETS = {
    "drivers": (GOLDEN, STATES, RUNS),
    "compositions": (DATA / "driver_golden_compositions.npz", SEPARABLE_STATES, COMPOSITION_RUNS),
}


def runs(cache_dir=None, states=STATES, options_by_label=RUNS):
    """label -> (t, y) of every run of `options_by_label` from every example of `states`, computed now."""
    out = {}
    for example, (q0, qd0) in states.items():
        model = lc.compile(get(example), cache_dir=cache_dir)
        for label, options in options_by_label.items():
            options = dict(options)
            sol = model.simulate(options.pop("t_span"), q0, qd0, **options)
            out[f"{example}/{label}/t"] = sol.t
            out[f"{example}/{label}/y"] = sol.y
    return out


if __name__ == "__main__":
    for name in sys.argv[1:] or SETS:
        path, states, options_by_label = SETS[name]
        np.savez_compressed(path, **runs(states=states, options_by_label=options_by_label))
        print(f"wrote {path}")
