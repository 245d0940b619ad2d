"""
Rope with friction on the table
===============================

The rope of the previous example with Coulomb friction, coefficient f, on the part still lying
on the table (`lagcomp.examples.unconstrained.rope_friction`).  Three values of f, swept in one
compiled loop.
"""

import numpy as np

import lagcomp as lc
from lagcomp import examples, plots

model = lc.compile(examples.get("rope_friction"))
sweep = model.sweep((0, 0.55), {"f": np.linspace(0.0, 0.3, 4)}, output=("dense",),
                    t_eval=np.linspace(0, 0.55, 56))
fig = plots.plot_sweep(sweep, sweep.final[:, 0], label="x(0.55)")
