"""
Heavy symmetric top, animated
=============================

A `lagcomp.RigidBody` in Euler angles with a fixed point (`lagcomp.examples.bodies.symmetric_top`): the
body draws itself, its axes evaluated along the run by the ``geometry`` kernel emitted with the model.
"""

import numpy as np

import lagcomp as lc
from lagcomp import examples, plots

top = lc.compile(examples.get("symmetric_top"))
sol = top.simulate((0, 0.6), t_eval=np.linspace(0, 0.6, 61))
fig = plots.plot_coordinates(sol)
anim = lc.animate(sol, links=[("origin", "top")], trace=["top"], fps=10, speed=0.2, size=(4, 4), dpi=60)
