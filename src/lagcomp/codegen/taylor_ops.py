"""The Taylor program as data: its operations and setup statements, and each operation written as code.

`lagcomp.codegen.taylor` decomposes a model's ``rhs`` into these records
(`Op`, `Setup`) and writes the loop kernel ``taylor_coefficients`` from them;
`lagcomp.codegen.taylor_lanes` writes the unrolled batched kernels from the
same records, stored with the model as plain data (no sympy needed then).
The code of an operation is written from its fields (`convolution_loop`,
`linear_line`): the series it reads and writes, and its constant.
"""

from __future__ import annotations

from dataclasses import dataclass

INDENT = "    "

#: The operations with a convolution (coefficient k sums over the lower ones): `taylor_lanes` unrolls them.
CONVOLUTIONS = ("mul", "square", "div", "rdiv", "sqrt", "pow", "exp", "log", "sin_cos")
#: The linear operations (coefficient k from the arguments' coefficient k alone).
LINEAR = ("add", "add_const", "neg", "sub", "rsub_const", "scale")


@dataclass(frozen=True)
class Op:
    """One step of the program at order k.

    ``kind`` is an operation of `CONVOLUTIONS` or `LINEAR`, ``"state"`` (the
    state's next coefficient X[index, k + 1] = f_index[k]/(k + 1)), ``"pivot"``
    (at k = 0, return ``index`` when the pivot ``args[0]`` is not positive
    relative to M's diagonal entry, ``args[1]`` or the constant) or
    ``"comment"`` (the statement of ``rhs`` the next operations compute, in
    ``const``).  ``out`` names the series written (sin_cos: sine, cosine),
    ``args`` the series read, ``const`` a constant operand as code (a number
    or the name of a scalar of the setup).
    """

    kind: str
    out: tuple[str, ...] = ()
    args: tuple[str, ...] = ()
    const: str = ""
    index: int = 0

    def renamed(self, names: dict[str, str]) -> Op:
        """This operation with its series renamed by `names` (others kept)."""
        return Op(self.kind, tuple(names.get(x, x) for x in self.out), tuple(names.get(x, x) for x in self.args),
                  self.const, self.index)


@dataclass(frozen=True)
class Setup:
    """One statement before the order loop.

    ``kind`` ``"state"``: the series ``name`` is row ``index`` of X (the state);
    ``"param"``: ``name = p[index]``; ``"constant"``: ``name = code``, over the
    parameters; ``"check"``: return ``index`` unless ``code`` (a constant pivot
    test) holds; ``"partial"``: ``name = code``, the partial derivative of a
    constant with respect to parameter ``index`` (only the variational kernel,
    `lagcomp.codegen.taylor_variational`, evaluates these).
    """

    kind: str
    name: str = ""
    code: str = ""
    index: int = 0


def setup_statements(setup, parameters: tuple[int, ...] = (), indent: str = "    ") -> list[str]:
    """The lines of the `Setup` statements of a kernel that reads p itself (``taylor_coefficients``, the
    variational kernels): the parameters' and constants' scalars, the pivot checks returning their index, and the
    partials with respect to the `parameters` (the variational kernels' parameter columns; none otherwise).  The
    lanes' kernel reads P by lane and folds its checks into a flag: `lagcomp.codegen.taylor_lanes` writes its
    own."""
    lines = []
    for statement in setup:
        if statement.kind == "param":
            lines.append(f"{statement.name} = p[{statement.index}]")
        elif statement.kind == "constant" or (statement.kind == "partial" and statement.index in parameters):
            lines.append(f"{statement.name} = {statement.code}")
        elif statement.kind == "check":
            lines += [f"if not {statement.code}:", f"{indent}return {statement.index}"]
    return lines


def partial_name(name: str, parameter: int) -> str:
    """The name of the setup's ``partial`` of the scalar `name` with respect to parameter `parameter`."""
    return f"_dp{parameter}{name}"


def support_names(kinds, checks: bool, lanes: bool) -> set[str]:
    """The `lagcomp.kernel_support` names a Taylor program calls: sin and cos (vsin and vcos in lane
    kernels) for a ``sin_cos`` among the operation `kinds`, and ``PIVOT_TOLERANCE`` for a pivot test
    (a ``pivot`` operation, or setup `checks`)."""
    names = set()
    if "sin_cos" in kinds:
        names |= {"vsin", "vcos"} if lanes else {"sin", "cos"}
    if checks or "pivot" in kinds:
        names.add("PIVOT_TOLERANCE")
    return names


