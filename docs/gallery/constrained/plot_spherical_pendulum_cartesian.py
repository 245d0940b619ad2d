"""
Spherical pendulum, two ways
============================

The same bob in Cartesian coordinates with the rod as a holonomic constraint
(`lagcomp.examples.constrained.spherical_pendulum_cartesian`) and in spherical angles
(`lagcomp.examples.constrained.spherical_pendulum`).  The multiplier λ gives the rod's tension; the two
runs trace the same motion.
"""

import numpy as np

import lagcomp as lc
from lagcomp import examples

from matplotlib.figure import Figure

t = np.linspace(0, 5, 501)
cartesian = lc.compile(examples.get("spherical_pendulum_cartesian")).simulate((0, 5), t_eval=t, rtol=1e-11, atol=1e-11)
angles = lc.compile(examples.get("spherical_pendulum")).simulate((0, 5), t_eval=t, rtol=1e-11, atol=1e-11)
theta = angles.q[:, 0]
print("largest |z − (−cos θ)|:", np.max(np.abs(cartesian.q[:, 2] + np.cos(theta))))
fig = Figure(figsize=(7, 4))
ax = fig.add_subplot()
ax.plot(t, cartesian.q[:, 2], label="z (Cartesian)")
ax.plot(t, -np.cos(theta), "--", label="−cos θ (angles)")
ax.plot(t, list(cartesian.reactions.values())[0], label="λ (rod)")
ax.set_xlabel("t")
ax.legend()
