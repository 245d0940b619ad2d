"""
Rolling disc
============

A thin disc rolling without slipping on a plane (`lagcomp.examples.constrained.rolling_disc`).  Its
upright rolling is stable above a critical spin: `lagcomp.analysis.stability_sweep` finds it,
ω² = g/(3r), without compiling the model.
"""

import numpy as np

from lagcomp import analysis as an
from lagcomp import examples, plots

disc = examples.get("rolling_disc")
cyclic = ("x", "y", "psi", "phi", "phi_dot")   # drift on straight rolling; nothing depends on them
sweep = an.stability_sweep(disc, "phi_dot", np.linspace(1, 12, 12), [0] * 5, drop=cyclic)
print(sweep.changes)
fig = plots.plot_stability(sweep)
