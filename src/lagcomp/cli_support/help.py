"""What the subcommands' help says that is shared: the MODEL argument, the examples each shows, common flags."""

from __future__ import annotations

import argparse

#: What a MODEL argument may be (`lagcomp.cli_support.models`).
MODEL_HELP = ("a bundled example (lagcomp list), else a model compiled earlier under that name; or a file "
              "path/to/model.py[:NAME] or module package.module[:NAME] defining a System (NAME: the System, or a "
              "function returning one; without it, the one System the file defines). A model of yours named like "
              "a bundled example: --cached, or its file")

#: Commands each subcommand's help shows; `tests/test_cli_user_models.py` runs every one from the repository's
#: root (the files under examples/cli/ are there).
EXAMPLES = {
    "show": ["lagcomp show double_pendulum", "lagcomp show examples/cli/cart_pole.py --latex"],
    "run": ["lagcomp run double_pendulum --t-end 5 --param g=9.81 --out run.npz",
            "lagcomp run examples/cli/cart_pole.py --input F=examples/cli/push.csv --out run.csv --plot run.png",
            "lagcomp run examples/cli/cart_pole.py:cart_pole --config examples/cli/cart_pole.toml --input F=0.5"],
    "sweep": ["lagcomp sweep simple_pendulum --grid theta=0.1:1.5:8 --t-end 5 --out sweep.csv",
              ("lagcomp sweep examples/cli/cart_pole.py --param m=0.1:0.5:3 --input F=examples/cli/push.csv "
               "--out sweep.nc")],
    "bench": [("lagcomp bench examples/cli/cart_pole.py --input F=1.0 --methods rk4 dop853 --repeats 1 "
               "--steps 2000")],
    "stability": ["lagcomp stability hoop_bead --param Omega --range 1 8 --set epsilon=0 --q 3.14159265",
                  ("lagcomp stability examples/cli/cart_pole.py:pendulum_on_cart --arg pushed=0 --param l "
                   "--range 0.2 1 --num 5 --q 0 0")],
    "animate": ["lagcomp animate double_pendulum -o double_pendulum.gif --t-end 2 --fps 15",
                "lagcomp animate examples/cli/cart_pole.py --config examples/cli/cart_pole.toml -o cart_pole.html"],
}


def examples_epilog(command: str) -> str:
    """The ``examples:`` block of `command`'s help."""
    return "examples:\n" + "\n".join(f"  {line}" for line in EXAMPLES[command])


def initial_state_flags(p: argparse.ArgumentParser) -> None:
    """--param, --q0 and --qd0, as run, bench and animate take them."""
    p.add_argument("--param", action="append", metavar="K=V", help="parameter value, e.g. g=9.81")
    p.add_argument("--q0", type=float, nargs="+", help="initial coordinates (default: the model's)")
    p.add_argument("--qd0", type=float, nargs="+",
                   help="initial velocities q̇ (Lagrange models: one per coordinate; default: the model's, else 0)")
