r"""Render a model's equations as LaTeX and plain text with sympy, for its generated module (`EQUATIONS`).

`lagrange_equations(eom)` and `kane_equations(form, energy)` give the `lagcomp.equations.Equation`
lines (their order and content: `lagcomp.equations`); `equations_source` writes them into the
generated module as a tuple of string tuples, which `Model.equations()` reads without sympy.

Names are printed the way sympy's `latex` prints a symbol of the user's name (``theta1`` as
``\theta_{1}``, ``x_a`` as ``x_{a}``); a velocity puts a dot on the name's base, before its
subscripts (``\dot{\theta}_{1}``), an acceleration two; the multiplier of constraint ``rod`` is
the symbol ``lambda_rod`` (``\lambda_{rod}``).  M, F, Λ and b are the tidied expressions the
kernels are made from (`lagcomp.mechanics.lagrange.derive`); Φ, T and V are as the system states
them.  In the text (sympy's `str`), q̇ is ``<name>_dot`` and q̈ ``<name>_ddot``, the labels of
lagcomp's results.
"""

from __future__ import annotations

import sympy as sp
from sympy.printing.conventions import split_super_sub
from sympy.printing.str import StrPrinter

from lagcomp.equations import Equation
from lagcomp.model.system import t

#: A side of an equation longer than this in LaTeX is replaced by a marker (`OMITTED`): the bicycle's mass
#: matrix and forcing would be tens of kilobytes each, which nobody reads and every import of its module loads.
MAX_CHARACTERS = 4000
#: What stands for such a side, in LaTeX and in the text.
OMITTED = (rf"\text{{[omitted: longer than {MAX_CHARACTERS} characters]}}",
           f"[omitted: longer than {MAX_CHARACTERS} characters]")


def _surely_too_long(terms) -> bool:
    """Whether `terms` have more than MAX_CHARACTERS nodes together (each prints as a character at least):
    such a side is omitted without printing it, which for the bicycle took seconds."""
    budget = MAX_CHARACTERS
    for term in terms:
        for _ in sp.preorder_traversal(term):
            budget -= 1
            if budget < 0:
                return True
    return False


def symbol_latex(name: str) -> str:
    """How sympy's `latex` prints a symbol named `name`."""
    return sp.latex(sp.Symbol(name))


def dotted_latex(name: str, accent: str) -> str:
    r"""The LaTeX of `name` with `accent` (``\dot``, ``\ddot``) on its base, before its sub- and superscripts."""
    base = split_super_sub(name)[0]
    whole, bare = symbol_latex(name), symbol_latex(base) if base else ""
    if bare and whole.startswith(bare):
        return f"{accent}{{{bare}}}{whole[len(bare):]}"
    return f"{accent}{{{whole}}}"


class TextPrinter(StrPrinter):
    """sympy's `str` with some symbols printed under other names (velocities, accelerations, multipliers)."""

    def __init__(self, names: dict):
        super().__init__()
        self.names = names

    def _print_Symbol(self, expr) -> str:
        return self.names.get(expr) or super()._print_Symbol(expr)

    _print_Dummy = _print_Symbol


class _Renderer:
    """Sides and equations in LaTeX and text, under the names of `names`: symbol -> (LaTeX, text)."""

    def __init__(self, names: dict, signals: dict | None = None):
        self.latex_names = {s: latex for s, (latex, _) in names.items()}
        self.text = TextPrinter({s: text for s, (_, text) in names.items()})
        self.signals = signals or {}  # inputs u(t), u̇(t), ... -> their symbols (xreplace takes a derivative whole)

    def side(self, *terms) -> tuple[str, str]:
        """(LaTeX, text) of the sum of `terms`, each printed by sympy and joined in order (F, then Λᵀλ), or
        `OMITTED` when the LaTeX would be longer than MAX_CHARACTERS."""
        terms = [term for term in (sp.sympify(x).xreplace(self.signals) for x in terms) if term != 0]
        if _surely_too_long(terms):
            return OMITTED
        latex = _joined([sp.latex(term, symbol_names=self.latex_names) for term in terms])
        if len(latex) > MAX_CHARACTERS:
            return OMITTED
        return latex, _joined([self.text.doprint(term) for term in terms])

    def equation(self, part: str, label: str, lhs, rhs) -> Equation:
        """The `Equation` lhs = rhs; a side given as a tuple is the sum of its terms (`side`)."""
        (left, left_text), (right, right_text) = (self.side(*x) if isinstance(x, tuple) else self.side(x)
                                                  for x in (lhs, rhs))
        return Equation(part, label, left, right, f"{left_text} = {right_text}")


def _joined(printed: list[str]) -> str:
    """The printed terms of a sum, joined by `` + ``, or by `` - `` where a term starts with a minus."""
    if not printed:
        return "0"
    return printed[0] + "".join(f" - {p[1:].lstrip()}" if p.startswith("-") else f" + {p}" for p in printed[1:])


def _products(row, symbols) -> sp.Expr:
    """Σ_j row_j symbols_j (the symbols non-commutative: sympy prints each after its coefficient)."""
    return sp.Add(*(entry * symbol for entry, symbol in zip(row, symbols, strict=True)))


