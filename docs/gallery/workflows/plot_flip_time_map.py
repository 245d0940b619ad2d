"""
Sweep: when does the double pendulum flip?
==========================================

A grid of release angles (θ1, θ2) at rest, each run stopped by a terminal event when either rod
passes the upright position.  One compiled sweep loop runs every trajectory, on every core;
the region energy forbids never flips.  (The full-resolution version is ``examples/double_pendulum_flip.py``.)
"""

import numpy as np
import sympy as sp

import lagcomp as lc
from lagcomp import examples, plots

base = examples.get("double_pendulum")
th1, th2 = base.coordinates
flip = [lc.Event("flip1", sp.cos(th1 / 2), terminal=True), lc.Event("flip2", sp.cos(th2 / 2), terminal=True)]
system = lc.System(list(base.coordinates), T=base.T, V=base.V, events=flip, name="double_pendulum_flip_docs",
                   defaults=base.defaults)
model = lc.compile(system)
grid = {"theta1": np.linspace(-3, 3, 41), "theta2": np.linspace(-3, 3, 41)}
sweep = model.sweep((0, 10), grid, q0=[0, 0], qd0=[0, 0], rtol=1e-8, atol=1e-8, workers=2)
fig = plots.plot_sweep(sweep, "t_final", label="time to flip (10: none)")
