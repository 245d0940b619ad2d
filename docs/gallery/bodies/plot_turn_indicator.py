"""
Turn indicator
==============

A gyroscope in a gimbal inside an aircraft turning about the vertical
(`lagcomp.examples.bodies.turn_indicator`): a rigid body in a `lagcomp.MovingFrame`.  The gimbal
settles at the tilt that reads the rate of turn.
"""

import lagcomp as lc
from lagcomp import examples, plots

model = lc.compile(examples.get("turn_indicator"))
sol = model.simulate((0, 10))
fig = plots.plot_coordinates(sol)
