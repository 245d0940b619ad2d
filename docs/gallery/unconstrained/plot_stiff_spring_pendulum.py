"""
Stiff spring pendulum
=====================

A bob on a stiff, damped spring (`lagcomp.examples.unconstrained.stiff_spring_pendulum`): the spring's
fast, damped motion makes the problem stiff.  ``method="radau"`` takes large steps where DOP853 is held
at its stability limit.
"""

import lagcomp as lc
from lagcomp import examples, plots

model = lc.compile(examples.get("stiff_spring_pendulum"))
stiff = model.simulate((0, 10), method="radau", rtol=1e-6, atol=1e-6)
print("radau:", stiff.nsteps, "steps,", stiff.nfev, "f-evaluations")
fig = plots.plot_coordinates(stiff)
