"""The Taylor runs whose results must stay bitwise equal when its drivers move (tests/data/taylor_golden.npz).

Stored from the template drivers (templates/taylor.py, templates/taylor_lanes.py) at d18c60c, before
the Taylor method became library code (#19).  Re-stored when `lagcomp.kernel_support.trig`'s sin and
cos got ``fastmath=False``: until then numba compiled them with the flags of their first caller, and
the stored runs had sin with FMAs (compiled first by the Taylor kernel, ``contract``) and cos without.
Four results moved in the last bits (double_pendulum/y, double_pendulum_steps/t and /y, sweep/final:
at most 1.5e-14 apart), as accurate as before against a long-double RK4 reference (the commit message
gives the errors); the other results stayed bitwise equal.

    python -m tests.golden_taylor   # rewrites tests/data/taylor_golden.npz (only when a change is meant)

The runs cover the driver's paths: periodic reduction (the double pendulum's angles), events located
on the series (Hénon-Heiles' section), a gravitational system without periodic coordinates (the
Pythagorean three-body problem), ``t_eval`` points on the series, the per-trajectory sweep and the
batched (SIMD lane) sweep.
"""

from __future__ import annotations

import pathlib

import numpy as np

import lagcomp as lc
from lagcomp.examples import get

GOLDEN = pathlib.Path(__file__).parent / "data" / "taylor_golden.npz"

#: label -> (example, simulate options, t_span first)
RUNS = {
    "double_pendulum": ("double_pendulum", dict(t_span=(0.0, 10.0), q0=[1.2, -0.4], qd0=[0.3, 0.8],
                                                t_eval=np.linspace(0.0, 10.0, 101))),
    "double_pendulum_steps": ("double_pendulum", dict(t_span=(0.0, 5.0), q0=[2.5, -1.0], rtol=1e-12, atol=1e-12)),
    "henon_heiles": ("henon_heiles", dict(t_span=(0.0, 60.0), t_eval=np.linspace(0.0, 60.0, 61))),
    "three_body": ("pythagorean_three_body", dict(t_span=(0.0, 2.0), t_eval=np.linspace(0.0, 2.0, 21))),
}

#: label -> (example, sweep grid, sweep options)
SWEEPS = {
    "sweep": ("double_pendulum", {"theta1": np.linspace(-2.0, 2.0, 5)}, dict(rtol=1e-10, atol=1e-10)),
    "batched": ("double_pendulum", {"theta1": np.linspace(-2.0, 2.0, 9), "theta2": np.linspace(-1.0, 1.0, 5)},
                dict(rtol=1e-8, atol=1e-8, qd0=[0.3, -0.2], batched=True, workers=1, output="energy")),
    "batched_driven": ("driven_pendulum", {"theta": np.linspace(-2.0, 2.0, 7)},
                       dict(rtol=1e-8, atol=1e-8, batched=True, workers=1)),
}


def runs(cache_dir=None):
    """label -> array of every golden result, computed now."""
    models, out = {}, {}

    def model(example):
        if example not in models:
            models[example] = lc.compile(get(example), cache_dir=cache_dir)
        return models[example]

    for label, (example, options) in RUNS.items():
        options = dict(options)
        sol = model(example).simulate(options.pop("t_span"), method="taylor", progress=False, **options)
        out[f"{label}/t"], out[f"{label}/y"] = sol.t, sol.y
        out[f"{label}/counts"] = np.array([sol.status, sol.nfev, sol.nsteps])
        for name, record in (sol.events or {}).items():
            out[f"{label}/event/{name}/t"], out[f"{label}/event/{name}/q"] = record.t, record.q
            out[f"{label}/event/{name}/qd"] = record.qd
    for label, (example, grid, options) in SWEEPS.items():
        sweep = model(example).sweep((0.0, 3.0), grid, method="taylor", progress=False, **options)
        out[f"{label}/final"], out[f"{label}/t_final"] = sweep.final, sweep.t_final
        out[f"{label}/counts"] = np.stack([sweep.status, sweep.nfev, sweep.nsteps])
        if sweep.energy_error is not None:
            out[f"{label}/energy_error"] = sweep.energy_error
    return out


if __name__ == "__main__":
    np.savez_compressed(GOLDEN, **runs())
    print(f"wrote {GOLDEN}")
