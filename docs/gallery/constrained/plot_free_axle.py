"""
Free axle on an incline
=======================

An axle with two independently turning wheels rolling without slipping on an inclined plane
(`lagcomp.examples.constrained.free_axle`): three nonholonomic constraints, three multipliers.
"""

import lagcomp as lc
from lagcomp import examples

from matplotlib.figure import Figure

model = lc.compile(examples.get("free_axle"))
sol = model.simulate((0, 6))
fig = Figure(figsize=(5, 5))
ax = fig.add_subplot()
ax.plot(sol.q[:, 0], sol.q[:, 1])
ax.set_xlabel("X")
ax.set_ylabel("Y")
ax.set_title("the axle's centre")
print("constraint residual:", sol.constraint_residual)
