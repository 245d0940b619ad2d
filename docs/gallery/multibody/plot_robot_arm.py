"""
Robot arm from URDF, animated
=============================

A five-joint arm read from the URDF file shipped with lagcomp (`lagcomp.examples.trees.ARM5_URDF`: a turntable,
shoulder, elbow and wrist pitch joints, a wrist roll, a tool fixed to the hand) by `lagcomp.from_urdf`, and
compiled through the recursive multibody path: the articulated-body algorithm as straight-line code, not an
expanded T.  Released from a bent posture with the turntable and the wrist spinning, it falls under gravity
against the viscous damping of its joints (the URDF's ``<dynamics damping>``), and the energy it loses is what
the dampers took.

The links draw themselves: the tree's ``geometry`` kernel (`lagcomp.codegen.tree_geometry`, built the first time
the animation asks) gives each link frame's origin and axes, and a rod joins each link to its children.
"""

import numpy as np

import lagcomp as lc
from lagcomp import plots
from lagcomp.examples.trees import ARM5_URDF

tree = lc.from_urdf(ARM5_URDF)
print(tree.coordinate_names)
arm = lc.compile(tree)

# %%
# Three seconds from rest in a bent posture, with the turntable and the wrist roll turning.

sol = arm.simulate((0, 3), q0=[0.0, 0.9, 0.6, 0.4, 0.0], qd0=[1.5, 0.0, 0.0, 0.0, 3.0],
                   t_eval=np.linspace(0, 3, 151), rtol=1e-10, atol=1e-10)
fig = plots.plot_coordinates(sol)

# %%
# The energy T + V only decreases: each damper takes c q̇² from it.

energy = sol.energy      # T + V at the saved rows
print(f"T + V: {energy[0]:.4f} J at t = 0, {energy[-1]:.4f} J at t = 3 s; "
      f"largest rise between saved rows {max(np.diff(energy).max(), 0.0):.1e} J")

# %%
# The animation: each link's origin (its joint), its axes x, y, z (red, green, blue), rods from the base to the
# hand, and the path of the hand.

anim = lc.animate(sol, trace=["hand"], axes_length=0.06, fps=10, speed=1.0, size=(4.5, 4.5), dpi=60)
