"""Emit the modules of the bundled examples into a directory (the repository's `generated/`).

Each example has its eager module there, ``<name>.py``, and its companion modules (`lagcomp.codegen.kinds`), one
per on-demand kind that has kernels for it, ``<name>_on_demand/<kind>.py``.
`generated/` lets a reviewer see, in a diff, what a compiler change does to
the code lagcomp writes; a test fails when a file there is stale.
Regenerate with ``lagcomp generate generated/``.
"""

from __future__ import annotations

from pathlib import Path


def bundled_sources() -> dict[str, str]:
    """Path (relative to the directory) -> emitted source, for every bundled example (factory defaults): its eager
    module ``<name>.py`` and its companion modules ``<name>_on_demand/<kind>.py`` (`lagcomp.codegen.kinds`), as
    the cache stores them; a kind with no kernel and no data for the example has none (its cache entry holds a
    module that defines nothing)."""
    from lagcomp import examples
    from lagcomp.cache import import_name
    from lagcomp.codegen.companion_module import companion_source
    from lagcomp.codegen.emit import emit_eager
    from lagcomp.codegen.kinds import ON_DEMAND
    from lagcomp.codegen.lower import lower
    from lagcomp.mechanics.lagrange import derive

    sources = {}
    for factory in examples.EXAMPLES.values():
        system = factory()
        eom = derive(system)
        eager = sources[f"{system.name}.py"] = emit_eager(lower(eom, "eager"))
        for kind in ON_DEMAND:
            source, metadata = companion_source(eom, kind, import_name(system.name, eager))
            if metadata["operations"] or kind.name in ("taylor", "equations"):
                sources[f"{system.name}_on_demand/{kind.name}.py"] = source
    return sources


def write_generated(directory: Path, check: bool = False) -> list[Path]:
    """Write every stale or missing file (or, with `check`, only list them)."""
    stale = []
    for name, source in bundled_sources().items():
        path = directory / name
        if not path.exists() or path.read_text(encoding="utf-8") != source:
            stale.append(path)
            if not check:
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text(source, encoding="utf-8")
    return stale
