"""
Chain of n pendulums
====================

A planar chain of n point masses on massless rods (`lagcomp.examples.unconstrained.n_link_pendulum`);
``n`` is an argument of the factory and names the System (``n_link_pendulum_5``).
"""

import lagcomp as lc
from lagcomp import examples, plots

model = lc.compile(examples.get("n_link_pendulum", n=5))
print(model.parameters)
sol = model.simulate((0, 5), q0=[1.0, 0.8, 0.6, 0.4, 0.2], rtol=1e-10, atol=1e-10)
fig = plots.plot_run(sol)
