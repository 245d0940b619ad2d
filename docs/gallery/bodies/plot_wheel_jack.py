"""
Wheel jack: statics by virtual work
===================================

A crank turns a screw that closes a lozenge and lifts a load (`lagcomp.examples.bodies.wheel_jack`).
`lagcomp.analysis.balance` solves the virtual-work balance for the load P the effort F holds.
"""

import numpy as np
import sympy as sp

from lagcomp import analysis as an
from lagcomp import examples

from matplotlib.figure import Figure

jack = examples.get("wheel_jack")
(solution,) = an.balance(jack, "P")
P = sp.Symbol("P", positive=True)
ratio = [value for key, value in solution.items() if str(key) == "P"][0]
print("P =", ratio)
F, a, h = sp.symbols("F a h", positive=True)
theta = list(ratio.free_symbols - {F, a, h})
curve = sp.lambdify(theta, (ratio / F).subs({a: 0.2, h: 0.002}))
angles = np.linspace(0.1, 1.4, 100)
fig = Figure(figsize=(6, 4))
ax = fig.add_subplot()
ax.semilogy(angles, curve(angles))
ax.set_xlabel("θ")
ax.set_ylabel("P / F")