def support_import_lines(program: dict, lanes: bool) -> str:
    """The import lines of what the kernels written from the stored `program` (`lagcomp.codegen.taylor.
    taylor_program`) call from `lagcomp.kernel_support` (`support_names`), for code appended to a module whose
    own imports may lack them (``noqa: E402``: after its code)."""
    kinds = {op["kind"] for op in program["body"]}
    checks = any(entry["kind"] == "check" for entry in program["setup"])
    names = support_names(kinds, checks, lanes)
    trig = ", ".join(name for name in ("cos", "sin", "vcos", "vsin") if name in names)
    lines = [f"from lagcomp.kernel_support.trig import {trig}  # noqa: E402\n"] if trig else []
    if "PIVOT_TOLERANCE" in names:
        lines.append("from lagcomp.kernel_support.linear_solvers import PIVOT_TOLERANCE  # noqa: E402\n")
    return "".join(lines) + "\n"


def pivot_test(pivot: str, scale: str) -> str:
    """The condition that the pivot (code) is positive relative to M's diagonal entry `scale` (code)."""
    return f"{pivot} > PIVOT_TOLERANCE*abs({scale})"


def convolution_loop(op: Op, at) -> tuple[str, list[str]]:
    """Operation `op` of `CONVOLUTIONS` as the loop computing coefficient k of its result: (summary, lines).

    The loop reads coefficients 0..k of the arguments and 0..k−1 of the result; ``at(name, index)``
    is the code of coefficient `index` (code) of the series `name`.  The frequent operations (mul,
    square, div, sin/cos) sum even and odd terms into two accumulators: a single running sum is a
    chain of dependent additions (the loops are too short for vectorization to pay), and halving
    the chain makes the double pendulum's coefficients 1.8x faster (4.1 -> 2.3 us per call at
    order 20).
    """
    kind, c = op.kind, op.const
    if kind == "sin_cos":
        (a,), (s, co) = op.args, op.out
        return f"{s}, {co} = sin({a}), cos({a})", [
            "if k == 0:", f"    {at(s, 0)} = sin({at(a, 0)})", f"    {at(co, 0)} = cos({at(a, 0)})", "else:",
            f"    _ja = k*{at(a, 'k')}", f"    _s = _ja*{at(co, 0)} if k % 2 == 1 else 0.0",
            f"    _c = _ja*{at(s, 0)} if k % 2 == 1 else 0.0", "    _r = 0.0", "    _d = 0.0",
            "    for _j in range(1, k, 2):", f"        _ja = _j*{at(a, '_j')}",
            f"        _jb = (_j + 1)*{at(a, '_j + 1')}",
            f"        _s += _ja*{at(co, 'k - _j')}", f"        _c += _ja*{at(s, 'k - _j')}",
            f"        _r += _jb*{at(co, 'k - 1 - _j')}", f"        _d += _jb*{at(s, 'k - 1 - _j')}",
            f"    {at(s, 'k')} = (_s + _r)*_ik", f"    {at(co, 'k')} = -(_c + _d)*_ik"]
    (w,) = op.out
    if kind == "mul":
        a, b = op.args
        return f"{w} = {a}*{b}", [
            f"_s = {at(a, 'k')}*{at(b, 0)} if k % 2 == 0 else 0.0", "_r = 0.0", "for _j in range(0, k, 2):",
            f"    _s += {at(a, '_j')}*{at(b, 'k - _j')}", f"    _r += {at(a, '_j + 1')}*{at(b, 'k - 1 - _j')}",
            f"{at(w, 'k')} = _s + _r"]
    (a, *rest) = op.args
    if kind == "square":
        return f"{w} = {a}**2", [
            "_m = (k + 1)//2", f"_s = {at(a, '_m - 1')}*{at(a, 'k - _m + 1')} if _m % 2 == 1 else 0.0", "_r = 0.0",
            "for _j in range(0, _m - 1, 2):", f"    _s += {at(a, '_j')}*{at(a, 'k - _j')}",
            f"    _r += {at(a, '_j + 1')}*{at(a, 'k - 1 - _j')}",
            f"{at(w, 'k')} = 2.0*(_s + _r) + ({at(a, 'k//2')}*{at(a, 'k//2')} if k % 2 == 0 else 0.0)"]
    if kind in ("div", "rdiv"):
        # div: w = a/b; rdiv: w = c/b with the constant c (op.args holds b alone)
        b = rest[0] if kind == "div" else a
        if kind == "div":
            top, summary = at(a, "k"), f"{w} = {a}/{b}"
        else:
            top, summary = f"({c} if k == 0 else 0.0)", f"{w} = {c}/{b}"
        return summary, [
            f"_s = {top} - ({at(b, 'k')}*{at(w, 0)} if k % 2 == 1 else 0.0)", "_r = 0.0", "for _j in range(1, k, 2):",
            f"    _s -= {at(b, '_j')}*{at(w, 'k - _j')}", f"    _r += {at(b, '_j + 1')}*{at(w, 'k - 1 - _j')}",
            f"{at(w, 'k')} = (_s - _r)/{at(b, 0)}"]
    if kind == "sqrt":
        return f"{w} = sqrt({a})", [
            "if k == 0:", f"    {at(w, 0)} = math.sqrt({at(a, 0)})", "else:", f"    _s = {at(a, 'k')}",
            "    for _j in range(1, k):", f"        _s -= {at(w, '_j')}*{at(w, 'k - _j')}",
            f"    {at(w, 'k')} = _s/(2.0*{at(w, 0)})"]
    if kind == "pow":
        return f"{w} = {a}**{c}", [
            "if k == 0:", f"    {at(w, 0)} = {at(a, 0)}**{c}", "else:", "    _s = 0.0", "    for _j in range(k):",
            f"        _s += ({c}*(k - _j) - _j)*{at(a, 'k - _j')}*{at(w, '_j')}",
            f"    {at(w, 'k')} = _s*_ik/{at(a, 0)}"]
    if kind == "exp":
        return f"{w} = exp({a})", [
            "if k == 0:", f"    {at(w, 0)} = math.exp({at(a, 0)})", "else:", "    _s = 0.0",
            "    for _j in range(1, k + 1):", f"        _s += _j*{at(a, '_j')}*{at(w, 'k - _j')}",
            f"    {at(w, 'k')} = _s*_ik"]
    if kind == "log":
        return f"{w} = log({a})", [
            "if k == 0:", f"    {at(w, 0)} = math.log({at(a, 0)})", "else:", "    _s = 0.0",
            "    for _j in range(1, k):", f"        _s += _j*{at(w, '_j')}*{at(a, 'k - _j')}",
            f"    {at(w, 'k')} = ({at(a, 'k')} - _s*_ik)/{at(a, 0)}"]
    raise ValueError(f"no loop for the operation {kind!r}")


