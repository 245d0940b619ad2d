"""What the generated kernels import: sin and cos (`trig`), and the linear solvers (`linear_solvers`).

numba caches each function here beside this package's files, keyed on its own file only, while its machine code
holds what it calls from the others (`resting` calls `impacts`): `lagcomp.numba_cache.refresh_stale_kernel_support`
removes those cache files when any file of the package changed, before any of its modules is imported.
The contact and friction solvers, and the constrained systems' linear solvers (``kkt_solve``, ``kkt_solve_matrix``,
``gram_solve``, ``lu_solve_matrix``), are called by symbol, not linked into each kernel (`symbol_calls`).
"""

from lagcomp.numba_cache import refresh_stale_kernel_support

refresh_stale_kernel_support()
