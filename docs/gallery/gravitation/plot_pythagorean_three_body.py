"""
Pythagorean three-body problem
==============================

Burrau's problem: masses 3, 4 and 5 released at rest at the corners of a 3-4-5 triangle
(`lagcomp.examples.gravitation.pythagorean_three_body`).  Close approaches; a tight tolerance keeps the
energy error small through them (DOP853 at a tight tolerance; ``method="taylor"`` does too).
"""

import lagcomp as lc
from lagcomp import examples

from matplotlib.figure import Figure

model = lc.compile(examples.get("pythagorean_three_body"))
sol = model.simulate((0, 20), rtol=1e-13, atol=1e-13)
print("largest energy error:", sol.energy_drift())
fig = Figure(figsize=(5, 5))
ax = fig.add_subplot()
for i in range(3):
    ax.plot(sol.q[:, 2 * i], sol.q[:, 2 * i + 1], lw=0.8, label=f"body {i + 1}")
ax.set_aspect("equal")
ax.legend()
