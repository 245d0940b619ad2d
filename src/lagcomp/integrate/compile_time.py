"""Library drivers compiled for one model's kernels, known when numba compiles them: what `specialize` builds on.

Two pieces, both small uses of numba's extension API:

* `CompileTimeKernel`, the numba type of a kernel given to a driver as a value that exists only at compile
  time: numba types a call of it as a call of the kernel's dispatcher (``numba.types.Dispatcher``, of which
  it is a subclass) and calls the kernel's compiled function directly.  Its value is a dummy.  (A
  dispatcher passed as a value is lowered by `numba.experimental.function_type`, which lagcomp imports,
  as the dispatcher object's address: a "dynamic global" that numba refuses to cache.)  `compile_time`
  wraps a dispatcher so that numba types it so.
* `uncached_copy`, a library driver or helper compiled again from its own Python function (``py_func``,
  same code, same options) without numba's disk cache, with the library helpers it calls copied the same
  way.  A cached library function called with a `CompileTimeKernel` would write an entry for that model
  into the library's own numba cache at every process (the type's key is the dispatcher, which pickles
  afresh each time): the copies keep the library's cache files as they are.  The specialised module's
  ``run``, which calls a copy, is what numba caches.
"""

from __future__ import annotations

import functools
import types as pytypes

from numba import njit, types
from numba.core.datamodel import models, register_default
from numba.core.dispatcher import Dispatcher
from numba.core.imputils import lower_constant

#: The packages whose numba functions `uncached_copy` copies when a copied function calls them.
COPIED_PACKAGES = ("lagcomp.integrate.drivers",)


class CompileTimeKernel(types.Dispatcher):
    """numba type of a kernel that a driver calls as a compile-time callee (module docstring)."""

    def __init__(self, dispatcher):
        super().__init__(dispatcher)
        self.name = f"CompileTimeKernel({dispatcher.py_func.__module__}.{dispatcher.py_func.__qualname__})"


register_default(CompileTimeKernel)(models.OpaqueModel)


@lower_constant(CompileTimeKernel)
def _dummy_constant(context, builder, ty, pyval):
    """A compile-time kernel has no run-time value: calls of it name its compiled function."""
    return context.get_dummy_value()


class _CompileTime:
    """A dispatcher as a module global that numba types as a `CompileTimeKernel`."""

    def __init__(self, dispatcher):
        self.dispatcher = dispatcher
        self._numba_type_ = CompileTimeKernel(dispatcher)


def compile_time(dispatcher) -> _CompileTime:
    """`dispatcher` (a kernel) as a value numba types as a `CompileTimeKernel`."""
    return _CompileTime(dispatcher)


@functools.cache
def uncached_copy(dispatcher) -> Dispatcher:
    """`dispatcher`'s Python function compiled again with its options but no disk cache, the functions of
    `COPIED_PACKAGES` it calls copied likewise (module docstring); one copy per process."""
    function = dispatcher.py_func
    globals_ = dict(function.__globals__)
    for name in function.__code__.co_names:
        value = globals_.get(name)
        if isinstance(value, Dispatcher) and value.py_func.__module__.startswith(COPIED_PACKAGES):
            globals_[name] = uncached_copy(value)
    copy = pytypes.FunctionType(function.__code__, globals_, function.__name__, function.__defaults__,
                                function.__closure__)
    copy.__qualname__, copy.__doc__ = function.__qualname__, function.__doc__
    options = {k: v for k, v in dispatcher.targetoptions.items() if k not in ("cache", "nopython")}
    return njit(**options)(copy)


def run_signature(library: Dispatcher, kernels: int):
    """The explicit signature of `library` (a driver compiled from one) without its first `kernels` arguments: what
    a specialised ``run`` takes, so that numba compiles it once, when its module is imported, and calls coerce
    their arguments as they do for the library driver."""
    signature = library.nopython_signatures[0]
    return signature.return_type(*signature.args[kernels:])
