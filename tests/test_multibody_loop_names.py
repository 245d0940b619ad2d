"""A user's names cannot change the answer of a tree with closed loops (DESIGN.md, "Two contracts of the emitted
code: Names"), as tests/test_multibody_names.py checks it for trees without loops.

A tree with loops (`lc.Loop`) has kernels of its own: the augmented solve's (``rhs_and_reactions``, the constraint
residuals and matrix, `lagcomp.codegen.tree_constraints`) and its companions' (the Jacobians, the DAE and the
directional kernels of `lagcomp.codegen.tree_loop_companion`), with locals ``_kkt``, ``_acc<i>``, ``_mult<c>``,
``_w<i>``, ``_lam<c>``, ``_mu<c>``, ``_dy<j>``, ``_dp<j>``, ``_jac``, ``_direction`` and the Baumgarte gains
``_baumgarte_alpha``, ``_baumgarte_beta``.  Hypothesis names the links, coordinates, parameters and the loop of a
probe (a spatial four-bar: a crank, a coupler on a ball joint, a rocker, the coupler's end joined to the rocker's
by the loop) after every identifier the emitted modules of the plain-named probe use, Python's builtins and
keywords and test_names' `COMMON`; the tree built under them must compile and give the outputs of the plain names.
"""

from __future__ import annotations

import builtins
import keyword

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from random_systems import python_kernels
from test_names import COMMON, _identifiers

import lagcomp as lc

#: Links, coordinates (a revolute crank, a ball joint, a revolute rocker), parameters and the loop of `probe_tree`.
LINKS, COORDINATES, PARAMETERS = 3, 5, 7
PLAIN = (tuple(f"link{i}" for i in range(LINKS)), tuple(f"c{i}" for i in range(COORDINATES)),
         tuple(f"p{i}" for i in range(PARAMETERS)), "loop")


def probe_tree(links, coordinates, parameters, loop) -> lc.Tree:
    """The spatial four-bar under the given names: a crank with a spring, a coupler on a ball joint with a damper, a
    rocker, the coupler's far end held to the rocker's tip in x, y, z by `loop`; every parameter enters."""
    a, b, c, d, m, k, g = (sp.Symbol(name, positive=True) for name in parameters)
    return lc.Tree([
        lc.Link(links[0], lc.Revolute(coordinates[0], stiffness=k, rest=0.1), mass=m, com=(a / 2, 0, 0),
                inertia=(0.01, 0.02, 0.02)),
        lc.Link(links[1], lc.Spherical(coordinates[1:4], origin=(a, 0, 0), damping=k / 10), parent=links[0],
                mass=2 * m, com=(b / 2, 0, 0), inertia=(0.005, 0.04, 0.045)),
        lc.Link(links[2], lc.Revolute(coordinates[4], axis="x", origin=(d, 0, a)), mass=m, com=(0, c / 2, 0),
                inertia=(0.01, 0.004, 0.01)),
    ], gravity=(0, 0, -g), name="loop_names_tree",
        loops=[lc.Loop(loop, (links[1], (b, 0, 0)), (links[2], (0, c, 0)))])


VALUES = (0.2, 0.8, 0.45, 0.5, 0.75, 3.0, 9.75)
STATE = np.array([0.3, 0.1, -0.2, 0.3, 2.9, 0.5, -0.25, 0.75, 0.125, -0.5])
GAINS = (1.5, 2.5)
V, W = np.linspace(-1.0, 1.0, 2 * COORDINATES), np.linspace(0.5, -0.5, PARAMETERS)


def _outputs(model: lc.Model, names: tuple, kernels: dict | None = None) -> dict:
    """(q̇, q̈) and λ of the augmented solve, the constraint residuals and matrix, the energy, the Jacobians of f and
    λ, the DAE's residual and Jacobian and the directional derivative at `STATE`, the parameters `VALUES` given by
    `names`, with the model's numba kernels or the plain-Python `kernels`."""
    p = model.parameter_vector(dict(zip(names, VALUES)), baumgarte=GAINS)
    call = (lambda name: kernels[name]) if kernels is not None else (lambda name: getattr(model.kernels, name))
    n, k = model.n, model.k
    N, P = 2 * n, len(model.parameters)
    order = [names.index(name) for name in model.parameters]   # (the model's parameters sort by name)
    f, lam, residuals, matrix = np.empty(N), np.empty(k), np.empty(2 * k), np.empty((k, n + 1))
    J, R, ydot, direction = np.empty((N, N)), np.empty((k, N + P)), np.empty(N), np.empty(N)
    z = np.concatenate([STATE, np.linspace(-0.4, 0.4, n + 2 * k)])
    G, dG = np.empty(z.size), np.empty((z.size, z.size))
    assert call("rhs_and_reactions")(0.0, STATE, p, f, lam) == 0
    call("constraint_residuals")(0.0, STATE, p, residuals)
    call("constraint_matrix")(0.0, STATE, p, matrix)
    assert call("rhs_with_jacobian")(0.0, STATE, p, ydot, J) == 0
    assert call("reaction_jacobian")(0.0, STATE, p, R) == 0
    assert call("rhs_directional")(0.0, STATE, p, V, W[order], ydot, direction) == 0
    assert call("dae_residual")(0.0, z, p, G) == 0
    assert call("dae_jacobian")(0.0, z, p, dG) == 0
    R[:, N:] = R[:, N:][:, np.argsort(order)]   # (columns in `names`' order)
    return {"rhs": f, "reactions": lam, "constraint_residuals": residuals, "constraint_matrix": matrix,
            "energy": np.array(call("energy")(0.0, STATE, p)), "rhs_jacobian": J, "reaction_jacobian": R,
            "rhs_directional": direction, "dae_residual": G, "dae_jacobian": dG}


