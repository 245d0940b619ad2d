"""
Kapitza's pendulum in its support's frame
=========================================

The driven pendulum written in the frame of its vibrating support
(`lagcomp.examples.bodies.driven_pendulum_support`): lagcomp adds the driving inertial force.  It moves
exactly as the inertial-frame model.
"""

import numpy as np

import lagcomp as lc
from lagcomp import examples, plots

t = np.linspace(0, 5, 201)
in_frame = lc.compile(examples.get("driven_pendulum_support")).simulate((0, 5), t_eval=t, rtol=1e-11, atol=1e-11)
inertial = lc.compile(examples.get("driven_pendulum")).simulate((0, 5), t_eval=t, rtol=1e-11, atol=1e-11)
print("largest difference in θ:", np.max(np.abs(in_frame.q - inertial.q)))
fig = plots.plot_coordinates(in_frame)
