"""
LQR: balancing a cart-pole
==========================

A cart-pole built from two bodies (the cart, and the bob on its pole) with a force F on the cart as an input
(``lc.Input("F")``), linearized about the upright position into a state-space model ẋ = A x + B F,
z = C x (``lagcomp.analysis.linearize(..., inputs=..., outputs=...)``: the outputs are the cart's position and
the bob's, a point of a body, whose row of C is the derivative of its position).  python-control
(``pip install 'lagcomp[control]'``) computes the LQR gains from ``StateSpace.to_control()``; the nonlinear
model is then simulated with F = −K x as a numba function input, against the pendulum left alone, and the
bob's position is compared with the linear closed loop's prediction C x(t).  The energy balance tells where
the controller's work went: h(t) − h(0) is the work of F, to the run's tolerance.
"""

import control
import matplotlib.pyplot as plt
import numba
import numpy as np
import sympy as sp

import lagcomp as lc
from lagcomp import analysis as an

x, th = lc.coordinates("x th")
M, m, l, g = sp.symbols("M m l g", positive=True)
cart = lc.Particle(M, (x, 0, 0), name="cart")
bob = lc.Particle(m, (x + l * sp.sin(th), l * sp.cos(th), 0), name="bob")
cart_pole = lc.compile(lc.System([x, th], bodies=[cart, bob], loads=[lc.Gravity((0, -g, 0))],
                                 forces=[lc.Input("F"), 0], name="gallery_cart_pole",
                                 defaults={"M": 1.0, "m": 0.1, "l": 0.5, "g": 9.81}))

space = an.linearize(cart_pole, [0.0, 0.0], inputs={"F": 0.0}, outputs=["x", "bob.x"]).state_space()
print(space, "\nC =", space.C)
Q, R = np.diag([1.0, 10.0, 1.0, 1.0]), np.array([[0.1]])
gains, _, poles = control.lqr(space.to_control(), Q, R)
print("K =", gains, "\nclosed-loop poles", poles)
k0, k1, k2, k3 = (float(k) for k in np.asarray(gains)[0])


@numba.njit
def lqr(t, y, p):
    return -(k0 * y[0] + k1 * y[1] + k2 * y[2] + k3 * y[3])


span, start = (0.0, 8.0), ([0.1, 0.25], [0.0, 0.0])
times = np.linspace(*span, 801)
closed = cart_pole.simulate(span, *start, inputs={"F": lqr}, t_eval=times)
opened = cart_pole.simulate(span, *start, inputs={"F": 0.0}, t_eval=times)
balance = closed.energy_balance()
print(balance)

# the linear closed loop ẋ = (A − B K) x, z = C x, from the same start
loop = control.ss(space.A - space.B @ np.asarray(gains), space.B, space.C, space.D)
predicted = control.initial_response(loop, times, np.concatenate(start)).outputs
bob_x = closed.q[:, 0] + 0.5 * np.sin(closed.q[:, 1])

fig, (top, middle, bottom) = plt.subplots(3, 1, sharex=True, figsize=(7, 7), layout="constrained")
top.plot(opened.t, opened.q[:, 1], label="θ, no control")
top.plot(closed.t, closed.q[:, 1], label="θ, LQR")
top.set_ylim(-1, 1)
top.legend(loc="lower right")
middle.plot(closed.t, bob_x, label="bob's x, nonlinear model")
middle.plot(times, predicted[1], "--", label="C x(t), linear closed loop")
middle.plot(times, predicted[0], ":", label="cart's x, linear closed loop")
middle.legend(loc="upper right")
bottom.plot(balance.t, balance.change, label="h(t) − h(0)")
bottom.plot(balance.t, balance.work["forces"], "--", label="work of F")
bottom.set_xlabel("t")
bottom.legend()