@pytest.fixture(scope="module")
def plain(cache_dir) -> tuple[lc.Model, dict]:
    """The plain-named probe and its outputs, the reference of both tests: its kernels run as plain Python (the
    same emitted code; numba compiles the risky-named tree's, the subject, in the first test)."""
    model = lc.compile(probe_tree(*PLAIN), cache_dir=cache_dir)
    return model, _outputs(model, PLAIN[2], _python_kernels(model))


@pytest.fixture(scope="module")
def loop_names(plain) -> list[str]:
    """Every identifier of the probe's modules (eager and companions), builtins, keywords, `COMMON`."""
    model = plain[0]
    found = set(dir(builtins)) | set(keyword.kwlist) | set(COMMON)
    for source in [model.source_path.read_text(encoding="utf-8"),
                   *(entry.path.read_text(encoding="utf-8") for entry in model.on_demand_entries.values())]:
        found |= _identifiers(source)
    assert {"_kkt", "_acc0", "_mult0", "_mu0", "_dy0", "_baumgarte_alpha", "_b000000"} <= found
    return sorted(name for name in found if name.isidentifier() and name != "t")   # (t: lagcomp's time)


def _agree(got: dict, want: dict) -> None:
    """Each output within 1e-13 of the largest entry of its plain-named counterpart: the names may reorder a sum,
    and the augmented solve carries that rounding through K⁻¹ (a clash of names gives O(1) errors)."""
    for name, value in want.items():
        assert np.max(np.abs(got[name] - value)) <= 1e-13 * np.max(np.abs(value)), name


def test_a_loop_tree_named_with_its_own_emitted_names_compiles_and_agrees(plain, loop_names, cache_dir):
    """Links, coordinates, parameters and the loop named like the augmented solve's and the companions' locals,
    builtins and modules, compiled by numba: every output that of the plain names."""
    risky = [name for name in ("_kkt", "_acc0", "_mult0", "_lam", "_mu0", "_w0", "_dy0", "_dp0", "_jac",
                               "_direction", "_baumgarte_alpha", "_baumgarte_beta", "_ydot", "lam", "out", "np",
                               "_b000001", "range", "status")
             if name in loop_names or name in COMMON]
    pool = risky + [name for name in loop_names if name not in risky and not keyword.iskeyword(name)]
    names = (tuple(pool[:LINKS]), tuple(pool[LINKS:LINKS + COORDINATES]),
             tuple(pool[LINKS + COORDINATES:LINKS + COORDINATES + PARAMETERS]), pool[LINKS + COORDINATES + PARAMETERS])
    model = lc.compile(probe_tree(*names), cache_dir=cache_dir)
    _agree(_outputs(model, names[2]), plain[1])


@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                  HealthCheck.too_slow])
@given(data=st.data())
def test_loop_names_drawn_from_the_emitted_ones(plain, loop_names, cache_dir, data):
    """Hypothesis draws the names; the kernels (the eager module, the loops' companions) run as plain Python, as the
    plain names' do: the outputs of the plain names."""
    identifiers = [name for name in loop_names if not keyword.iskeyword(name)]
    links = data.draw(st.lists(st.sampled_from(identifiers), min_size=LINKS, max_size=LINKS, unique=True))
    coordinates = data.draw(st.lists(st.sampled_from(identifiers), min_size=COORDINATES, max_size=COORDINATES,
                                     unique=True))
    parameters = data.draw(st.lists(st.sampled_from(loop_names), min_size=PARAMETERS, max_size=PARAMETERS,
                                    unique=True))
    loop = data.draw(st.sampled_from(identifiers))
    names = (tuple(links), tuple(coordinates), tuple(parameters), loop)
    model = lc.compile(probe_tree(*names), cache_dir=cache_dir)
    _agree(_outputs(model, names[2], _python_kernels(model)), plain[1])


def _python_kernels(model: lc.Model) -> dict:
    """The eager module and the companions of the loops' Jacobians, DAE and directional kernels as plain Python
    (numba would compile each drawn tree); the eager module last (`random_systems.python_model_kernels`)."""
    kinds = ("jacobians", "directional", "dae")
    return python_kernels(*(model.on_demand_entry(kind).path.read_text(encoding="utf-8") for kind in kinds),
                          model.source_path.read_text(encoding="utf-8"))
