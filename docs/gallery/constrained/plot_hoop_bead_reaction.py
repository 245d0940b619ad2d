"""
The hoop's push on the bead
===========================

The bead on the turning hoop with the hoop's angle φ released and imposed again by a constraint
(`lagcomp.examples.constrained.hoop_bead_reaction`): the constraint's multiplier λ is the torque the
motor must give to keep the hoop turning as prescribed.
"""

import lagcomp as lc
from lagcomp import examples

from matplotlib.figure import Figure

model = lc.compile(examples.get("hoop_bead_reaction"))
sol = model.simulate((0, 10))
fig = Figure(figsize=(7, 4))
ax = fig.add_subplot()
for name, values in sol.reactions.items():
    ax.plot(sol.t, values, label=f"λ {name}")
ax.set_xlabel("t")
ax.legend()
print("largest constraint residual:", sol.constraint_residual)
