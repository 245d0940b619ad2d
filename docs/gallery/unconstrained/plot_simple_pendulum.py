"""
Simple pendulum
===============

A point mass m on a massless rod of length l in gravity g: the smallest bundled example
(`lagcomp.examples.unconstrained.simple_pendulum`).  Released at 2 rad, far from the
small-angle regime; the energy error of DOP853 at its default tolerance stays near 1e-10.
"""

import lagcomp as lc
from lagcomp import examples, plots

model = lc.compile(examples.get("simple_pendulum"))
sol = model.simulate((0, 10), q0=[2.0])
print(sol.message, "| largest energy error:", sol.energy_drift())
fig = plots.plot_run(sol)
