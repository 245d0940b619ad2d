"""
Huygens' isochronous pendulum
=============================

A bead sliding on a cycloid (`lagcomp.examples.unconstrained.huygens`): its period does not depend
on the amplitude.  Three amplitudes, one sweep; the crossings of θ = 0 give the half periods.
"""

import numpy as np

import lagcomp as lc
from lagcomp import examples, plots

model = lc.compile(examples.get("huygens"))
sweep = model.sweep((0, 10), {"theta": [0.5, 1.5, 2.5]}, output=("dense",), t_eval=np.linspace(0, 10, 401),
                    rtol=1e-10, atol=1e-10)
fig = plots.plot_sweep(sweep, sweep.final[:, 0], label="θ(10)")
print("θ(10) for the three amplitudes:", sweep.final[:, 0])
