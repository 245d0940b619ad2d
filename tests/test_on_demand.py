"""Kernels on demand (`lagcomp.codegen.kinds`, `lagcomp.companion`): a plain run compiles only the eager
kernels; the first call of a feature that needs more builds the companion modules of its kinds (those only)
once, and a second process reuses them (no lowering, no sympy with `lagcomp.load`, no numba compilation of any
kernel)."""

from __future__ import annotations

import json
import os
import pickle
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from compile_probe import run_probe

import lagcomp as lc
from lagcomp import examples
from lagcomp.codegen.kinds import KIND_OF, ON_DEMAND, on_demand
from lagcomp.errors import ModelError

#: One fresh process: compile (or, with "load", `lagcomp.load`) the example, then run `feature`; report which
#: kernels of the generated modules numba compiled (numba's "numba:compile" events fire on compilation only,
#: never on a load from its disk cache), whether sympy and the lowering were imported, and the cache's files.
SCRIPT = """
    name, feature, how, root = sys.argv[1:5]
    if how == "load":
        model = lc.load(name, cache_dir=root)
    else:
        from lagcomp import examples
        model = lc.compile(examples.get(name), cache_dir=root)
    if feature == "plain":
        sol = model.simulate((0, 0.5), progress=False)     # the default method, dop853
        sol.energy, sol.energy_function, sol.summary
    elif feature == "radau":
        model.simulate((0, 0.5), method="radau", progress=False)
    elif feature == "sensitivities":
        model.simulate((0, 0.5), sensitivities="params", progress=False)
    elif feature == "taylor":
        model.simulate((0, 0.5), method="taylor", progress=False)
    elif feature == "geometry":
        sol = model.simulate((0, 0.5), progress=False)
        sol.geometry.frames(sol.t[:3], sol.q[:3])
    modules = sorted(p.name for p in Path(root, "modules").glob("*.py"))
    print(json.dumps({"compiled": compiled, "modules": modules, "sympy": "sympy" in sys.modules,
                      "lowering": "lagcomp.codegen.lower" in sys.modules}))
"""


def _run(name: str, feature: str, how: str, root) -> dict:
    return run_probe(SCRIPT, name, feature, how, root)[0]


def _companions(modules: list[str]) -> list[str]:
    return [m for m in modules if "_on_demand_" in m]


def test_a_plain_run_compiles_only_eager_kernels(tmp_path):
    """compile + the default method + energies: the eager module alone is written, and every kernel numba
    compiles is one of its kernels."""
    result = _run("double_pendulum", "plain", "compile", tmp_path)
    assert len(result["modules"]) == 1 and not _companions(result["modules"])
    names = {function for _, function in result["compiled"]}
    assert "rhs" in names and "observables" in names
    assert not [name for name in names if on_demand(name)], names


@pytest.mark.parametrize(("name", "feature", "kernels"), [
    ("simple_pendulum", "radau", {"rhs_jacobian", "rhs_with_jacobian"}),
    ("simple_pendulum", "sensitivities", {"rhs_tangents_parameters"}),
    ("simple_pendulum", "taylor", {"taylor_coefficients"}),
    ("wheel_jack", "geometry", {"geometry"}),
])
def test_a_feature_builds_its_kernels_once_and_a_second_process_reuses_them(tmp_path, name, feature, kernels):
    """The first process builds the companion modules of the feature's kinds only (once: one file each) and
    numba compiles the feature's kernels from them, and nothing else of theirs; a second process, from
    `lagcomp.load`, runs the feature with no lowering, no sympy and no numba compilation of any kernel."""
    first = _run(name, feature, "compile", tmp_path)
    kinds = {KIND_OF[kernel].name for kernel in kernels}
    companions = _companions(first["modules"])
    assert sorted(kind for kind in kinds for m in companions if f"_on_demand_{kind}_" in m) == sorted(kinds)
    assert len(companions) == len(kinds) and len(first["modules"]) == 1 + len(kinds)
    from_companions = {function for module, function in first["compiled"] if "_on_demand_" in module}
    assert kernels <= from_companions, first["compiled"]
    assert all(KIND_OF[function].name in kinds for function in from_companions), from_companions
    second = _run(name, feature, "load", tmp_path)
    assert second["modules"] == first["modules"]
    assert second["compiled"] == [] and not second["sympy"] and not second["lowering"]


