"""Kernels call the heavy `lagcomp.kernel_support` routines by symbol (`lagcomp.kernel_support.symbol_calls`).

A jitted caller must not hold the routine's code (numba would optimise it again in every kernel), must get the
routine's own results, and must load from numba's cache in a later process, where nothing compiled the routine
before the caller's machine code is loaded.

The case: a block of mass m = 2 resting on a floor (contact gap y, gradient [0, 1]) under gravity, free
accelerations q̈ = [0, −g]: the closed contact holds it, λ = m g, q̈ = 0.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import numpy as np
from numba import njit

from lagcomp.kernel_support import resting

G = 9.81


@njit(cache=False)  # compiled in this process, so that numba keeps its LLVM for inspection
def _block_on_floor(mass, gradients, bias, modes, qdd, forces):
    return resting.closed_contact_accelerations(mass, gradients, bias, modes, qdd, forces, 1.0)


def _arguments():
    return (np.diag([2.0, 2.0]), np.array([[0.0, 1.0]]), np.zeros(1), np.ones(1), np.array([0.0, -G]), np.empty(1))


def test_the_caller_declares_the_routine_and_holds_none_of_its_code():
    args = _arguments()
    assert _block_on_floor(*args) == 0
    symbols = [compiled.fndesc.mangled_name for compiled in resting._closed_contact_accelerations.overloads.values()]
    llvm = _block_on_floor.inspect_llvm(_block_on_floor.signatures[0])
    declarations = [line for line in llvm.splitlines()
                    if line.startswith(("declare", "define")) and any(symbol in line for symbol in symbols)]
    assert declarations and all(line.startswith("declare") for line in declarations), declarations
    assert "held_row_accelerations" not in llvm  # nor what the routine calls


def test_the_caller_gets_the_closed_contact_force_m_g():
    mass, gradients, bias, modes, qdd, forces = _arguments()
    assert _block_on_floor(mass, gradients, bias, modes, qdd, forces) == 0
    assert forces[0] == 2.0 * G and np.array_equal(qdd, [0.0, 0.0])


#: A module whose cached caller calls the routine by symbol; run twice, each in a fresh process.
CALLER = textwrap.dedent(
    """
    import json
    import numpy as np
    from numba import njit
    from lagcomp.kernel_support import resting

    @njit(cache=True)
    def caller(mass, gradients, bias, modes, qdd, forces):
        return resting.closed_contact_accelerations(mass, gradients, bias, modes, qdd, forces, 1.0)

    if __name__ == "__main__":
        forces, qdd = np.empty(1), np.array([0.0, -9.81])
        status = caller(np.diag([2.0, 2.0]), np.array([[0.0, 1.0]]), np.zeros(1), np.ones(1), qdd, forces)
        print(json.dumps({"status": status, "force": forces[0], "qdd": qdd.tolist(),
                          "hits": sum(caller.stats.cache_hits.values()),
                          "misses": sum(caller.stats.cache_misses.values())}))
    """
)


def test_a_later_process_loads_the_caller_from_numbas_cache_and_runs_it(tmp_path):
    """The second process loads the caller's machine code, which calls the routine's symbol: numba must have
    loaded the routine first (its reload_init), else the JIT cannot resolve the call."""
    script = tmp_path / "symbol_caller.py"
    script.write_text(CALLER)

    def run() -> dict:
        out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, cwd=tmp_path, check=False)
        assert out.returncode == 0, out.stderr
        return json.loads(out.stdout.strip().splitlines()[-1])

    first, second = run(), run()
    assert (first["misses"], first["hits"]) == (1, 0) and (second["misses"], second["hits"]) == (0, 1)
    for result in (first, second):
        assert result["status"] == 0 and result["force"] == 2.0 * G and result["qdd"] == [0.0, 0.0]
