"""Cheap simplification of derived expressions: Fu's rules on sums of sines and cosines, nothing else expanded.

Lagrange's equations of a chain written in Cartesian form are full of
l1 l2 (sin θ1 sin θ2 + cos θ1 cos θ2) and m l² (sin² θ + cos² θ); two of Fu's
rules (TR5, TR10i) turn them into l1 l2 cos(θ1 − θ2) and m l², which pays off
in operation count.  They need the sums multiplied out, and multiplying out
is harmless for sums of sines and cosines but costs accuracy elsewhere: a
squared distance (x1 − x2)² expanded to x1² − 2 x1 x2 + x2² cancels when two
bodies come close.  So everything here works on the expression with its
other structure (differences, norms, powers, other functions) held in
placeholders (`_kept_structure`), and puts it back unchanged.
"""

from __future__ import annotations

import symengine as se
import sympy as sp
from sympy.simplify.fu import TR5, TR10i

__all__ = ["tidy", "tidy_small", "tidy_symengine", "TIDY_MAX_TERMS", "TIDY_MAX_OPS", "TIDY_MAX_GROUPS"]

#: Expressions with more terms than this (expanded) are not simplified (see `tidy`).
TIDY_MAX_TERMS = 400
#: The energies are simplified only up to this many operations (see `tidy_small`).
TIDY_MAX_OPS = 300
#: Fu's rules run on at most this many groups of terms (see `tidy`).
TIDY_MAX_GROUPS = 60


def _kept_structure(expr, variables, backend=sp) -> tuple:
    """`expr` with the parts that must not be expanded replaced by placeholders, and the map back.

    Expanding is what Fu's rules need to see l1 l2 (sin θ1 sin θ2 + cos θ1 cos θ2)
    as separate products, and it is harmless for sums of sines and cosines.
    Elsewhere it costs accuracy: a squared distance (x1 − x2)² multiplied out
    to x1² − 2 x1 x2 + x2², or a force G m1 m2 (x2 − x1)/r³ split into
    G m1 m2 x2/r³ − G m1 m2 x1/r³, cancels when the bodies come close.  So a
    sum over the `variables` is kept whole (a placeholder) unless each of its
    terms in the variables holds a sine or cosine; so is a power of the
    variables with an exponent other than a positive integer (r⁻³, √·) and
    any call of another function.  `backend` is sympy or symengine (the
    expression's own); the placeholders are Dummies or fresh symbols of it.
    """
    return _Keeper({backend.sympify(v) for v in variables}, backend).run(backend.sympify(expr))


class _Keeper:
    """The walk of `_kept_structure`, with the dependence on the variables and the
    trigonometric test memoized per subexpression (each is linear in the tree then)."""

    def __init__(self, names: set, backend):
        self.names, self.backend = names, backend
        self.kept: dict = {}
        self.memo: dict = {}
        self.dependent: dict = {}
        self.trig: dict = {}

    def run(self, expr) -> tuple:
        result = self.walk(expr)
        return result, {placeholder: original for original, placeholder in self.kept.items()}

    def depends(self, e) -> bool:
        found = self.dependent.get(e)
        if found is None:
            found = self.dependent[e] = (e in self.names) if not e.args else any(map(self.depends, e.args))
        return found

    def walk(self, e):
        if not e.args or not self.depends(e):
            return e
        done = self.memo.get(e)
        if done is None:
            done = self.memo[e] = self._rebuilt(e)
        return done

    def _rebuilt(self, e):
        b = self.backend
        if isinstance(e, (b.sin, b.cos)):
            return e  # its argument is not expanded (sp.expand's trig=False)
        if isinstance(e, b.Pow) and not _positive_integer(e.args[1]):
            return self.placeholder(e)
        if isinstance(e, b.Add) and not self.trigonometric_sum(e):
            return self.placeholder(e)
        if not isinstance(e, (b.Add, b.Mul, b.Pow)):
            return self.placeholder(e)  # another function: kept whole
        args = [self.walk(a) for a in e.args]
        return e if all(x is y for x, y in zip(args, e.args)) else e.func(*args)

    def placeholder(self, e):
        if e not in self.kept:
            self.kept[e] = sp.Dummy() if self.backend is sp else se.Symbol(f"_lagcomp_kept{len(self.kept)}")
        return self.kept[e]

    def trigonometric_sum(self, e) -> bool:
        """Whether each term of the sum `e` that depends on the variables holds a sine or cosine of them."""
        return all(self.trigonometric(term) for term in e.args if self.depends(term))

    def trigonometric(self, factor) -> bool:
        found = self.trig.get(factor)
        if found is None:
            b = self.backend
            if isinstance(factor, (b.sin, b.cos)):
                found = True
            elif isinstance(factor, b.Pow):
                found = _positive_integer(factor.args[1]) and self.trigonometric(factor.args[0])
            elif isinstance(factor, b.Mul):
                found = any(self.trigonometric(f) for f in factor.args)
            else:
                found = isinstance(factor, b.Add) and self.trigonometric_sum(factor)
            self.trig[factor] = found
        return found


