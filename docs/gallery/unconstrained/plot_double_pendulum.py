"""
Double pendulum, animated
=========================

Two point masses on massless rods, the second hanging from the first
(`lagcomp.examples.unconstrained.double_pendulum`): chaotic from this start.  The animation
names the points to draw as expressions of the coordinates and parameters.
"""

import numpy as np
import sympy as sp

import lagcomp as lc
from lagcomp import examples, plots

model = lc.compile(examples.get("double_pendulum"))
sol = model.simulate((0, 5), q0=[2.0, 1.0], t_eval=np.linspace(0, 5, 251), rtol=1e-10, atol=1e-10)
fig = plots.plot_coordinates(sol, velocities=True)

# %%
# The bobs as expressions of the coordinates and of the parameters ``l1``, ``l2``, valued from the run:

th1, th2 = lc.coordinates("theta1 theta2")
l1, l2 = sp.symbols("l1 l2")
bob1 = (l1 * sp.sin(th1), -l1 * sp.cos(th1))
bob2 = (bob1[0] + l2 * sp.sin(th2), bob1[1] - l2 * sp.cos(th2))
anim = lc.animate(sol, {"bob1": bob1, "bob2": bob2}, links=[("origin", "bob1"), ("bob1", "bob2")],
                  trace=["bob2"], fps=10, speed=1.0, size=(4, 4), dpi=60)
