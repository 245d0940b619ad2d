"""Compile the library's numba drivers once, on every core, before pytest-xdist's workers start.

The drivers (`lagcomp.integrate.drivers`) are ``@njit(SIGNATURE, cache=True)`` functions: a process compiles
them when it imports their module, unless numba's cache beside the module holds them, and every process shares
that cache.  In a run from an empty cache (a clean clone: CI) each worker used to compile the drivers it met
itself, at the same time as the other: both compiled radau's while collecting (a test module imports it), both
dop853's in their first tests; about 90 s of CPU for all of them in one process (`COST`), much of it twice.
`warm` compiles the modules whose cache files are missing in as many processes as there will be workers,
split by their cost, before the workers start; a run whose cache is warm pays one directory listing.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

#: CPU seconds of importing each driver module into an empty numba cache, in the order of `lagcomp.cli.precompile`
#: (a module's import compiles what it calls, so canonical's 2 s count in collocation's, sweep_rows' in the sweeps'),
#: measured at d715e14 in one process; a module not listed counts `UNKNOWN_COST`.
COST = {
    "collocation": 17.5, "radau": 14.1, "embedded": 12.0, "taylor": 10.0, "lanes": 6.5, "sweep_impulses": 4.8,
    "rattle": 4.3, "lyapunov": 4.2, "radau_sweep": 4.2, "embedded_sweep": 3.0, "taylor_lanes": 2.5,
    "fixed_step": 1.9, "fixed_sweeps": 1.5,
}
UNKNOWN_COST = 5.0
#: Driver modules that `lagcomp.cli.library_drivers` does not name (no method's driver or sweep).
EXTRA_MODULES = ("lagcomp.integrate.drivers.lyapunov",)


def driver_modules() -> list[str]:
    """The driver modules a run may import: those of `lagcomp.cli.library_drivers` and `EXTRA_MODULES`."""
    from lagcomp.cli import library_drivers

    return list(dict.fromkeys([reference.partition(":")[0] for reference in library_drivers()] + list(EXTRA_MODULES)))


def uncached(modules: list[str]) -> list[str]:
    """The `modules` without numba index files (``<module>.<function>-<line>.pyXY.nbi``) in ``__pycache__`` beside
    their source.  Importing the drivers' package first removes the stale ones (`refresh_stale_drivers`)."""
    import lagcomp.integrate.drivers as drivers

    cache = Path(drivers.__file__).parent / "__pycache__"
    return [module for module in modules if not any(cache.glob(module.rpartition(".")[2] + ".*.nbi"))]


def split(modules: list[str], groups: int) -> list[list[str]]:
    """`modules` in at most `groups` lists of about equal `COST`: the costliest first, each to the lightest list."""
    lists: list[list[str]] = [[] for _ in range(min(groups, len(modules)))]
    loads = [0.0] * len(lists)
    for module in sorted(modules, key=lambda name: -COST.get(name.rpartition(".")[2], UNKNOWN_COST)):
        lightest = loads.index(min(loads))
        lists[lightest].append(module)
        loads[lightest] += COST.get(module.rpartition(".")[2], UNKNOWN_COST)
    return lists


_IMPORT = "import sys\nfrom lagcomp.numba_cache import import_library_module\nfor name in sys.argv[1:]:\n" \
          "    import_library_module(name)\n"


def warm(processes: int) -> list[list[str]]:
    """Compile the uncached driver modules in `processes` subprocesses at once and wait for them; the groups
    compiled.  A subprocess that fails is not an error here: the workers then compile (and fail) as they would."""
    groups = split(uncached(driver_modules()), processes)
    running = [subprocess.Popen([sys.executable, "-c", _IMPORT, *group], stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL) for group in groups]
    for process in running:
        process.wait()
    return groups
