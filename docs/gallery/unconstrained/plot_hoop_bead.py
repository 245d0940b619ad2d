"""
Bead on a turning hoop
======================

A bead on a frictionless hoop turned about its vertical diameter (`lagcomp.examples.unconstrained.hoop_bead`).
Above Ω² = g/R the bottom loses its stability to two off-axis equilibria, cos θ* = −g/(RΩ²):
`lagcomp.analysis` finds them and their small-oscillation frequencies.
"""

import numpy as np

import lagcomp as lc
from lagcomp import analysis as an
from lagcomp import examples, plots

hoop = lc.compile(examples.get("hoop_bead"))
spun = dict(Omega=6.0, epsilon=0.0)
equilibria = an.find_equilibria(hoop, (-1, 2 * np.pi - 1), spun)
for eq in equilibria:
    print(eq)
print(an.normal_modes(hoop, equilibria[1].q, spun))   # about θ*, where cos θ* = −g/(RΩ²)
sol = hoop.simulate((0, 10), q0=[2.5], params=spun)
fig = plots.plot_phase_portrait(sol)
