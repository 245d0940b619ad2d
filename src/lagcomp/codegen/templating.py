"""The driver templates' text (``templates/*.py``), read without importing sympy.

Kept apart from `lagcomp.codegen.emit` (which needs sympy to print
kernels): batched Taylor sweeps append templates to a module at sweep time,
in processes that loaded their models from the cache and never import sympy.
"""

from __future__ import annotations

import re
from importlib import resources

#: Template lines between these markers (and the markers) serve only systems with events.
_EVENT_BLOCK = re.compile(r"^[ \t]*# >>> events\n.*?^[ \t]*# <<< events\n", re.DOTALL | re.MULTILINE)


def template(name: str, events: bool = True) -> str:
    """The text of ``templates/<name>.py``, appended to every module (see its docstring).

    Without `events`, the blocks marked ``# >>> events`` ... ``# <<< events``
    are left out: event handling makes the adaptive drivers take about 1.8 s
    longer to compile (DOP853 on the double pendulum, 2.8 s -> 4.7 s), a
    cost only systems that declare events should pay.
    """
    text = resources.files("lagcomp.codegen").joinpath(f"templates/{name}.py").read_text(encoding="utf-8")
    return text if events else _EVENT_BLOCK.sub("", text)
