"""Taylor coefficients of the solution, by automatic differentiation of the ``rhs`` kernel.

The ``rhs`` kernel of an unconstrained system is a straight-line program:
loads, CSE temporaries, the stores of q̇, M and F, and the LDLᵀ solve of
M q̈ = F.  Split into elementary operations (add, sub, mul, div, square,
sqrt, pow with a constant exponent, exp, log, sin and cos together), every
intermediate value u(t) along the solution has a Taylor series
u(t + τ) = Σ_k u[k] τ^k whose *normalized* coefficients u[k] = u⁽ᵏ⁾/k!
follow from those of its arguments by the standard recurrences
(Moore 1966; Jorba & Zou, Experiment. Math. 14 (2005) 99-117, sec. 3):

    w = a ± b      w[k] = a[k] ± b[k]
    w = a b        w[k] = Σ_{j=0..k} a[j] b[k−j]
    w = a²         w[k] = 2 Σ_{j<k/2} a[j] a[k−j]  (+ a[k/2]² for even k)
    w = a / b      w[k] = (a[k] − Σ_{j=1..k} b[j] w[k−j]) / b[0]
    w = √a         w[k] = (a[k] − Σ_{j=1..k−1} w[j] w[k−j]) / (2 w[0])
    w = a^α        w[k] = Σ_{j=0..k−1} (α (k−j) − j) a[k−j] w[j] / (k a[0])
    w = exp a      w[k] = Σ_{j=1..k} j a[j] w[k−j] / k
    w = log a      w[k] = (a[k] − Σ_{j=1..k−1} j w[j] a[k−j] / k) / a[0]
    s, c = sin a, cos a
                   s[k] = Σ_{j=1..k} j a[j] c[k−j] / k,  c[k] = −Σ_{j=1..k} j a[j] s[k−j] / k

and the state itself from the ODE: y[k+1] = f(y)[k] / (k + 1).  So one pass
over the program per order k, in order k = 0, 1, ..., p − 1, gives the
series of the solution to order p at a point.  Values that depend on the
parameters only are plain scalars computed once (their series is constant);
time, when the equations depend on it, is the series (t, 1, 0, ...): t is
treated as a state whose derivative is 1.  Integer powers become products
(a[0] = 0 is allowed, as for q̇² at rest); other powers use the pow
recurrence, which needs a[0] ≠ 0.

`decompose` writes the program as data, one record per operation
(`lagcomp.codegen.taylor_ops.Op`: kind, series written and read, constant);
`taylor_source` prints it as one numba function
``taylor_coefficients(t, y, p, X, W)`` with each operation written out as
its loop (`taylor_ops.convolution_loop`: numba passes arrays to a called
function with reference counting, which costs more than these short loops:
inline, the double pendulum runs 1.5x faster), each block commented with the
statement of ``rhs`` it computes; plus ``TAYLOR_WORK`` (rows of the work
array ``W``) and ``TAYLOR_PERIODIC``, the data the driver takes with it.
A program of more than `lagcomp.codegen.taylor_split.SPLIT_OPERATIONS`
operations per order has its order loop call chunks of its operations, each
its own numba function (numba's compile time of one function grows as its
size squared).
The driver is library code: ``lagcomp.integrate.drivers.taylor.taylor_run``.
Systems the method does not cover (constraints, or a function without a
recurrence here: sign, Abs, Piecewise, ...) get ``TAYLOR_REFUSED``, a
string saying why, instead.

A module with contacts or friction (modes in p, `lagcomp.ir.ContactModes`) gets one program per set of
held rows (closed contacts, sticking friction elements), each the motion of that mode set
(`_held_rows`: q̈_free corrected by the held rows' multipliers, in series arithmetic), and a
``taylor_coefficients`` that branches on the modes to the current set's (`ModePrograms`), up to
`MODE_PROGRAMS_MAX` sets; beyond, the program of ``rhs_free``, the motion with every contact open.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import sympy as sp

from lagcomp.codegen.periodic import periodic_coordinates
from lagcomp.codegen.printer import to_code
from lagcomp.codegen.taylor_ops import (
    Op,
    Setup,
    partial_name,
    pivot_test,
    setup_statements,
    support_names,
    value_lines,
)
from lagcomp.codegen import taylor_split
from lagcomp.codegen.taylor_split import NJIT, chunked_loop
from lagcomp.ir import ContactModes, Kernel, LinearSolve, ModuleIR, ReturnZero, target_local
from lagcomp.kernel_support.resting import DEPENDENT_CLOSED_CONTACTS

INDENT = "    "


class Unsupported(Exception):
    """The rhs holds something without a Taylor recurrence here (the message says what)."""


@dataclass
class TaylorProgram:
    """The decomposed rhs: scalar setup, the series rows, the per-order body.

    ``setup`` are the statements before the order loop (state rows,
    parameter loads, constants, constant pivot tests), ``rows`` the names of
    the series held in rows of the work array ``W`` (in order), ``body`` the
    operations of one order k; ``periodic`` the coordinates the rhs sees only through sin and cos
    (`lagcomp.codegen.periodic`), which ``taylor_run`` reduces to [−π, π].
    """

    n_state: int
    setup: list[Setup] = field(default_factory=list)
    rows: list[str] = field(default_factory=list)
    body: list[Op] = field(default_factory=list)
    uses_t: bool = False
    periodic: tuple[int, ...] = ()
    #: The series of the held rows' multipliers λ (`_held_rows`), rows 0.. of W: the driver's step bounds them too
    multipliers: tuple[str, ...] = ()

    @property
    def operation_count(self) -> int:
        """Series operations per order (pivot tests and comments not counted)."""
        return sum(1 for op in self.body if op.kind not in ("pivot", "comment"))


@dataclass(frozen=True)
class Value:
    """A value of the program: a series (name of a 1-d array of coefficients) or a scalar constant.

    A constant is a sympy Number or a Symbol naming a scalar local.
    """

    series: str | None = None
    const: sp.Expr | None = None

    @property
    def is_const(self) -> bool:
        return self.series is None


def _c(expr) -> Value:
    return Value(const=sp.sympify(expr))


class _Builder:
    """Turns expressions over the rhs locals into elementary series operations."""

    def __init__(self, n_state: int):
        self.program = TaylorProgram(n_state=n_state)
        self.env: dict[sp.Symbol, Value] = {}
        self.count = 0
        self.sincos: dict[str, tuple[Value, Value]] = {}
        self.memo: dict[tuple, Value] = {}
        self.renamed: dict[str, str] = {}
        self.scalars: dict[sp.Expr, Value] = {}
        #: {parameter local: its index in p}; {scalar name: {parameter index: its partial's name}}
        self.parameters: dict[str, int] = {}
        self.partials: dict[str, dict[int, str]] = {}

    # -- naming ---------------------------------------------------------------------------

    def _new_series(self) -> str:
        name = f"_u{self.count}"
        self.count += 1
        self.program.rows.append(name)
        return name

    def _scalar(self, expr: sp.Expr, name: str | None = None) -> Value:
        """A constant, bound to a scalar local unless it is a number or a symbol already.  The locals of `expr` are
        replaced by the scalars they are bound to: a constant temporary of ``closed_contacts`` is bound under another
        name (``_h``…, `_bind_closed`) than the one its kernel reads, which may also be one of rhs's."""
        expr = sp.sympify(expr)
        expr = expr.xreplace({s: self.env[s].const for s in expr.free_symbols if s in self.env and self.env[s].is_const})
        if name is None and (expr.is_Number or expr.is_Symbol):
            return _c(expr)
        if name is None:
            if expr in self.scalars:
                return self.scalars[expr]
            name = f"_k{self.count}"
            self.count += 1
            self.scalars[expr] = _c(sp.Symbol(name, real=True))
        self.program.setup.append(Setup("constant", name, to_code(expr)))
        self._partials(name, expr)
        return _c(sp.Symbol(name, real=True))

    def _partials(self, name: str, expr: sp.Expr) -> None:
        """Setup statements ``partial`` of the scalar `name` = `expr`: ∂name/∂p_j for every parameter j it
        depends on, by the chain rule over the parameters and scalars in `expr` (their partials named before);
        `lagcomp.codegen.taylor_variational` differentiates the program with respect to parameters with them."""
        for j in sorted(set(self.parameters.values())):
            total = sp.S.Zero
            for symbol in expr.free_symbols:
                if self.parameters.get(symbol.name) == j:
                    inner = sp.S.One
                elif j in self.partials.get(symbol.name, {}):
                    inner = sp.Symbol(self.partials[symbol.name][j], real=True)
                else:
                    continue
                total += sp.diff(expr, symbol) * inner
            if total != 0:
                partial = partial_name(name, j)
                self.partials.setdefault(name, {})[j] = partial
                self.program.setup.append(Setup("partial", partial, to_code(total), index=j))

    def _emit(self, kind: str, out: tuple[str, ...] = (), args: tuple[str, ...] = (), const: str = "",
              index: int = 0) -> None:
        self.program.body.append(Op(kind, out, args, const, index))

    def _op(self, key: tuple, make) -> Value:
        """A series operation; equal operations on the same arguments are computed once."""
        if key not in self.memo:
            w = self._new_series()
            make(w)
            self.memo[key] = Value(series=w)
        return self.memo[key]

    # -- elementary operations on Values -------------------------------------------------

    def add(self, a: Value, b: Value) -> Value:
        if a.is_const and b.is_const:
            return self._scalar(a.const + b.const)
        if a.is_const:
            a, b = b, a
        if b.is_const:
            if b.const == 0:
                return a
            return self._op(("add_c", a.series, b.const), lambda w: self._emit(
                "add_const", (w,), (a.series,), to_code(b.const)))
        key = ("add",) + tuple(sorted((a.series, b.series)))
        return self._op(key, lambda w: self._emit("add", (w,), (a.series, b.series)))

    def neg(self, a: Value) -> Value:
        if a.is_const:
            return self._scalar(-a.const)
        return self._op(("neg", a.series), lambda w: self._emit("neg", (w,), (a.series,)))

    def sub(self, a: Value, b: Value) -> Value:
        if b.is_const:
            return self.add(a, self._scalar(-b.const))
        if a.is_const:
            if a.const == 0:
                return self.neg(b)
            return self._op(("rsub_c", a.const, b.series), lambda w: self._emit(
                "rsub_const", (w,), (b.series,), to_code(a.const)))
        return self._op(("sub", a.series, b.series), lambda w: self._emit("sub", (w,), (a.series, b.series)))

    def mul(self, a: Value, b: Value) -> Value:
        if a.is_const and b.is_const:
            return self._scalar(a.const * b.const)
        if a.is_const:
            a, b = b, a
        if b.is_const:
            if b.const == 1:
                return a
            if b.const == 0:
                return _c(0)
            if b.const == -1:
                return self.neg(a)
            return self._op(("scale", a.series, b.const), lambda w: self._emit(
                "scale", (w,), (a.series,), to_code(b.const)))
        if a.series == b.series:
            return self.square(a)
        key = ("mul",) + tuple(sorted((a.series, b.series)))
        return self._op(key, lambda w: self._emit("mul", (w,), (a.series, b.series)))

    def square(self, a: Value) -> Value:
        if a.is_const:
            return self._scalar(a.const**2)
        return self._op(("sqr", a.series), lambda w: self._emit("square", (w,), (a.series,)))

    def div(self, a: Value, b: Value) -> Value:
        if b.is_const:
            if a.is_const:
                return self._scalar(a.const / b.const)
            return self.mul(a, self._scalar(1 / b.const))
        if a.is_const:
            if a.const == 0:
                return _c(0)
            return self._op(("rdiv", a.const, b.series), lambda w: self._emit(
                "rdiv", (w,), (b.series,), to_code(a.const)))
        return self._op(("div", a.series, b.series), lambda w: self._emit("div", (w,), (a.series, b.series)))

    def sqrt(self, a: Value) -> Value:
        if a.is_const:
            return self._scalar(sp.sqrt(a.const))
        return self._op(("sqrt", a.series), lambda w: self._emit("sqrt", (w,), (a.series,)))

    def pow(self, a: Value, alpha: sp.Expr) -> Value:
        if a.is_const:
            return self._scalar(a.const**alpha)
        if alpha.is_Integer or (alpha.is_Float and alpha == int(alpha)):
            e = int(alpha)
            if e == 0:
                return _c(1)
            if e < 0:
                return self.div(_c(1), self.pow(a, sp.Integer(-e)))
            if e == 1:
                return a
            half = self.pow(a, sp.Integer(e // 2))
            return self.square(half) if e % 2 == 0 else self.mul(self.square(half), a)
        if alpha == sp.S.Half:
            return self.sqrt(a)
        return self._op(("pow", a.series, alpha), lambda w: self._emit(
            "pow", (w,), (a.series,), to_code(sp.Float(alpha, 17))))

    def exp(self, a: Value) -> Value:
        if a.is_const:
            return self._scalar(sp.exp(a.const))
        return self._op(("exp", a.series), lambda w: self._emit("exp", (w,), (a.series,)))

    def log(self, a: Value) -> Value:
        if a.is_const:
            return self._scalar(sp.log(a.const))
        return self._op(("log", a.series), lambda w: self._emit("log", (w,), (a.series,)))

    def sin_cos(self, a: Value) -> tuple[Value, Value]:
        if a.is_const:
            return self._scalar(sp.sin(a.const)), self._scalar(sp.cos(a.const))
        if a.series not in self.sincos:
            s, c = self._new_series(), self._new_series()
            self._emit("sin_cos", (s, c), (a.series,))
            self.sincos[a.series] = (Value(series=s), Value(series=c))
        return self.sincos[a.series]

    # -- expressions ----------------------------------------------------------------------

    def is_const(self, expr) -> bool:
        """Whether `expr` depends on parameters only (its free symbols are bound to scalars)."""
        for s in expr.free_symbols:
            if s not in self.env:
                raise Unsupported(f"unknown local {s}")
            if not self.env[s].is_const:
                return False
        return True

    def value(self, expr: sp.Expr) -> Value:
        """The Value of a sympy expression over the bound locals."""
        if expr.is_Symbol:
            if expr.name == "t":
                self.program.uses_t = True
            self.is_const(expr)
            return self.env[expr]
        if self.is_const(expr):
            return self._scalar(expr)
        if expr.is_Add:
            return self._sum(expr.args)
        if expr.is_Mul:
            return self._product(expr.args)
        if expr.is_Pow:
            base, e = expr.args
            if not self.is_const(e):
                return self.exp(self.mul(self.value(e), self.log(self.value(base))))
            if not e.is_Number:
                e_value = self.value(e)
                return self.exp(self.mul(e_value, self.log(self.value(base))))
            return self.pow(self.value(base), e)
        f = expr.func
        if f in (sp.sin, sp.cos):
            s, c = self.sin_cos(self.value(expr.args[0]))
            return s if f is sp.sin else c
        if f is sp.tan:
            return self.div(*self.sin_cos(self.value(expr.args[0])))
        if f is sp.exp:
            return self.exp(self.value(expr.args[0]))
        if f is sp.log and len(expr.args) == 1:
            return self.log(self.value(expr.args[0]))
        if f in (sp.sinh, sp.cosh, sp.tanh):
            a = self.value(expr.args[0])
            ep, em = self.exp(a), self.exp(self.neg(a))
            if f is sp.tanh:
                return self.div(self.sub(ep, em), self.add(ep, em))
            return self.mul(self.sub(ep, em) if f is sp.sinh else self.add(ep, em), _c(sp.S.Half))
        raise Unsupported(f"the function {f.__name__} (no Taylor recurrence for it)")

    def _sum(self, args) -> Value:
        consts = [a for a in args if self.is_const(a)]
        terms = []
        for a in args:
            if self.is_const(a):
                continue
            coefficient, _ = a.as_coeff_Mul()
            terms.append((-1, self.value(-a)) if coefficient.is_negative else (1, self.value(a)))
        terms.sort(key=lambda term: term[0] < 0)  # a positive term first when there is one
        sign, acc = terms[0]
        if sign < 0:
            acc = self.neg(acc)
        for sign, v in terms[1:]:
            acc = self.add(acc, v) if sign > 0 else self.sub(acc, v)
        if consts:
            acc = self.add(acc, self.value(sp.Add(*consts)))
        return acc

    def _product(self, args) -> Value:
        consts = [a for a in args if self.is_const(a)]
        numerator, denominator = [], []
        for a in args:
            if self.is_const(a):
                continue
            if a.is_Pow and a.exp.is_Number and a.exp.is_negative:
                denominator.append(a.base if a.exp == -1 else a.base ** (-a.exp))
            else:
                numerator.append(a)
        c = self.value(sp.Mul(*consts)) if consts else _c(1)
        num = den = None
        for a in numerator:
            v = self.value(a)
            num = v if num is None else self.mul(num, v)
        for a in denominator:
            v = self.value(a)
            den = v if den is None else self.mul(den, v)
        if den is None:
            return self.mul(num, c)
        if num is None:
            return self.div(c, den)
        return self.mul(self.div(num, den), c)

    def bind(self, name: str, expr: sp.Expr) -> Value:
        """The Value of the statement ``name = expr`` of rhs; its last new series is renamed `name`."""
        if self.is_const(expr):
            return self._scalar(expr, name)
        self._emit("comment", const=f"{name} = {to_code(expr)}")
        return self.name(self.value(expr), name)

    def name(self, v: Value, name: str, start: int | None = None) -> Value:
        """Call the series `v` `name` if this statement created it; else `v` as it is (an alias)."""
        if v.is_const or v.series in self.renamed or not v.series.startswith("_u"):
            return v
        self.renamed[v.series] = name
        return v


def _factor(b: _Builder, m: list[list[Value]], tag: str = "", status: int | None = None) -> tuple[list, dict]:
    """The LDLᵀ factors (d, l) of the symmetric matrix whose lower triangle is `m` (Values), series named with
    `tag`: the factorization ``_unrolled_ldlt`` emits, in series arithmetic.  The pivots are tested at order 0
    (the value at t): a pivot j that is not positive returns `status` there (default j + 1, as ``rhs`` does)."""
    n = len(m)
    d, low = [], {}
    for j in range(n):
        dj = m[j][j]
        for k in range(j):
            dj = b.sub(dj, b.mul(b.square(low[j, k]), d[k]))
        if dj.is_const:
            dj = b._scalar(dj.const, f"_d{tag}{j}") if not dj.const.is_Symbol else dj
        else:
            dj = b.name(dj, f"_d{tag}{j}")
        d.append(dj)
        mjj = m[j][j]
        index = j + 1 if status is None else status
        if dj.is_const:     # then so is m_jj (d_j is m_jj minus terms that vanish)
            b.program.setup.append(Setup("check", code=pivot_test(to_code(dj.const), to_code(mjj.const)), index=index))
        elif mjj.is_const:
            b._emit("pivot", args=(dj.series,), const=to_code(mjj.const), index=index)
        else:
            b._emit("pivot", args=(dj.series, mjj.series), index=index)
        for i in range(j + 1, n):
            lij = m[i][j]
            for k in range(j):
                lij = b.sub(lij, b.mul(b.mul(low[i, k], low[j, k]), d[k]))
            low[i, j] = b.name(b.div(lij, dj), f"_l{tag}{i}_{j}")
    return d, low


def _substitute(b: _Builder, d: list[Value], low: dict, f: list[Value], tag: str = "") -> list[Value]:
    """x of L D Lᵀ x = f by forward and back substitution (series named with `tag`)."""
    n = len(d)
    z = []
    for i in range(n):
        zi = f[i]
        for k in range(i):
            zi = b.sub(zi, b.mul(low[i, k], z[k]))
        z.append(b.name(zi, f"_z{tag}{i}"))
    x = [None] * n
    for i in reversed(range(n)):
        xi = b.div(z[i], d[i])
        for k in range(i + 1, n):
            xi = b.sub(xi, b.mul(low[k, i], x[k]))
        x[i] = b.name(xi, f"_x{tag}{i}")
    return x


def _load(b: _Builder, local: str, source: str) -> None:
    """Bind the kernel load ``local = source`` ("y[i]": a state series, "p[i]": a parameter scalar)."""
    symbol = sp.Symbol(local, real=True)
    array, index = source[0], int(source[2:-1])    # the IR loads "y[i]" and "p[i]"
    b.program.setup.append(Setup("state" if array == "y" else "param", local, index=index))
    b.env[symbol] = Value(series=local) if array == "y" else _c(symbol)
    if array != "y":
        b.parameters[local] = index


def decompose(rhs: Kernel, n: int, closed: Kernel | None = None, held: tuple[int, ...] = ()) -> TaylorProgram:
    """The Taylor program of an unconstrained ``rhs`` kernel (n coordinates, state size 2n); with the module's
    ``closed_contacts`` kernel `closed`, the program of the motion that holds its rows `held` (`_held_rows`).

    `rhs` either solves M q̈ = F (`lagcomp.ir.LinearSolve`: a Lagrange module's) or stores every component of
    f = (q̇, q̈) itself (`lagcomp.ir.ReturnZero`: an explicit q̈, as the articulated-body algorithm of a kinematic
    tree gives it, `lagcomp.codegen.tree_taylor`).  Raises `Unsupported` for anything without a recurrence here.
    """
    if isinstance(rhs.solve, ReturnZero):
        return _explicit_program(rhs, n, closed, held)
    if not isinstance(rhs.solve, LinearSolve):
        raise Unsupported("constraints (the augmented system is solved with pivoting)")
    b, derivative = _bound_kernel(rhs, n)
    m = [[b.env[sp.Symbol(target_local(rhs.solve.m[i][j]), real=True)] for j in range(i + 1)] for i in range(n)]
    f = [b.env[sp.Symbol(target_local(rhs.solve.f[i]), real=True)] for i in range(n)]
    b._emit("comment", const="Solve M x = f by LDLᵀ; a non-positive pivot means M is singular here.")
    d, low = _factor(b, m)
    accelerations = _substitute(b, d, low, f)
    multipliers = ()
    if held:
        _bind_closed(b, closed)
        accelerations, multipliers = _held_rows(b, closed, held, d, low, accelerations)
    for i, v in enumerate(accelerations):
        derivative[rhs.solve.offset + i] = v
    return _finished(b, rhs, n, derivative, multipliers, closed)


def _bound_kernel(rhs: Kernel, n: int) -> tuple[_Builder, list]:
    """A builder with the loads, temporaries and stores of `rhs` bound: the Values of its ``out[i]`` stores in
    the list (None where `rhs` leaves the component to its solve)."""
    b = _Builder(2 * n)
    for local, source in rhs.loads:
        _load(b, local, source)
    b.env[sp.Symbol("t", real=True)] = Value(series="_t")
    for name, expr in rhs.temps:
        b.env[sp.Symbol(name, real=True)] = b.bind(name, expr)
    derivative = [None] * (2 * n)
    for target, expr in rhs.stores:
        if target.startswith("out["):
            derivative[int(target[4:-1])] = b.value(expr)
        else:
            local = target_local(target)
            b.env[sp.Symbol(local, real=True)] = b.bind(local, expr)
    return b, derivative


def _explicit_program(rhs: Kernel, n: int, closed: Kernel | None = None, held: tuple[int, ...] = ()) -> TaylorProgram:
    """The Taylor program of an ``rhs`` that stores all of f itself (no solve: `decompose`); with the rows `held`
    of ``closed_contacts`` `closed`, its q̈ corrected by their multipliers (`_held_rows`).

    Such an rhs (a tree's articulated-body algorithm) has no factors of M, which `_held_rows` needs for M⁻¹ G_Aᵀ:
    they come from the ``_mass`` stores of `closed` (M by the composite-rigid-body algorithm, the M whose factors
    the tree's own ``closed_contacts`` solves with at run time, `lagcomp.kernel_support.resting`), factored by
    the same series LDLᵀ as a Lagrange module's M (`_factor`).  The articulated-body algorithm run with unit test
    forces (one more recursion per held row, q̈(Gᵀ e_a) − q̈(0)) would avoid the O(n³) factorization, but its
    columns would not be the run time's M⁻¹ Gᵀ to rounding, and the held rows' programs are for trees of few
    coordinates (at most `MODE_PROGRAMS_MAX` mode sets); the factors are computed only in the programs that hold
    some row.
    """
    if rhs.helpers:
        raise Unsupported("an rhs whose steps are outlined into helper functions (build its program from the "
                          "un-outlined kernel)")
    b, derivative = _bound_kernel(rhs, n)
    missing = [i for i, v in enumerate(derivative) if v is None]
    if missing:
        raise Unsupported(f"an rhs that does not store the components {missing} of f")
    multipliers = ()
    if held:
        _bind_closed(b, closed)
        b._emit("comment", const="M of closed_contacts (the composite-rigid-body algorithm's), factored by LDLᵀ.")
        d, low = _factor(b, _closed_mass(b, closed, n))
        derivative[n:], multipliers = _held_rows(b, closed, held, d, low, derivative[n:])
    return _finished(b, rhs, n, derivative, multipliers, closed)


def _bind_closed(b: _Builder, closed: Kernel) -> None:
    """Bind the loads of ``closed_contacts`` `closed` that rhs has not, and its temporaries (renamed ``_h``…: the
    two kernels' temporaries share names; rhs's Values are built, so its bindings may be shadowed)."""
    for local, source in closed.loads:
        if sp.Symbol(local, real=True) not in b.env:
            _load(b, local, source)
    for name, expr in closed.temps:
        b.env[sp.Symbol(name, real=True)] = b.bind(f"_h{name}", expr)


def _closed_mass(b: _Builder, closed: Kernel, n: int) -> list[list[Value]]:
    """The lower triangle of M from the ``_mass[i, j]`` stores of `closed` (bound by `_bind_closed`; an entry it
    does not store is 0)."""
    m = [[_c(0)] * (i + 1) for i in range(n)]
    for target, expr in closed.stores:
        array, index = target[:-1].split("[")
        if array == "_mass":
            i, j = (int(k) for k in index.split(", "))
            m[i][j] = b.bind(f"_m{i}_{j}", expr)
    return m


def _finished(b: _Builder, rhs: Kernel, n: int, derivative: list, multipliers, closed: Kernel | None) -> TaylorProgram:
    """The program of `b`: the state's recurrences y[k + 1] = f[k]/(k + 1) from `derivative` appended, the series
    renamed after the statements of `rhs` that form them, the held rows' `multipliers` and the periodic
    coordinates recorded."""
    b._emit("comment", const="The state's next coefficient: y[k + 1] = f[k]/(k + 1).")
    for i, v in enumerate(derivative):
        if v.is_const:
            b._emit("state", const=to_code(v.const), index=i)
        else:
            b._emit("state", args=(v.series,), index=i)
    b.program.body = [op.renamed(b.renamed) for op in b.program.body]
    b.program.rows = [b.renamed.get(row, row) for row in b.program.rows]
    series = [b.renamed.get(v.series, v.series) for v in multipliers if not v.is_const]
    b.program.multipliers = tuple(dict.fromkeys(name for name in series if name in b.program.rows))
    b.program.periodic = periodic_coordinates(rhs, n)
    if closed is not None:      # (the reduction to [−π, π] applies to every mode's program)
        b.program.periodic = tuple(i for i in b.program.periodic if i in periodic_coordinates(closed, n))
    return b.program


def _held_rows(b: _Builder, closed: Kernel, held: tuple[int, ...], d: list[Value], low: dict,
               free: list[Value]) -> tuple[list[Value], list[Value]]:
    """q̈ with the rows `held` of ``closed_contacts`` (closed contacts, sticking friction elements: G_A q̈ + b_A = 0)
    held, from q̈_free `free` and the LDLᵀ factors (d, low) of M, in series arithmetic
    (`lagcomp.kernel_support.resting.held_row_accelerations`, written out for one set of rows):

        q̈ = q̈_free + M⁻¹ G_Aᵀ λ_A,    W_AA λ_A = −(G_A q̈_free + b_A),    W_AA = G_A M⁻¹ G_Aᵀ.

    λ_A has either sign: a series cannot clip a pulling contact (as ``rhs``'s stages do), and needs not, since
    a closed contact's event is its λ, located on the series where it turns negative (`ModePrograms`).  A W_AA
    pivot that is not positive at order 0 returns `DEPENDENT_CLOSED_CONTACTS`, as ``rhs`` does.  `closed`'s loads and
    temporaries are bound (`_bind_closed`).  Returns (q̈, λ_A).
    """
    n = len(free)
    gradients = {r: [_c(0)] * n for r in held}
    biases = {}
    for target, expr in closed.stores:
        array, index = target[:-1].split("[")
        row = int(index.split(", ")[0])
        if row not in gradients:
            continue
        if array == "_gradient":
            j = int(index.split(", ")[1])
            gradients[row][j] = b.bind(f"_g{row}_{j}", expr)
        elif array == "_bias":
            biases[row] = b.bind(f"_b{row}", expr)

    def dot(u: list[Value], v: list[Value], start: Value) -> Value:
        total = start
        for ui, vi in zip(u, v, strict=True):
            total = b.add(total, b.mul(ui, vi))
        return total

    b._emit("comment", const=f"Rows {list(held)} held: W λ = −(G q̈_free + b), W = G M⁻¹ Gᵀ; q̈ = q̈_free + M⁻¹ Gᵀ λ.")
    columns = [_substitute(b, d, low, gradients[r], tag=f"h{r}_") for r in held]     # M⁻¹ G_aᵀ
    delassus = [[dot(gradients[r], columns[c], _c(0)) for c in range(a + 1)] for a, r in enumerate(held)]
    residual = [b.neg(dot(gradients[r], free, biases.get(r, _c(0)))) for r in held]
    b._emit("comment", const=f"W's pivots: one not positive means dependent held rows (status "
                             f"{DEPENDENT_CLOSED_CONTACTS}).")
    dw, lw = _factor(b, delassus, tag="w", status=DEPENDENT_CLOSED_CONTACTS)
    multipliers = _substitute(b, dw, lw, residual, tag="w")
    accelerations = [b.name(dot([column[i] for column in columns], multipliers, free[i]), f"_a{i}") for i in range(n)]
    return accelerations, multipliers


#: The docstring of ``taylor_coefficients`` (lines).
COEFFICIENTS_DOC = (
    '"""Normalized Taylor coefficients X[i, k] = y_i⁽ᵏ⁾(t)/k!, k = 0..order (order = X.shape[1] − 1),',
    "of the solution through y at t; W is a work array of shape (TAYLOR_WORK, order + 1).",
    "",
    "One pass over the operations of `rhs` per order k (lagcomp.codegen.taylor gives the",
    "recurrences); each block is commented with the statement of `rhs` it computes.",
    'Returns 0, or j > 0 when pivot j of the LDLᵀ factorization of M is not positive at t."""',
)


def emit_taylor(program: TaylorProgram, split_operations: int | None = None,
                chunk_operations: int | None = None) -> str:
    """The source of ``taylor_coefficients``, ``TAYLOR_WORK`` and ``TAYLOR_PERIODIC`` for `program` (in chunks of
    `chunk_operations` above `split_operations` series operations per order: `lagcomp.codegen.taylor_split`, whose
    ``SPLIT_OPERATIONS`` and ``CHUNK_OPERATIONS`` are the defaults)."""
    return (_coefficients_function(program, "taylor_coefficients", COEFFICIENTS_DOC, split_operations,
                                   chunk_operations)
            + _taylor_data(program.operation_count, len(program.rows) + program.uses_t, program.periodic))


def _coefficients_function(program: TaylorProgram, name: str, doc: tuple[str, ...],
                           split_operations: int | None = None, chunk_operations: int | None = None) -> str:
    """The source of the njit function `name`(t, y, p, X, W) that writes the coefficients of `program`: its order
    loop written out, or calling its chunks of `chunk_operations` when it has more than `split_operations` series
    operations per order (`lagcomp.codegen.taylor_split`, whose constants are the defaults, read at each call)."""
    split_operations = taylor_split.SPLIT_OPERATIONS if split_operations is None else split_operations
    chunk_operations = taylor_split.CHUNK_OPERATIONS if chunk_operations is None else chunk_operations
    multipliers = list(program.multipliers)
    rows = multipliers + (["_t"] if program.uses_t else []) + [row for row in program.rows if row not in multipliers]
    states = {s.name: s.index for s in program.setup if s.kind == "state"}
    array_of = {**{name: "W" for name in rows}, **{name: "X" for name in states}}

    def at(name: str, index) -> str:
        """Coefficient `index` of the series `name`: its row of X or W (indexing the 2-d arrays directly
        instead of through row views is 8% faster: no views to build and count references to)."""
        return f"{array_of[name]}[{name}, {index}]"
    row_lines = {**{name: f"{name} = {i}" for name, i in states.items()},
                 **{row: f"{row} = {i}" for i, row in enumerate(rows)}}
    split = program.operation_count > split_operations
    lines = [*doc, "order = X.shape[1] - 1", *setup_statements(program.setup, indent=INDENT)]
    if split:       # (the chunks define the rows they use)
        lines += [row_lines["_t"]] if program.uses_t else []
    else:
        lines.append("# Row indices: a state component's series is a row of X, an intermediate value's a row of W.")
        lines += list(row_lines.values())
    lines += [f"for i in range({program.n_state}):", f"{INDENT}X[i, 0] = y[i]"]
    if program.uses_t:
        lines += ["for k in range(order + 1):", f"{INDENT}{at('_t', 'k')} = 0.0", f"{at('_t', 0)} = t",
                  "if order > 0:", f"{INDENT}{at('_t', 1)} = 1.0"]
    parts = ""
    if split:
        scalars = [s.name for s in program.setup if s.kind in ("param", "constant")]
        parts, loop = chunked_loop(name, program.body, at, row_lines, scalars, chunk_operations)
        lines += loop
    else:
        reciprocals = "_ik = 1.0/k if k > 0 else 0.0  # 1/k and 1/(k + 1): one division each per order"
        lines += ["for k in range(order):", INDENT + reciprocals, f"{INDENT}_ik1 = 1.0/(k + 1)"]
        lines += [INDENT + line for op in program.body for line in value_lines(op, at)]
    lines.append(f"return {-len(multipliers)}" if multipliers else "return 0")
    body = "\n".join(INDENT + line if line else "" for line in lines)
    return f'{parts}\n\n{NJIT}\ndef {name}(t, y, p, X, W):\n{body}\n'


def _taylor_data(operations: int, rows: int, periodic: tuple[int, ...]) -> str:
    """``TAYLOR_WORK`` (`rows` of the work array, `operations` series operations per order) and
    ``TAYLOR_PERIODIC``."""
    return (
        "\n\n"
        f"#: Rows of the work array of `taylor_coefficients` ({operations} series operations "
        "per order).\n"
        f"TAYLOR_WORK = {max(rows, 1)}\n\n"
        "#: The coordinates (state indices) the rhs sees only through sin and cos: taylor_run evaluates the\n"
        "#: series with them reduced to [−π, π] (lagcomp.codegen.periodic).\n"
        f"TAYLOR_PERIODIC = np.array({list(periodic)}, dtype=np.int64)\n"
    )


def emit_mode_programs(modes: ModePrograms) -> str:
    """``taylor_coefficients`` of a module with modes: one function per set of held rows, and
    ``taylor_coefficients`` branching on the mode slots of p to the one of the current set; its data, with
    ``TAYLOR_MODE_PROGRAMS``."""
    solve = modes.modes
    parts = []
    for mask, program in enumerate(modes.programs):
        held = modes.held(mask)
        doc = (f'"""`taylor_coefficients` while the rows {list(held)} of closed_contacts are held (closed contacts,',
               'sticking friction elements), the others not; returns as taylor_coefficients does."""')
        parts.append(_coefficients_function(program, f"_taylor_held_{mask}", doc))
    tests = [f"p[{solve.first + r}] != 0.0" for r in range(solve.count)]
    tests += [f"p[{solve.friction_slot(f)}] == 0.0" for f in range(len(solve.frictions))]
    lines = [*COEFFICIENTS_DOC[:-1],
             "Branches on the modes in p to the program of the rows held now (bit r of _held: row r of",
             "closed_contacts, a closed contact or a sticking friction element, is held).",
             "Returns 0; −c when rows 0..c−1 of W hold the series (orders 0..order−1) of the held rows'",
             "multipliers λ, whose steps taylor_run bounds as the state's (λ of a body at rest may vary",
             "while the state does not); j > 0 when pivot j of the LDLᵀ factorization of M is not positive",
             'at t, or DEPENDENT_CLOSED_CONTACTS (lagcomp.kernel_support.resting) when the held rows are dependent."""',
             "_held = 0"]
    for r, test in enumerate(tests):
        lines += [f"if {test}:", f"{INDENT}_held += {1 << r}"]
    for mask in range(len(modes.programs) - 1):
        lines += [f"if _held == {mask}:", f"{INDENT}return _taylor_held_{mask}(t, y, p, X, W)"]
    lines.append(f"return _taylor_held_{len(modes.programs) - 1}(t, y, p, X, W)")
    body = "\n".join(INDENT + line if line else "" for line in lines)
    parts.append(f"\n\n{NJIT}\n"
                 f"def taylor_coefficients(t, y, p, X, W):\n{body}\n")
    operations = max(program.operation_count for program in modes.programs)
    rows = max(len(program.rows) + program.uses_t for program in modes.programs)
    periodic = tuple(sorted(set.intersection(*(set(program.periodic) for program in modes.programs))))
    return "".join(parts) + _taylor_data(operations, rows, periodic) + (
        "\n#: The programs `taylor_coefficients` branches to, one per set of held rows (lagcomp.codegen.taylor).\n"
        f"TAYLOR_MODE_PROGRAMS = {len(modes.programs)}\n")


#: The most programs one ``taylor_coefficients`` of a module with modes branches to (2^rows, rows its contacts and
#: friction elements): beyond, its program is the motion with every row free, and its Taylor runs keep contacts
#: open and refuse friction (`lagcomp.integrate.contacts`).
MODE_PROGRAMS_MAX = 8


@dataclass
class ModePrograms:
    """The Taylor programs of a module with modes (`lagcomp.ir.ContactModes` `modes`): ``programs[mask]`` holds the
    rows r of ``closed_contacts`` with bit r of mask set (contacts first, then friction elements).

    Each is the symbolic motion of its mode set (`_held_rows`); the drivers switch programs where ``event_reset``
    switches modes.  Within a step a held contact's λ is not clipped at 0 as ``rhs``'s stages clip it: its event,
    λ, is a function of the state on the series' dense output, whose sign change the drivers locate, and the
    program of the next step has the contact open.  A step whose λ dips below 0 and back within it (between the
    drivers' samples of its dense output) would miss that lift-off, as an embedded method misses a bounce that
    short.
    """

    modes: ContactModes
    programs: list[TaylorProgram]

    def held(self, mask: int) -> tuple[int, ...]:
        """The rows held by program `mask`."""
        return tuple(r for r in range(self.modes.rows) if mask >> r & 1)


def taylor_decomposition(ir: ModuleIR) -> TaylorProgram | ModePrograms | Unsupported:
    """The Taylor program of `ir` (programs, with modes), or the `Unsupported` saying why it has none (computed
    once per module)."""
    try:
        if ir.k:
            raise Unsupported("constraints (their multipliers are not covered)")
        if ir.input_names:
            raise Unsupported("inputs supplied at run time (their tables' Taylor coefficients are not emitted)")
        if not any(kernel.name == "rhs_free" for kernel in ir.kernels):
            return decompose(ir.kernel("rhs"), ir.n)
        return held_programs(ir.kernel("rhs_free"), ir.kernel("closed_contacts"), ir.n)
    except Unsupported as err:
        return err


def held_programs(free: Kernel, closed: Kernel, n: int) -> TaylorProgram | ModePrograms:
    """The programs of a module with modes: one per set of held rows of ``closed_contacts`` `closed` (`ModePrograms`),
    each `free` (``rhs_free``, the motion with every row free; n coordinates) corrected by its rows; or the program of
    `free` alone, whose runs keep contacts open and refuse friction, beyond `MODE_PROGRAMS_MAX` sets or with friction
    pressed by a contact (its slip force is a column of the held rows, `lagcomp.kernel_support.resting`, not a term
    of rhs_free that the programs of the held rows would take).  Raises `Unsupported` as `decompose` does."""
    modes = closed.solve
    if 2 ** modes.rows > MODE_PROGRAMS_MAX or any(d >= 0 for d in modes.pressing):
        return decompose(free, n)
    programs = ModePrograms(modes, [])
    programs.programs = [decompose(free, n, closed, programs.held(mask)) for mask in range(2 ** modes.rows)]
    return programs


def taylor_program(taylor: TaylorProgram | Unsupported) -> dict | None:
    """The program as plain data (JSON), or None when the module has none.

    Stored with the module (cache metadata): `lagcomp.codegen.taylor_lanes`
    writes batched kernels of any order from it, without sympy.  ``setup``
    and ``body`` hold the fields of `Setup` and `Op`; ``states`` the series
    name of each state component, in order.
    """
    if isinstance(taylor, Unsupported | ModePrograms):     # (batched sweeps, variational: one program)
        return None
    states = [None] * taylor.n_state
    for statement in taylor.setup:
        if statement.kind == "state":
            states[statement.index] = statement.name
    return dict(n_state=taylor.n_state, setup=[dataclasses.asdict(s) for s in taylor.setup], states=states,
                uses_t=taylor.uses_t, body=[dataclasses.asdict(op) for op in taylor.body],
                operations=taylor.operation_count, periodic=list(taylor.periodic), parameter_partials=True)


def taylor_source(taylor: TaylorProgram | Unsupported) -> str:
    """``taylor_coefficients`` with its data, or ``TAYLOR_REFUSED`` saying why the module has none.

    The driver is library code (`lagcomp.integrate.drivers.taylor`).
    """
    if isinstance(taylor, Unsupported):
        return f"\n\n#: Why this module has no Taylor integrator (method='taylor').\nTAYLOR_REFUSED = {str(taylor)!r}\n"
    if isinstance(taylor, ModePrograms):
        return emit_mode_programs(taylor)
    return emit_taylor(taylor)


def taylor_support_names(taylor: TaylorProgram | Unsupported) -> set[str]:
    """The `lagcomp.kernel_support` names ``taylor_coefficients`` calls (none without a program)."""
    if isinstance(taylor, Unsupported):
        return set()
    programs = taylor.programs if isinstance(taylor, ModePrograms) else [taylor]
    checks = any(statement.kind == "check" for program in programs for statement in program.setup)
    return support_names({op.kind for program in programs for op in program.body}, checks, lanes=False)
