"""The library drivers are compiled once per installation: a new model in a new process recompiles none of them.

Each process compiles a model it has never seen (into its own module cache, so numba compiles that
model's kernels), integrates it with every library method the model admits (sweeping too where
the method has a library sweep loop), then reports numba's dispatcher statistics of every library
driver the method registry names (`lagcomp.cli.library_drivers`: `Method.driver` and `Method.sweep`
of the methods whose `Method.in_library` is true), and of `sweep_rows.fold_rows`.  The second process must find each of
them in numba's cache, which the first process filled (or an earlier test run did): no miss.
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

    model = lc.compile(examples.get(sys.argv[2]), cache_dir=sys.argv[1])
    model.rhs(0.0, [0.1] * model.state_size)
    methods = [m for m in METHODS.values() if m.in_library and (model.separable or not m.separable_only)
               and (not model.k or not m.unconstrained_only)]
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
