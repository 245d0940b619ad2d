"""
LQR: balancing a cart-pole
==========================

The cart-pole with a force F on the cart as an input (``lc.Input("F")``), linearized about the upright
position into a state-space model ẋ = A x + B F (``lagcomp.analysis.linearize(..., inputs=...)``); the LQR
gains from python-control when it is installed (scipy's Riccati solver otherwise), then the nonlinear model
simulated with F = −K x as a numba function input, against the pendulum left alone.  The energy balance
tells where the controller's work went: h(t) − h(0) is the work of F, to the run's tolerance.
"""

import matplotlib.pyplot as plt
import numba
import numpy as np
import sympy as sp
from scipy import linalg

import lagcomp as lc
from lagcomp import analysis as an

x, th = lc.coordinates("x th")
M, m, l, g = sp.symbols("M m l g", positive=True)
T = (M + m) * x.diff(lc.t) ** 2 / 2 + m * l * x.diff(lc.t) * th.diff(lc.t) * sp.cos(th) + m * l**2 * th.diff(lc.t) ** 2 / 2
cart_pole = lc.compile(lc.System([x, th], T=T, V=m * g * l * sp.cos(th), forces=[lc.Input("F"), 0],
                                 name="gallery_cart_pole", defaults={"M": 1.0, "m": 0.1, "l": 0.5, "g": 9.81}))

space = an.linearize(cart_pole, [0.0, 0.0], inputs={"F": 0.0}).state_space()
Q, R = np.diag([1.0, 10.0, 1.0, 1.0]), np.array([[0.1]])
try:
    import control

    gains = control.lqr(space.to_control(), Q, R)[0][0]
except ImportError:
    gains = linalg.solve(R, space.B.T @ linalg.solve_continuous_are(space.A, space.B, Q, R))[0]
k0, k1, k2, k3 = (float(k) for k in gains)


@numba.njit
def lqr(t, y, p):
    return -(k0 * y[0] + k1 * y[1] + k2 * y[2] + k3 * y[3])


span, start = (0.0, 8.0), ([0.1, 0.25], [0.0, 0.0])
closed = cart_pole.simulate(span, *start, inputs={"F": lqr}, t_eval=np.linspace(*span, 801))
opened = cart_pole.simulate(span, *start, inputs={"F": 0.0}, t_eval=np.linspace(*span, 801))
balance = closed.energy_balance()
print(balance)

fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7, 5), layout="constrained")
top.plot(opened.t, opened.q[:, 1], label="θ, no control")
top.plot(closed.t, closed.q[:, 1], label="θ, LQR")
top.plot(closed.t, closed.q[:, 0], label="x, LQR")
top.set_ylim(-1, 1)
top.legend(loc="lower right")
bottom.plot(balance.t, balance.change, label="h(t) − h(0)")
bottom.plot(balance.t, balance.work["forces"], "--", label="work of F")
bottom.set_xlabel("t")
bottom.legend()
