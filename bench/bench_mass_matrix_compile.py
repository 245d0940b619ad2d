"""The first ``Model.mass_matrix`` of a tree (the on-demand kind "dynamics"): its cost in CPU seconds, cold.

For each system (`bench.bench_scale`'s names: ``planar_N``, ``spherical_N``, ...), in this process with an empty
cache directory: ``lc.compile`` (the eager module, not compiled by numba until called), then the first
``Model.mass_matrix`` (the companion module derived and emitted, numba's compile of ``mass_matrix``) and the
first ``Model.forcing``, each timed with `time.process_time`, and the process's peak memory.  Run one system per
process for a cold figure (numba's own start-up is paid by the first call of the process).

    python -m bench.bench_mass_matrix_compile spherical_10
"""

from __future__ import annotations

import resource
import sys
import tempfile
import time


def measure(system: str) -> str:
    """One line: n, the CPU seconds of compile, first mass_matrix and first forcing, peak MB."""
    import numpy as np

    import lagcomp as lc
    from bench.bench_scale import build

    tree, values = build(system)
    start = time.process_time()
    model = lc.compile(tree, progress=False, cache_dir=tempfile.mkdtemp(prefix="lagcomp-bench-mm-"))
    compiled = time.process_time()
    q = np.random.default_rng(1).uniform(-0.5, 0.5, size=model.n)
    model.mass_matrix(q, params=values)
    mass = time.process_time()
    model.forcing(q, q, params=values)
    forcing = time.process_time()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return (f"{system}: n={model.n} compile {compiled - start:.1f} s, first mass_matrix {mass - compiled:.1f} s, "
            f"first forcing {forcing - mass:.1f} s (CPU), peak {peak:.0f} MB")


def main(argv=None) -> None:
    """Print `measure`'s line for each system named on the command line."""
    for name in (sys.argv[1:] if argv is None else argv):
        print(measure(name), flush=True)


if __name__ == "__main__":
    main()
