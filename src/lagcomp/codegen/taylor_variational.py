r"""The Taylor program differentiated in forward mode: the series of the state and of its sensitivities.

The Taylor program (`lagcomp.codegen.taylor`: elementary operations on series, stored with the model as data)
computes the normalized coefficients u[k] of every intermediate value u(t) along the solution.  Differentiating
each operation with respect to a direction of the initial state gives the tangent series u̇ (the sensitivity of
u along that direction), one per sensitivity column; every recurrence has a tangent recurrence, linear in the
tangents, from the derivative of the function (an identity between series, so exact in coefficients too):

    w = a ± b, c a, a + c, c − a, −a     ẇ[k] = ȧ[k] ± ḃ[k], c ȧ[k], ȧ[k], −ȧ[k], −ȧ[k]
    w = a b        ẇ[k] = Σ_{j=0..k} ȧ[j] b[k−j] + a[j] ḃ[k−j]
    w = a²         ẇ[k] = 2 Σ_{j=0..k} a[j] ȧ[k−j]
    w = a / b      ẇ = (ȧ − w ḃ)/b:  ẇ[k] = (ȧ[k] − Σ_{j=0..k} w[j] ḃ[k−j] − Σ_{j=1..k} b[j] ẇ[k−j]) / b[0]
    w = c / b      the same with ȧ = 0
    w = √a         ẇ = ȧ/(2w):  ẇ[k] = (ȧ[k] − 2 Σ_{j=1..k} w[j] ẇ[k−j]) / (2 w[0])
    w = a^α        ẇ = α w ȧ/a:  ẇ[k] = (α Σ_{j=0..k} w[j] ȧ[k−j] − Σ_{j=1..k} a[j] ẇ[k−j]) / a[0]
    w = exp a      ẇ = w ȧ:  ẇ[k] = Σ_{j=0..k} w[j] ȧ[k−j]
    w = log a      ẇ = ȧ/a:  ẇ[k] = (ȧ[k] − Σ_{j=1..k} a[j] ẇ[k−j]) / a[0]
    s, c = sin a, cos a
                   ṡ[k] = Σ_{j=0..k} c[j] ȧ[k−j],  ċ[k] = −Σ_{j=0..k} s[j] ȧ[k−j]

and the state's operation y[k+1] = f[k]/(k+1) gives Ṡ[k+1] = ḟ[k]/(k+1), ḟ = J S: the coefficients of the
variational equations' solution S' = J S, with no Jacobian formed.  The tangents of order k need the values of
order ≤ k (w[k] itself for a quotient): the kernel computes the values of every order first, then the
tangents order by order.
Values that depend on the parameters only (the setup's scalars) and time have no tangent; a series computed from
those alone has none either (`varying`).

`variational_source` writes the kernel ``taylor_variational_coefficients(t, y, p, X, W)`` for k columns, with
the signature of ``taylor_coefficients`` (`lagcomp.integrate.drivers.kernel_types.TAYLOR`), over the augmented
state y = (x, S[:, 0], ..., S[:, k−1]) of N (1 + k) components: X (N (1 + k), order + 1) the coefficients of x,
then of each column of S, in y's layout (what the driver sums and interpolates); W (``VARIATIONAL_WORK``,
order + 1) the values' rows as ``taylor_coefficients`` has them, then the tangents T in a layout of their own:
per series (the states' first), per order, the columns adjacent; then the tangents of the scalars.  The columns
of one pass (`block_width`: all of them up to 9) are written out, so each convolution sums them as independent
chains in one loop over j, and with the columns adjacent LLVM makes those chains one vector: the double
pendulum's kernel at k = 4 (per call, order 13 / 20) took 5.2 / 10.7 µs with a loop over the columns inside,
3.1 / 6.1 µs so (the plain kernel: 0.9 / 1.7 µs).  More columns, or a large program, take a loop over blocks
of columns, whose code numba compiles in bounded time.  The values are the model's ``taylor_coefficients``
itself, called before the tangents' loop (`lagcomp.codegen.taylor_kernel_frame.VALUES`): the state rows of X are
its, and numba compiles the values once per model, not in every kernel of every choice of columns (the double
pendulum's kernel for 4 columns took 4.3 s of CPU to compile with the values written out in it, 2.8 s with the
call; `bench.bench_kernel_compile`).  A kernel so large that numba would take hours is refused
(`lagcomp.codegen.taylor_kernel_frame.check_size`).
`lagcomp.integrate.taylor_sensitivities` appends the kernel to the model's module and compiles it once per
model and choice of columns (cached on disk like any module).

A column costs about a program here.  `lagcomp.codegen.taylor_jacobian` writes the same kernel from the
series of J's nonzero entries (and ∂f/∂p's), computed once per order for all columns, then nnz(J)
convolutions per column: `variational_source` writes whichever takes less time by their products per order
(`forward_products`, `jacobian_products`, `JACOBIAN_PRODUCT_COST`): the Jacobian's for a sparse J (the
double pendulum, from k = 1), forward mode for a dense J and few columns (the three bodies at k < 4).

Parameter columns: the tangent with respect to p_j starts at 0 (the state does not depend on p_j at t0) and
enters through the program's scalars: p_j itself (tangent 1), and every scalar computed from parameters, whose
partial ∂c/∂p_j the decomposition stores with the setup (``partial`` statements, `lagcomp.codegen.taylor`).
An operation with a scalar operand then gets its term: w = c a → ẇ = ċ a + c ȧ; w = a + c → ẇ[0] += ċ;
w = c − a → ẇ[0] = ċ − ȧ[0]; w = c / b → the quotient's rule with ȧ = ċ at order 0; a constant derivative of
the state → its tangent at order 0.  That is ∂f/∂p_j in the column's Ṡ, with no ∂f/∂p formed.
"""