def linear_line(op: Op, at, first: bool | None = None) -> str:
    """Coefficient k of a `LINEAR` operation or a ``"state"`` one, as one statement.

    `first` tells whether k = 0 (the constant of add_const and rsub_const, and of a constant
    derivative, enters at order 0 only); None writes the choice into the statement (``if k == 0``).
    ``at(name, "k")`` is the code of coefficient k of the series `name`.
    """
    kind, c = op.kind, op.const

    def at_zero(value: str, rest: str) -> str:
        return f"{value} if k == 0 else {rest}" if first is None else (value if first else rest)
    if kind == "state":
        value = at(op.args[0], "k") if op.args else (f"({at_zero(c, '0.0')})" if first is None else at_zero(c, "0.0"))
        return value
    (w,) = op.out
    a = op.args[0]
    value = {
        "add": lambda: f"{at(a, 'k')} + {at(op.args[-1], 'k')}",
        "sub": lambda: f"{at(a, 'k')} - {at(op.args[-1], 'k')}",
        "neg": lambda: f"-{at(a, 'k')}",
        "scale": lambda: f"{c}*{at(a, 'k')}",
        "add_const": lambda: at_zero(f"{at(a, 'k')} + {c}", at(a, "k")),
        "rsub_const": lambda: at_zero(f"{c} - {at(a, 'k')}", f"-{at(a, 'k')}"),
    }[kind]()
    return f"{at(w, 'k')} = {value}"


def value_lines(op: Op, at) -> list[str]:
    """Coefficient k of `op`'s value(s): the code of ``taylor_coefficients`` (`lagcomp.codegen.taylor`), with
    ``at(name, index)`` the code of a coefficient (a writer's ``at``)."""
    if op.kind == "comment":
        return [f"# {op.const}"]
    if op.kind == "pivot":
        scale = at(op.args[1], 0) if len(op.args) > 1 else op.const
        return [f"if k == 0 and not {pivot_test(at(op.args[0], 0), scale)}:", f"{INDENT}return {op.index}"]
    if op.kind == "state":
        return [f"X[{op.index}, k + 1] = {linear_line(op, at)}*_ik1"]
    if op.kind in LINEAR:
        return [linear_line(op, at)]
    summary, loop = convolution_loop(op, at)
    return [f"# {summary}", *loop]
