"""Emit the modules of the bundled examples into a directory (the repository's `generated/`).

`generated/` lets a reviewer see, in a diff, what a compiler change does to
the code lagcomp writes; a test fails when a file there is stale.
Regenerate with ``lagcomp generate generated/``.
"""

from __future__ import annotations

from pathlib import Path


def bundled_sources() -> dict[str, str]:
    """File name -> emitted source, for every bundled example (factory defaults)."""
    from lagcomp import examples
    from lagcomp.codegen.emit import emit
    from lagcomp.codegen.latex import lagrange_equations
    from lagcomp.codegen.lower import lower
    from lagcomp.mechanics.lagrange import derive

    sources = {}
    for factory in examples.EXAMPLES.values():
        system = factory()
        eom = derive(system)
        sources[f"{system.name}.py"] = emit(lower(eom), equations=lagrange_equations(eom))
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
