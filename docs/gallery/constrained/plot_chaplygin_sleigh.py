"""
Chaplygin's sleigh
==================

A rigid body on a plane held by a knife edge that cannot slide sideways
(`lagcomp.examples.constrained.chaplygin_sleigh`): a nonholonomic constraint.
"""

import lagcomp as lc
from lagcomp import examples

from matplotlib.figure import Figure

model = lc.compile(examples.get("chaplygin_sleigh"))
sol = model.simulate((0, 20))
fig = Figure(figsize=(5, 5))
ax = fig.add_subplot()
ax.plot(sol.q[:, 0], sol.q[:, 1])
ax.set_aspect("equal")
ax.set_xlabel("x")
ax.set_ylabel("y")
