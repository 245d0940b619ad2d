"""numba's compile of a model's heavy kernels, one by one: CPU seconds and the size of the LLVM IR, cold.

The test suite's numba time goes mostly to four kernels per model (issue 35): ``taylor_variational_coefficients``
(the Taylor program differentiated, `lagcomp.codegen.taylor_variational`), ``taylor_coefficients``,
``rhs_jacobian`` and ``rhs_parameter_jacobian``.  For each system named (`SYSTEMS`), in this process with an empty
cache directory: ``lc.compile``, then each kernel's first call timed with `time.process_time` (numba's type
inference, lowering and LLVM's passes of that kernel and of what it calls that is not compiled yet), and the lines
of its optimized LLVM IR (``inspect_llvm``).  The variational kernel is timed for the state's columns (k = N) and
for the state's and every parameter's (k = N + P), as the sensitivity tests ask for them.  Run one system per
process for figures free of numba's start-up (paid by the first compile of the process):

    python -m bench.bench_kernel_compile double_pendulum
    python -m bench.bench_kernel_compile planar_chain_4 --kernels variational
"""

from __future__ import annotations

import argparse
import tempfile
import time

#: The systems by name: (module, builder, its arguments), a `lagcomp.System` or a tree (every parameter is given
#: 1 + i/8, the i-th's value: defaults or not, the kernels' code does not depend on them).
SYSTEMS = {
    "double_pendulum": ("lagcomp.examples", "double_pendulum", ()),
    "n_link_pendulum_3": ("lagcomp.examples", "n_link_pendulum", (3,)),
    "planar_chain_4": ("lagcomp.examples.trees", "planar_chain", (4,)),
    "four_bar_linkage": ("lagcomp.examples.constrained", "four_bar_linkage", ()),
    "spherical_pendulum_cartesian": ("lagcomp.examples.constrained", "spherical_pendulum_cartesian", ()),
}

#: The kernels measured, in this order (each one's first call after those before it).
KERNELS = ("taylor_coefficients", "rhs_jacobian", "rhs_parameter_jacobian", "variational", "variational_p")


def build(system: str):
    import importlib

    module, function, arguments = SYSTEMS[system]
    return getattr(importlib.import_module(module), function)(*arguments)


def ir_lines(dispatcher) -> int:
    """Lines of the optimized LLVM IR of the dispatcher's (one) compiled signature."""
    return sum(text.count("\n") for text in dispatcher.inspect_llvm().values())


def _first_call(model, kernel: str, y, p):
    """The dispatcher of `kernel` after its first call with arguments of `model`'s shapes."""
    import numpy as np

    from lagcomp.integrate import taylor_sensitivities

    n = y.size
    if kernel.startswith("variational"):
        parameters = tuple(range(p.size)) if kernel == "variational_p" else ()
        k = n + len(parameters)
        module = taylor_sensitivities.variational_module(model, k, parameters, 1.0)
        dispatcher = module.taylor_variational_coefficients
        augmented = np.concatenate([y, np.eye(n, k).T.reshape(-1)])
        dispatcher(0.0, augmented, p, np.empty((n * (1 + k), 21)), np.empty((module.VARIATIONAL_WORK, 21)))
        return dispatcher
    dispatcher = getattr(model.kernels, kernel)
    if kernel == "taylor_coefficients":
        dispatcher(0.0, y, p, np.empty((n, 21)), np.empty((model.kernels.TAYLOR_WORK, 21)))
    else:
        columns = n if kernel == "rhs_jacobian" else p.size
        dispatcher(0.0, y, p, np.empty((n, columns)))
    return dispatcher


def measure(system: str, kernels=KERNELS) -> list[str]:
    """One line per kernel: the CPU seconds of its first call and the lines of its LLVM IR."""
    import numpy as np

    import lagcomp as lc

    start = time.process_time()
    model = lc.compile(build(system), progress=False, cache_dir=tempfile.mkdtemp(prefix="lagcomp-bench-kernel-"))
    lines = [f"{system}: n={model.n}, lc.compile {time.process_time() - start:.1f} s CPU"]
    p = model.parameter_vector({name: 1.0 + 0.125 * i for i, name in enumerate(model.parameters)})
    y = np.random.default_rng(1).uniform(-0.5, 0.5, size=2 * model.n)
    for kernel in kernels:
        if kernel.startswith(("taylor", "variational")) and model._taylor_program is None:
            lines.append(f"  {kernel:24s} none (no Taylor program: a constrained model's)")
            continue
        start = time.process_time()
        dispatcher = _first_call(model, kernel, y, p)
        seconds = time.process_time() - start
        lines.append(f"  {kernel:24s} {seconds:6.1f} s CPU, {ir_lines(dispatcher):7d} lines of LLVM IR")
    return lines


def main(argv=None) -> None:
    """Print `measure`'s lines for each system named on the command line."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("systems", nargs="+", choices=sorted(SYSTEMS))
    parser.add_argument("--kernels", nargs="+", choices=KERNELS, default=KERNELS)
    args = parser.parse_args(argv)
    for name in args.systems:
        for line in measure(name, args.kernels):
            print(line, flush=True)


if __name__ == "__main__":
    main()