def test_the_companions_equal_the_bundled_ones_after_a_round_trip_of_the_equations(tmp_path):
    """A later process lowers each companion from the equations the entry keeps (pickled): the same source as
    from the derivation (the bundled `generated/` file), and no file for a kind with nothing to define."""
    from pathlib import Path

    model = lc.compile(examples.get("double_pendulum"), cache_dir=tmp_path)
    model.kernels.companion.eom = None       # as in a later process: the kept equations, not this one's
    bundled = Path(__file__).resolve().parents[1] / "generated" / "double_pendulum_on_demand"
    built = {kind: entry.path.read_text(encoding="utf-8") for kind, entry in model.on_demand_entries.items()}
    assert set(built) == {kind.name for kind in ON_DEMAND}
    empty = {"dae", "input_jacobian"}       # (no constraints: no DAE; no inputs: no input Jacobian)
    assert {path.stem for path in bundled.glob("*.py")} == set(built) - empty
    for kind, source in built.items():
        if kind not in empty:
            assert source == (bundled / f"{kind}.py").read_text(encoding="utf-8"), kind


def test_a_companion_imports_the_eager_kernels_it_calls(tmp_path):
    """The Jacobians' companion calls the eager module's own ``rhs`` (imported by name, not a copy), and a
    kind that calls none (the Taylor program) defines no ``rhs``."""
    model = lc.compile(examples.get("double_pendulum"), cache_dir=tmp_path)
    companion = model.kernels.companion
    assert companion.module("jacobians").rhs is model.kernels.eager_module.rhs
    assert not hasattr(companion.module("taylor"), "rhs")
    y = np.array([0.3, -0.2, 0.1, 0.4])
    jacobian, ydot = np.empty((4, 4)), np.empty(4)
    assert model.kernels.rhs_with_jacobian(0.0, y, model.parameter_vector(), ydot, jacobian) == 0
    expected = np.empty(4)
    model.kernels.rhs(0.0, y, model.parameter_vector(), expected)
    assert np.array_equal(ydot, expected)


def test_a_loaded_model_without_kept_equations_names_the_feature(tmp_path):
    """`lagcomp.load` of an entry that keeps no equations: the on-demand kernel's read raises a ModelError
    naming the kernel and the feature, and how to build it ahead."""
    model = lc.compile(examples.get("simple_pendulum"), cache_dir=tmp_path)
    for kept in (tmp_path / "equations").glob("*.pickle"):
        kept.unlink()
    from lagcomp import runtime

    runtime._NAMESPACES.clear()     # (as in a new process)
    loaded = lc.load("simple_pendulum", cache_dir=tmp_path)
    assert loaded.simulate((0, 0.1), progress=False).success     # eager kernels: no equations needed
    with pytest.raises(ModelError, match=r"`rhs_jacobian` \(the exact Jacobians.*precompile simple_pendulum --all"):
        loaded.jacobian(0.0, [0.1, 0.0])
    assert model.system is not None
    runtime._NAMESPACES.clear()
    again = lc.compile(examples.get("simple_pendulum"), cache_dir=tmp_path)   # a System at hand: derived again
    assert again.jacobian(0.0, [0.1, 0.0]).shape == (2, 2)


def test_equations_are_kept_beside_the_entry(tmp_path):
    """The equations the companion is lowered from are stored with the entry, and read back equal."""
    model = lc.compile(examples.get("double_pendulum"), cache_dir=tmp_path)
    (kept,) = (tmp_path / "equations").glob("*.pickle")
    assert kept.stem == model.cache_key
    eom = pickle.loads(kept.read_bytes())
    original = model.kernels.companion.eom
    assert eom.M == original.M and eom.F == original.F and eom.energy == original.energy


