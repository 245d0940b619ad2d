"""
Unbalanced cylinder
===================

A cylinder whose centre of mass is off its axis, rolling without slipping on level ground
(`lagcomp.examples.unconstrained.unbalanced_cylinder`); its phase portrait from the energy integral.
"""

import numpy as np

import lagcomp as lc
from lagcomp import analysis as an
from lagcomp import examples, plots

cylinder = lc.compile(examples.get("unbalanced_cylinder"))
energy0 = cylinder.energy([np.pi], [0.0])   # the energy of the centre of mass at the top, at rest
portrait = an.phase_portrait(cylinder, np.linspace(0.2, 1.6, 6) * energy0, (-np.pi, np.pi), periodic=True)
fig = plots.plot_phase_portrait(portrait)
