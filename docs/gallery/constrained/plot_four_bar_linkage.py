"""
Four-bar linkage as a DAE
=========================

Crank, coupler and rocker closing a loop with the ground (`lagcomp.examples.constrained.four_bar_linkage`):
two holonomic constraints.  ``method="radau"`` integrates the index-2 DAE, the constraints solved with the
motion at every step: no projection, no drift.
"""

import lagcomp as lc
from lagcomp import examples, plots

model = lc.compile(examples.get("four_bar_linkage"))
sol = model.simulate((0, 3), method="radau", rtol=1e-10, atol=1e-10)
print("constraint residual without projection:", sol.constraint_residual)
fig = plots.plot_coordinates(sol)
