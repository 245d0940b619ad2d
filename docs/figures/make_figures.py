"""Draw the figures in this directory: one run of each plot function of `lagcomp.plots`.

    PYTHONPATH=src python docs/figures/make_figures.py [docs/figures]

(needs matplotlib; about a minute, most of it numba compiling the examples'
drivers once).  ``run_double_pendulum.png`` is what the command line writes:
``lagcomp run double_pendulum --t-end 20 --plot docs/figures/run_double_pendulum.png``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import lagcomp as lc
from lagcomp import analysis, examples, plots


def main(directory: Path) -> None:
    directory.mkdir(parents=True, exist_ok=True)

    def save(fig, name: str) -> None:
        fig.savefig(directory / name, dpi=110)
        print(f"wrote {directory / name}")

    # coordinates and velocities vs time: the bead on a wobbling hoop (ε = 0.2)
    hoop = lc.compile(examples.get("hoop_bead"))
    sol = hoop.simulate((0, 10), rtol=1e-10, atol=1e-10, t_eval=np.linspace(0, 10, 2001))
    save(plots.plot_coordinates(sol, velocities=True, title="hoop_bead (ε = 0.2): θ(t), θ'(t)"), "coordinates.png")

    # energy error vs time: Gauss-Legendre (symplectic, bounded) against DOP853 (drifting)
    pendulum = lc.compile(examples.get("double_pendulum"))
    sol = pendulum.simulate((0, 200), method="gauss2", dt=0.01, q0=[1.0, 0.5], save_every=10)
    save(plots.plot_energy_error(sol, title="double pendulum, gauss2 dt = 0.01: bounded energy error"),
         "energy_error.png")

    # phase portrait: the badly balanced cylinder, regimes on both sides of the separatrix
    cylinder = lc.compile(examples.get("unbalanced_cylinder"))
    M, R, a, g = (cylinder.system.defaults[k] for k in ("M", "R", "a", "g"))
    E_bottom, E_top = M * g * (R - a), M * g * (R + a)
    energies = E_bottom + (E_top - E_bottom) * np.array([0.1, 0.35, 0.7, 1.3, 1.8])
    portrait = analysis.phase_portrait(cylinder, energies, (-np.pi, np.pi), periodic=True)
    save(plots.plot_phase_portrait(portrait, title="unbalanced cylinder: oscillation, separatrix, rolling"),
         "phase_portrait.png")

    # Poincaré section: Hénon-Heiles at E = 1/6 (x = 0, ẋ > 0), 64 orbits
    hh = lc.compile(examples.get("henon_heiles"))
    E = 1 / 6
    y0 = np.concatenate([np.linspace(-0.4, 0.65, 48), np.full(16, -0.15)])  # along ẏ = 0, and across it
    yd0 = np.concatenate([np.zeros(48), np.linspace(-0.45, 0.45, 16)])
    start = np.column_stack([np.zeros_like(y0), y0, np.zeros_like(y0), yd0])
    start, valid = analysis.on_energy_surface(hh, E, start, "x_dot")
    section = analysis.poincare_section(hh, (0, 3000), start[valid], max_points=1500)
    save(plots.plot_poincare(section, "y", "y_dot", title="Hénon–Heiles, E = 1/6: section x = 0, ẋ > 0"),
         "poincare.png")

    # Lyapunov: chaotic and regular orbits of the same energy
    chaotic, _ = analysis.on_energy_surface(hh, E, [[0.0, -0.1, 0.0, 0.0]], "x_dot")
    regular, _ = analysis.on_energy_surface(hh, E, [[0.0, 0.1, 0.0, 0.0]], "x_dot")
    runs = [
        analysis.lyapunov_exponents(hh, (0, 20000), chaotic[0, :2], chaotic[0, 2:], dt=0.02),
        analysis.two_trajectory_lyapunov(hh, (0, 20000), chaotic[0, :2], chaotic[0, 2:], dt=0.02),
        analysis.lyapunov_exponents(hh, (0, 20000), regular[0, :2], regular[0, 2:], dt=0.02),
    ]
    save(plots.plot_lyapunov(*runs, labels=["chaotic y0 = −0.1, variational", "chaotic, two trajectories",
                                            "regular y0 = 0.1, variational"],
                             title="Hénon–Heiles, E = 1/6: largest Lyapunov exponent"), "lyapunov.png")

    # sweep map: where the double pendulum's second rod ends up after 10 s
    grid = {"theta1": np.linspace(-np.pi, np.pi, 81), "theta2": np.linspace(-np.pi, np.pi, 81)}
    sweep = pendulum.sweep((0, 10), grid, rtol=1e-9, atol=1e-9)
    save(plots.plot_sweep(sweep, sweep.final[..., 1] / (2 * np.pi), label="θ2(10 s) / 2π", cmap="RdBu_r",
                          symmetric=True, title="double pendulum from rest: turns of the second rod after 10 s"),
         "sweep_map.png")

    # eigenvalues along a parameter: a thin disc rolling upright is stable above φ̇² = g/(3r)
    cyclic = ("x", "y", "psi", "phi", "phi_dot")
    disc = analysis.stability_sweep(examples.get("rolling_disc"), "phi_dot", np.linspace(0.5, 12, 47), [0.0] * 5,
                                    drop=cyclic)
    save(plots.plot_stability(disc, title="rolling disc, upright: eigenvalues vs spin (stable for φ̇² > g/(3r))"),
         "stability_disc.png")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parent)