#: A process that compiles the example, waits for the file `go`, then asks for an on-demand kernel; reports
#: whether it built the companion module itself.
RACE = textwrap.dedent("""
    import json, sys, time
    from pathlib import Path
    import lagcomp as lc
    import lagcomp.companion as companion
    from lagcomp import examples

    root = sys.argv[1]
    builds = []
    original = companion.build_companion
    companion.build_companion = lambda *args: builds.append(1) or original(*args)
    model = lc.compile(examples.get("simple_pendulum"), cache_dir=root)
    Path(root, f"ready-{sys.argv[2]}").touch()
    while not Path(root, "go").exists():
        time.sleep(0.01)
    jacobian = model.jacobian(0.0, [0.3, 0.0])
    path = str(model.on_demand_entry("jacobians").path)
    print(json.dumps({"builds": len(builds), "jacobian": jacobian.tolist(), "path": path}))
""")


def test_processes_asking_at_once_build_the_companion_once(tmp_path):
    """Two processes that read an on-demand kernel at the same moment: one builds the companion (the lock of
    its key), the other waits and loads it; one module file, the same Jacobian."""
    lc.compile(examples.get("simple_pendulum"), cache_dir=tmp_path)     # the eager entry, so both start alike
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    processes = [subprocess.Popen([sys.executable, "-c", RACE, str(tmp_path), str(i)], stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, text=True, env=env) for i in range(2)]
    import time

    deadline = time.monotonic() + 300
    while not all((tmp_path / f"ready-{i}").exists() for i in range(2)) and time.monotonic() < deadline:
        time.sleep(0.01)
    (tmp_path / "go").touch()
    results = []
    for process in processes:
        out, err = process.communicate(timeout=600)
        assert process.returncode == 0, err[-3000:]
        results.append(json.loads(out.strip().splitlines()[-1]))
    assert sum(r["builds"] for r in results) == 1
    assert results[0]["jacobian"] == results[1]["jacobian"] and results[0]["path"] == results[1]["path"]
    assert len(list((tmp_path / "modules").glob("*_on_demand_*.py"))) == 1
    assert not list(tmp_path.rglob("*.tmp"))


#: A process without sympy (its import fails): load the model, use a kind built earlier, then read a kernel of
#: a kind never built.
WITHOUT_SYMPY = textwrap.dedent("""
    import json, sys
    sys.modules["sympy"] = None         # `import sympy` raises ImportError from here on
    import lagcomp as lc
    from lagcomp.errors import ModelError

    model = lc.load("simple_pendulum", cache_dir=sys.argv[1])
    jacobian = model.jacobian(0.0, [0.3, 0.0]).tolist()
    try:
        model.kernels.taylor_coefficients
        message = None
    except ModelError as err:
        message = str(err)
    print(json.dumps({"jacobian": jacobian, "message": message}))
""")


def test_a_load_without_sympy_uses_the_kinds_built_and_names_the_feature_of_the_others(tmp_path):
    """`lagcomp.load` where sympy cannot be imported: the Jacobians' companion, built by an earlier process,
    serves; the Taylor kind, never built, is refused by a ModelError that names the kernel, its feature and
    sympy (its equations cannot be read back without it)."""
    model = lc.compile(examples.get("simple_pendulum"), cache_dir=tmp_path)
    expected = model.jacobian(0.0, [0.3, 0.0]).tolist()
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    done = subprocess.run([sys.executable, "-c", WITHOUT_SYMPY, str(tmp_path)], capture_output=True, text=True,
                          env=env, timeout=600, check=False)
    assert done.returncode == 0, done.stderr[-3000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["jacobian"] == expected
    assert result["message"] is not None
    assert "`taylor_coefficients` (method='taylor')" in result["message"] and "needs sympy" in result["message"]
    assert "precompile simple_pendulum --all" in result["message"]


def test_a_companion_goes_to_the_cache_of_the_model_that_asked(tmp_path):
    """The same System compiled into two cache roots in one process (one eager module, by name): the companion
    a feature of the second model builds is stored in the second root, which a later process reads."""
    first = lc.compile(examples.get("simple_pendulum"), cache_dir=tmp_path / "a")
    first.jacobian(0.0, [0.3, 0.0])
    second = lc.compile(examples.get("simple_pendulum"), cache_dir=tmp_path / "b")
    second.jacobian(0.0, [0.3, 0.0])
    assert len(list((tmp_path / "b" / "modules").glob("*_on_demand_jacobians_*.py"))) == 1
