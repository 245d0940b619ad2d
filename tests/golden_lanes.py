"""The batched (SIMD lane) sweeps whose outputs must stay bitwise equal when their code moves (tests/data/lanes_golden.npz).

Stored from the template loops (``templates/lanes.py``) and the lane kernel built by rewriting the
scalar kernel's source, before both became library code and IR (#19):

    python -m tests.golden_lanes   # rewrites tests/data/lanes_golden.npz (only when a change is meant)

The double pendulum (sin and cos in its lanes) and the driven pendulum (a time-dependent system:
every lane reads its own time) over 45 trajectories: with the template's 32 lanes a full block and a partial one.
"""

from __future__ import annotations

import pathlib

import numpy as np

import lagcomp as lc
from lagcomp.examples import get

GOLDEN = pathlib.Path(__file__).parent / "data" / "lanes_golden.npz"

#: example -> (grid, fixed initial velocities)
GRIDS = {
    "double_pendulum": ({"theta1": np.linspace(-1.5, 1.5, 9), "theta2": np.linspace(-1.0, 1.0, 5)}, [0.3, -0.2]),
    "driven_pendulum": ({"theta": np.linspace(-2.0, 2.0, 45)}, [0.1]),
}

#: run label -> sweep options (t_span first)
RUNS = {
    "rk4": {"t_span": (0.0, 5.0), "method": "rk4", "dt": 1e-2, "save_every": 50, "output": ("dense", "energy")},
    "rk4_last_step_short": {"t_span": (0.0, 1.0), "method": "rk4", "dt": 0.3, "output": "energy"},
    "dop853": {"t_span": (0.0, 10.0), "method": "dop853", "rtol": 1e-10, "atol": 1e-10, "output": "energy"},
    "dop853_loose": {"t_span": (0.0, 10.0), "method": "dop853", "rtol": 1e-5, "atol": 1e-7, "max_step": 0.5},
}

#: Sweep outputs compared.
KEYS = ("final", "t_final", "status", "nfev", "nsteps", "nrejected", "dense", "energy_error")


def runs(cache_dir=None):
    """label -> output array of every golden sweep, computed now."""
    out = {}
    for example, (grid, qd0) in GRIDS.items():
        model = lc.compile(get(example), cache_dir=cache_dir)
        for label, options in RUNS.items():
            options = dict(options)
            result = model.sweep(options.pop("t_span"), grid, qd0=qd0, batched=True, workers=1, **options)
            for key in KEYS:
                value = getattr(result, key)
                if value is not None:
                    out[f"{example}/{label}/{key}"] = value
    return out


if __name__ == "__main__":
    np.savez_compressed(GOLDEN, **runs())
    print(f"wrote {GOLDEN}")
