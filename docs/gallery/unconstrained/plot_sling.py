"""
Sling: a bead on a turning rod
==============================

A bead slides without friction along a rod turned at a constant rate ω in a horizontal plane
(`lagcomp.examples.unconstrained.sling`): ρ̈ = ω² ρ, so ρ(t) = ρ₀ cosh ωt from rest.  The
imposed rotation enters T through ``lc.t``.
"""

import numpy as np

import lagcomp as lc
from lagcomp import examples, plots

model = lc.compile(examples.get("sling"))
sol = model.simulate((0, 2), rtol=1e-12, atol=1e-12)
omega = sol.params["omega"]
print("largest relative error against rho0 cosh(omega t):",
      np.max(np.abs(sol.q[:, 0] / (0.1 * np.cosh(omega * sol.t)) - 1)))
fig = plots.plot_coordinates(sol, velocities=True)
