"""A user's names cannot change a tree model's answer (DESIGN.md, "Two contracts of the emitted code: Names"), as
tests/test_names.py checks it for Systems.

A tree lets the user name its links, its joints' coordinates and its parameters (the symbols of its description).
The emitted modules of a tree have names of their own besides a System's: the recursions' locals ``_b000012``, the
outlined steps ``_<kernel>_step<k>`` and their arguments ``_a<k>`` and locals ``_t<k>``, the ball joints' shadow
events ``<link>_shadow``.  Hypothesis draws the names from every identifier the emitted modules of a probe tree
use (its eager module and companions), Python's builtins and keywords and test_names' `COMMON`; the tree built
under them must compile and compute the same rhs (and M, F, energy and Jacobians) as under plain names.
"""

from __future__ import annotations

import builtins
import keyword
import re

import multibody_models as mm
import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from random_systems import python_kernels
from test_names import COMMON, _identifiers

import lagcomp as lc

#: Links, coordinates (a revolute root, a universal joint, a ball joint) and parameters of `probe_tree`.
LINKS = 3
COORDINATES = 6
PARAMETERS = 7
PLAIN = (tuple(f"link{i}" for i in range(LINKS)), tuple(f"c{i}" for i in range(COORDINATES)),
         tuple(f"p{i}" for i in range(PARAMETERS)))


def probe_tree(links, coordinates, parameters) -> lc.Tree:
    """Three links under the given names: a revolute root with a spring, a universal joint, a ball joint with a
    damper (its shadow event is named after its link); every parameter enters the dynamics."""
    m0, m1, m2, k, length, g, c = (sp.Symbol(name, positive=True) for name in parameters)
    return lc.Tree([
        lc.Link(links[0], lc.Revolute(coordinates[0], axis="z", stiffness=k, rest=0.1), mass=m0, com=(length, 0, 0),
                inertia=(m0, m0, m0)),
        lc.Link(links[1], lc.Universal(coordinates[1:3], origin=(length, 0, 0)), parent=links[0], mass=m1,
                com=(0, 0, -length), inertia=(1, 2, 3)),
        lc.Link(links[2], lc.Spherical(coordinates[3:6], origin=(0, 0, -2 * length), damping=c), parent=links[1],
                mass=m2, com=(0.1, 0.2, -0.3), inertia=(0.3, 0.4, 0.5)),
    ], gravity=(0, -g, 0), name="names_tree")


VALUES = (1.5, 0.75, 2.0, 3.0, 0.5, 9.75, 0.25)
STATE = np.array([0.3, -0.2, 0.4, 0.1, -0.2, 0.3, 0.5, -0.25, 0.75, 0.125, -0.5, 0.25])


def _outputs(model: lc.Model, names: tuple, kernels: dict | None = None, jacobian=None) -> dict:
    """rhs, M, F, energy at `STATE`, the parameters `VALUES` given by `names` (in `probe_tree`'s order), with the
    model's numba kernels or the plain-Python `kernels`; and ∂f/∂y with the kernel `jacobian` if one is given."""
    p = model.parameter_vector(dict(zip(names, VALUES)))
    call = (lambda name: kernels[name]) if kernels is not None else (lambda name: getattr(model.kernels, name))
    n = model.n
    f, M, F = np.empty(2 * n), np.empty((n, n)), np.empty(n)
    assert call("rhs")(0.0, STATE, p, f) == 0
    call("mass_matrix")(0.0, STATE, p, M)
    call("forcing")(0.0, STATE, p, F)
    found = {"rhs": f, "mass_matrix": M, "forcing": F, "energy": np.array(call("energy")(0.0, STATE, p))}
    if jacobian is not None:
        J = found["rhs_jacobian"] = np.empty((2 * n, 2 * n))
        assert jacobian(0.0, STATE, p, J) == 0
    return found


def _python_kernels(model: lc.Model, kind: str = "dynamics") -> dict:
    """The eager module and the companion of the on-demand `kind` (M and F: "dynamics") as plain Python (numba
    would compile each drawn tree)."""
    companion = model.on_demand_entry(kind).path.read_text(encoding="utf-8")
    return python_kernels(model.source_path.read_text(encoding="utf-8"), companion)


@pytest.fixture(scope="module")
def plain(cache_dir) -> tuple[lc.Model, dict]:
    """The probe tree under plain names and its outputs: rhs, M, F and the energy by numba, ∂f/∂y as plain Python
    (the reference the risky names' numba Jacobian must meet; numba spends ~25 s of CPU on this kernel)."""
    model = lc.compile(probe_tree(*PLAIN), cache_dir=cache_dir)
    return model, _outputs(model, PLAIN[2], jacobian=_python_kernels(model, "jacobians")["rhs_jacobian"])


