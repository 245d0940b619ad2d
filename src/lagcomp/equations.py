r"""A model's equations as LaTeX and plain text: what `Model.equations()` returns (no sympy here).

sympy renders the equations once, when the model is compiled (`lagcomp.codegen.latex`), and the
generated module keeps them as data, the constant ``EQUATIONS``: one `Equation` per line, as
plain strings.  So a model from the cache (`lagcomp.load`, which never imports sympy) shows
the same equations as a fresh build.

The lines of a Lagrange model, in order (the normal form of `lagcomp.mechanics.lagrange`):

- ``motion``, one per coordinate q_i: Σ_j M_ij q̈_j = F_i + Σ_k Λ_ki λ_k, the multipliers
  λ_k named ``lambda_<constraint>``;
- ``constraint``, one per constraint: Φ_k = 0 (holonomic) or Σ_i Λ_ki q̇_i + b_k = 0;
- ``energy``: T and V as the system states them.

A Kane model (`lagcomp.kane_model`) has ``kinematics`` q̇_i = N_i first, then ``motion``
M u̇ = F per row (sympy's mass matrix and forcing), ``constraint`` Φ = 0 and Ψ = 0, and
``energy`` T + V where it could be formed.

A kinematic tree (`lagcomp.Tree`) has its recursion, never expanded (`lagcomp.codegen.tree_latex`):
``tree``, a table of its nodes (parent, link, joint, coordinate, axis, placement X_i, motion
subspace S_i, inertia I_i, joint force τ_i), then ``motion``, the articulated-body algorithm in
Featherstone's notation over that table (with loops: M q̈ = F + Λᵀλ, M and F by their recursions),
``constraint``, the loops' Φ_k = 0, and ``energy``, T = ½ Σ v_iᵀ I_i v_i and V.

A side of an equation whose LaTeX is longer than `lagcomp.codegen.latex.MAX_CHARACTERS` is
replaced by a marker, ``\text{[omitted: longer than 4000 characters]}`` (the same without
``\text`` in the text), so that a large system's module stays small.
"""

from __future__ import annotations

from typing import NamedTuple

#: The parts of a model's equations, in the order they are listed.
PARTS = ("tree", "kinematics", "motion", "constraint", "energy")
#: How each part is headed in the plain text (`Equations.__str__`).
HEADINGS = {"tree": "Kinematic tree (nodes i = 1..n, parents first; the base is node 0)",
            "kinematics": "Kinematic differential equations", "motion": "Equations of motion",
            "constraint": "Constraints", "energy": "Energy"}


class Equation(NamedTuple):
    """One line of a model's equations: ``lhs = rhs``.

    part : str
        One of `PARTS`.
    label : str
        What the line is about: a coordinate (``motion``, ``kinematics``; a tree's node in ``tree``), a
        constraint's name, ``T``, ``V``, ``T + V`` (``energy``), or the quantity a line of a tree's
        recursion defines.
    lhs, rhs : str
        The two sides in LaTeX (sympy's `latex`), math mode without delimiters.
    text : str
        The whole equation as plain text (sympy's `str`; q̇ written ``q_dot``, q̈ ``q_ddot``).
    """

    part: str
    label: str
    lhs: str
    rhs: str
    text: str


class Equations:
    """The equations of the model `name`: `latex`, `lines`, ``str()``, and Jupyter's `_repr_latex_`.

    Iterating gives the `Equation` lines; `part` selects one kind of them.
    """

    def __init__(self, name: str, equations):
        self.name = name
        self.equations = tuple(Equation(*e) for e in equations)

    def __iter__(self):
        return iter(self.equations)

    def __len__(self) -> int:
        return len(self.equations)

    def part(self, part: str) -> tuple[Equation, ...]:
        """The lines of one of `PARTS`, in order."""
        if part not in PARTS:
            raise ValueError(f"`part` is one of {PARTS}, got {part!r}.")
        return tuple(e for e in self.equations if e.part == part)

    @property
    def lines(self) -> tuple[str, ...]:
        """One LaTeX line per equation, ``lhs &= rhs`` (the alignment point at the equals sign)."""
        return tuple(f"{e.lhs} &= {e.rhs}" for e in self.equations)

    @property
    def latex(self) -> str:
        r"""The equations as an ``align*`` environment (amsmath), ready to paste into a LaTeX document."""
        return "\\begin{align*}\n" + " \\\\\n".join(self.lines) + "\n\\end{align*}"

    def _repr_latex_(self) -> str:
        """What Jupyter renders: display math with an ``aligned`` block (MathJax and KaTeX)."""
        return "$$\\begin{aligned}\n" + " \\\\\n".join(self.lines) + "\n\\end{aligned}$$"

    def __str__(self) -> str:
        blocks = []
        for part in PARTS:
            lines = self.part(part)
            if lines:
                blocks.append(f"{HEADINGS[part]}:\n" + "\n".join(f"  {e.text}" for e in lines))
        return f"Equations of {self.name!r}\n\n" + "\n\n".join(blocks)

    def __repr__(self) -> str:
        counts = ", ".join(f"{len(self.part(p))} {p}" for p in PARTS if self.part(p))
        return f"Equations({self.name!r}: {counts})"
