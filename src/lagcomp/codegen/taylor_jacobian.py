r"""The sensitivities' series from the series of the Jacobian's entries: the variational kernel heyoka's way.

`lagcomp.codegen.taylor_variational` differentiates every operation of the Taylor program in every sensitivity
column (forward mode): a column costs about a program.  The variational equations S' = J S (+ ∂f/∂p) need less:
with the series of J's nonzero entries along the solution, column c's coefficients are

    Ṡ_i[k] = Σ_j Σ_{m=0..k} J_ij[m] S_j[k−m]  (+ ∂f_i/∂p[k] for a parameter's column),   S_i[k+1] = Ṡ_i[k]/(k+1),

nnz(J) convolutions per column.  The series of J's column j is a sweep of the program's tangents in direction
e_j with the state's tangent held at the constant unit series (not evolved: then u̇ = ∂u/∂y_j along y(t), a
series like any other), once per order for all columns; ∂f/∂p_j's the same sweep from the scalars' partials
(the setup's ``partial`` statements), with the state's tangent 0.  heyoka's ``var_ode_sys`` differentiates the
ODE symbolically and decomposes J's entries with CSE; a sweep gets the same simplifications as it writes the
code, by carrying each tangent as a sum of terms rather than a series:

* ``one``: c δ_k0 (the unit series of the direction's own state; a constant's partial);
* ``value``: c u, a value series of the program times a scalar (c code: a number, a scalar, their product);
* ``slot``: c T, a series the sweep computes (a row of W after the values').

A linear operation combines terms; a product with a ``one`` term is a ``value`` one (sin θ's tangent in θ's
direction is cos θ itself, no convolution); only products of two series are convolutions, each computed once
per kernel into a slot (sin(θ₁ − θ₂)'s partials in θ₁ and θ₂ are one series but for the sign: the sweeps share
it); a tangent of several series is convolved term by term when the directions share those convolutions
(a parameter's tangents are multiples of a few value series: ∂f₀/∂p_j = a_j sin θ₁ + b_j u, for every j), else
summed into a slot first (one convolution); an operation whose tangent is 0 in a direction (it does not depend
on it) has no code there.  The quotient, root, power and log keep their tangent recurrences
(`lagcomp.codegen.taylor_variational`), one direction at a time, the quotient's w ⊛ ḃ term by term as a
product's (its 1 product per direction the recurrence's).
The code goes operation by operation, every direction's convolutions of the operation independent chains of
one loop over j (so they overlap: a single chain waits on its additions), which the operations after join
while they read none of the slots it writes (the double pendulum: 3 loops per order, not 6).

The columns' update is written out over the columns of a pass (`column_width`: all up to 9), with S's
coefficients in W with the columns adjacent (as forward mode's tangents), so that LLVM makes a J entry's
convolution in the pass's columns one vector; the parameters' terms ∂f/∂p[k] come in as F.

`jacobian_source` writes the kernel, with the signature, the layout of X and the constants of
`lagcomp.codegen.taylor_variational.forward_source`'s; the values are ``taylor_coefficients``'s, called
first (the state rows of X are its), the columns' rows agree with the forward mode's
to rounding.  `jacobian_products` counts its products per order (the convolutions' terms), which
`lagcomp.codegen.taylor_variational.variational_source` weighs against the forward mode's to pick one.  The
double pendulum: 19 (J's series) + 8 per column, + 19 for ∂f/∂p's five columns (23 when a sum of series was
always summed into a slot first), against 19 per column in forward mode; per call (the two kernels interleaved
in one process), k = 4: 5.2 against 6.6 µs at order 20; k = 9 with the parameters: 8.7 against 17.5 µs at
order 20, 4.6 against 8.9 at order 13 (then 8.1 and 4.2 with the parameters' convolutions shared, the same
load: 0.93 and 0.92 of the figures before).  Compiling it takes
no longer than forward mode's kernel (cold, CPU shared: k = 4, 4.7 s against 6.1 s; k = 9, 12.7 against 12.9;
n_link_pendulum(3), k = 6, 67 against 125).
"""

from __future__ import annotations

from collections import Counter

