"""A large Taylor program's order loop as a sequence of numba functions of bounded size (issues 35, 39).

numba's compile time of one function grows about as its size squared (measured, CPU, numba alone, one function
``taylor_coefficients`` of a planar chain: 3 links, 192 series operations per order, 15 s; 5 links, 404, 62 s;
10 links, 934, 399 s and 4.5 GB).  So a program of more than `SPLIT_OPERATIONS` operations per order is emitted as
chunks of consecutive operations, each an ``@njit`` function ``_<name>_part<i>(k, X, W, scalars...)`` computing
coefficient k of its operations (the same code as the unsplit loop's body, `lagcomp.codegen.taylor_ops.value_lines`,
on the same rows of X and W, with the same fastmath flags), and the function's order loop calls them in order.
The setup's scalars a chunk reads are its arguments (computed once, before the loop, as in the unsplit function).
A chunk with pivot tests returns 0 or the failing pivot's index, which the loop returns; the others return nothing.

A program up to `SPLIT_OPERATIONS` (every bundled example) is emitted as one function, its source unchanged.  The
calls cost run time (order 20: a 3-link planar chain, 192 operations in 3 chunks, 16.7 µs against 13.8 µs in one
function; 2 ball joints, 596 in 10, 59.1 against 52.9 µs) and save compile time (3 links: 11.3 s of CPU against 15 s;
2 ball joints: 39 s and 0.31 GB against 121 s and 2.3 GB); with chunks of 16 to 128 operations a 4-link chain's
compile took 18 to 22 s, its calls fastest from 64 up.

The chunks compute what the one function computes, in its order, so their results are bitwise its own as far as the
compiler keeps them: under ``fastmath={"contract"}`` LLVM fuses a product into a sum (one rounding, an fma) where both
end in one basic block after its own transformations, which depend on the code around a cut.  Observed: bitwise
equal with chunks of 64 (a 4-link planar chain, a chain of 2 ball joints, the 3-link pendulum); the 3-link pendulum
cut into chunks of 8 to 32 differs in the last bit of a few coefficients (`tests/test_taylor_split.py`).
"""

from __future__ import annotations

from lagcomp.codegen.taylor_ops import INDENT, Op, value_lines

#: Programs of more series operations per order than this are split into chunks (`split_body`).
SPLIT_OPERATIONS = 160
#: Series operations per chunk (at least; a chunk ends at the next statement of ``rhs``, up to twice this).
CHUNK_OPERATIONS = 64
#: The flags of every function of the program: the chunks contract as the unsplit function does.
NJIT = '@njit(cache=True, error_model="numpy", fastmath={"contract"})'


def counted(op: Op) -> bool:
    """Whether `op` is a series operation (`lagcomp.codegen.taylor.TaylorProgram.operation_count`)."""
    return op.kind not in ("pivot", "comment")


def split_body(body: list[Op], chunk: int = CHUNK_OPERATIONS) -> list[list[Op]]:
    """`body` cut into consecutive chunks of `chunk` series operations or more: a chunk ends before the next
    comment (the next statement of ``rhs``) once it holds `chunk`, or at 2 `chunk` within a long statement."""
    chunks, current, count = [], [], 0
    for op in body:
        if count >= 2 * chunk or (count >= chunk and op.kind == "comment"):
            chunks.append(current)
            current, count = [], 0
        current.append(op)
        count += counted(op)
    return [*chunks, current] if current else chunks


def chunked_loop(name: str, body: list[Op], at, rows: dict[str, str], scalars: list[str],
                 chunk: int = CHUNK_OPERATIONS) -> tuple[str, list[str]]:
    """The chunk functions of `body` (source) and the order loop calling them (lines of the function `name`).

    ``at(series, index)`` is the code of a coefficient, `rows` maps each series to the line defining its row index
    (``"_u3 = 7"``), `scalars` are the setup's scalar names in order (a chunk takes those its operations read)."""
    sources, loop = [], ["for k in range(order):"]
    for i, ops in enumerate(split_body(body, chunk)):
        part = f"_{name}_part{i}"
        read = {op.const for op in ops}
        arguments = ", ".join(["k", "X", "W", *(s for s in scalars if s in read)])
        sources.append(_chunk_source(part, name, ops, at, rows, arguments))
        if any(op.kind == "pivot" for op in ops):
            loop += [f"{INDENT}_status = {part}({arguments})", f"{INDENT}if _status != 0:",
                     f"{INDENT * 2}return _status"]
        else:
            loop.append(f"{INDENT}{part}({arguments})")
    return "".join(sources), loop


def _chunk_source(part: str, name: str, ops: list[Op], at, rows: dict[str, str], arguments: str) -> str:
    """The source of the chunk function `part` of `name`'s operations `ops` at order k."""
    used = dict.fromkeys(series for op in ops for series in (*op.out, *op.args))
    pivots = any(op.kind == "pivot" for op in ops)
    summary = f"Coefficient k of {sum(map(counted, ops))} series operations of `{name}`, in its order (the loop calls"
    lines = [f'"""{summary} its parts in turn);',
             f'returns {"0, or the index of a pivot that is not positive" if pivots else "nothing"}."""',
             *(rows[series] for series in used if series in rows),
             "_ik = 1.0/k if k > 0 else 0.0", "_ik1 = 1.0/(k + 1)",
             *(line for op in ops for line in value_lines(op, at))]
    if pivots:
        lines.append("return 0")
    body = "\n".join(INDENT + line if line else "" for line in lines)
    return f"\n\n{NJIT}\ndef {part}({arguments}):\n{body}\n"
