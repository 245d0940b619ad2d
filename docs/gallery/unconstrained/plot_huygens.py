"""
Huygens' isochronous pendulum
=============================

A bead sliding on a cycloid (`lagcomp.examples.unconstrained.huygens`): its period does not depend
on the amplitude.  Three amplitudes, one sweep with dense output: the three runs cross zero together.
"""

import numpy as np

import lagcomp as lc
from lagcomp import examples

from matplotlib.figure import Figure

model = lc.compile(examples.get("huygens"))
t = np.linspace(0, 10, 401)
sweep = model.sweep((0, 10), {"theta": [0.5, 1.5, 2.5]}, output=("dense",), t_eval=t, rtol=1e-10, atol=1e-10)
fig = Figure(figsize=(7, 4))
ax = fig.add_subplot()
for amplitude, run in zip((0.5, 1.5, 2.5), sweep.dense):
    ax.plot(sweep.t_dense, run[:, 0], label=f"θ(0) = {amplitude}")
ax.axhline(0, color="k", lw=0.5)
ax.set_xlabel("t")
ax.set_ylabel("θ")
ax.legend()