from lagcomp.codegen import taylor_kernel_frame as frame
from lagcomp.codegen.taylor_kernel_frame import (
    INDENT,
    ScalarTangents,
    kernel_source,
    program_ops,
    setup_lines,
    work_rows,
)
from lagcomp.codegen.taylor_ops import LINEAR, Op

#: A term of a tangent: (factor (code), kind ("one", "value" or "slot"), series (a value's name, a slot's index)).
Term = tuple[str, str, str]
#: The operations whose tangent is a sum of products of a value series with the operand's tangent:
#: mul (ȧ b + a ḃ), square (2 a ȧ), exp (w ȧ), sin_cos (c ȧ, −s ȧ).
BILINEAR = ("mul", "square", "exp", "sin_cos")
#: The series a tangent keeps as terms (beyond: summed into a slot, so that its code stays short).
TERMS_KEPT = 4


def _product(a: str, b: str) -> str:
    """The code of the product of the factors `a` and `b` (codes), the signs and unit factors folded."""
    negative = a.startswith("-") != b.startswith("-")
    a, b = a.removeprefix("-"), b.removeprefix("-")
    body = b if a == "1.0" else a if b == "1.0" else f"{a}*{b}"
    return f"-{body}" if negative else body


def _scaled(factor: str, code: str) -> str:
    return code if factor == "1.0" else f"-{code}" if factor == "-1.0" else f"{factor}*{code}"


def combine(*parts: tuple[str, tuple[Term, ...]]) -> tuple[Term, ...]:
    """Σ factor · tangent over the (factor, tangent) `parts`, the terms of one series merged."""
    merged: dict[tuple[str, str], str] = {}
    for factor, tangent in parts:
        for own, kind, name in tangent:
            term = _product(factor, own)
            merged[kind, name] = f"({merged[kind, name]} + {term})" if (kind, name) in merged else term
    return tuple((factor, kind, name) for (kind, name), factor in merged.items())


def _series_terms(tangent: tuple[Term, ...]) -> int:
    return sum(kind != "one" for _, kind, _ in tangent)


class _Kernel:
    """What the sweeps share: the code of the values' coefficients, the slots, the convolutions computed."""

    def __init__(self, program: dict, parameters: tuple[int, ...], scale: float):
        self.states = {name: i for i, name in enumerate(program["states"])}
        self.rows = {name: i for i, name in enumerate(work_rows(program))}
        self.row_count = max(len(self.rows), 1)
        self.constants = ScalarTangents(program, parameters, scale)
        self.slots = 0
        self.accumulators = 0
        #: {(the two series' codes at _j, sorted): the slot of their convolution}
        self.convolutions: dict[tuple[str, str], str] = {}
        #: {convolution key: the directions convolving it in the operation at hand} (`_Sweep._convolved`)
        self.demand: Counter = Counter()
        #: {tangent of more than one series: the slot summing it} (`_Sweep.materialized`)
        self.sums: dict[tuple[Term, ...], str] = {}
        #: {series: (c, u)}: the series is c u, u a series not so computed (a scale or a negation of one)
        self.multiples: dict[str, tuple[str, str]] = {}
        for op in program_ops(program):
            if op.kind in ("scale", "neg"):
                factor, root = self.multiples.get(op.args[0], ("1.0", op.args[0]))
                self.multiples[op.out[0]] = _product(op.const if op.kind == "scale" else "-1.0", factor), root

    def value(self, factor: str, name: str) -> Term:
        """The term `factor` × the value series `name`, as a multiple of the series it is one of (`multiples`):
        so that the terms of a tangent in proportional series merge, and their convolutions are shared (the
        double pendulum's M₁₀ = c cos(θ₁ − θ₂) and L₁₀ = M₁₀/M₀₀: cos(θ₁ − θ₂)'s multiples)."""
        own, root = self.multiples.get(name, ("1.0", name))
        return _product(factor, own), "value", root

    def at(self, name: str, index) -> str:
        if name in self.states:
            return f"X[{self.states[name]}, {index}]"
        return f"W[{self.rows[name]}, {index}]"

    def slot(self, slot: str, index) -> str:
        return f"W[{self.row_count + int(slot)}, {index}]"

    def new_slot(self) -> str:
        self.slots += 1
        return str(self.slots - 1)

    def convolution_key(self, term: Term, value: str) -> tuple[str, str]:
        """The key in `convolutions` of the series term (``value`` or ``slot``) ⊛ the value series `value`."""
        _, kind, series = term
        value = self.multiples.get(value, ("1.0", value))[1]
        read = self.at(series, "_j") if kind == "value" else self.slot(series, "_j")
        return tuple(sorted((read, self.at(value, "_j"))))

    def term_at(self, term: Term, index) -> str:
        """Coefficient `index` of the term (a ``one`` term: at index k)."""
        factor, kind, name = term
        if kind == "one":
            return f"({factor} if k == 0 else 0.0)"
        return _scaled(factor, self.at(name, index) if kind == "value" else self.slot(name, index))

    def sum_at(self, tangent: tuple[Term, ...], index="k") -> str:
        return " + ".join(self.term_at(term, index) for term in tangent) or "0.0"


