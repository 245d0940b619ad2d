"""Work arrays in the calling kernel's stack frame: kernels that need arrays allocate nothing per call.

A kernel whose solve is a loop (n > ``lagcomp.codegen.lower.UNROLL_MAX``: ``ldlt_solve_inline`` and the
product loop of ``momenta``; n > ``JACOBIAN_UNROLL_MAX``: ``ldlt_solve_matrix``) gathers M and f into
arrays first, and ``rhs_jacobian`` passes ``rhs_with_jacobian`` a vector for the f it drops.  As
``np.array``/``np.empty`` these were heap allocations through numba's runtime on every call, which
a 13-link chain's rhs spent 5 % of its time on, a 16-link one's 16 % (CPU time in one process, loaded
machine; the rest of the step from 12 links, unrolled, to 13, looped, is the loop).  Here they are
``alloca``s in the entry block of the function that calls `stack_array` or `stack_empty` (numba's
``cgutils.alloca_once``): reserved with the frame, nothing to free, and each thread of a parallel sweep
has its own.

The arrays have no meminfo (numba's reference counting skips them), so they are valid only while
the calling function runs: a kernel passes them down to the solvers, never returns or stores one.
Their sizes are compile-time constants (the model's n), a few kilobytes for the largest chains
compiled here (a 24-link chain's M: 4.6 kB), far below a thread's stack.
"""

import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.core.errors import TypingError
from numba.extending import intrinsic, overload


def stack_array(values):
    """A float64 array holding `values` (a tuple of floats: 1-D; a tuple of equal tuples: 2-D, rows), C order.

    Compiled, in the calling kernel's stack frame (see the module docstring: valid while the caller runs);
    run as plain Python (the tests run kernels' source so), a numpy array."""
    return np.array(values, dtype=np.float64)


def stack_empty(size):
    """An uninitialized float64 vector of the literal int `size`: compiled, in the calling kernel's stack frame."""
    return np.empty(size)


def _stack_buffer(context, builder, count: int):
    """A float64 pointer to `count` doubles reserved in the current function's entry block."""
    return cgutils.alloca_once(builder, context.get_data_type(types.float64), size=count)


def _array_value(context, builder, array_type, data, shape: tuple[int, ...]):
    """The C-contiguous float64 array of `shape` over the stack buffer `data`, without meminfo."""
    array = context.make_array(array_type)(context, builder)
    intp = context.get_value_type(types.intp)
    strides, step = [], 8
    for extent in reversed(shape):
        strides.insert(0, step)
        step *= extent
    context.populate_array(array, data=data, shape=[ir.Constant(intp, s) for s in shape],
                           strides=[ir.Constant(intp, s) for s in strides], itemsize=8, meminfo=None)
    return array._getvalue()


def _tuple_shape(values) -> tuple[int, ...] | None:
    """(n,) for a tuple of n floats, (r, c) for a tuple of r tuples of c floats; None for anything else."""
    if isinstance(values, types.UniTuple) and isinstance(values.dtype, types.Float):
        return (values.count,)
    if isinstance(values, types.UniTuple) and isinstance(values.dtype, types.UniTuple) \
            and isinstance(values.dtype.dtype, types.Float):
        return (values.count, values.dtype.count)
    return None


@intrinsic
def _stack_array(typingctx, values):
    """`stack_array` compiled: the buffer reserved in the entry block of the function this is lowered into."""
    shape = _tuple_shape(values)
    if shape is None:
        raise TypingError(f"stack_array takes a tuple of floats or of equal tuples of floats, not {values}")
    array_type = types.Array(types.float64, len(shape), "C")

    def codegen(context, builder, signature, args):
        rows, columns = shape if len(shape) == 2 else (shape[0], 0)
        data = _stack_buffer(context, builder, rows * max(columns, 1))
        item_type = values.dtype if not columns else values.dtype.dtype
        for i in range(rows):
            row = builder.extract_value(args[0], i)
            items = [row] if not columns else [builder.extract_value(row, j) for j in range(columns)]
            for j, item in enumerate(items):
                at = ir.Constant(ir.IntType(64), i * max(columns, 1) + j)
                builder.store(context.cast(builder, item, item_type, types.float64), builder.gep(data, [at]))
        return _array_value(context, builder, array_type, data, shape)

    return array_type(values), codegen


@intrinsic(prefer_literal=True)
def _stack_empty(typingctx, size):
    """`stack_empty` compiled: the buffer reserved in the entry block of the function this is lowered into."""
    if not isinstance(size, types.IntegerLiteral):
        raise TypingError(f"stack_empty takes a literal int size, not {size}")
    count = size.literal_value
    array_type = types.Array(types.float64, 1, "C")

    def codegen(context, builder, signature, args):
        return _array_value(context, builder, array_type, _stack_buffer(context, builder, max(count, 1)), (count,))

    return array_type(size), codegen


# Inlined into the caller at numba's IR level (``inline="always"``), so that the intrinsics above are lowered
# into the calling kernel and their ``alloca`` is in its frame, not in a callee's that has returned.
@overload(stack_array, inline="always")
def _stack_array_compiled(values):
    if _tuple_shape(values) is not None:
        return lambda values: _stack_array(values)
    return None


@overload(stack_empty, inline="always", prefer_literal=True)
def _stack_empty_compiled(size):
    if isinstance(size, types.IntegerLiteral):
        return lambda size: _stack_empty(size)
    return None
