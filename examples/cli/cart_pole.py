"""A cart-pole pushed by a force F(t) read at run time: the model file the command line's help runs.

Cart of mass M at x on a horizontal rail, a point mass m at the end of a massless pole of length l,
θ measured from the upward vertical (θ = 0 balanced), gravity g down, a force along the rail on the cart
(the input F, or the parameter F0 in the variant without inputs):

    T = ½ (M + m) ẋ² + m l ẋ θ̇ cos θ + ½ m l² θ̇²,   V = m g l cos θ,   Q = (F, 0).

    lagcomp run examples/cli/cart_pole.py --input F=examples/cli/push.csv --out run.csv
    lagcomp animate examples/cli/cart_pole.py --config examples/cli/cart_pole.toml -o cart_pole.gif
    lagcomp stability examples/cli/cart_pole.py:pendulum_on_cart --arg pushed=0 --param l --range 0.2 1 --q 0 0
"""

import sympy as sp

import lagcomp as lc


def pendulum_on_cart(pushed: int = 1) -> lc.System:
    """The cart-pole; `pushed` 1: the force is the run-time input F, 0: a constant parameter F0."""
    x, theta = lc.coordinates("x theta")
    M, m, l, g, F0 = sp.symbols("M m l g F0", positive=True)
    force = lc.Input("F") if pushed else F0
    return lc.System(
        [x, theta],
        bodies=[lc.Particle(M, (x, 0, 0), name="cart"),
                lc.Particle(m, (x + l * sp.sin(theta), l * sp.cos(theta), 0), name="bob")],
        V=m * g * l * sp.cos(theta),
        forces=[force, 0],
        name="cart_pole" if pushed else "cart_pole_constant_force",
        description="Cart-pole pushed along its rail by F, pole from the upward vertical.",
        defaults={"M": 1.0, "m": 0.1, "l": 0.5, "g": 9.81, **({} if pushed else {"F0": 0.0})},
        q0=(0.0, 0.1),
        t_end=2.0,
    )


cart_pole = pendulum_on_cart()