class _Code:
    """The code of operations' tangents in every direction: lines before a loop over j = 1..k, the statements
    of that loop (each direction's sums independent chains in it), lines after; `products` its products per
    term; the slots its lines before and its loop read (`reads`: of order k, written by earlier operations) and
    the slots it writes (`writes`), so that a later operation that reads none of them joins its loop
    (`absorb`)."""

    def __init__(self, kernel: _Kernel, name: str):
        self.kernel, self.names = kernel, [name]
        self.before: list[str] = []
        self.loop: list[str] = []
        self.after: list[str] = []
        self.products = 0
        self.reads: set[str] = set()
        self.writes: set[str] = set()

    def accumulator(self, start: str) -> str:
        """A new accumulator of the loop, set to `start` (code) before it (named across the kernel)."""
        self.kernel.accumulators += 1
        self.before.append(f"_a{self.kernel.accumulators - 1} = {start}")
        return f"_a{self.kernel.accumulators - 1}"

    def absorb(self, other: _Code) -> bool:
        """Take the later operations' code `other` into this one (its loop's chains into this loop: more
        chains to overlap, one loop less per order) when it reads none of this code's slots; whether it did.
        Each chain's sum is the same, term by term: the series are bitwise as in a loop of their own."""
        if other.reads & self.writes:
            return False
        self.names += other.names
        self.before += other.before
        self.loop += other.loop
        self.after += other.after
        self.products += other.products
        self.reads |= other.reads
        self.writes |= other.writes
        return True

    def lines(self) -> list[str]:
        loop = ["for _j in range(1, k + 1):", *(INDENT + line for line in self.loop)] if self.loop else []
        return [f"# d({', '.join(self.names)})", *self.before, *loop, *self.after]


