"""The first ``rhs_jacobian`` of a tree (the on-demand kind "jacobians"): its cost in CPU seconds, cold.

For each system (`bench.bench_scale`'s names: ``planar_N``, ``spherical_N``, ...), in this process with an empty
cache directory: ``lc.compile`` (the eager module), then ``model.kernels.rhs_jacobian`` (the companion module
derived and emitted) and its first call (numba's compile of ``rhs_jacobian`` and of the ``rhs_with_jacobian`` it
delegates to), each timed with `time.process_time`, the operations numba compiled for ``rhs_with_jacobian`` and
the process's peak memory.  With ``--calls N``, also the run time of ``rhs_with_jacobian`` per call (the best of
five loops of N calls, wall time: compare two checkouts' figures only from the same run of the same machine).
Run one system per process for a cold figure (numba's own start-up is paid by the first call of the process).

    python -m bench.bench_jacobian_compile planar_20 spherical_3 --calls 2000
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time


def measure(system: str, calls: int = 0) -> str:
    """One line: n, the CPU seconds of compile and of the first rhs_jacobian, its operations, peak MB (and the
    µs per call of rhs_with_jacobian with `calls`)."""
    import numpy as np

    import lagcomp as lc
    from bench.bench_scale import build

    tree, values = build(system)
    start = time.process_time()
    model = lc.compile(tree, progress=False, cache_dir=tempfile.mkdtemp(prefix="lagcomp-bench-jac-"))
    compiled = time.process_time()
    n, p = model.n, model.parameter_vector(values)
    y = np.random.default_rng(1).uniform(-0.5, 0.5, size=2 * n)
    out = np.empty((2 * n, 2 * n))
    kernel = model.kernels.rhs_jacobian
    built = time.process_time()
    kernel(0.0, y, p, out)
    jacobian = time.process_time()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    operations = model.kernels.companion.entry("jacobians").metadata["operations"]["rhs_with_jacobian"]
    line = (f"{system}: n={n} compile {compiled - start:.1f} s, jacobians built {built - compiled:.1f} s, "
            f"first rhs_jacobian (numba) {jacobian - built:.1f} s (CPU), {operations} operations, peak {peak:.0f} MB")
    if calls:
        line += f", rhs_with_jacobian {per_call(model.kernels.rhs_with_jacobian, y, p, calls) * 1e6:.2f} µs/call"
    return line


def per_call(kernel, y, p, calls: int) -> float:
    """Seconds per call of ``kernel(0.0, y, p, ydot, out)`` in a compiled loop: the best of five loops."""
    import numba
    import numpy as np

    @numba.njit
    def loop(y, p, ydot, out, calls):
        for _ in range(calls):
            kernel(0.0, y, p, ydot, out)

    ydot, out = np.empty(y.size), np.empty((y.size, y.size))
    loop(y, p, ydot, out, 1)
    best = np.inf
    for _ in range(5):
        start = time.perf_counter()
        loop(y, p, ydot, out, calls)
        best = min(best, (time.perf_counter() - start) / calls)
    return best


def main(argv=None) -> None:
    """Print `measure`'s line for each system named on the command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("systems", nargs="+")
    parser.add_argument("--calls", type=int, default=0, help="also time rhs_with_jacobian over this many calls")
    args = parser.parse_args(argv)
    for name in args.systems:
        print(measure(name, args.calls), flush=True)


if __name__ == "__main__":
    main()
