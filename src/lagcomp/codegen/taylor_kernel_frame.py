"""The frame of a ``taylor_variational_coefficients`` kernel, shared by its two writers: forward mode
(`lagcomp.codegen.taylor_variational`) and the Jacobian's series (`lagcomp.codegen.taylor_jacobian`).

Both write the same kernel around a body of their own: the columns of one pass (`block_width` and its
limits), the rows of W (`work_rows`), the tangents of the program's scalars (`ScalarTangents`), the
statements before the order loop (`setup_lines`) and the function around the body with its constants
(`kernel_source`, which refuses a body too large for numba: `check_size`); the values' coefficients, every
order, are the model's ``taylor_coefficients`` called before the tangents' loop (`VALUES`).
"""

from __future__ import annotations

from lagcomp.codegen.taylor_ops import (
    Op,
    Setup,
    partial_name,
    setup_statements,
)
from lagcomp.errors import OptionError

INDENT = "    "
KERNEL = "taylor_variational_coefficients"
#: The kernel the variational kernel calls for the values' coefficients, every order, before its tangents' loop:
#: the model's own (`lagcomp.integrate.taylor_sensitivities.values_import`), compiled once per model, not once per
#: choice of columns, and its X and W rows bitwise the variational kernel's by construction.
VALUES = "taylor_coefficients"
#: Up to this many columns are written out in one pass (`block_width`); more take a loop over blocks of `BLOCK`.
UNROLLED_COLUMNS = 9
#: Columns of one pass of the loop over blocks: an AVX2 vector of float64.
BLOCK = 4
#: Most lines of a kernel's body (`check_size`): the tangents are one function (the values' coefficients are the
#: model's ``taylor_coefficients``, split in chunks when large), whose numba compile took (CPU, cold,
#: `bench.bench_kernel_compile`) 2.6 s at 208 lines (the double pendulum, 4 columns), 5.1 s at 381 (9 columns with
#: the parameters): growing faster than the lines (one function's, as size² in `lagcomp.codegen.taylor_split`), so
#: that 4000 lines, extrapolated, take minutes to a quarter of an hour; a 6-link planar chain's 12 columns are 6,200.
KERNEL_LINES_MAX = 4000
#: Most columns × operations written out in one pass (`block_width`): numba's compile time grows faster than
#: the code (n_link_pendulum(5), 261 operations, 10 columns in one pass: 12 minutes).
COLUMN_OPERATIONS_MAX = 600


def block_width(program: dict, columns: int) -> int:
    """The columns of one pass of the kernel's loop over them.  Every column written out is fastest (the double
    pendulum, order 20: 8 columns in one pass 11 µs, in two of 4 in a loop 18 µs: in a loop LLVM no longer makes
    a block's chains one vector), up to `UNROLLED_COLUMNS`; then blocks of `BLOCK`; fewer when the program is
    so large that compiling them would take minutes (`COLUMN_OPERATIONS_MAX`)."""
    width = columns if columns <= UNROLLED_COLUMNS else BLOCK
    return max(1, min(width, COLUMN_OPERATIONS_MAX // max(program["operations"], 1)))


def work_rows(program: dict) -> list[str]:
    """The series held in rows of W, in order, as ``taylor_coefficients`` holds them (time first, if used)."""
    outputs = [name for op in program["body"] for name in op["out"]]
    return (["_t"] if program["uses_t"] else []) + outputs


def program_ops(program: dict) -> list[Op]:
    return [Op(op["kind"], tuple(op["out"]), tuple(op["args"]), op["const"], op["index"]) for op in program["body"]]


class ScalarTangents:
    """The tangents of the program's scalars: a parameter's own column gets `scale` (the columns' factor,
    `lagcomp.integrate.sensitivities`), a scalar its setup's ``partial`` (times `scale`), any other nothing."""

    def __init__(self, program: dict, parameters: tuple[int, ...], scale: float):
        self.parameters, self.scale = parameters, scale
        self.own = {entry["name"]: entry["index"] for entry in program["setup"] if entry["kind"] == "param"}
        self.partials = {entry["name"] for entry in program["setup"] if entry["kind"] == "partial"}

    def tangent(self, const: str, j: int | None) -> str | None:
        """The code of ∂const/∂p_j (times the scale), or None when it is 0 (j None: an initial-state column)."""
        if j is None:
            return None
        if self.own.get(const) == j:
            return repr(self.scale)
        if partial_name(const, j) in self.partials:
            partial = partial_name(const, j)
            return partial if self.scale == 1.0 else f"{self.scale!r}*{partial}"
        return None

    def varies(self, const: str) -> bool:
        return any(self.tangent(const, j) is not None for j in self.parameters)


def setup_lines(program: dict, columns: int, parameters: tuple[int, ...]) -> list[str]:
    """The kernel's statements before its order loop: the setup's scalars (and the partials of the `parameters`'
    columns), the pivot checks, coefficient 0 of the columns' rows of X (N (1 + c) + i), then every value's
    coefficients, all orders, by a call of ``taylor_coefficients`` (`VALUES`), returning its status if not 0."""
    n_state = program["n_state"]
    lines = ["order = X.shape[1] - 1", *setup_statements((Setup(**entry) for entry in program["setup"]), parameters,
                                                          INDENT)]
    lines += [f"for i in range({n_state}, {n_state * (1 + columns)}):", f"{INDENT}X[i, 0] = y[i]"]
    return lines + [f"_status = {VALUES}(t, y, p, X, W)   # x's rows of X, the values' rows of W",
                    "if _status != 0:", f"{INDENT}return _status"]


def kernel_source(docstring: list[str], lines: list[str], columns: int, work: int) -> str:
    """The kernel ``taylor_variational_coefficients`` of the body `lines` (and its `docstring`'s lines), then
    ``VARIATIONAL_COLUMNS`` (`columns`) and ``VARIATIONAL_WORK`` (`work`, the rows of W); an OptionError for a
    body of more than `KERNEL_LINES_MAX` lines (`check_size`)."""
    check_size(len(lines), columns)
    docstring = [f'"""{docstring[0]}', *docstring[1:-1], f'{docstring[-1]}"""']
    body = "\n".join(INDENT + line if line else "" for line in [*docstring, *lines])
    return (
        '\n\n@njit(cache=True, error_model="numpy", fastmath={"contract"})\n'
        f"def {KERNEL}(t, y, p, X, W):\n"
        f"{body}\n\n\n"
        f"#: The sensitivity columns of `{KERNEL}`, and the rows of its work array W.\n"
        f"VARIATIONAL_COLUMNS = {columns}\nVARIATIONAL_WORK = {work}\n"
    )


def check_size(lines: int, columns: int) -> None:
    """Refuse a kernel body of more than `KERNEL_LINES_MAX` `lines` (for `columns` columns): an OptionError naming
    the kernel, its size and what to do instead, before numba spends hours on it."""
    if lines > KERNEL_LINES_MAX:
        raise OptionError(
            f"Sensitivities with method='taylor': the kernel `{KERNEL}` for {columns} sensitivity columns would be "
            f"{lines} lines of code, more than the {KERNEL_LINES_MAX} numba compiles in a few minutes (its compile "
            "time grows faster than the code: a large program or many columns would take hours).  Use "
            "method='dop853' (its sensitivities use the model's Jacobian kernels), or ask for fewer sensitivities.")