def _positive_integer(x) -> bool:
    return isinstance(x, (sp.Integer, se.Integer)) and x > 0


def tidy(expr: sp.Expr, variables) -> sp.Expr:
    """Cheap simplification that pays off in operation count (e.g. sin²+cos² → 1).

    Two of Fu's rules (far cheaper than a full `trigsimp`): chains of links
    written in Cartesian form give l1 l2 (sin θ1 sin θ2 + cos θ1 cos θ2), which
    becomes l1 l2 cos(θ1 − θ2), and m l² (sin² θ + cos² θ), which becomes m l².
    The rules are quadratic in the number of terms, so they run on the
    expression grouped by its factors that depend on the `variables` (q, q̇,
    t), each group's coefficient a single placeholder: Σ_a m_a l1² sin²θ1 +
    Σ_a m_a l1² cos²θ1 is c sin²θ1 + c cos²θ1 for them, whatever the number
    of masses.  The result is kept only when it has no more operations than
    the input; expressions with more than TIDY_MAX_TERMS terms once expanded
    are left alone (CSE recovers much of the sharing anyway).  Only sums of
    sines and cosines are expanded: the structure that keeps a kernel
    accurate (differences, norms, powers) is kept whole (`_kept_structure`).
    """
    expr = sp.sympify(expr)
    if expr.is_Atom or (expr.is_Add and len(expr.args) > TIDY_MAX_TERMS):
        return expr
    expr = _collected(expr, variables)
    compact, kept = _kept_structure(expr, variables)
    variables = (*variables, *kept)
    if not compact.is_Add and not any((f.is_Add or (f.is_Pow and f.base.is_Add)) and f.has(*variables)
                                      for f in sp.Mul.make_args(compact)):
        return expr  # a single term in the variables: nothing to combine
    groups: dict = {}
    for term in sp.Add.make_args(compact):  # expand only the parts that depend on the variables
        coefficient, factor = term.as_independent(*variables, as_Add=False)
        for part in sp.Add.make_args(sp.expand(factor)):
            c, f = part.as_independent(*variables, as_Add=False)
            groups.setdefault(f, []).append(coefficient * c)
    if sum(map(len, groups.values())) > TIDY_MAX_TERMS:
        return expr
    result = _tidy_groups(groups).xreplace(kept)
    return result if sp.count_ops(result) <= sp.count_ops(expr) else expr


def _collected(expr: sp.Expr, variables) -> sp.Expr:
    """`expr` with the terms of its top-level sum that share their factor in the `variables` summed
    first: a₁ x + a₂ x + … becomes (a₁ + a₂ + …) x.  Nothing is expanded, so no cancellation in the
    variables is introduced; without it a sum that `_kept_structure` keeps whole (the gradient of
    Σ_a a x²/2, a linear sum over many parameters) would cost one product per term at run time."""
    if not expr.is_Add:
        return expr
    groups: dict = {}
    for term in expr.args:
        coefficient, factor = term.as_independent(*variables, as_Add=False)
        groups.setdefault(factor, []).append(coefficient)
    if len(groups) == len(expr.args):
        return expr
    return sp.Add(*(_common_factor(coefficients) * factor for factor, coefficients in groups.items()))


