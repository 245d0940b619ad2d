"""What the equations as LaTeX and text (``EQUATIONS``, `lagcomp.codegen.latex`) add to generated modules.

    python -m bench.bench_equations_size              # every bundled example and a 10-link chain
    python -m bench.bench_equations_size --bicycle    # and the Whipple bicycle (Kane; about 15 s more)

For each model: the module's size without the constant, what the constant adds (bytes and percent),
the time sympy takes to render it, and how many sides of equations were omitted for their length
(`lagcomp.codegen.latex.MAX_CHARACTERS`).  Sizes only; nothing is compiled by numba.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from lagcomp import examples
from lagcomp.codegen.emit import emit
from lagcomp.codegen.latex import OMITTED, equations_source, kane_equations, lagrange_equations
from lagcomp.codegen.lower import lower
from lagcomp.mechanics.lagrange import derive


def _row(name: str, base: int, equations, seconds: float) -> tuple[int, int]:
    added = len(equations_source(equations).encode())
    omitted = sum(OMITTED[0] in side for e in equations for side in (e.lhs, e.rhs))
    print(f"{name:32s} {base:8d} B  +{added:7d} B ({100 * added / base:5.1f}%)  render {seconds:5.2f} s  "
          f"omitted sides {omitted}/{2 * len(equations)}")
    return base, added


def _lagrange(system) -> tuple[int, int]:
    eom = derive(system)
    base = len(emit(lower(eom)).encode())
    start = time.perf_counter()
    equations = lagrange_equations(eom)
    return _row(system.name, base, equations, time.perf_counter() - start)


def _bicycle() -> None:
    from lagcomp.codegen.kane import emit_kane
    from lagcomp.mechanics.kane import auxiliary_reactions, kane_energy, kane_form

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    import kane_models

    km, _, _ = kane_models.bicycle()
    form = kane_form(km)
    energy = kane_energy(km, form)
    names, reactions = auxiliary_reactions(km, form)
    start = time.perf_counter()
    equations = kane_equations(form, energy)
    seconds = time.perf_counter() - start
    source, _ = emit_kane("whipple_bicycle", form, energy, names, reactions)
    _row("whipple_bicycle (Kane)", len(source.encode()) - len(equations_source(equations).encode()), equations,
         seconds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bicycle", action="store_true", help="also the Whipple bicycle (about 15 s)")
    args = parser.parse_args()
    total = [0, 0]
    for factory in examples.EXAMPLES.values():
        base, added = _lagrange(factory())
        total[0] += base
        total[1] += added
    print(f"{'bundled examples':32s} {total[0]:8d} B  +{total[1]:7d} B ({100 * total[1] / total[0]:5.1f}%)")
    _lagrange(examples.get("n_link_pendulum", n=10))
    if args.bicycle:
        _bicycle()


if __name__ == "__main__":
    main()