from __future__ import annotations

from lagcomp.codegen import taylor_kernel_frame as frame
from lagcomp.codegen.taylor_jacobian import jacobian_products, jacobian_source
from lagcomp.codegen.taylor_kernel_frame import (
    INDENT,
    ScalarTangents,
    block_width,
    kernel_source,
    program_ops,
    setup_lines,
    work_rows,
)
from lagcomp.codegen.taylor_ops import (
    LINEAR,
    Op,
    support_import_lines,
)


def varying(program: dict, constants: ScalarTangents) -> set[str]:
    """The series with a tangent: the state's, and those computed from one of them or from a scalar with one."""
    names = set(program["states"])
    for op in program_ops(program):
        if op.kind not in ("comment", "pivot", "state") and (any(a in names for a in op.args)
                                                             or constants.varies(op.const)):
            names.update(op.out)
    return names


class _Writer:
    """Code of coefficients of values (`at`) and of the tangents of column c (`tangent`), for `columns` columns,
    the last of them those of the `parameters` (indices into p)."""

    def __init__(self, program: dict, columns: int, parameters: tuple[int, ...] = (), scale: float = 1.0):
        self.n_state, self.total = program["n_state"], columns
        self.columns = block_width(program, columns)           # the columns of one pass of the block loop
        self.padded = -(-columns // self.columns) * self.columns   # the columns held: whole blocks
        self.column_parameter = [None] * (columns - len(parameters)) + list(parameters)
        self.constants = ScalarTangents(program, parameters, scale)
        self.states = {name: i for i, name in enumerate(program["states"])}
        self.slots_state = list(program["states"])
        self.rows = {name: i for i, name in enumerate(work_rows(program))}
        self.row_count = max(len(self.rows), 1)
        self.varying = varying(program, self.constants)
        # the tangent series, states first: slot s holds coefficient j of column c at T[_t{s} + j*padded + c]
        self.slots = {name: s for s, name in enumerate(
            [*program["states"], *(name for name in work_rows(program) if name in self.varying)])}
        # the scalars with a tangent (parameters and what depends on them): column c's at T[_g{i} + c]
        names = [*self.constants.own, *(entry["name"] for entry in program["setup"] if entry["kind"] == "constant")]
        self.scalars = {name: i for i, name in enumerate(n for n in names if self.constants.varies(n))}

    def constant(self, const: str, c: int) -> str | None:
        """The tangent of the scalar `const` in column ``_b + c`` of the block loop (code), None for 0: in one
        pass, the code of the column's partial (none in an initial-state column); in a loop, data in T."""
        if self.padded == self.columns:
            return self.constants.tangent(const, self.column_parameter[c])
        if const not in self.scalars:
            return None
        return f"T[_g{self.scalars[const]} + _b + {c}]"

    def at(self, name: str, index) -> str:
        if name in self.states:
            return f"X[{self.states[name]}, {index}]"
        return f"W[{self.rows[name]}, {index}]"

    @property
    def looped(self) -> bool:
        """Whether the columns take a loop over blocks (``_b`` its variable; else the one pass has none)."""
        return self.padded > self.columns

    def tangent(self, name: str, index, c: int) -> str:
        """Coefficient `index` (k, k + 1, _j or k − _j) of the tangent of `name` in column ``_b + c`` of the block
        loop, in T (the columns of a coefficient are adjacent: the loads of a convolution's chains in a block are
        one vector).  The position of the coefficient's block is an integer of the pass or of the loop over j
        (`position_lines`), not written out at every access: numba types and lowers each operation of the
        source, and the positions' were most of them."""
        position = _POSITIONS[index]
        return "T[" + " + ".join([f"_t{self.slots[name]}", position] + [str(c)] * bool(c)) + "]"

    def position_lines(self) -> list[str]:
        """The positions of coefficients k and k + 1 of the pass's block: ``(k)*padded + _b``, and k + 1."""
        return [f"_pk = k*{self.padded}" + " + _b" * self.looped, f"_pk1 = _pk + {self.padded}", "_kn = k + 1"]

    def state_row(self, c: int, index: int) -> str:
        """X's row of state `index`'s coefficient in column ``_b + c``: N (_b + c + 1) + index."""
        row = self.n_state * (c + 1) + index
        return f"{self.n_state}*_b + {row}" if self.looped else str(row)

    @property
    def tangent_rows(self) -> int:
        """Rows of W (of order + 1 floats, at least one) that T takes: every slot's coefficients of every column,
        and the scalars' tangents."""
        return (len(self.slots) + len(self.scalars)) * self.padded

    def moves(self, name: str) -> bool:
        return name in self.varying

    def _columns(self, line) -> list[str]:
        """``line(c)`` for every column."""
        return [line(c) for c in range(self.columns)]

    def _sum_over(self, first: int, init, terms, finish) -> list[str]:
        """Every column's accumulator(s) ``_s{c}`` (and ``_r{c}``): `init(c)` lines, then for j = first..k the
        statements `terms(c)`, then `finish(c)`.  The sums of the block's columns are independent chains in one
        loop over j: the products of one j share their loads, and LLVM makes the chains one vector."""
        columns = range(self.columns)
        lines = [line for c in columns for line in init(c)]
        lines.append(f"for _j in range({first}, k + 1):")
        jumps = f"_j*{self.padded}"          # coefficients _j and k − _j of the block (`tangent`)
        lines += [f"{INDENT}_pj = {jumps}" + " + _b" * self.looped, f"{INDENT}_pkj = _pk - {jumps}"]
        lines += [INDENT + line for c in columns for line in terms(c)]
        return lines + [line for c in columns for line in finish(c)]

    def tangent_lines(self, op: Op) -> list[str]:
        """Coefficient k of the tangents of `op`'s result(s) in every column (nothing when it has none)."""
        kind, const, t, at = op.kind, op.const, self.tangent, self.at
        if kind == "state":
            def derivative(c):
                if op.args:
                    return f"{t(op.args[0], 'k', c)}*_ik1" if self.moves(op.args[0]) else "0.0"
                tangent = self.constant(const, c)     # a constant derivative: its tangent at order 0 only
                return "0.0" if tangent is None else f"({tangent} if k == 0 else 0.0)"
            state = self.slots_state[op.index]
            lines = []
            for c in range(self.columns):
                store = f"X[{self.state_row(c, op.index)}, _kn] = {t(state, 'k + 1', c)}"
                lines.append(f"{t(state, 'k + 1', c)} = {derivative(c)}")
                # (a padding column of the last block has no row in X)
                lines += [store] if self.padded == self.total else [f"if _b + {c} < {self.total}:", INDENT + store]
            return lines
        if kind in ("comment", "pivot") or not self.moves(op.out[0]):
            return []
        if kind in LINEAR:
            (w,) = op.out
            a, b = op.args[0], op.args[-1]

            def value(c):
                if kind in ("add", "sub"):
                    terms = [f"+ {t(a, 'k', c)}"] if self.moves(a) else []
                    terms += [f"{'+' if kind == 'add' else '-'} {t(b, 'k', c)}"] if self.moves(b) else []
                else:   # ẇ = c ȧ + ċ a (scale), ȧ + ċ δ_k0 (add_const), ċ δ_k0 − ȧ (rsub_const), −ȧ (neg)
                    sign = "-" if kind in ("neg", "rsub_const") else "+"
                    factor = f"{const}*" if kind == "scale" else ""
                    terms = [f"{sign} {factor}{t(a, 'k', c)}"] if self.moves(a) else []
                    tangent = self.constant(const, c) if kind != "neg" else None
                    if tangent is not None:
                        terms.append(f"+ {tangent}*{at(a, 'k')}" if kind == "scale"
                                     else f"+ ({tangent} if k == 0 else 0.0)")
                if not terms:
                    return "0.0"
                first = terms[0][2:] if terms[0].startswith("+") else f"-{terms[0][2:]}"
                return " ".join([first, *terms[1:]])
            return self._columns(lambda c: f"{t(w, 'k', c)} = {value(c)}")
        if kind == "sin_cos":
            (a,), (s, co) = op.args, op.out
            return self._sum_over(
                0, lambda c: [f"_s{c} = 0.0", f"_r{c} = 0.0"],
                lambda c: [f"_s{c} += {at(co, '_j')}*{t(a, 'k - _j', c)}",
                           f"_r{c} += {at(s, '_j')}*{t(a, 'k - _j', c)}"],
                lambda c: [f"{t(s, 'k', c)} = _s{c}", f"{t(co, 'k', c)} = -_r{c}"])
        (w,) = op.out
        a = op.args[0]
        if kind == "mul":
            b = op.args[1]

            def terms(c):
                products = [f"{t(a, '_j', c)}*{at(b, 'k - _j')}" for _ in (0,) if self.moves(a)]
                products += [f"{at(a, '_j')}*{t(b, 'k - _j', c)}" for _ in (0,) if self.moves(b)]
                return [f"_s{c} += {' + '.join(products)}"]
            return self._sum_over(0, lambda c: [f"_s{c} = 0.0"], terms, lambda c: [f"{t(w, 'k', c)} = _s{c}"])
        if kind in ("square", "exp"):
            base, factor = (a, "2.0*") if kind == "square" else (w, "")
            return self._sum_over(0, lambda c: [f"_s{c} = 0.0"],
                                  lambda c: [f"_s{c} += {at(base, '_j')}*{t(a, 'k - _j', c)}"],
                                  lambda c: [f"{t(w, 'k', c)} = {factor}_s{c}"])
        if kind in ("div", "rdiv"):   # ẇ[k] b[0] = ȧ[k] − w[0] ḃ[k] − Σ_{j=1..k} (w[j] ḃ[k−j] + b[j] ẇ[k−j])
            b = op.args[-1]

            def top(c):   # ȧ[k] (div), or ċ δ_k0 for a constant numerator (rdiv)
                if kind == "div":
                    return t(a, "k", c) if self.moves(a) else "0.0"
                tangent = self.constant(const, c)
                return "0.0" if tangent is None else f"({tangent} if k == 0 else 0.0)"
            if self.moves(b):
                init = lambda c: [f"_s{c} = {top(c)} - {at(w, 0)}*{t(b, 'k', c)}"]  # noqa: E731
                terms = lambda c: [f"_s{c} -= {at(w, '_j')}*{t(b, 'k - _j', c)} + {at(b, '_j')}*{t(w, 'k - _j', c)}"]  # noqa: E731
            else:
                init = lambda c: [f"_s{c} = {top(c)}"]  # noqa: E731
                terms = lambda c: [f"_s{c} -= {at(b, '_j')}*{t(w, 'k - _j', c)}"]  # noqa: E731
            return self._sum_over(1, init, terms, lambda c: [f"{t(w, 'k', c)} = _s{c}/{at(b, 0)}"])
        if kind == "sqrt":            # 2 w[0] ẇ[k] = ȧ[k] − 2 Σ_{j=1..k} w[j] ẇ[k−j]
            return self._sum_over(1, lambda c: [f"_s{c} = 0.0"],
                                  lambda c: [f"_s{c} += {at(w, '_j')}*{t(w, 'k - _j', c)}"],
                                  lambda c: [f"{t(w, 'k', c)} = ({t(a, 'k', c)} - 2.0*_s{c})/(2.0*{at(w, 0)})"])
        if kind == "pow":             # a[0] ẇ[k] = α Σ_{j=0..k} w[j] ȧ[k−j] − Σ_{j=1..k} a[j] ẇ[k−j]
            return self._sum_over(
                1, lambda c: [f"_s{c} = {at(w, 0)}*{t(a, 'k', c)}", f"_r{c} = 0.0"],
                lambda c: [f"_s{c} += {at(w, '_j')}*{t(a, 'k - _j', c)}",
                           f"_r{c} += {at(a, '_j')}*{t(w, 'k - _j', c)}"],
                lambda c: [f"{t(w, 'k', c)} = ({const}*_s{c} - _r{c})/{at(a, 0)}"])
        if kind == "log":             # a[0] ẇ[k] = ȧ[k] − Σ_{j=1..k} a[j] ẇ[k−j]
            return self._sum_over(1, lambda c: [f"_s{c} = {t(a, 'k', c)}"],
                                  lambda c: [f"_s{c} -= {at(a, '_j')}*{t(w, 'k - _j', c)}"],
                                  lambda c: [f"{t(w, 'k', c)} = _s{c}/{at(a, 0)}"])
        raise ValueError(f"no tangent recurrence for the operation {kind!r}")


#: The variables of `_Writer.tangent`'s positions, by coefficient.
_POSITIONS = {"k": "_pk", "k + 1": "_pk1", "_j": "_pj", "k - _j": "_pkj"}


#: The products of a tangent recurrence per term of its sums, by operation (a mul's: per moving operand).
_TANGENT_PRODUCTS = {"sin_cos": 2, "square": 1, "exp": 1, "sqrt": 1, "log": 1, "pow": 2, "rdiv": 1, "div": 1}


def forward_products(program: dict, columns: int, parameters: tuple[int, ...] = ()) -> int:
    """The products per term of the convolutions (the cost of an order, at order ≫ 1) of `forward_source`'s
    tangents: each operation's tangent recurrence, in every column."""
    writer = _Writer(program, columns, parameters)
    count = 0
    for op in program_ops(program):
        if op.kind in ("comment", "pivot", "state") or op.kind in LINEAR or not writer.moves(op.out[0]):
            continue
        moving = sum(writer.moves(a) for a in op.args)
        count += moving if op.kind == "mul" else _TANGENT_PRODUCTS[op.kind] + (op.kind in ("div", "rdiv")
                                                                               and writer.moves(op.args[-1]))
    return count * columns


def forward_source(program: dict, columns: int, parameters: tuple[int, ...] = (), scale: float = 1.0) -> str:
    """The source of ``taylor_variational_coefficients`` for `columns` sensitivity columns, the last of them
    those of `parameters` (indices into p), and of ``VARIATIONAL_COLUMNS`` and ``VARIATIONAL_WORK`` (rows of W)
    for `program` (see the module docstring), to follow the model's module (it uses the module's imports:
    math, sin, cos, ...).  `scale` is the columns' factor (`lagcomp.integrate.sensitivities`): the seeds of
    the parameter columns, the initial-state ones' coming with y."""
    writer = _Writer(program, columns, parameters, scale)
    n_state, ops, rows = program["n_state"], program_ops(program), writer.row_count
    docstring = [
        f"The Taylor coefficients of y = (x, S[:, 0], ..., S[:, {columns - 1}]): x's as `taylor_coefficients`",
        "computes them (rows 0..N-1 of X), then those of each sensitivity column (rows N (1 + c) + i), from",
        "the program differentiated in forward mode (lagcomp.codegen.taylor_variational).  W: the work",
        f"array, {rows} rows of values, then as many of tangents per column.",
        "Returns 0, or j > 0 when pivot j of the LDLᵀ factorization of M is not positive at t."]
    lines = setup_lines(program, columns, parameters)
    lines += ["T = W.reshape(-1)   # the tangents, after the values' rows"]
    padded, base = writer.padded, f"{rows}*(order + 1)"
    lines += [f"_t{s} = {base} + {s * padded}*(order + 1)" for s in range(len(writer.slots))]
    scalars = f"{base} + {len(writer.slots) * padded}*(order + 1)"
    lines += [f"_g{i} = {scalars} + {i * padded}" for i in range(len(writer.scalars))]
    lines += [f"for _c in range({padded}):   # the initial-state columns' seeds come with y; padding: 0"]
    lines += [f"{INDENT}T[_t{i} + _c] = y[{n_state}*(_c + 1) + {i}] if _c < {columns} else 0.0"
              for i in range(n_state)]
    if writer.scalars:
        lines += [f"for _c in range({len(writer.scalars) * padded}):", f"{INDENT}T[_g0 + _c] = 0.0"]
        for position, j in enumerate(parameters):
            column = columns - len(parameters) + position
            for name, i in writer.scalars.items():
                tangent = writer.constants.tangent(name, j)
                if tangent is not None:
                    lines.append(f"T[_g{i} + {column}] = {tangent}")
    lines += ["for k in range(order):", f"{INDENT}_ik1 = 1.0/(k + 1)"]
    looped = writer.looped
    lines += [f"{INDENT}# The tangents of order k, {writer.columns} columns at a time.",
              *[f"{INDENT}for _b in range(0, {padded}, {writer.columns}):"] * looped]
    lines += [INDENT * (2 if looped else 1) + line for line in writer.position_lines()]
    for op in ops:
        tangent = writer.tangent_lines(op)
        if tangent and op.kind != "state":
            tangent = [f"# d({', '.join(op.out)})", *tangent]
        lines += [INDENT * (2 if looped else 1) + line for line in tangent]
    lines.append("return 0")
    return kernel_source(docstring, lines, columns, rows + writer.tangent_rows)


#: The time of a product of `lagcomp.codegen.taylor_jacobian`'s kernel, in products of forward mode's: its
#: convolutions are independent chains (the directions', the columns') in a loop, forward mode's a column's
#: chain (k < 4) or a vector of columns.  Per call at order 13 / 20, the two kernels interleaved (jacobian /
#: forward: time, products; in brackets the weight at which the products' rule ties): double pendulum k = 1:
#: 0.89 / 0.95 for 27/19 (0.63 / 0.67), k = 2: 0.92 / 0.96 for 35/38 (1.0); the three bodies (J dense) k = 1:
#: 1.15 / 1.60 for 108/30 (0.32 / 0.45), k = 2: 0.93 / 0.96 for 144/60 (0.40), k = 4: 0.89 / 0.89 for
#: 216/120 (0.50), k = 6: 0.47 / 0.48 for 288/180 (0.30).  1/2 picks the faster kernel in each but the three
#: bodies' k = 2, a tie.  (2/3 before the column update's accumulators per row, when the three bodies' k = 4
#: took 1.18x forward mode's time; it now took forward mode up to k = 8, at k = 6 twice as slow.)
JACOBIAN_PRODUCT_COST = 1 / 2


def variational_source(program: dict, columns: int, parameters: tuple[int, ...] = (), scale: float = 1.0) -> str:
    """The source of ``taylor_variational_coefficients`` (and its constants) for `columns` sensitivity columns,
    the last of them those of `parameters`, by whichever of `forward_source` and
    `lagcomp.codegen.taylor_jacobian.jacobian_source` takes less time per order: their products per order
    (`forward_products`, `jacobian_products`), the latter's weighted by `JACOBIAN_PRODUCT_COST`."""
    jacobian = JACOBIAN_PRODUCT_COST * jacobian_products(program, columns, parameters)
    if jacobian < forward_products(program, columns, parameters):
        return jacobian_source(program, columns, parameters, scale)
    return forward_source(program, columns, parameters, scale)


def variational_module(module_source: str, program: dict, columns: int, parameters: tuple[int, ...] = (),
                       scale: float = 1.0, values_module: str | None = None) -> str:
    """The model's eager module (whole: the kernel uses its imports), what the variational kernel calls from
    `lagcomp.kernel_support`, ``taylor_coefficients`` from `values_module` (the import name of the model's module
    of the kind "taylor"; None when `module_source` defines it), and the kernel (`variational_source`)."""
    values = "" if values_module is None else f"from {values_module} import {frame.VALUES}  # noqa: E402\n"
    return (module_source.rstrip("\n") + f"\n\n\n# {'-' * 76}\n# The Taylor program differentiated in forward mode"
            f", {columns} columns (lagcomp.codegen.taylor_variational)\n\n"
            + values + support_import_lines(program, lanes=False)
            + variational_source(program, columns, parameters, scale))
