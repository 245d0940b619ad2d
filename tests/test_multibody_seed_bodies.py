"""The seed's bodies examples that are kinematic trees, rebuilt as `lc.Tree` and held to the Lagrangian path's
`lagcomp.examples.bodies` model (issue 39's acceptance: 1e-12).

Of the seed's bodies, the heavy symmetric top is a tree: a fixed point O and three revolute joints about z, x, z
(precession ψ, nutation θ, spin φ; the first two links massless), the top the third link with its centre of
mass on its axis at l and moments I1, I1, I3. The others are not: the turn indicator and the driven support are
moved by imposed motions (a turning frame, a motor's rate), Compton's disc and the wheel jack roll
(nonholonomic).
"""

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp.examples import bodies

PARAMS = {"M": 0.5, "l": 0.05, "g": 9.81, "I1": 5e-4, "I3": 8e-4}


def _top_as_a_tree() -> lc.Tree:
    M, l, g, I1, I3 = sp.symbols("M l g I1 I3")
    links = [lc.Link("precession", lc.Revolute("psi", axis="z"), mass=0),
             lc.Link("nutation", lc.Revolute("theta", axis="x"), parent="precession", mass=0),
             lc.Link("top", lc.Revolute("phi", axis="z"), parent="nutation", mass=M, com=(0, 0, l),
                     inertia=(I1, I1, I3))]
    return lc.Tree(links, gravity=(0, 0, -g), name="symmetric_top_tree", defaults=PARAMS)


@pytest.fixture(scope="module")
def tops(cache_dir):
    return lc.compile(_top_as_a_tree(), cache_dir=cache_dir), lc.compile(bodies.symmetric_top(), cache_dir=cache_dir)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(angles=st.tuples(st.floats(-3, 3), st.floats(0.1, 3.0), st.floats(-3, 3)),
       rates=st.tuples(st.floats(-20, 20), st.floats(-20, 20), st.floats(-200, 200)))
def test_the_symmetric_top_as_a_tree_moves_as_the_seeds_top(tops, angles, rates):
    """q̈ of the tree (articulated-body algorithm) equals the Lagrangian path's (T's Hessian solved) to 1e-12
    normwise, at states away from θ = 0 (where Euler angles are singular), and so do the energies."""
    tree, seed = tops
    y = np.array([*angles, *rates])
    found = [model.rhs(0.0, y, params=PARAMS) for model in (tree, seed)]
    assert np.abs(found[0] - found[1]).max() <= 1e-12 * np.abs(found[1]).max()
    energies = [model.energy(y[:3], y[3:], params=PARAMS) for model in (tree, seed)]
    assert abs(energies[0] - energies[1]) <= 1e-12 * abs(energies[1])
