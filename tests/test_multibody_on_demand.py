"""Kernels on demand for a kinematic tree (`lagcomp.codegen.kinds.TREE_ON_DEMAND`), as tests/test_on_demand.py checks
them for a System: a plain run of a tree compiles only the eager kernels (no ``mass_matrix``, no ``forcing``: its
``rhs`` is the articulated-body algorithm), and the first ``Model.mass_matrix`` builds the companion module of the
kind "dynamics" alone, once, which a second process reuses (no lowering, no sympy, no numba compilation)."""

from __future__ import annotations

import multibody_models as mm
import numpy as np
from compile_probe import run_probe

import lagcomp as lc
from lagcomp.codegen.kinds import KIND_OF, TREE_KIND_OF, TREE_ON_DEMAND

#: One fresh process: compile the 3-link planar chain (or `lagcomp.load` it), then run `feature`; report which
#: kernels of the generated modules numba compiled (its "numba:compile" events), whether sympy and the lowering
#: were imported, and the cache's module files (tests/test_on_demand.py's SCRIPT, for a tree).
SCRIPT = """
    feature, how, root = sys.argv[1:4]
    if how == "load":
        model = lc.load("planar_chain_3", cache_dir=root)
    else:
        from lagcomp.examples.trees import planar_chain
        model = lc.compile(planar_chain(3), cache_dir=root)
    params = {name: 1.0 for name in model.parameters}
    if feature == "plain":
        sol = model.simulate((0, 0.5), q0=[0.1, 0.2, 0.3], qd0=[0.0, 0.0, 0.0], params=params, progress=False)
        sol.energy, sol.energy_function, sol.momenta, sol.summary
    elif feature == "mass_matrix":
        print(json.dumps(model.mass_matrix([0.1, 0.2, 0.3], params=params).tolist()))
    modules = sorted(p.name for p in Path(root, "modules").glob("*.py"))
    print(json.dumps({"compiled": compiled, "modules": modules, "sympy": "sympy" in sys.modules,
                      "lowering": "lagcomp.codegen.tree_lower" in sys.modules}))
"""


def _run(feature: str, how: str, root) -> tuple[dict, list[str]]:
    return run_probe(SCRIPT, feature, how, root)


def _companions(modules: list[str]) -> list[str]:
    return [m for m in modules if "_on_demand_" in m]


def test_the_tree_kinds_leave_a_systems_kinds_alone():
    """M and F are on demand for a tree only: a System's eager module keeps them (`KIND_OF` does not name them)."""
    assert {"mass_matrix", "forcing"} <= set(TREE_KIND_OF) and not {"mass_matrix", "forcing"} & set(KIND_OF)
    assert all(TREE_KIND_OF[name] is kind for name, kind in KIND_OF.items())
    assert "momenta" not in TREE_KIND_OF   # (every recorded run reads it: `observables`, the summary)


def test_a_plain_tree_run_compiles_only_eager_kernels_and_mass_matrix_builds_its_kind_once(tmp_path):
    """compile + dop853 + energies, momenta, summary: the eager module alone is written and every kernel numba
    compiles is one of it, none of an on-demand kind; then ``Model.mass_matrix`` in a second process builds the
    companion of the kind "dynamics" only and compiles ``mass_matrix`` from it, and a third process (from
    `lagcomp.load`) reads M with no lowering, no sympy and no numba compilation."""
    plain, _ = _run("plain", "compile", tmp_path)
    assert len(plain["modules"]) == 1 and not _companions(plain["modules"])
    names = {function for _, function in plain["compiled"]}
    assert {"rhs", "observables", "momenta", "energy"} <= names, names
    assert not names & set(TREE_KIND_OF), names
    first, printed = _run("mass_matrix", "compile", tmp_path)
    (dynamics,) = TREE_ON_DEMAND
    assert _companions(first["modules"]) == [m for m in first["modules"] if f"_on_demand_{dynamics.name}_" in m]
    assert len(first["modules"]) == 2
    built = {f for m, f in first["compiled"] if "_on_demand_" in m}
    assert {f for f in built if not f.startswith("_mass_matrix_step")} == {"mass_matrix"}, built  # (and its helpers)
    second, printed_again = _run("mass_matrix", "load", tmp_path)
    assert second["modules"] == first["modules"] and printed_again == printed
    assert second["compiled"] == [] and not second["sympy"] and not second["lowering"]


def test_mass_matrix_and_forcing_on_demand_are_the_eager_ones_of_before(cache_dir):
    """The companion's M and F solve for the articulated-body rhs's q̈: M q̈ = F to rounding, at random states of a
    tree with a universal, a revolute and a prismatic joint (the cart-pole) and of a 2-link universal chain."""
    rng = np.random.default_rng(3)
    for tree in (mm.cart_pole(), mm.universal_chain(2)):
        model = lc.compile(tree, cache_dir=cache_dir)
        params = {name: rng.uniform(0.5, 2.0) for name in model.parameters}
        for _ in range(5):
            q, qd = rng.uniform(-1, 1, model.n), rng.uniform(-1, 1, model.n)
            M, F = model.mass_matrix(q, params=params), model.forcing(q, qd, params=params)
            qdd = model.rhs(0.0, np.concatenate([q, qd]), params)[model.n:]
            assert np.max(np.abs(M @ qdd - F)) <= 1e-13 * (np.max(np.abs(M)) * np.max(np.abs(qdd)) + np.max(np.abs(F)))
