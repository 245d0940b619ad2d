"""The integration drivers: library code compiled once per installation, taking the model's kernels as values.

Layers, from the user down:

1. `lagcomp.integrate.simulate` / `lagcomp.integrate.sweep` check the options once, allocate the
   run's arrays and call a driver chunk by chunk (progress, Ctrl-C and output buffers live there);
2. the registry `lagcomp.integrate.methods` names each method's driver and its coefficients
   (`lagcomp.integrate.tableaux`, `compositions`, `collocation`): a new method of an existing
   family is a tableau and one registry line;
3. the drivers in this package: ``@njit(SIGNATURE, cache=True)`` functions whose loops run
   entirely in compiled code, one per family of methods; numba caches them once per
   installation, for every model;
4. the generated module of each model: its kernels only (``rhs``, ``project``, ...), passed to
   the drivers as first-class function values (`kernel_types` gives their types).

The driver protocol: the kernels first, then the run's state in small in/out arrays (``y``,
``clock``, ``counters``, whose slots `run_state` names), the parameter vector, the run's settings, the output buffers
and the method's coefficient arrays; every driver returns ``(status, n_saved)`` with status a
`lagcomp.integrate.status.Status`, and a run continues with another call after ``BUFFER_FULL``
or ``PAUSED``.
"""

from lagcomp.numba_cache import refresh_stale_drivers

refresh_stale_drivers()  # before any driver module loads its cached code: numba keys that on the module's own file only