class _Sweep:
    """The tangents of the program's series in one direction: a state's (its tangent the unit series) or a
    parameter's (`parameter`: its index in p), as sums of terms, and the tangent of each state's derivative
    (`derivatives`: J's column, or ∂f/∂p_j)."""

    def __init__(self, kernel: _Kernel, state: str | None = None, parameter: int | None = None):
        self.kernel, self.parameter = kernel, parameter
        self.tangents: dict[str, tuple[Term, ...]] = {state: (("1.0", "one", ""),)} if state is not None else {}
        self.derivatives: dict[int, tuple[Term, ...]] = {}

    def of(self, name: str) -> tuple[Term, ...]:
        return self.tangents.get(name, ())

    def constant(self, const: str) -> tuple[Term, ...]:
        """The tangent of the scalar `const`: its partial as a ``one`` term (none in a state's direction)."""
        tangent = self.kernel.constants.tangent(const, self.parameter)
        return () if tangent is None else ((tangent, "one", ""),)

    def materialized(self, tangent: tuple[Term, ...], code: _Code, before: bool = False) -> str:
        """A slot holding the series `tangent` (its own, when it is one slot; the same slot for the same sum in
        every direction), computed by a line of `code` after its loop, or `before` it (for the loop to read)."""
        if before:
            code.reads |= {name for _, kind, name in tangent if kind == "slot"}
        if len(tangent) == 1 and tangent[0][1] == "slot" and tangent[0][0] == "1.0":
            return tangent[0][2]
        if tangent not in self.kernel.sums:
            slot = self.kernel.sums[tangent] = self.kernel.new_slot()
            (code.before if before else code.after).append(f"{self.kernel.slot(slot, 'k')} = "
                                                           f"{self.kernel.sum_at(tangent)}")
            code.writes.add(slot)
        return self.kernel.sums[tangent]

    def _set(self, name: str, tangent: tuple[Term, ...], code: _Code) -> None:
        """The tangent of `name`: its terms, summed into one slot (after `code`'s loop, whose results it may sum)
        only beyond `TERMS_KEPT` series (a sum is convolved term by term, `_convolved`, so that the terms'
        convolutions are shared across directions: a parameter's tangents are multiples of the values')."""
        if _series_terms(tangent) > TERMS_KEPT:
            tangent = (("1.0", "slot", self.materialized(tangent, code)),)
        if tangent:
            self.tangents[name] = tangent

    def add(self, op: Op, code: _Code) -> None:
        """The tangent(s) of `op`'s result(s), their code (the new series') into `code`."""
        kind, const = op.kind, op.const
        if kind in ("comment", "pivot"):
            return
        if kind == "state":
            tangent = self.of(op.args[0]) if op.args else self.constant(const)
            if self.parameter is None and _series_terms(tangent) > 1:   # (J's entry: one series per column update)
                tangent = (("1.0", "slot", self.materialized(tangent, code)),)
            self.derivatives[op.index] = tangent
        elif kind in LINEAR:
            a, b = self.of(op.args[0]), self.of(op.args[-1])
            tangent = {
                "add": lambda: combine(("1.0", a), ("1.0", b)),
                "sub": lambda: combine(("1.0", a), ("-1.0", b)),
                "neg": lambda: combine(("-1.0", a)),
                "scale": lambda: combine((const, a), ("1.0", tuple(self.kernel.value(f, op.args[0])
                                                                   for f, _, _ in self.constant(const)))),
                "add_const": lambda: combine(("1.0", a), ("1.0", self.constant(const))),
                "rsub_const": lambda: combine(("1.0", self.constant(const)), ("-1.0", a)),
            }[kind]()
            self._set(op.out[0], tangent, code)
        elif kind in BILINEAR:
            self._bilinear(op, code)
        else:
            self._recurrence(op, code)

    def _bilinear_products(self, op: Op) -> dict[str, list[tuple[str, tuple[Term, ...], str]]]:
        """{result of an operation of `BILINEAR`: [(factor, an operand's tangent, value series)]}: its tangent is
        Σ factor (tangent ⊛ value series)."""
        a = op.args[0]
        if op.kind == "mul":
            b = op.args[1]
            return {op.out[0]: [("1.0", self.of(a), b), ("1.0", self.of(b), a)]}
        if op.kind == "square":
            return {op.out[0]: [("2.0", self.of(a), a)]}
        if op.kind == "exp":
            return {op.out[0]: [("1.0", self.of(a), op.out[0])]}
        s, c = op.out
        return {s: [("1.0", self.of(a), c)], c: [("-1.0", self.of(a), s)]}

    def convolutions_of(self, op: Op) -> list[tuple[tuple[Term, ...], str]]:
        """The (tangent, value series) pairs `op`'s tangent convolves (`_convolved`) in this direction."""
        if op.kind in BILINEAR:
            return [(tangent, value) for products in self._bilinear_products(op).values()
                    for _, tangent, value in products]
        if op.kind in ("div", "rdiv"):
            return [(self.of(op.args[-1]), op.out[0])]
        return []

    def _bilinear(self, op: Op, code: _Code) -> None:
        """An operation of `BILINEAR`: per result, Σ factor (operand's tangent ⊛ value series) (`_convolved`)."""
        tangents = {name: combine(*((f, self._convolved(tangent, v, code)) for f, tangent, v in products))
                    for name, products in self._bilinear_products(op).items()}
        for name, tangent in tangents.items():
            self._set(name, tangent, code)

    def _convolved(self, tangent: tuple[Term, ...], value: str, code: _Code) -> tuple[Term, ...]:
        """The tangent ⊛ the value series `value`: term by term (`_times`) when its share of the terms' new
        convolutions (each 1 / the directions that convolve it, `_Kernel.demand`) is at most one convolution,
        else the tangent's series summed into a slot first (one convolution of its own).  A parameter's
        tangents are multiples of a few value series: their convolutions serve every parameter."""
        kernel = self.kernel
        series = tuple(term for term in tangent if term[1] != "one")
        keys = [kernel.convolution_key(term, value) for term in series]
        if sum(1 / kernel.demand[key] for key in keys if key not in kernel.convolutions) > 1:
            tangent = (*(term for term in tangent if term[1] == "one"),
                       ("1.0", "slot", self.materialized(series, code, before=True)))
        return tuple(self._times(term, value, code) for term in tangent)

    def _times(self, term: Term, value: str, code: _Code) -> Term:
        """The term ⊛ the value series `value`: a ``one`` term's factor times `value`; otherwise the factor times
        the convolution of the two series, a slot computed once per kernel (the sweeps of other directions
        reuse it: sin(θ₁ − θ₂)'s partials in θ₁ and θ₂ are the same series but for the sign)."""
        factor, kind, series = term
        kernel = self.kernel
        if kind == "one":
            return kernel.value(factor, value)
        own, value = kernel.multiples.get(value, ("1.0", value))
        factor = _product(factor, own)
        read = (lambda i: kernel.at(series, i)) if kind == "value" else (lambda i: kernel.slot(series, i))
        key = kernel.convolution_key(term, value)
        if key not in kernel.convolutions:
            slot = kernel.convolutions[key] = kernel.new_slot()
            code.writes.add(slot)
            if kind == "slot":
                code.reads.add(series)
            total = code.accumulator(f"{read(0)}*{kernel.at(value, 'k')}")
            code.loop.append(f"{total} += {read('_j')}*{kernel.at(value, 'k - _j')}")
            code.after.append(f"{kernel.slot(slot, 'k')} = {total}")
            code.products += 1
        return factor, "slot", kernel.convolutions[key]

    def _recurrence(self, op: Op, code: _Code) -> None:
        """A quotient, root, power or log: its tangent recurrence (`lagcomp.codegen.taylor_variational`), the
        operands' tangents read at k as terms, or in the loop over j from a slot."""
        kind, (w,), kernel = op.kind, op.out, self.kernel
        a, b = op.args[0], op.args[-1]
        top = self.of(a) if kind != "rdiv" else self.constant(op.const)
        moves_b = kind in ("div", "rdiv") and bool(self.of(b))
        if not top and not moves_b:
            return
        slot = kernel.new_slot()
        code.writes.add(slot)
        own, at, loop, after = (lambda index: kernel.slot(slot, index)), kernel.at, code.loop, code.after
        if kind in ("div", "rdiv"):   # ẇ[k] b[0] = ȧ[k] − (w ⊛ ḃ)[k] − Σ_{j=1..k} b[j] ẇ[k−j]
            # (w ⊛ ḃ term by term, `_convolved`: a parameter's ḃ is multiples of value series, whose
            # convolutions with w the directions share)
            numerator = combine(("1.0", top), ("-1.0", self._convolved(self.of(b), w, code)))
            total = code.accumulator("0.0")
            loop.append(f"{total} += {at(b, '_j')}*{own('k - _j')}")
            after.append(f"{own('k')} = ({kernel.sum_at(numerator)} - {total})/{at(b, 0)}")
            code.products += 1
        elif kind == "sqrt":          # 2 w[0] ẇ[k] = ȧ[k] − 2 Σ_{j=1..k} w[j] ẇ[k−j]
            total = code.accumulator("0.0")
            loop.append(f"{total} += {at(w, '_j')}*{own('k - _j')}")
            after.append(f"{own('k')} = ({kernel.sum_at(top)} - 2.0*{total})/(2.0*{at(w, 0)})")
            code.products += 1
        elif kind == "pow":           # a[0] ẇ[k] = α Σ_{j=0..k} w[j] ȧ[k−j] − Σ_{j=1..k} a[j] ẇ[k−j]
            da = self.materialized(top, code, before=True)
            total = code.accumulator(f"{op.const}*{at(w, 0)}*{kernel.slot(da, 'k')}")
            loop.append(f"{total} += {op.const}*{at(w, '_j')}*{kernel.slot(da, 'k - _j')} - "
                        f"{at(a, '_j')}*{own('k - _j')}")
            after.append(f"{own('k')} = {total}/{at(a, 0)}")
            code.products += 2
        elif kind == "log":           # a[0] ẇ[k] = ȧ[k] − Σ_{j=1..k} a[j] ẇ[k−j]
            total = code.accumulator(kernel.sum_at(top))
            loop.append(f"{total} -= {at(a, '_j')}*{own('k - _j')}")
            after.append(f"{own('k')} = {total}/{at(a, 0)}")
            code.products += 1
        else:
            raise ValueError(f"no tangent recurrence for the operation {kind!r}")
        self.tangents[w] = (("1.0", "slot", slot),)