@pytest.fixture(scope="module")
def tree_names(plain, cache_dir) -> list[str]:
    """Every identifier of the modules (eager and companions) of the probe tree and of a 4-link planar chain (whose
    identical links' steps are emitted as helpers), builtins, keywords, `COMMON`."""
    found = set(dir(builtins)) | set(keyword.kwlist) | set(COMMON)
    for model in (plain[0], lc.compile(mm.planar_chain(4), cache_dir=cache_dir)):   # (emitted: numba compiles
        for source in [model.source_path.read_text(encoding="utf-8"),        # nothing here)
                       *(entry.path.read_text(encoding="utf-8") for entry in model.on_demand_entries.values())]:
            found |= _identifiers(source)
    assert {"_b000000", "_a0", "_t0"} <= found and any(re.fullmatch(r"_rhs_step\d+", s) for s in found)
    return sorted(name for name in found if name.isidentifier() and name != "t")   # (t: lagcomp's time)


def _agree(got: dict, want: dict) -> None:
    """Each output within 4 ulps of the largest entry of its plain-named counterpart: the names may reorder a sum."""
    for name, value in want.items():
        scale = np.spacing(np.max(np.abs(value)))
        assert np.max(np.abs(got[name] - value)) <= 4 * scale, name


def test_a_tree_named_with_its_own_emitted_names_compiles_and_agrees(plain, tree_names, cache_dir):
    """Links, coordinates and parameters named like the kernels' own locals, helpers, builtins and modules (np,
    math, range, ...), compiled by numba: rhs, M, F, the energy and the Jacobian those of the plain names."""
    risky = [name for name in ("_b000001", "_rhs_step0", "_a0", "_t0", "np", "range", "out", "y", "p", "t_", "k",
                               "lambda_", "math", "njit", "q_c0", "p_p0", "_ydot", "status")
             if name in tree_names or name in COMMON]
    pool = risky + [name for name in tree_names if name not in risky]
    names = (tuple(pool[:LINKS]), tuple(pool[LINKS:LINKS + COORDINATES]),
             tuple(pool[LINKS + COORDINATES:LINKS + COORDINATES + PARAMETERS]))
    model = lc.compile(probe_tree(*names), cache_dir=cache_dir)
    _agree(_outputs(model, names[2], jacobian=model.kernels.rhs_jacobian), plain[1])


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                  HealthCheck.too_slow])
@given(data=st.data())
def test_names_drawn_from_the_emitted_ones(plain, tree_names, cache_dir, data):
    """Hypothesis draws the links', coordinates' and parameters' names (a link and a coordinate may share a name,
    so may a coordinate and a parameter); the kernels run as plain Python (the emitted eager module and the
    companion of M and F): the same outputs as under plain names."""
    identifiers = [name for name in tree_names if not keyword.iskeyword(name)]
    links = data.draw(st.lists(st.sampled_from(identifiers), min_size=LINKS, max_size=LINKS, unique=True))
    coordinates = data.draw(st.lists(st.sampled_from(identifiers), min_size=COORDINATES, max_size=COORDINATES,
                                     unique=True))
    parameters = data.draw(st.lists(st.sampled_from(tree_names), min_size=PARAMETERS, max_size=PARAMETERS,
                                    unique=True))
    names = (tuple(links), tuple(coordinates), tuple(parameters))
    model = lc.compile(probe_tree(*names), cache_dir=cache_dir)
    want = {name: value for name, value in plain[1].items() if name != "rhs_jacobian"}
    _agree(_outputs(model, names[2], _python_kernels(model)), want)


@pytest.mark.parametrize("names, culprit", [
    ((("a", "a", "b"), PLAIN[1], PLAIN[2]), "link name 'a'"),            # two links of one name
    ((("a", "b c", "d"), PLAIN[1], PLAIN[2]), "link name 'b c'"),        # not an identifier
    ((PLAIN[0], ("x", "y", "x", "u", "v", "w"), PLAIN[2]), "['x']"),     # one coordinate, two joints
    ((PLAIN[0], ("x", "y", "z", "u", "v", "1w"), PLAIN[2]), "'1w'"),    # not an identifier
    ((PLAIN[0], PLAIN[1], ("m0", "m1", "m2", "k", "l", "g", "t")), "symbol named t"),   # t is lagcomp's time
])
def test_clashing_or_invalid_names_are_refused(names, culprit):
    with pytest.raises(lc.ModelError, match=re.escape(culprit)):
        probe_tree(*names)


def test_two_parameters_of_one_name_are_refused():
    """``Symbol("m")`` and ``Symbol("m", positive=True)`` in one tree: values are passed by name, so a tree refuses
    them as a System does (docs/errors.md, same-name-symbols).  Before, the tree was built with the parameters
    ('m', 'm'), one value for both names."""
    loose, positive = sp.Symbol("m"), sp.Symbol("m", positive=True)
    with pytest.raises(lc.ModelError, match=re.escape("['m']")):
        lc.Tree([lc.Link("a", lc.Revolute("q"), mass=loose, com=(positive, 0, 0), inertia=(1, 1, 1))],
                gravity=(0, -9.8, 0))
