"""The Taylor program unrolled at one order, over SIMD lanes: the kernel of batched Taylor sweeps.

``taylor_coefficients`` (`lagcomp.codegen.taylor`) loops over the orders k
and, inside each series operation, over the terms j of its convolution.
Those short loops with data-dependent trip counts keep LLVM from vectorizing
anything across trajectories (a probe with the lanes as the innermost array
axis ran no faster per trajectory than the scalar kernel: the accumulators
cannot stay in registers, and numba's arrays may alias).  Here the order p
is fixed when the source is written, so every coefficient u[k] of every
intermediate series is a local variable ``u_k`` and every convolution a
sum written out: the per-trajectory program is straight-line code, the
same shape as ``rhs_lanes``, and the loop over lanes around it vectorizes
(4 lanes per AVX2 instruction).  heyoka's batch mode compiles the same way.

The source depends on the order, so it is written when a sweep asks for it
(`taylor_lanes_source`), from the program's records alone (no sympy):
`lagcomp.codegen.taylor.taylor_program` stores it with the model's module
(cache metadata).  Each operation
sums its terms in the order of the loop kernel (even and odd terms in two
accumulators), so a lane follows the scalar method closely; it is not
bitwise the same, since LLVM may fuse a different product of a sum into a
multiply-add.

Generated functions, p the order and L the lanes; every array is flat with
the lane last, ``A[row*L + l]`` (numba indexes 2-d arrays with run-time
strides, and LLVM needs one run-time overlap check per store then: past 8 of
them it does not vectorize)::

    taylor_lanes(T, Y, P, X)
        T (L,) times, Y (4n·L,) states, then the carries of the
        compensated sum (read for the periodic coordinates only, which enter
        the series reduced to [−π, π] as in ``taylor_run``),
        P (n_p·L,) parameters; out X:
        rows i(p + 1) + k the normalized coefficients y_i⁽ᵏ⁾/k!, k = 0..p,
        then rows 2n(p + 1) + 0, 1, 2 the max norms of y, of its
        coefficients p and p − 1, and row 2n(p + 1) + 3 is 1.0 where a
        pivot of M is not positive (M singular), else 0.0.
    taylor_lanes_advance(H, X, S, S_new)
        S (4n·L,) states (rows 0..2n−1) and carries of the compensated sum
        (rows 2n..4n−1); out S_new: the same after a step H[l] in each lane.
"""

from __future__ import annotations

import math

from lagcomp.codegen.taylor_ops import (
    CONVOLUTIONS,
    LINEAR,
    Op,
    Setup,
    linear_line,
    pivot_test,
    support_import_lines,
)

INDENT = "    "


def _series(name: str, k: int) -> str:
    """The local holding coefficient k of the series `name` (a prefix no parameter or rhs local has)."""
    return f"_o{k}_{name}"


def _sum(terms: list[str]) -> str:
    return " + ".join(terms) if terms else "0.0"


def _convolution(k: int, a: str, b: str, first: int = 0) -> tuple[list[str], list[str]]:
    """Terms a_j b_{k−j}, j = first..k, split as the loop kernel sums them: even and odd j."""
    even = [f"{_series(a, j)}*{_series(b, k - j)}" for j in range(first, k + 1) if (j - first) % 2 == 0]
    odd = [f"{_series(a, j)}*{_series(b, k - j)}" for j in range(first, k + 1) if (j - first) % 2 == 1]
    return even, odd


def _both(even: list[str], odd: list[str]) -> str:
    """The two accumulators added, as the loop kernel does at the end."""
    if not odd:
        return _sum(even)
    return f"({_sum(even)}) + ({_sum(odd)})"