class _Sweeps:
    """Every direction's sweep of `program` (the states', J's columns; the `parameters'`, ∂f/∂p's, their
    scalars' partials times `scale`), and their code per order: operation by operation, the directions'
    convolutions independent chains of one loop, shared with the operations before when they read none of
    their slots (`_Code.absorb`)."""

    def __init__(self, program: dict, parameters: tuple[int, ...], scale: float):
        self.kernel = _Kernel(program, parameters, scale)
        self.states = [_Sweep(self.kernel, state=name) for name in program["states"]]
        self.parameters = [_Sweep(self.kernel, parameter=j) for j in parameters]
        codes: list[_Code] = []
        for op in program_ops(program):
            code = _Code(self.kernel, ", ".join(op.out) or "f")
            self.kernel.demand = Counter(
                self.kernel.convolution_key(term, value) for sweep in (*self.states, *self.parameters)
                for tangent, value in sweep.convolutions_of(op) for term in tangent if term[1] != "one")
            for sweep in (*self.states, *self.parameters):
                sweep.add(op, code)
            if (code.before or code.after) and not (codes and codes[-1].absorb(code)):
                codes.append(code)
        self.lines = [line for code in codes for line in code.lines()]
        self.products = sum(code.products for code in codes)

    def entries(self, n_state: int) -> list[tuple[int, int, Term]]:
        """J's nonzero entries, (i, j, term) per term of J_ij's tangent, by row."""
        return [(i, j, term) for i in range(n_state) for j, sweep in enumerate(self.states)
                for term in sweep.derivatives.get(i, ())]


