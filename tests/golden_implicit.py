"""The implicit and canonical runs that must stay bitwise equal when they move into the library (#19).

Gauss-Legendre collocation (fixed point and simplified Newton, simulate and sweep), the
Hamiltonian and canonical Jacobian, and the Lyapunov loops (variational and two-trajectory) of
the double pendulum, stored from the template code at d18c60c, before `collocation_run`,
``templates/hamiltonian.py`` and ``templates/lyapunov.py`` became library code:

    python -m tests.golden_implicit   # rewrites tests/data/implicit_golden.npz (only when a change is meant)
"""

from __future__ import annotations

import pathlib

import numpy as np

import lagcomp as lc
from lagcomp import analysis as an
from lagcomp.examples import get

GOLDEN = pathlib.Path(__file__).parent / "data" / "implicit_golden.npz"

#: The double pendulum's start: a chaotic one, so that any change of rounding grows visibly.
Q0, QD0 = [1.2, -0.4], [0.3, 0.8]

#: run label -> simulate options (t_span first)
RUNS = {
    "gauss1": {"t_span": (0.0, 2.0), "method": "gauss1", "dt": 1e-2},
    "gauss2_fixed_point": {"t_span": (0.0, 5.0), "method": "gauss2", "dt": 1e-2, "save_every": 3},
    "gauss2_newton": {"t_span": (0.0, 5.0), "method": "gauss2", "dt": 1e-2, "implicit_solver": "newton"},
    "gauss3_fixed_point": {"t_span": (0.0, 5.0), "method": "gauss3", "dt": 2e-2},
    "gauss3_newton": {"t_span": (0.0, 5.0), "method": "gauss3", "dt": 5e-2, "implicit_solver": "newton"},
}


def runs(cache_dir=None):
    """label -> array of every golden result, computed now."""
    model = lc.compile(get("double_pendulum"), cache_dir=cache_dir)
    out = {}
    for label, options in RUNS.items():
        options = dict(options)
        sol = model.simulate(options.pop("t_span"), Q0, QD0, **options)
        out[f"{label}/t"], out[f"{label}/y"], out[f"{label}/nfev"] = sol.t, sol.y, np.asarray(sol.nfev)
    swept = model.sweep((0.0, 2.0), {"theta1": np.linspace(0.5, 1.5, 3)}, qd0=QD0, method="gauss2", dt=1e-2,
                        save_every=10, output=("dense", "energy"), workers=1, progress=False)
    for key in ("final", "t_final", "status", "nfev", "nsteps", "dense", "energy_error"):
        out[f"sweep_gauss2/{key}"] = getattr(swept, key)
    x = model.canonical_state(Q0, QD0)
    out["hamiltonian"] = np.asarray(model.hamiltonian(0.0, x))
    out["canonical_jacobian"] = model.canonical_jacobian(0.0, x)
    spectrum = an.lyapunov_spectrum(model, (0.0, 20.0), Q0, QD0, dt=0.01, samples=20, progress=False)
    shadow = an.two_trajectory_lyapunov(model, (0.0, 20.0), Q0, QD0, dt=0.01, renorm_every=5, samples=20,
                                        progress=False)
    for label, result in (("lyapunov", spectrum), ("divergence", shadow)):
        out[f"{label}/t"], out[f"{label}/history"] = result.t, result.history
        out[f"{label}/final_state"] = result.final_state
    return out


if __name__ == "__main__":
    np.savez_compressed(GOLDEN, **runs())
    print(f"wrote {GOLDEN}")