def _operation(op: Op, k: int) -> list[str]:
    """Coefficient k of one operation of `CONVOLUTIONS` (the recurrences of `lagcomp.codegen.taylor`)."""
    s = _series
    inverse_k = repr(1.0 / k) if k else "0.0"
    f, w, c = op.kind, op.out[0], op.const
    if f == "mul":
        a, b = op.args
        even, odd = _convolution(k, a, b)
        return [f"{s(w, k)} = {_both(even, odd)}"]
    if f == "square":
        (a,) = op.args
        pairs = [f"{s(a, j)}*{s(a, k - j)}" for j in range((k + 1) // 2)]
        middle = f"{s(a, k // 2)}*{s(a, k // 2)}" if k % 2 == 0 else None
        if not pairs:
            return [f"{s(w, k)} = {middle}"]
        doubled = f"2.0*({_both(pairs[0::2], pairs[1::2])})"
        return [f"{s(w, k)} = {doubled}" + (f" + {middle}" if middle else "")]
    if f in ("div", "rdiv"):
        b = op.args[-1]
        top = s(op.args[0], k) if f == "div" else (c if k == 0 else "0.0")
        even, odd = _convolution(k, b, w, first=1)
        if not even:
            return [f"{s(w, k)} = {top}/{s(b, 0)}"]
        return [f"{s(w, k)} = ({top} - ({_both(even, odd)}))/{s(b, 0)}"]
    a = op.args[0]
    if f == "sqrt":
        if k == 0:
            return [f"{s(w, 0)} = math.sqrt({s(a, 0)})"]
        terms = [f"{s(w, j)}*{s(w, k - j)}" for j in range(1, k)]
        return [f"{s(w, k)} = ({s(a, k)} - ({_sum(terms)}))/(2.0*{s(w, 0)})"]
    if f == "pow":
        if k == 0:
            return [f"{s(w, 0)} = {s(a, 0)}**{c}"]
        terms = [f"({c}*{k - j} - {j})*{s(a, k - j)}*{s(w, j)}" for j in range(k)]
        return [f"{s(w, k)} = ({_sum(terms)})*{inverse_k}/{s(a, 0)}"]
    if f == "exp":
        if k == 0:
            return [f"{s(w, 0)} = math.exp({s(a, 0)})"]
        terms = [f"{j}.0*{s(a, j)}*{s(w, k - j)}" for j in range(1, k + 1)]
        return [f"{s(w, k)} = ({_sum(terms)})*{inverse_k}"]
    if f == "log":
        if k == 0:
            return [f"{s(w, 0)} = math.log({s(a, 0)})"]
        terms = [f"{j}.0*{s(w, j)}*{s(a, k - j)}" for j in range(1, k)]
        return [f"{s(w, k)} = ({s(a, k)} - ({_sum(terms)})*{inverse_k})/{s(a, 0)}"]
    if f == "sin_cos":
        sine, cosine = op.out
        if k == 0:
            return [f"{s(sine, 0)} = vsin({s(a, 0)})", f"{s(cosine, 0)} = vcos({s(a, 0)})"]
        scaled = lambda j: f"{j}.0*{s(a, j)}"  # noqa: E731
        # the loop kernel's accumulators: odd k starts with j = k; then pairs (j, j + 1) for odd j
        def split(other: str) -> str:
            first = [f"{scaled(k)}*{s(other, 0)}"] if k % 2 == 1 else []
            odd = [f"{scaled(j)}*{s(other, k - j)}" for j in range(1, k, 2)]
            even = [f"{scaled(j + 1)}*{s(other, k - 1 - j)}" for j in range(1, k, 2)]
            return _both(first + odd, even)
        return [f"{s(sine, k)} = ({split(cosine)})*{inverse_k}", f"{s(cosine, k)} = -({split(sine)})*{inverse_k}"]
    raise ValueError(f"no unrolled form of {f}")


def _order_lines(body: list[Op], k: int, states: dict[int, str]) -> list[str]:
    """The statements of order `k`: every operation of the program at k, pivot tests at k = 0."""
    def at(name: str, index: str) -> str:
        return _series(name, k if index == "k" else int(index))
    lines = []
    for op in body:
        if op.kind == "comment":
            continue
        if op.kind == "pivot":
            if k == 0:
                scale = _series(op.args[1], 0) if len(op.args) > 1 else op.const
                lines.append(f"_ok = _ok & ({pivot_test(_series(op.args[0], 0), scale)})")
        elif op.kind == "state":
            lines.append(f"{_series(states[op.index], k + 1)} = {linear_line(op, at, first=k == 0)}*{1.0 / (k + 1)!r}")
        elif op.kind in LINEAR:
            lines.append(linear_line(op, at, first=k == 0))
        else:
            lines += _operation(op, k)
    return lines


def taylor_lanes_source(program: dict, order: int, lanes: int) -> str:
    """The source of ``taylor_lanes`` and ``taylor_lanes_advance`` at `order` for `program`.

    `program` is `lagcomp.codegen.taylor.taylor_program`'s data:
    ``n_state``, ``setup`` and ``body`` (the fields of its `Setup` and `Op`
    records, `lagcomp.codegen.taylor_ops`), ``states`` (series name of each state component, in order),
    ``uses_t`` and ``periodic``.
    """
    n_state, states = program["n_state"], dict(enumerate(program["states"]))
    body = [Op(op["kind"], tuple(op["out"]), tuple(op["args"]), op["const"], op["index"]) for op in program["body"]]
    lines = ["_ok = True"]
    for statement in (Setup(**entry) for entry in program["setup"]):
        if statement.kind == "param":
            lines.append(f"{statement.name} = P[{statement.index * lanes} + _l]")
        elif statement.kind == "constant":
            lines.append(f"{statement.name} = {statement.code}")
        elif statement.kind == "check":
            lines.append(f"_ok = _ok & ({statement.code})")
    periodic = set(program.get("periodic", ()))
    lines += [f"{_series(states[i], 0)} = reduced_angle(Y[{i * lanes} + _l], Y[{(n_state + i) * lanes} + _l])"
              if i in periodic else f"{_series(states[i], 0)} = Y[{i * lanes} + _l]" for i in range(n_state)]
    if program["uses_t"]:
        lines += [f"{_series('_t', 0)} = T[_l]", f"{_series('_t', 1)} = 1.0"]
        lines += [f"{_series('_t', k)} = 0.0" for k in range(2, order + 1)]
    for k in range(order):
        lines.append(f"# order {k}")
        lines += _order_lines(body, k, states)
    # coefficient 0 is y itself, also for a periodic coordinate (as in taylor_run)
    lines += [f"X[{(i * (order + 1) + k) * lanes} + _l] = "
              + (f"Y[{i * lanes} + _l]" if k == 0 else _series(states[i], k))
              for i in range(n_state) for k in range(order + 1)]
    # then the max norms of y and of its last two coefficients (for the step, as in taylor_run), and the pivots
    first = n_state * (order + 1)
    for row, k in ((first, 0), (first + 1, order), (first + 2, order - 1)):
        lines.append("_norm = 0.0")
        lines += [f"_norm = max(_norm, abs({f'Y[{i * lanes} + _l]' if k == 0 else _series(states[i], k)}))"
                  for i in range(n_state)]
        lines.append(f"X[{row * lanes} + _l] = _norm")
    lines.append(f"X[{(first + 3) * lanes} + _l] = 0.0 if _ok else 1.0")
    doc = f"Coefficients of order 0..{order} of every lane; see lagcomp.codegen.taylor_lanes."
    kernel = _lane_loop("taylor_lanes(T, Y, P, X)", doc, lanes, lines)
    return kernel + "\n\n" + _advance_source(n_state, order, lanes)


def _advance_source(n_state: int, order: int, lanes: int) -> str:
    """``taylor_lanes_advance``: every lane's new state, Horner's rule and compensated sums as ``taylor_run``'s."""
    lines = ["_h = H[_l]"]
    for i in range(n_state):
        top = f"X[{(i * (order + 1) + order) * lanes} + _l]"
        horner = f"{top}*_h"
        for k in range(order - 1, 0, -1):
            horner = f"({horner} + X[{(i * (order + 1) + k) * lanes} + _l])*_h"
        y, carry = f"S[{i * lanes} + _l]", f"S[{(n_state + i) * lanes} + _l]"
        lines += [f"_increment = {horner} - {carry}", f"_y = {y} + _increment",
                  f"S_new[{i * lanes} + _l] = _y", f"S_new[{(n_state + i) * lanes} + _l] = (_y - {y}) - _increment"]
    doc = "Every lane's state and carry S_new after its step H[l] from S; see lagcomp.codegen.taylor_lanes."
    return _lane_loop("taylor_lanes_advance(H, X, S, S_new)", doc, lanes, lines)


def _lane_loop(signature: str, doc: str, lanes: int, lines: list[str]) -> str:
    """A function whose body is `lines` in a loop over the lanes ``_l`` (which LLVM vectorizes).

    Arrays are flat, indexed ``row*lanes + _l`` with constant rows (see the module docstring).
    """
    body = "\n".join(2 * INDENT + line for line in lines)
    return (
        f'@njit(cache=True, error_model="numpy", fastmath={{"contract"}}, nogil=True)\n'
        f"def {signature}:\n"
        f'{INDENT}"""{doc}"""\n'
        f"{INDENT}for _l in range({lanes}):\n"
        f"{body}\n"
    )


#: Lanes of a batch: enough for LLVM to vectorize the loop around the straight-line body (with 8 it
#: unrolls the loop instead, and keeps the code scalar), few enough for the coefficients of a batch
#: to stay in the L1 cache (double pendulum at order 13: 14 KiB).
LANES = 32


def taylor_order(rtol: float, atol: float) -> int:
    """The order ``taylor_run`` uses for these tolerances: ceil(−½ ln min(rtol, atol) + 1), at least 2."""
    return max(2, int(math.ceil(-0.5 * math.log(min(rtol, atol)) + 1.0)))


#: Largest unrolled program written (`unrolled_terms`).  numba's compile time grows about linearly
#: with the terms: the wall time of a model's first batched Taylor sweep at rtol = atol = 1e-10
#: (order 13), empty caches, was 10 s for the double pendulum (1,508 terms) and 21 s for
#: n_link_pendulum(3) (4,303), so the limit stands at about a minute.
TERMS_MAX = 12_000


def unrolled_terms(program: dict, order: int) -> int:
    """About how many products and sums `taylor_lanes_source` writes for `program` at `order`.

    A convolution (an operation of `CONVOLUTIONS`) has k + 1 terms at order k,
    sin and cos twice that; any other operation (comments and pivot tests
    aside) one per order.
    """
    operations = [op["kind"] for op in program["body"] if op["kind"] not in ("pivot", "comment")]
    calls = [kind for kind in operations if kind in CONVOLUTIONS]
    convolutions = sum(2 if kind == "sin_cos" else 1 for kind in calls)
    return convolutions * order * (order + 1) // 2 + (len(operations) - len(calls)) * order


def taylor_lanes_module(module_source: str, program: dict, order: int, lanes: int = LANES) -> str:
    """A module for batched Taylor sweeps at `order`: the model's module and its lane kernels of that order.

    The model's module comes first, whole, so that the new module stands on
    its own (numba caches it by its own file; a Dask worker builds it from
    this text alone); numba compiles only the kernels a sweep calls.  The
    loop around the kernels is library code
    (`lagcomp.integrate.drivers.taylor_lanes.sweep_taylor_lanes`), which takes
    ``TAYLOR_ORDER`` and ``TAYLOR_LANES`` with them.
    """
    return (
        module_source.rstrip("\n")
        + f"\n\n\n# {'-' * 76}\n# Batched Taylor sweeps at order {order}, {lanes} lanes"
        + " (lagcomp.codegen.taylor_lanes)\n\n"
        + "from lagcomp.kernel_support.angles import reduced_angle  # noqa: E402\n"
        + support_import_lines(program, lanes=True)
        + "#: The order and lane count of the lane kernels below.\n"
        + f"TAYLOR_ORDER = {order}\nTAYLOR_LANES = {lanes}\n\n\n"
        + taylor_lanes_source(program, order, lanes)
    )