def column_width(program: dict, columns: int, convolutions: int) -> int:
    """The columns of one pass of the column update (`lagcomp.codegen.taylor_kernel_frame.block_width`'s rule,
    with J's `convolutions` per column for the program's operations)."""
    width = columns if columns <= frame.UNROLLED_COLUMNS else frame.BLOCK
    return max(1, min(width, frame.COLUMN_OPERATIONS_MAX // max(convolutions, 1)))


def jacobian_products(program: dict, columns: int, parameters: tuple[int, ...] = ()) -> int:
    """The products per term of the convolutions (the cost of an order, at order ≫ 1) of `jacobian_source`'s
    kernel: the sweeps', and the columns' (J's entries that are series, per column)."""
    sweeps = _Sweeps(program, parameters, 1.0)
    per_column = sum(term[1] != "one" for _, _, term in sweeps.entries(program["n_state"]))
    return sweeps.products + columns * per_column


def _update_lines(sweeps: _Sweeps, n_state: int, columns: int, width: int, padded: int,
                  forced: set[int], looped: bool) -> list[str]:
    """The code of column ``_b + c``'s coefficient k + 1, for c < `width`: Ṡ_i[k] = Σ_j (J_ij ⊛ S_j)[k] + F_i
    (F: the parameters' terms ∂f/∂p[k], 0 in the others; only in the rows of `forced`), into S (the columns
    adjacent, ``_S``) and X.  A row's
    convolutions sum into one accumulator per column: a pass's accumulators stay a few vectors (one per entry
    and column, the double pendulum's 72 at k = 9, spill: 6.1 against 4.6 µs per call at order 13).

    The positions in S are integers computed once per pass (``_pk``, ``_pk1``) or per j (``_pj``) and added to
    the rows' offsets ``_sr{i}`` (`_row_offsets`): numba types and lowers every operation of the source, and a
    position written out per access (seven operations) was most of the update's code.  In a pass of several
    columns, the rows' positions (``_o{i}``, ``_q{i}``) and J's factors (`_Shared`) are locals too, set once for
    the pass's columns (the double pendulum, numba's compile CPU, `bench.bench_kernel_compile`: k = 4, 3.1 → 2.6 s;
    k = 9 with the parameters, 6.4 → 5.1 s)."""
    kernel = sweeps.kernel
    positions = {"k": "_pk", "k + 1": "_pk1", "k - _j": "_pj"}

    rows = {"k": "_o", "k - _j": "_q"} if width > 1 else {}    # S_i's coefficient k, k − j: locals of the pass

    def s(i, index, c):     # coefficient `index` of S_i in column _b + c
        if i and index in rows:
            return f"_S[{rows[index]}{i}" + f" + {c}" * bool(c) + "]"
        return "_S[" + " + ".join([f"_sr{i}"] * bool(i) + [positions[index]] + [str(c)] * bool(c)) + "]"

    def block(offset):      # the code of the position `offset` + _b (in a loop over blocks)
        return f"_b + {offset}" if looped else str(offset)
    init = [f"_pk = k*{padded} + _b" if looped else f"_pk = k*{padded}", f"_pk1 = _pk + {padded}",
            "_kn = k + 1", *(f"_o{i} = _sr{i} + _pk" for i in range(1, n_state) if rows)]
    loop = [f"{INDENT}_pj = _pk - _j*{padded}", *(f"{INDENT}_q{i} = _sr{i} + _pj" for i in range(1, n_state) if rows)]
    stores = []
    entries = sweeps.entries(n_state)
    start, step = _Shared(init, "_e", width), _Shared(loop, "_w", width, INDENT)
    for i in range(n_state):
        ones = [(factor, j) for row, j, (factor, kind, _) in entries if row == i and kind == "one"]
        series = [(factor, j, kernel.at if kind == "value" else kernel.slot, name)
                  for row, j, (factor, kind, name) in entries if row == i and kind != "one"]
        firsts = [(start(_scaled(f, read(name, 0))), j) for f, j, read, name in series]
        terms = [(step(_scaled(f, read(name, "_j"))), j) for f, j, read, name in series]
        for c in range(width):
            if series:
                init.append(f"_a{i}_{c} = " + " + ".join(f"{first}*{s(j, 'k', c)}" for first, j in firsts))
                loop.append(f"{INDENT}_a{i}_{c} += " + " + ".join(f"{term}*{s(j, 'k - _j', c)}" for term, j in terms))
            total = [f"_a{i}_{c}"] * bool(series) + [_scaled(f, s(j, "k", c)) for f, j in ones]
            total += [f"_F[{block(i * padded + c)}]"] * (i in forced)
            stores.append(f"_v = ({' + '.join(total)})*_ik1" if total else "_v = 0.0")
            stores.append(f"{s(i, 'k + 1', c)} = _v")
            row = n_state * (c + 1) + i        # X's row of S_i in column _b + c: N (_b + c + 1) + i
            store = f"X[{n_state}*_b + {row}, _kn] = _v" if looped else f"X[{row}, _kn] = _v"
            stores += [store] if padded == columns else [f"if _b + {c} < {columns}:", INDENT + store]
    loop = ["for _j in range(1, k + 1):", *loop] if any(row[-1][1] != "one" for row in entries) else []
    return [*init, *loop, *stores]


class _Shared:
    """The factors of J's entries that every column of a pass multiplies (``-_k20*_c3*W[60, _j]``), each a local
    set once before the pass's uses (``_w3 = ...``, appended to `lines`) when the pass has more than one column:
    numba types and lowers every operation of the source, and those factors written out in every column were a
    third of the update's.  The product is the same, term for term (``a*b*c*S`` is ``((a*b)*c)*S``: the local
    holds ``(a*b)*c``), so the columns' sums are bitwise those of the factors written out."""

    def __init__(self, lines: list[str], prefix: str, width: int, indent: str = ""):
        self.lines, self.prefix, self.width, self.indent = lines, prefix, width, indent
        self.names: dict[str, str] = {}

    def __call__(self, code: str) -> str:
        """The name of the local holding `code` (set on first use), or `code` itself in a pass of one column."""
        if self.width == 1:
            return code
        if code not in self.names:
            self.names[code] = f"{self.prefix}{len(self.names)}"
            self.lines.append(f"{self.indent}{self.names[code]} = {code}")
        return self.names[code]


def _row_offsets(n_state: int, padded: int) -> list[str]:
    """The offsets in ``_S`` of the rows S_i (i > 0: S_0's is 0), before the loop over the orders."""
    return [f"_sr{i} = {i}*(order + 1)*{padded}" for i in range(1, n_state)]


def jacobian_source(program: dict, columns: int, parameters: tuple[int, ...] = (), scale: float = 1.0) -> str:
    """The source of ``taylor_variational_coefficients`` (as `lagcomp.codegen.taylor_variational.forward_source`'s:
    `columns` columns, the last of them those of `parameters`, `scale` their seeds' factor) from the series of
    J's entries and of ∂f/∂p's (see the module docstring)."""
    n_state = program["n_state"]
    sweeps = _Sweeps(program, parameters, scale)
    kernel = sweeps.kernel
    entries = sum(term[1] != "one" for _, _, term in sweeps.entries(n_state))
    width = column_width(program, columns, entries)
    padded = -(-columns // width) * width
    docstring = [
        f"The Taylor coefficients of y = (x, S[:, 0], ..., S[:, {columns - 1}]): x's as `taylor_coefficients`",
        "computes them (rows 0..N-1 of X), then those of each sensitivity column (rows N (1 + c) + i) from",
        "the series of the Jacobian's entries (lagcomp.codegen.taylor_jacobian).  W: the work array, the",
        f"values' {kernel.row_count} rows, the sweeps' series, then S's coefficients (the columns adjacent)",
        "and the parameters' terms of order k.",
        "Returns 0, or j > 0 when pivot j of the LDLᵀ factorization of M is not positive at t."]
    base = f"{kernel.row_count + kernel.slots}*(order + 1)"
    # the rows whose derivative depends on a parameter of the columns: F's (none without parameter columns)
    forced = {i for sweep in sweeps.parameters for i, tangent in sweep.derivatives.items() if tangent}
    lines = setup_lines(program, columns, parameters)
    lines += [f"_S = W.reshape(-1)[{base}:{base} + {n_state * padded}*(order + 1)]   # S_i[m] of column c: "
              f"_S[(i*(order + 1) + m)*{padded} + c]",
              f"_F = W.reshape(-1)[{base} + {n_state * padded}*(order + 1):{base} + {n_state * padded}*(order + 2)]"
              f"   # F_i of column c (the parameters' ∂f/∂p[k]): _F[i*{padded} + c]",
              *["_F[:] = 0.0"] * bool(forced), f"for _c in range({padded}):   # (padding: 0)"]
    lines += [f"{INDENT}_S[{i}*(order + 1)*{padded} + _c] = y[{n_state}*(_c + 1) + {i}] if _c < {columns} else 0.0"
              for i in range(n_state)]
    lines += _row_offsets(n_state, padded)
    lines += ["for k in range(order):", f"{INDENT}_ik1 = 1.0/(k + 1)"]
    lines += [f"{INDENT}# The series of J's entries and of ∂f/∂p, order k"] + [INDENT + line for line in sweeps.lines]
    for position, sweep in enumerate(sweeps.parameters):
        column = columns - len(parameters) + position
        lines += [f"{INDENT}_F[{i * padded + column}] = {kernel.sum_at(tangent)}"
                  for i, tangent in sorted(sweep.derivatives.items()) if tangent]
    looped = padded > width
    lines += [f"{INDENT}# Every column: Ṡ = J S + F, {width} columns at a time",
              f"{INDENT}for _b in range(0, {padded}, {width}):"] * looped
    lines += [INDENT * (2 if looped else 1) + line
              for line in _update_lines(sweeps, n_state, columns, width, padded, forced, looped)]
    lines.append("return 0")
    # (S: N × padded rows of order + 1; F: N × padded floats, at most as many rows)
    return kernel_source(docstring, lines, columns, kernel.row_count + kernel.slots + 2 * n_state * padded)
