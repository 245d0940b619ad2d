"""
Arenstorf orbit
===============

The planar circular restricted three-body problem in the frame rotating with the primaries
(`lagcomp.examples.gravitation.restricted_three_body`): from its default start, Arenstorf's periodic
orbit, closed after one period.
"""

import lagcomp as lc
from lagcomp import examples

from matplotlib.figure import Figure

system = examples.get("restricted_three_body")
model = lc.compile(system)
sol = model.simulate((0, system.t_end), rtol=1e-12, atol=1e-12)
print("distance from the start after one period:", abs(sol.q[-1] - sol.q[0]).max())
fig = Figure(figsize=(5, 5))
ax = fig.add_subplot()
ax.plot(sol.q[:, 0], sol.q[:, 1])
ax.set_aspect("equal")
ax.set_xlabel("x")
ax.set_ylabel("y")
