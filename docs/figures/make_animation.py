"""Draw docs/figures/double_pendulum.gif (three seconds of the double pendulum, 15 frames per second) and
docs/figures/symmetric_top.gif (the top's first 1.2 s, played 5 times slower).

    PYTHONPATH=src python docs/figures/make_animation.py [docs/figures]

(needs matplotlib and pillow; about 40 s, most of it numba compiling the models once).
The bobs are the points of `lagcomp.examples.double_pendulum`'s docstring, written in its coordinates;
the top, built from a `lagcomp.RigidBody`, draws itself from its geometry kernel: its centre of mass on
a rod from the fixed point, its path, and its body axes (the spinning x and y, the symmetry axis z).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import sympy as sp

import lagcomp as lc
from lagcomp import examples


def main(directory: Path) -> None:
    directory.mkdir(parents=True, exist_ok=True)
    model = lc.compile(examples.get("double_pendulum"))
    sol = model.simulate((0, 3), t_eval=np.linspace(0, 3, 46))  # the frames' times: no interpolation
    th1, th2 = lc.coordinates("theta1 theta2")
    l1, l2 = sp.symbols("l1 l2")
    bob1 = (l1 * sp.sin(th1), -l1 * sp.cos(th1))
    bob2 = (bob1[0] + l2 * sp.sin(th2), bob1[1] - l2 * sp.cos(th2))
    path = directory / "double_pendulum.gif"
    lc.animate(sol, {"bob1": bob1, "bob2": bob2}, links=[("origin", "bob1"), ("bob1", "bob2")], trace=["bob2"],
               fps=15, size=(4.0, 4.0), dpi=72, title="double pendulum", save=path)
    print(f"wrote {path} ({path.stat().st_size // 1024} KB)")
    top = lc.compile(examples.get("symmetric_top")).simulate((0, 1.2), t_eval=np.linspace(0, 1.2, 91))
    path = directory / "symmetric_top.gif"
    lc.animate(top, links=[("origin", "top")], trace=["top"], fps=15, speed=0.2, size=(4.0, 4.0), dpi=72,
               title="symmetric top", save=path)
    print(f"wrote {path} ({path.stat().st_size // 1024} KB)")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent)
