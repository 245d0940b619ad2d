r"""Exact first derivatives of a `FirstOrderForm`, compiled once into numerical functions.

For the steady-motion linearization (`lagcomp.analysis.steady`): with fresh
symbols a (the accelerations u̇, n_u of them) and l (the multipliers λ, k of
them) the dynamics are the residuals

    R(q, u, a, l, t) = M a − F − Cᵀ l = 0,     S(q, u, a, t) = C a − γ = 0,

and their derivatives with respect to q and u, differentiated symbolically
(symengine where every function is one it differentiates as sympy does,
sympy otherwise), give the implicit-function-theorem derivatives of
(a, λ) exactly — no finite differences.  Derivatives of sign, Abs,
Heaviside and Piecewise (DiracDelta terms) are taken away from their kinks,
and a point on a kink is refused.  Two compiled functions:

- `point(q, u, p, t)`: N, M, F, C, γ, Φ, Ψ and the Jacobians N_q, N_u, Φ_q,
  Ψ_q, Ψ_u, everything the accelerations and the constraint manifold need, and
  the sizes of Φ and Ψ (`magnitude`: what "Φ = 0" is judged against);
- `residual_partials(q, u, a, l, p, t)`: [R; S]_q and [R; S]_u.

`evaluator(form)` caches them per form (keyed by identity; a form is
immutable), so a parameter sweep compiles once.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
import symengine as se
import sympy as sp

from lagcomp.errors import LinearizationError, ModelError
from lagcomp.mechanics.lagrange import _symengine_maps, symengine_ready
from lagcomp.model.system import t as TIME

#: How many forms keep their compiled functions (least recently used dropped first).
CACHE_SIZE = 16

#: Names of the outputs of `FormJacobians.point`, in order.
POINT_OUTPUTS = ("N", "M", "F", "C", "gamma", "Phi", "Psi", "N_q", "N_u", "Phi_q", "Psi_q", "Psi_u", "Phi_size",
                 "Psi_size")

_cache: OrderedDict = OrderedDict()


@dataclass(frozen=True)
class FormJacobians:
    """The compiled functions of one form (module docstring)."""

    form: object
    _point: object
    _partials: object
    kinks: tuple = ()

    def point(self, q, u, p, t: float) -> dict:
        """N, M, F, C, γ, Φ, Ψ (as matrices) and N_q, N_u, Φ_q, Ψ_q, Ψ_u at (q, u, t), by name.

        Raises LinearizationError at a kink (the argument of a sign, Abs,
        Heaviside or Piecewise condition is 0 there): no derivative exists.
        """
        values = self._point(np.concatenate([q, u, p, [t]]))
        if self.kinks:
            at = np.abs(np.array(values[len(POINT_OUTPUTS)], dtype=float).ravel())
            size = max(1.0, float(np.max(np.abs(np.concatenate([q, u])), initial=0.0)))
            if np.any(at <= 1e-14 * size):
                culprit = self.kinks[int(np.argmin(at))]
                raise LinearizationError(f"The equations are not differentiable at this point: {culprit} = 0 is a "
                                         "kink of a sign, Abs, Heaviside or Piecewise in them. Linearize away from it "
                                         "(e.g. while sliding, not at rest, for Coulomb friction).")
        return {name: np.array(v, dtype=float).reshape(shape) for name, v, shape in
                zip(POINT_OUTPUTS, values, self._point_shapes())}

    def residual_partials(self, q, u, a, l, p, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(∂[R; S]/∂q, ∂[R; S]/∂u) at (q, u, a, λ, t), shapes (n_u + k, n_q) and (n_u + k, n_u)."""
        G_q, G_u, *_ = self._partials(np.concatenate([q, u, a, l, p, [t]]))
        rows = self.form.n_u + self.form.C.rows
        return (np.array(G_q, dtype=float).reshape(rows, self.form.n_q),
                np.array(G_u, dtype=float).reshape(rows, self.form.n_u))

    def input_partials(self, q, u, a, l, p, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(∂N/∂w, ∂[R; S]/∂w) at (q, u, a, λ, t) along the inputs w held constant (`FirstOrderForm.input_names`),
        shapes (n_q, U) and (n_u + k, U)."""
        U = len(self.form.input_names)
        rows = self.form.n_u + self.form.C.rows
        if not U:
            return np.zeros((self.form.n_q, 0)), np.zeros((rows, 0))
        _, _, N_w, G_w = self._partials(np.concatenate([q, u, a, l, p, [t]]))
        return (np.array(N_w, dtype=float).reshape(self.form.n_q, U), np.array(G_w, dtype=float).reshape(rows, U))

    def _point_shapes(self):
        f = self.form
        n_h, n_v = f.Phi.rows, f.Psi.rows
        return ((f.n_q, 1), (f.n_u, f.n_u), (f.n_u, 1), f.C.shape, (f.C.rows, 1), (n_h, 1), (n_v, 1),
                (f.n_q, f.n_q), (f.n_q, f.n_u), (n_h, f.n_q), (n_v, f.n_q), (n_v, f.n_u), (n_h, 1), (n_v, 1))


def evaluator(form) -> FormJacobians:
    """The compiled derivatives of `form`, built on first use and cached."""
    key = id(form)
    if key in _cache and _cache[key].form is form:
        _cache.move_to_end(key)
        return _cache[key]
    built = _build(form)
    _cache[key] = built
    while len(_cache) > CACHE_SIZE:
        _cache.popitem(last=False)
    return built


def _build(form) -> FormJacobians:
    q, u, p = list(form.q), list(form.u), list(form.parameters)
    a = list(sp.symbols(f"_lc_a0:{form.n_u}", real=True))
    l = list(sp.symbols(f"_lc_l0:{form.C.rows}", real=True))
    _check_symbols(form, set(q + u + p + [TIME]))
    a_col, l_col = sp.Matrix(len(a), 1, a), sp.Matrix(len(l), 1, l)
    residual = (form.M * a_col - form.F - form.C.T * l_col).col_join(form.C * a_col - form.gamma)
    plain = [form.N, form.M, form.F, form.C, form.gamma, form.Phi, form.Psi]
    sizes = [form.Phi.applyfunc(magnitude), form.Psi.applyfunc(magnitude)]
    jacobians = [(form.N, q), (form.N, u), (form.Phi, q), (form.Psi, q), (form.Psi, u), (residual, q), (residual, u)]
    w = p[len(p) - len(form.input_names):] if form.input_names else []
    jacobians += [(form.N, w), (residual, w)] if w else []
    point_args, partial_args = q + u + p + [TIME], q + u + a + l + p + [TIME]
    everything = [e for m in plain + [residual] for e in m]
    if symengine_ready(everything):
        to_se, _ = _symengine_maps(set(partial_args).union(*(e.free_symbols for e in everything)))
        image = lambda m: se.Matrix(m.rows, m.cols, [to_se(e) for e in m])  # noqa: E731
        derivs = [image(m).jacobian(se.Matrix([to_se(x) for x in xs])) for m, xs in jacobians]
        point = se.Lambdify([to_se(s) for s in point_args], *[image(m) for m in plain], *derivs[:5],
                            *[image(m) for m in sizes], cse=True, backend=_backend())
        partials = se.Lambdify([to_se(s) for s in partial_args], *derivs[5:], cse=True, backend=_backend())
    else:
        derivs = [sp.Matrix(m).jacobian(xs) for m, xs in jacobians]
        kinks = sorted({d.args[0] for m in derivs for d in m.atoms(sp.DiracDelta)}, key=sp.default_sort_key)
        derivs = [m.replace(sp.DiracDelta, lambda *args: sp.S.Zero) for m in derivs]
        point = _sympy_function(point_args, plain + derivs[:5] + sizes + [sp.Matrix(len(kinks), 1, kinks)])
        partials = _sympy_function(partial_args, derivs[5:])
        return FormJacobians(form, point, partials, tuple(kinks))
    return FormJacobians(form, point, partials)


def magnitude(expr: sp.Expr) -> sp.Expr:
    """The size of the terms `expr` sums, in its own units: sums and products of the magnitudes of its parts, |·|
    of anything else (a function, a quotient), so x² + y² − l² has size x² + y² + l² and R cos q − R has 2 R at
    q = 0.  Its value times ε bounds the rounding of `expr`; a residual is judged against it in any units."""
    if expr.is_Add:
        return sp.Add(*[magnitude(a) for a in expr.args])
    if expr.is_Mul:
        return sp.Mul(*[magnitude(a) for a in expr.args])
    if expr.is_Pow and expr.exp.is_Integer and expr.exp > 0:
        return magnitude(expr.base) ** expr.exp
    return sp.Abs(expr)


def _backend() -> str:
    """symengine's LLVM backend when it was built with it (compiled code), its interpreter otherwise."""
    return "llvm" if getattr(se, "have_llvm", False) else "lambda"


def _sympy_function(args, outputs):
    """One numpy function of the vector `args` returning the matrices `outputs` (sympy's lambdify)."""
    function = sp.lambdify(list(args), [sp.Matrix(m) for m in outputs], modules="numpy", cse=True, dummify=True)
    return lambda x: function(*x)


def _check_symbols(form, allowed: set) -> None:
    """Every free symbol of the form must be a coordinate, speed, parameter or t."""
    parts = [form.N, form.M, form.F, form.C, form.gamma, form.Phi, form.Psi]
    stray = sorted(set().union(*(m.free_symbols for m in parts)) - allowed, key=str)
    if stray:
        raise ModelError(f"The first-order form has symbol(s) {[str(s) for s in stray]} that are neither "
                         f"coordinates {list(form.coordinate_names)}, speeds {list(form.speed_names)}, "
                         f"parameters {[str(s) for s in form.parameters]} nor t; declare them as parameters.")
