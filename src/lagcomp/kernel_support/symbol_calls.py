"""Calls from a kernel to a heavy `lagcomp.kernel_support` routine by its compiled symbol, not by linking it in.

numba compiles a jitted function that calls another by linking the callee's whole LLVM module into the caller's
and optimising the linked module again (`numba.core.codegen.CPUCodeLibrary.finalize`): every generated kernel that
calls `lagcomp.kernel_support.resting.pressed_contact_event` paid LLVM's optimisation of the contact and friction
solvers, seconds for a kernel of twenty lines, although numba's cache held them compiled.  `called_by_symbol`
wraps such a routine so that the caller only declares its native function and calls it (an ordinary direct call
to a symbol of the JIT, not inlined): the routine is optimised once, when numba compiles or loads it from its
cache, and a caller costs what its own code costs.  The routine's native calling convention and flags are its
own, so its results are those of the linked call, bit for bit.

The symbol must be in numba's JIT before the caller's machine code is: the call's typing compiles the routine for
the argument types (or loads it from numba's cache), and the caller's compile result records `load_routine` for
those types among numba's ``reload_init`` functions, which numba runs before it loads the caller's machine code
from its cache in a later process.
"""

from __future__ import annotations

import functools
import importlib

from numba import njit
from numba.extending import intrinsic


def load_routine(module: str, name: str, argtypes: tuple) -> None:
    """Compile `module`'s routine `name` for `argtypes` (numba types), or load it from numba's cache: a caller's
    ``reload_init`` function, run before numba loads the caller's cached machine code, which calls its symbol."""
    getattr(importlib.import_module(module), name).compile(argtypes)


def called_by_symbol(routine):
    """A jitted function with `routine`'s name and docstring that calls `routine` (a numba dispatcher with
    ``cache=True``) by symbol: see the module docstring.  Callable from Python too (numba compiles it there)."""
    module, name = routine.py_func.__module__, routine.py_func.__name__

    @intrinsic
    def call(typingctx, arguments):
        argtypes = tuple(arguments)
        routine.compile(argtypes)
        compiled = routine.overloads[argtypes]

        def codegen(context, builder, signature, values):
            context.active_code_library._reload_init.add(functools.partial(load_routine, module, name, argtypes))
            packed = values[0]
            unpacked = [builder.extract_value(packed, i) for i in range(len(argtypes))]
            return context.call_internal(builder, compiled.fndesc, compiled.signature, unpacked)

        return compiled.signature.return_type(arguments), codegen

    def caller(*args):
        return call(args)

    caller.__name__ = caller.__qualname__ = name.lstrip("_")
    caller.__module__, caller.__doc__ = module, routine.py_func.__doc__
    return njit(error_model="numpy", fastmath=False)(caller)