def _state_names(names, q, qd, qdd=()) -> dict:
    """symbol -> (LaTeX, text) of coordinates `q`, their velocities `qd` and accelerations `qdd` (if given)
    under the user's `names`."""
    found = {}
    for name, coordinate, velocity in zip(names, q, qd, strict=True):
        found[coordinate] = (symbol_latex(name), name)
        found[velocity] = (dotted_latex(name, r"\dot"), f"{name}_dot")
    for name, acceleration in zip(names, qdd, strict=False):  # (no accelerations: Kane's coordinates)
        found[acceleration] = (dotted_latex(name, r"\ddot"), f"{name}_ddot")
    return found


#: The accents and text suffixes of an input's derivatives, by order (`_input_names`).
_INPUT_ACCENTS = ((None, ""), (r"\dot", "_dot"), (r"\ddot", "_ddot"), (r"\dddot", "_dddot"))


def _input_names(inputs) -> tuple[dict, dict]:
    r"""Each input u(t) (`lagcomp.Input`) and its derivatives up to the third, written like the coordinates:
    (replacements u(t), u̇(t), ... -> symbols, symbol -> (LaTeX, text)), so that a support motion reads
    ``\ddot{x}_{s}`` rather than sympy's d²/dt² x_s(t)."""
    replacements, names = {}, {}
    for u in inputs:
        name = u.func.__name__
        for order, (accent, suffix) in enumerate(_INPUT_ACCENTS):
            symbol = sp.Dummy(f"{name}{suffix}")
            replacements[u.diff(t, order) if order else u] = symbol
            names[symbol] = (dotted_latex(name, accent) if accent else symbol_latex(name), f"{name}{suffix}")
    return replacements, names


def lagrange_equations(eom) -> tuple[Equation, ...]:
    """The lines of Lagrange's equations `eom` (a `lagcomp.mechanics.lagrange.EOM`): motion, constraints, energy."""
    names = eom.system.coordinate_names
    qdd = tuple(sp.Dummy(f"{name}_ddot", commutative=False) for name in names)
    multipliers = tuple(sp.Dummy(f"lambda_{name}", commutative=False) for name in eom.constraint_names)
    symbols = _state_names(names, eom.q, eom.qd, qdd)
    symbols.update({lam: (symbol_latex(f"lambda_{name}"), f"lambda_{name}")
                    for lam, name in zip(multipliers, eom.constraint_names, strict=True)})
    signals, signal_names = _input_names(eom.system.inputs)
    symbols.update(signal_names)
    render = _Renderer(symbols, signals)
    lines = [render.equation("motion", name, _products(eom.M.row(i), qdd),
                             (eom.F[i], _products(eom.C.col(i), multipliers)))
             for i, name in enumerate(names)]
    holonomic = iter(eom.Phi)
    for k, name in enumerate(eom.constraint_names):
        residual = next(holonomic) if eom.holonomic[k] else _products(eom.C.row(k), eom.qd) + eom.b[k]
        lines.append(render.equation("constraint", name, residual, 0))
    lines += [render.equation("energy", name, sp.Symbol(name), value) for name, value in (("T", eom.T), ("V", eom.V))]
    return tuple(lines)


def kane_equations(form, energy=None) -> tuple[Equation, ...]:
    """The lines of Kane's equations `form` (a `FirstOrderForm` of `lagcomp.mechanics.kane.kane_form`) and their
    `energy` T + V (None when it could not be formed): kinematics, motion, constraints, energy."""
    qd = tuple(sp.Dummy(f"{name}_dot") for name in form.coordinate_names)
    ud = tuple(sp.Dummy(f"{name}_dot", commutative=False) for name in form.speed_names)
    symbols = {**_state_names(form.coordinate_names, form.q, qd), **_state_names(form.speed_names, form.u, ud)}
    render = _Renderer(symbols)
    lines = [render.equation("kinematics", name, velocity, form.N[i])
             for i, (name, velocity) in enumerate(zip(form.coordinate_names, qd, strict=True))]
    lines += [render.equation("motion", name, _products(form.M.row(i), ud), form.F[i])
              for i, name in enumerate(form.speed_names)]
    lines += [render.equation("constraint", f"configuration_{i}", residual, 0) for i, residual in enumerate(form.Phi)]
    lines += [render.equation("constraint", f"velocity_{i}", residual, 0) for i, residual in enumerate(form.Psi)]
    if energy is not None:
        lines.append(render.equation("energy", "T + V", sp.Symbol("T") + sp.Symbol("V"), energy))
    return tuple(lines)


def _literal(text: str) -> str:
    """`text` as a Python string literal: raw (LaTeX reads as written) when it can be, else `repr`."""
    if '"' in text or text.endswith("\\") or not text.isprintable():
        return repr(text)
    return f'r"{text}"' if "\\" in text else f'"{text}"'


def equations_source(equations: tuple[Equation, ...]) -> str:
    """The module constant ``EQUATIONS`` holding `equations`, with the comment that says what it is."""
    rows = "".join(f"    ({_literal(part)}, {_literal(label)},\n" + "".join(f"     {_literal(x)},\n" for x in rest[:-1])
                   + f"     {_literal(rest[-1])}),\n" for part, label, *rest in equations)
    return (
        "\n\n#: The equations as LaTeX and text, rendered by sympy when this module was generated\n"
        "#: (lagcomp.codegen.latex), for Model.equations(): (part, label, LaTeX lhs, LaTeX rhs, text) per line.\n"
        f"EQUATIONS = (\n{rows})\n"
    )
