"""The library drivers are compiled once per installation: a new model in a new process recompiles none of them.

Each process compiles a model it has never seen (into its own module cache, so numba compiles that
model's kernels), integrates it with every library method the model admits (sweeping too where
the method has a library sweep loop), then reports numba's dispatcher statistics of every library
driver the method registry names (`lagcomp.cli.library_drivers`: `Method.driver` and `Method.sweep`
of the registry's methods), and of `sweep_rows.fold_rows`.  The second process must find each of
them in numba's cache, which the first process filled (or an earlier test run did): no miss; nor of the
hooks every unconstrained, eventless model shares (`lagcomp.kernel_support.trivial`).
The list follows the registry, so each driver family is covered as it moves into the library.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

PROBE = textwrap.dedent(
    """
    import json, sys
    import lagcomp as lc
    from lagcomp import examples
    from lagcomp.cli import library_drivers
    from lagcomp.integrate.methods import METHODS, library_function
    from lagcomp.kernel_support import trivial

    model = lc.compile(examples.get(sys.argv[2]), cache_dir=sys.argv[1])
    model.rhs(0.0, [0.1] * model.state_size)
    methods = [m for m in METHODS.values() if (model.separable or not m.separable_only)
               and (not model.k or not m.unconstrained_only)
               and (model.holonomic_separable or not m.holonomic_separable_only)]
    for m in methods:
        steps = {"rtol": 1e-6, "atol": 1e-8} if m.adaptive else {"dt": 0.01}
        model.simulate((0, 0.1), method=m.name, **steps)
        if m.sweep is not None:
            model.sweep((0, 0.1), {model.coordinates[0]: [0.1, 0.2]}, method=m.name, workers=1, progress=False,
                        **steps)
    references = library_drivers() + ["lagcomp.integrate.drivers.sweep_rows:fold_rows"]
    print(json.dumps({
        "methods": [m.name for m in methods],
        "driver_misses": {ref: sum(library_function(ref).stats.cache_misses.values()) for ref in references},
        "rhs_misses": sum(model.kernels.rhs.stats.cache_misses.values()),
        "trivial_misses": {name: sum(getattr(trivial, name).stats.cache_misses.values())
                           for name in ("project", "constraint_residual", "event_values")},
        "trivial_bound": all(getattr(model.kernels, name) is getattr(trivial, name)
                             for name in ("project", "constraint_residual", "event_values")),
    }))
    """
)


def _probe(cache_dir, example: str) -> dict:
    env = {k: v for k, v in os.environ.items() if k != "LAGCOMP_CACHE_DIR"}
    out = subprocess.run([sys.executable, "-c", PROBE, str(cache_dir), example], capture_output=True, text=True,
                         env=env, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_a_new_model_in_a_new_process_recompiles_no_library_driver(tmp_path):
    _probe(tmp_path / "first", "simple_pendulum")
    second = _probe(tmp_path / "second", "double_pendulum")
    assert second["rhs_misses"] > 0  # a model new to this process and its cache: its kernels were compiled
    assert second["driver_misses"] and not any(second["driver_misses"].values()), second
    # an unconstrained model without events takes kernel_support.trivial's hooks: compiled once, by the first
    assert second["trivial_bound"] and not any(second["trivial_misses"].values()), second


DAMAGE_PROBE = textwrap.dedent(
    """
    import json, warnings
    from lagcomp.integrate.methods import library_function

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fold_rows = library_function("lagcomp.integrate.drivers.sweep_rows:fold_rows")
    print(json.dumps({"misses": sum(fold_rows.stats.cache_misses.values()),
                      "warnings": [str(w.message) for w in caught if w.category.__name__ == "CacheWarning"]}))
    """
)


def test_damaged_cache_files_of_a_driver_are_removed_and_the_driver_compiled_again(tmp_path):
    """numba reads a driver's files at its import: a truncated one would fail every process, not only this one."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}

    def probe() -> dict:
        out = subprocess.run([sys.executable, "-c", DAMAGE_PROBE], capture_output=True, text=True, env=env, check=True)
        return json.loads(out.stdout.strip().splitlines()[-1])

    assert probe() == {"misses": 1, "warnings": []}  # compiled into the empty cache
    (index,) = tmp_path.rglob("sweep_rows.fold_rows-*.nbi")
    index.write_bytes(index.read_bytes()[:100])
    healed = probe()
    assert healed["misses"] == 1 and len(healed["warnings"]) == 1 and "sweep_rows." in healed["warnings"][0]
    assert probe() == {"misses": 0, "warnings": []}  # and cached afresh


SUPPORT_PROBE = textwrap.dedent(
    """
    import json, sys, warnings
    import lagcomp as lc
    from lagcomp import examples

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = lc.compile(examples.get(sys.argv[2]), cache_dir=sys.argv[1])
        model.rhs(0.0, [0.1] * model.state_size)
    print(json.dumps([str(w.message) for w in caught if w.category.__name__ == "CacheWarning"]))
    """
)


def test_damaged_cache_files_of_kernel_support_are_removed_when_a_model_loads(tmp_path):
    """sin and cos are compiled once into numba's cache and then into every model's kernels: a damaged file of
    theirs would fail every new model's first call."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba")}

    def probe(example: str) -> list:
        out = subprocess.run([sys.executable, "-c", SUPPORT_PROBE, str(tmp_path / example), example],
                             capture_output=True, text=True, env=env, check=True)
        return json.loads(out.stdout.strip().splitlines()[-1])

    assert probe("simple_pendulum") == []
    (index,) = (tmp_path / "numba").rglob("trig.sin-*.nbi")
    index.write_bytes(index.read_bytes()[:100])
    (warning,) = probe("double_pendulum")
    assert index.name in warning
