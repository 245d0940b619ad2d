"""
Hénon–Heiles: a Poincaré section
================================

A star in an axisymmetric galactic potential (`lagcomp.examples.unconstrained.henon_heiles`).  Its
``section`` event (x = 0 crossed upwards) gives a Poincaré section; `lagcomp.analysis.on_energy_surface`
puts every start on one energy.
"""

import numpy as np

import lagcomp as lc
from lagcomp import analysis as an
from lagcomp import examples, plots

model = lc.compile(examples.get("henon_heiles"))
ys = np.linspace(-0.3, 0.5, 12)
starts = np.zeros((len(ys), 4))                      # (x, y, x_dot, y_dot): x = 0, y_dot = 0
starts[:, 1] = ys
states, valid = an.on_energy_surface(model, 1 / 8, starts, "x_dot")
states = states[valid]
section = an.poincare_section(model, (0, 300), states)
fig = plots.plot_poincare(section, "y", "y_dot", size=2.0)
