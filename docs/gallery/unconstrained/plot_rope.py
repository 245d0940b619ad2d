"""
Rope slipping off a table
=========================

A rope of mass M and length L slips off the edge of a frictionless table
(`lagcomp.examples.unconstrained.rope`); x is the length hanging.  From x₀ at rest,
x(t) = x₀ cosh(√(g/L) t).
"""

import lagcomp as lc
from lagcomp import examples, plots

model = lc.compile(examples.get("rope"))
sol = model.simulate((0, 0.6))
fig = plots.plot_run(sol)
