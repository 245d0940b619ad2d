"""A fresh Python process that reports which generated kernels numba compiled: the probe behind the tests of
kernels on demand (tests/test_on_demand.py, test_multibody_on_demand.py, test_multibody_jacobians.py).

numba's "numba:compile" events fire on compilation only, never on a load from its disk cache, so a process that
records them says what a feature built, and a second process on the same cache says what it reused.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

#: The opening of a probe script: a listener that appends ``[module, function]`` of every generated kernel numba
#: compiles to the list ``compiled``, then ``import lagcomp as lc``.  The script that follows reads its arguments
#: from ``sys.argv[1:]`` and prints its report as JSON on its last line.
LISTENER = textwrap.dedent("""
    import json, sys
    from pathlib import Path
    from numba.core import event

    compiled = []

    class Compiles(event.Listener):
        def on_start(self, ev):
            function = ev.data["dispatcher"].py_func
            if function.__module__.startswith("lagcomp_generated_"):
                compiled.append([function.__module__, function.__name__])

        def on_end(self, ev):
            pass

    event.register("numba:compile", Compiles())
    import lagcomp as lc
""")


def run_probe(script: str, *args) -> tuple[dict, list[str]]:
    """Run `LISTENER` followed by `script` (dedented) in a new process with this one's ``sys.path`` and `args` as
    its ``sys.argv[1:]``; the JSON of its last printed line, and the lines printed before it."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    source = LISTENER + textwrap.dedent(script)
    done = subprocess.run([sys.executable, "-c", source, *map(str, args)], capture_output=True, text=True, env=env,
                          timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    lines = done.stdout.strip().splitlines()
    return json.loads(lines[-1]), lines[:-1]
