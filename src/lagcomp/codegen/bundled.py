"""Emit the modules of the bundled examples into a directory (the repository's `generated/`).

Each example has two files there, its eager module and its companion module (`lagcomp.codegen.kinds`).
`generated/` lets a reviewer see, in a diff, what a compiler change does to
the code lagcomp writes; a test fails when a file there is stale.
Regenerate with ``lagcomp generate generated/``.
"""

from __future__ import annotations

from pathlib import Path


def bundled_sources() -> dict[str, str]:
    """File name -> emitted source, for every bundled example (factory defaults): its eager module
    ``<name>.py`` and its companion module ``<name>_on_demand.py`` (`lagcomp.codegen.kinds`), as the cache
    stores them."""
    from lagcomp import examples
    from lagcomp.codegen.emit import emit_companion, emit_eager
    from lagcomp.codegen.latex import lagrange_equations
    from lagcomp.codegen.lower import lower
    from lagcomp.mechanics.lagrange import derive

    sources = {}
    for factory in examples.EXAMPLES.values():
        system = factory()
        eom = derive(system)
        sources[f"{system.name}.py"] = emit_eager(lower(eom, "eager"))
        sources[f"{system.name}_on_demand.py"] = emit_companion(lower(eom, "on_demand"),
                                                                equations=lagrange_equations(eom))
    return sources


def write_generated(directory: Path, check: bool = False) -> list[Path]:
    """Write every stale or missing file (or, with `check`, only list them)."""
    stale = []
    for name, source in bundled_sources().items():
        path = directory / name
        if not path.exists() or path.read_text(encoding="utf-8") != source:
            stale.append(path)
            if not check:
                directory.mkdir(parents=True, exist_ok=True)
                path.write_text(source, encoding="utf-8")
    return stale
