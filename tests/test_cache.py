"""The disk cache: a second process does no derivation and no numba compilation; damage is rebuilt."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
import warnings

import pytest

import lagcomp as lc
from lagcomp import examples

PROBE = textwrap.dedent(
    """
    import json, sys
    import lagcomp as lc
    import lagcomp.mechanics.lagrange as lagrange
    from lagcomp import examples

    def batched_taylor_misses(model):
        # numba compilations of a batched Taylor sweep (its own module, written at the sweep)
        from lagcomp.integrate import sweep
        model.sweep((0, 1), {"theta": [0.1, 0.2]}, method="taylor", rtol=1e-6, atol=1e-6, batched=True)
        (module,) = [m for m in sweep._WORKER_MODULES.values() if hasattr(m, "taylor_lanes")]
        return sum(module.taylor_lanes.stats.cache_misses.values())

    derivations = []
    original = lagrange.derive
    lagrange.derive = lambda system: derivations.append(system.name) or original(system)

    model = lc.compile(examples.get("simple_pendulum"), cache_dir=sys.argv[1])
    sol = model.simulate((0, 1), method="rk4", dt=0.01)
    sol.energy  # the observables kernel runs when the energies are first read
    stats = {name: getattr(model.kernels, name).stats for name in ("rhs", "observables")}
    print(json.dumps({
        "batched_taylor": batched_taylor_misses(model),
        "from_cache": model.from_cache,
        "derivations": len(derivations),
        "misses": sum(sum(s.cache_misses.values()) for s in stats.values()),
        "hits": sum(sum(s.cache_hits.values()) for s in stats.values()),
        "final": sol.q[-1, 0],
    }))
    """
)


LOAD_PROBE = textwrap.dedent(
    """
    import json, sys
    import lagcomp as lc

    def batched_taylor_misses(model):
        # numba compilations of a batched Taylor sweep (its own module, written at the sweep)
        from lagcomp.integrate import sweep
        model.sweep((0, 1), {"theta": [0.1, 0.2]}, method="taylor", rtol=1e-6, atol=1e-6, batched=True)
        (module,) = [m for m in sweep._WORKER_MODULES.values() if hasattr(m, "taylor_lanes")]
        return sum(module.taylor_lanes.stats.cache_misses.values())

    model = lc.load("simple_pendulum", cache_dir=sys.argv[1])
    sol = model.simulate((0, 1), method="rk4", dt=0.01)
    sol.energy  # the observables kernel runs when the energies are first read
    stats = {name: getattr(model.kernels, name).stats for name in ("rhs", "observables")}
    print(json.dumps({
        "batched_taylor": batched_taylor_misses(model),
        "sympy_imported": "sympy" in sys.modules,
        "misses": sum(sum(s.cache_misses.values()) for s in stats.values()),
        "final": sol.q[-1, 0],
    }))
    """
)


def _probe(cache_dir, probe=PROBE) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "LAGCOMP_CACHE_DIR"}
    out = subprocess.run([sys.executable, "-c", probe, str(cache_dir)], capture_output=True, text=True, env=env, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_second_process_does_no_derivation_and_no_numba_compilation(tmp_path):
    first = _probe(tmp_path)
    assert first == {**first, "from_cache": False, "derivations": 1, "batched_taylor": 1}
    assert first["misses"] == 2  # rhs (for the rk4 driver) and observables compiled once, then saved
    second = _probe(tmp_path)
    assert second["from_cache"] is True and second["derivations"] == 0
    assert second["misses"] == 0 and second["hits"] == 2 and second["batched_taylor"] == 0
    assert second["final"] == first["final"]
    loaded = _probe(tmp_path, LOAD_PROBE)  # lagcomp.load: by name, without importing sympy at all
    assert loaded == {"sympy_imported": False, "misses": 0, "final": first["final"], "batched_taylor": 0}


def _module_files(cache_dir):
    return sorted((cache_dir / "modules").glob("*.py"))


def test_truncated_module_is_detected_and_rebuilt(tmp_path):
    system = examples.get("sling")
    lc.compile(system, cache_dir=tmp_path)
    (path,) = _module_files(tmp_path)
    text = path.read_text()
    path.write_text(text[: len(text) // 2])
    with pytest.warns(lc.CacheWarning, match="does not match its recorded sha256"):
        model = lc.compile(system, cache_dir=tmp_path)
    assert not model.from_cache
    assert path.read_text() == text
    assert model.simulate((0, 1), method="rk4", dt=0.1).success


def test_corrupt_index_entry_is_rebuilt(tmp_path):
    system = examples.get("sling")
    lc.compile(system, cache_dir=tmp_path)
    (index,) = (tmp_path / "index").glob("*.json")
    index.write_text("{not json")
    with pytest.warns(lc.CacheWarning, match="unusable"):
        model = lc.compile(system, cache_dir=tmp_path)
    assert not model.from_cache
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert lc.compile(system, cache_dir=tmp_path).from_cache


def test_unchanged_module_is_never_rewritten(tmp_path):
    # numba stamps its cache on the module's mtime: a rewrite would discard the machine code
    system = examples.get("rope")
    lc.compile(system, cache_dir=tmp_path)
    (path,) = _module_files(tmp_path)
    stamp = path.stat().st_mtime_ns
    for index in (tmp_path / "index").glob("*.json"):
        index.unlink()  # forces a fresh derivation, which emits the same source
    model = lc.compile(system, cache_dir=tmp_path)
    assert not model.from_cache
    assert path.stat().st_mtime_ns == stamp


def test_different_systems_get_different_modules(tmp_path):
    lc.compile(examples.get("rope"), cache_dir=tmp_path)
    lc.compile(examples.get("rope_friction"), cache_dir=tmp_path)
    assert len(_module_files(tmp_path)) == 2


def test_cache_location_from_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("LAGCOMP_CACHE_DIR", str(tmp_path / "env-cache"))
    model = lc.compile(examples.get("sling"))
    assert model.source_path.is_relative_to(tmp_path / "env-cache")


def test_load_restores_the_run_defaults_and_events(compiled, cache_dir):
    model = compiled("henon_heiles")
    loaded = lc.load("henon_heiles", cache_dir=cache_dir)
    assert loaded.system is None and loaded.cache_key == model.cache_key
    assert (loaded.defaults, loaded.q0, loaded.qd0, loaded.t_end) == (model.defaults, model.q0, model.qd0, model.t_end)
    assert loaded.events == model.events and [e.direction for e in loaded.events] == [1, -1]
    a = model.simulate((0, 50), rtol=1e-10, atol=1e-12, progress=False)
    b = loaded.simulate((0, 50), rtol=1e-10, atol=1e-12, progress=False)
    assert len(a.events["section"]) > 3
    assert b.events["section"].t.tolist() == a.events["section"].t.tolist()
    assert b.y[-1].tolist() == a.y[-1].tolist()


def test_load_of_an_unknown_name_says_what_to_do(tmp_path):
    with pytest.raises(lc.ModelError, match=r"No compiled model named 'nothing_here'.*lagcomp.compile"):
        lc.load("nothing_here", cache_dir=tmp_path)


def test_analysis_of_a_loaded_model_asks_for_the_system(compiled, cache_dir):
    from lagcomp.analysis import conserved_quantities

    compiled("simple_pendulum")
    with pytest.raises(lc.ModelError, match=r"lagcomp.load\(\) does not carry"):
        conserved_quantities(lc.load("simple_pendulum", cache_dir=cache_dir))