def tidy_small(expr: sp.Expr, variables) -> sp.Expr:
    """`tidy` for expressions of at most TIDY_MAX_OPS operations, others as they are: the energies,
    from T as written, can expand to thousands of terms for a long chain."""
    return expr if sp.count_ops(expr) > TIDY_MAX_OPS else tidy(expr, variables)


def tidy_symengine(image, variables, to_sympy) -> sp.Expr:
    """`tidy` of the symengine expression `image` (over `variables`, symengine symbols), expanded
    and grouped in symengine (no large sympy expression is ever built), the structure
    `_kept_structure` keeps left whole; `to_sympy` converts back."""
    compact, kept = _kept_structure(image, variables, backend=se)
    names = {*variables, *kept}
    image = se.expand(compact)
    groups: dict = {}
    for term in (image.args if isinstance(image, se.Add) else (image,)):
        factors = term.args if isinstance(term, se.Mul) else (term,)
        dependent = [f for f in factors if f.free_symbols & names]
        key = se.Mul(*dependent)
        groups.setdefault(key, []).append(se.Mul(*(f for f in factors if not f.free_symbols & names)))
    back = {to_sympy(k): to_sympy(v) for k, v in kept.items()}
    if sum(map(len, groups.values())) > TIDY_MAX_TERMS:
        return to_sympy(image).xreplace(back)
    return _tidy_groups({to_sympy(f): [to_sympy(c) for c in cs] for f, cs in groups.items()}).xreplace(back)


def _tidy_groups(groups: dict) -> sp.Expr:
    """Σ_f (Σ groups[f]) f, simplified by Fu's rules over placeholders for the coefficients (`tidy`)."""
    placeholders: dict = {}
    compact = []
    for factor, coefficients in groups.items():
        coefficient = _common_factor(coefficients)
        if coefficient != 0:
            compact.append(placeholders.setdefault(coefficient, sp.Dummy()) * factor)
    compact = sp.Add(*compact)
    if len(groups) <= TIDY_MAX_GROUPS:
        tidied = sp.expand(TR5(compact))  # sin² → 1 − cos², so sin² + cos² cancels
        tidied = sp.factor_terms(TR10i(tidied))  # cos a cos b + sin a sin b → cos(a − b)
        if sp.count_ops(tidied) <= sp.count_ops(compact):
            compact = tidied
    return compact.xreplace({placeholder: c for c, placeholder in placeholders.items()})


def _common_factor(terms: list) -> sp.Expr:
    """Σ terms with the symbolic factors common to all of them taken out (a cheap `factor_terms`).

    l1² m1 + l1² m2 + l1² m3 becomes l1² (m1 + m2 + m3).  Only positive
    integer powers are taken out, and a numeric coefficient only when all
    terms have the same one.
    """
    if len(terms) < 2:
        return sp.Add(*terms)
    split = [term.as_coeff_Mul() for term in terms]
    powers = [rest.as_powers_dict() for _, rest in split]
    common = {}
    for base, exp in powers[0].items():
        exps = [p.get(base, 0) for p in powers]
        if all(e.is_Integer and e > 0 for e in map(sp.sympify, exps)):
            common[base] = min(exps)
    numbers = {c for c, _ in split}
    number = numbers.pop() if len(numbers) == 1 else sp.S.One
    if not common and number == 1:
        return sp.Add(*terms)
    inner = [c / number * sp.Mul(*(b**(e - common.get(b, 0)) for b, e in p.items())) for (c, _), p in zip(split, powers)]
    return number * sp.Mul(*(b**e for b, e in common.items())) * sp.Add(*inner)
