"""
Cylinder on a moving tray
=========================

A cylinder rolling without slipping on a tray moved along a(t)
(`lagcomp.examples.unconstrained.tray_cylinder`): the tray's motion is an imposed function of ``lc.t``.
"""

import lagcomp as lc
from lagcomp import examples, plots

model = lc.compile(examples.get("tray_cylinder"))
sol = model.simulate((0, 10))
fig = plots.plot_coordinates(sol, velocities=True)
