"""
Kapitza's pendulum
==================

A pendulum whose support vibrates vertically as A cos Ωt (`lagcomp.examples.unconstrained.driven_pendulum`):
fast enough (A Ω > √(2 g l)), it stays upright.  Released near the top, with and without the vibration.
"""

import numpy as np

import lagcomp as lc
from lagcomp import examples

from matplotlib.figure import Figure

model = lc.compile(examples.get("driven_pendulum"))
t = np.linspace(0, 3, 601)
fig = Figure(figsize=(7, 4))
ax = fig.add_subplot()
for A in (0.0, 0.02):
    sol = model.simulate((0, 3), q0=[np.pi - 0.1], params={"A": A}, t_eval=t, rtol=1e-10, atol=1e-10)
    ax.plot(sol.t, sol.q[:, 0], label=f"A = {A}")
ax.axhline(np.pi, color="k", lw=0.5)
ax.set_xlabel("t")
ax.set_ylabel("θ")
ax.legend()
