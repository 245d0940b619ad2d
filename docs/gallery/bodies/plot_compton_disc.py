"""
Compton's disc
==============

A wheel on a turning carousel whose axis is swung over (`lagcomp.examples.bodies.compton_disc`):
φ is cyclic, and after the axis is reversed φ̇ = 2 ω sin λ.
"""

import lagcomp as lc
from lagcomp import examples, plots

model = lc.compile(examples.get("compton_disc"))
sol = model.simulate((0, 12))
fig = plots.plot_coordinates(sol, velocities=True)
