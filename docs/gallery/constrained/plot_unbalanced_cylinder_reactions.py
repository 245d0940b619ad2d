"""
Reactions on the unbalanced cylinder
====================================

The unbalanced cylinder with both rolling constraints released (`lagcomp.examples.constrained.unbalanced_cylinder_reactions`):
the multipliers are the ground's vertical push F_v and friction F_h.
"""

import lagcomp as lc
from lagcomp import examples

from matplotlib.figure import Figure

model = lc.compile(examples.get("unbalanced_cylinder_reactions"))
sol = model.simulate((0, 10))
fig = Figure(figsize=(7, 4))
ax = fig.add_subplot()
for name, values in sol.reactions.items():
    ax.plot(sol.t, values, label=name)
ax.set_xlabel("t")
ax.set_ylabel("multiplier")
ax.legend()
