"""Analysis on compiled models: equilibria, small oscillations, conserved quantities,
phase portraits, Poincaré sections, Lyapunov exponents and periodic orbits.

Each module has one job and works on a compiled `Model` (its kernels), with a
symbolic counterpart where one is useful:

=================  ===========================================================
``statics``        `find_equilibrium`, `find_equilibria` (F(q, 0, t) = 0);
                   symbolic `generalized_forces`, `balance` (virtual work)
``oscillations``   `linearize` (M₀, K₀, G₀, D₀), `normal_modes`, stability;
                   `linearize_symbolic`
``steady``         `linearize_steady`: about steady motions, constrained or not
                   (reduced state matrix, eigenvalues, modes); `consistent_speeds`
``stability``      `stability_sweep`: eigenvalues along a parameter, where
                   stability changes
``state_space``    `StateSpace` (A, B, C, D) for control, from `linearize` and
                   `linearize_steady` with ``inputs=``; scipy / python-control
``conserved``      `conserved_quantities`: first integrals and why
``portrait``       `phase_portrait` of 1-DoF systems from the energy integral
``poincare``       `poincare_section` over many initial states, `on_energy_surface`
``lyapunov``       `lyapunov_exponents` (variational, QR), `lyapunov_spectrum`,
                   `two_trajectory_lyapunov`
``periodic``       `periodic_orbit` by shooting on the monodromy matrix, with
                   its Floquet multipliers
=================  ===========================================================

Pictures of all of these: `lagcomp.plots`.
"""

from lagcomp.analysis.conserved import Conserved as Conserved, conserved_quantities as conserved_quantities
from lagcomp.analysis.lyapunov import (
    Lyapunov as Lyapunov,
    lyapunov_exponents as lyapunov_exponents,
    lyapunov_spectrum as lyapunov_spectrum,
    two_trajectory_lyapunov as two_trajectory_lyapunov,
)
from lagcomp.analysis.oscillations import (
    Linearization as Linearization,
    Modes as Modes,
    linearize as linearize,
    linearize_symbolic as linearize_symbolic,
    normal_modes as normal_modes,
)
from lagcomp.analysis.periodic import PeriodicOrbit as PeriodicOrbit, periodic_orbit as periodic_orbit
from lagcomp.analysis.poincare import Section as Section, on_energy_surface as on_energy_surface
from lagcomp.analysis.poincare import poincare_section as poincare_section
from lagcomp.analysis.portrait import Portrait as Portrait, phase_portrait as phase_portrait
from lagcomp.analysis.state_space import StateSpace as StateSpace
from lagcomp.analysis.steady import (
    SteadyLinearization as SteadyLinearization,
    consistent_speeds as consistent_speeds,
    linearize_steady as linearize_steady,
)
from lagcomp.analysis.stability import (
    StabilityChange as StabilityChange,
    StabilitySweep as StabilitySweep,
    stability_sweep as stability_sweep,
)
from lagcomp.analysis.statics import (
    Equilibrium as Equilibrium,
    balance as balance,
    find_equilibria as find_equilibria,
    find_equilibrium as find_equilibrium,
    generalized_forces as generalized_forces,
)

__all__ = [
    "Conserved", "Equilibrium", "Linearization", "Lyapunov", "Modes", "PeriodicOrbit", "Portrait", "Section",
    "StabilityChange", "StabilitySweep", "StateSpace", "SteadyLinearization", "balance", "conserved_quantities", "consistent_speeds",
    "find_equilibria", "find_equilibrium", "generalized_forces", "linearize", "linearize_steady", "linearize_symbolic",
    "lyapunov_exponents", "lyapunov_spectrum", "normal_modes", "on_energy_surface", "periodic_orbit", "phase_portrait",
    "poincare_section", "stability_sweep", "two_trajectory_lyapunov",
]
