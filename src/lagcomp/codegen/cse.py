"""One kernel's stores through one common-subexpression elimination: `cse_kernel`.

symengine does the CSE when every expression allows it (`symengine_cse`, with a chain's sines and
cosines of angle differences expanded where that saves calls: `angle_sums`), sympy otherwise; either
way the result is sympy expressions over the kernel's locals (`SympyFromSymengine`).
"""

from __future__ import annotations

import symengine as se
import sympy as sp

from lagcomp.errors import ModelError
from lagcomp.ir import Kernel
from lagcomp.mechanics.lagrange import symengine_ready
from lagcomp.model.inputs import MAX_ORDER, is_input


def cse_kernel(name, doc, args, stores, mapping, loads, solve=None) -> Kernel:
    """CSE the stores together and keep only the loads the code uses.

    Expressions are sympy's, or symengine's over the same symbols
    (`lagcomp.codegen.jacobian_blocks.acceleration_partials`,
    `lagcomp.codegen.constrained_jacobian.residual_partials`).
    """
    targets = [target for target, _ in stores]
    exprs = [e if isinstance(e, se.Basic) else sp.sympify(e) for _, e in stores]
    signals = {key: local for key, local in mapping.items() if not isinstance(key, sp.Symbol)}
    if signals:  # inputs u(t), u̇(t), ... become their locals first (xreplace takes a derivative whole), so that
        # what is left is symbols and functions symengine knows: its fast path applies to the rest
        exprs = [e if isinstance(e, se.Basic) else e.xreplace(signals) for e in exprs]
        refuse_high_derivatives(exprs, name)
    if symengine_ready([e for e in exprs if not isinstance(e, se.Basic)]):
        temps, reduced = symengine_cse(exprs, mapping)
    else:
        exprs = [e.xreplace(mapping) for e in exprs]
        temps, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("_c", real=True), order="canonical")
    used = set().union(*(e.free_symbols for e in reduced), *(e.free_symbols for _, e in temps))
    used_names = {s.name for s in used}
    needed = tuple((local, src) for local, src in loads if local in used_names)
    return Kernel(
        name=name, doc=doc, args=args, loads=needed,
        temps=tuple((s.name, e) for s, e in temps),
        stores=tuple(zip(targets, reduced)), solve=solve,
    )


def refuse_high_derivatives(exprs: list, kernel: str) -> None:
    """Refuse an input derivative of order above `MAX_ORDER` left after binding the others (its pieces are
    cubic: the kernels evaluate up to the third derivative)."""
    for e in exprs:
        left = [d for d in e.atoms(sp.Derivative) if is_input(d.expr)]
        if left:
            raise ModelError(f"The {kernel} kernel needs {left[0]}: lagcomp evaluates inputs' derivatives up to "
                             f"order {MAX_ORDER} (their tables are piecewise cubic).")


def symengine_cse(exprs: list, mapping: dict) -> tuple[list, list]:
    """`sympy.cse` of `exprs` after renaming by `mapping`, done by symengine: 10-100× faster on
    long chains, with no more operations.  Temporaries are ``_c0, _c1, ...``; every symbol
    comes back real, as in the sympy path."""
    rename = {se.sympify(k): se.Symbol(v.name) for k, v in mapping.items()}
    images = [se.sympify(e).xreplace(rename) for e in exprs]
    angles = angle_sums(images)
    pairs, reduced = se.cse([e.xreplace(angles) for e in images] if angles else images)
    symbols = {str(symbol): sp.Symbol(f"_c{k}", real=True) for k, (symbol, _) in enumerate(pairs)}
    back = SympyFromSymengine(symbols)
    return [(symbols[str(s)], back(e)) for s, e in pairs], [back(e) for e in reduced]


def angle_sums(images: list) -> dict:
    """sin and cos of ±a ± b (a, b symbols) as products of sin and cos of a and b, where that
    leaves fewer calls of sin and cos: a chain's sin(θi − θj) and cos(θi − θj) for every pair,
    n(n − 1) calls, become products of the 2n values sin θi, cos θi.  A call costs 10-20 ns at
    run time, a product about 1 ns; the double pendulum (4 calls either way) is left as it is.
    """
    trig = set().union(*(e.atoms(se.sin, se.cos) for e in images))
    sums = {}
    for f in trig:
        terms = f.args[0].as_coefficients_dict()
        angles = {s: c for s, c in terms.items() if c != 0}
        if len(angles) == 2 and all(isinstance(s, se.Symbol) and c in (1, -1) for s, c in angles.items()):
            sums[f] = angles
    singles = {g(s) for angles in sums.values() for s in angles for g in (se.sin, se.cos)}
    if len((trig - sums.keys()) | singles) >= len(trig):
        return {}
    replacement = {}
    for f, angles in sums.items():
        (a, ca), (b, cb) = sorted(angles.items(), key=lambda item: str(item[0]))
        sin_a, sin_b = ca * se.sin(a), cb * se.sin(b)  # sin(±a) = ±sin a
        if type(f).__name__ == "sin":
            replacement[f] = sin_a * se.cos(b) + se.cos(a) * sin_b
        else:
            replacement[f] = se.cos(a) * se.cos(b) - sin_a * sin_b
    return replacement


class SympyFromSymengine:
    """Converts symengine expressions back to sympy, a symbol named x becoming `symbols`[x]
    (by default the real symbol x), subexpressions converted once."""

    FUNCTIONS = {"sin": sp.sin, "cos": sp.cos, "tan": sp.tan, "cot": sp.cot, "exp": sp.exp, "log": sp.log,
                 "sinh": sp.sinh, "cosh": sp.cosh, "tanh": sp.tanh, "asin": sp.asin, "acos": sp.acos,
                 "atan": sp.atan, "atan2": sp.atan2}

    def __init__(self, symbols: dict):
        self.symbols = symbols
        self.memo: dict = {}

    def __call__(self, image):
        done = self.memo.get(image)
        if done is None:
            done = self.memo[image] = self._convert(image)
        return done

    def _convert(self, image):
        if isinstance(image, se.Symbol):
            name = str(image)
            if name not in self.symbols:
                self.symbols[name] = sp.Symbol(name, real=True)
            return self.symbols[name]
        if isinstance(image, se.Add):
            return sp.Add(*map(self, image.args))
        if isinstance(image, se.Mul):
            return sp.Mul(*map(self, image.args))
        if isinstance(image, se.Pow):
            return sp.Pow(*map(self, image.args))
        function = self.FUNCTIONS.get(type(image).__name__)
        if function is not None:
            return function(*map(self, image.args))
        return sp.sympify(image)  # a number or a constant (pi, E)
