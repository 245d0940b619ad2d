r"""Inputs given as the user's numba functions ``u(t, y, p) -> float``: evaluated before every kernel call.

``model.simulate(..., inputs={"tau": pd})`` with ``pd`` an ``@numba.njit``
function of

* ``t`` (float): the time;
* ``y`` (float64[::1], shape (2n,)): the state as the kernels get it, q then q̇
  (Kane models take no inputs);
* ``p`` (float64[::1], shape (len(Model.parameters),)): the parameters, in
  `Model.parameters` order (the function may read gains there, and a sweep may
  sweep them) — a view of the kernels' parameter vector that ends where the
  parameters do, not the vector itself (which goes on with the inputs' tables);

returning the input's value (a float).  Such an input packs as a one-piece
constant table (`lagcomp.integrate.inputs.pack_inputs`) whose constant is the
*value slot*: every kernel the run calls is wrapped by a small numba function
that writes ``p[slot] = u(t, y, p[:P])`` (P parameters) and then calls the
model's kernel with the same p, which reads the value like any table's
(`input_value`).

numba checks no bounds: a function reading ``p[40]`` of a model with four
parameters would read whatever memory follows, without a word.  So before a
run (`driven`) each function is called once, compiled again with numba's
bounds checking, at t = 0, y = 0 and the run's parameters (`check_bounds`): an
index outside y or p there is an `OptionError`.  An index that depends on the
state or time and leaves the arrays only later is not caught.  The
wrappers are closures over the generated module's dispatcher and the user's
function, compiled at the first run that needs them and kept for the process
(`_WRAPPERS`): the model's kernels and the library drivers are not compiled
again, and a second run with the same function compiles nothing.

Writing into p in place is safe because every trajectory has its own p: a run
its fresh `Model.parameter_vector`, and each trajectory of a sweep its own row
``P[k]`` of a fresh array (the sweep loops take ``p = P[k]``, and each thread a
disjoint block of rows: `lagcomp.integrate.sweep`).

Refused (`OptionError`): a function for an input whose derivative enters the
equations (the function gives values only: supply a table or a law); a callable
that numba did not compile, or that does not compile for ``(float64,
float64[::1], float64[::1]) -> float``; radau, whose Jacobian would miss ∂u/∂y
(a law's Jacobian is exact); a sweep on a Dask `client` (the function would
have to travel to the workers).  The Taylor method and batched sweeps are
refused for every model with inputs supplied at run time.

The Gauss-Legendre methods call ``velocities`` at x = (q, p_momenta), not
(q, q̇), and its wrapper evaluates u there too; that kernel solves
M q̇ = p − b of T alone, so it reads an input only if T holds it, and then the
equations hold its derivative, which functions are refused for: the value
written before it is never read, and the next kernel writes its own.  Outside the run's
driver the same wrappers serve the energies, momenta, reactions (per saved row)
and the animation's geometry kernel, which gets (q, 0): a body placed by a
function input of q̇ is drawn with q̇ = 0.
"""

from __future__ import annotations

import inspect
import threading

import numpy as np
from numba import njit, types
from numba.core.dispatcher import Dispatcher

from lagcomp.errors import OptionError
from lagcomp.integrate.contacts import mode_slot_count
from lagcomp.integrate.input_names import inputs_by_name

#: The argument types a function input is compiled for: t, y, p.
SIGNATURE = (types.float64, types.float64[::1], types.float64[::1])
#: Its signature as users write it (messages, docs).
SIGNATURE_TEXT = "u(t: float64, y: float64[::1], p: float64[::1]) -> float64"
#: The value slot's offset in a function input's table (m = 1, x_0, x_1, a, b, c, d): d, the constant.
VALUE_OFFSET = 6
#: Methods refused with function inputs, and why.
REFUSED_METHODS = {
    "radau": "radau's Newton iterations use the model's exact Jacobian ∂f/∂y, which cannot hold ∂u/∂y of a "
             "numba function: give the input as a law (lc.Input(name, law=...)), whose Jacobian is exact, or "
             "use dop853 or dopri5",
}


def is_function(value) -> bool:
    """Whether `value` is given as a function: a numba dispatcher (``@njit``), or any other callable, which
    `check` refuses with what to do."""
    return isinstance(value, Dispatcher) or (callable(value) and not hasattr(value, "c"))  # (a PPoly is callable)


def check(function, name: str, order: int) -> None:
    """Refuse a function that numba did not compile, that does not compile for `SIGNATURE` or returns no
    number, or that is given for an input whose derivative of `order` > 0 the kernels read."""
    if not isinstance(function, Dispatcher):
        raise OptionError(f"Input `{name}` is a {type(function).__name__}, not a numba function: decorate it with "
                          f"@numba.njit; its signature is {SIGNATURE_TEXT}.")
    if order > 0:
        raise OptionError(f"Input `{name}` enters the equations through its derivative of order {order}, which a "
                          "function does not give (it gives values only): supply a table (lc.Tabulated) or a law "
                          "(lc.Input(name, law=...)).")
    try:
        function.compile(SIGNATURE)
        returned = function.overloads[SIGNATURE].signature.return_type
    except Exception as err:  # numba's typing errors, a wrong number of arguments, compilation disabled
        first = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise OptionError(f"Input `{name}`: the function does not compile for {SIGNATURE_TEXT} ({first}).") from err
    if not isinstance(returned, types.Float | types.Integer):
        raise OptionError(f"Input `{name}`: the function returns {returned}, not a number; its signature is "
                          f"{SIGNATURE_TEXT}.")


def value_slots(model, functions: dict, p) -> tuple[tuple, ...]:
    """((function, value slot in p, count of parameters), ...) of the inputs of `model` given as `functions`
    (name -> function), in the model's input order; p holds the headers after the parameters and a constrained
    system's Baumgarte gains or the contacts' modes (`lagcomp.kernel_support.inputs`)."""
    first = len(model.parameters) + (2 if model.k else 0) + mode_slot_count(model.kernels)
    count = len(model.parameters)
    return tuple((functions[name], int(p[first + j]) + VALUE_OFFSET, count)
                 for j, name in enumerate(model.inputs) if name in functions)


def driven(model, inputs, p, method, client=None):
    """`model` itself, or, when `inputs` holds functions, a view of it whose kernels are wrapped
    (`DrivenModel`) — after refusing what cannot take them (`method`, a Dask `client`)."""
    if not model.inputs or not inputs:
        return model
    functions = {name: value for name, value in inputs_by_name(inputs).items() if isinstance(value, Dispatcher)}
    if not functions:
        return model
    names = sorted(functions)
    if method.name in REFUSED_METHODS:
        raise OptionError(f"Input(s) {names} are numba functions; {REFUSED_METHODS[method.name]}.")
    if client is not None:
        raise OptionError(f"Input(s) {names} are numba functions, which a Dask sweep cannot send to its workers: "
                          "sweep on this machine (drop `client`), or give them as tables or laws.")
    for name in names:
        check_bounds(functions[name], name, model, p)
    return DrivenModel(model, driven_kernels(model.kernels, value_slots(model, functions, p)), tuple(names))


class DrivenModel:
    """A model whose `kernels` write its function inputs' values into p before each call; everything else
    is the model's (what `simulate` and `sweep` read of a model, and the `Solution` they build).
    `function_inputs`: the names of the inputs given as functions."""

    def __init__(self, model, kernels: DrivenKernels, function_inputs: tuple = ()):
        self._model, self.kernels, self.function_inputs = model, kernels, function_inputs

    def __getattr__(self, name):
        return getattr(self._model, name)


def check_bounds(function, name: str, model, p) -> None:
    """Call `function` once, compiled with bounds checking, at t = 0, y = 0 (2n values) and the parameters of
    p: an index outside y or p there is an OptionError (in the run numba checks none)."""
    count = len(model.parameters)
    with _LOCK:
        if function not in _BOUNDS_CHECKED:
            _BOUNDS_CHECKED[function] = njit(boundscheck=True)(function.py_func)
        checked = _BOUNDS_CHECKED[function]
    try:
        checked(0.0, np.zeros(2 * model.n), np.array(p[:count], dtype=float))
    except IndexError as err:
        raise OptionError(f"Input `{name}`: the function reads outside the arrays it is given ({err}): `y` holds "
                          f"the {2 * model.n} values {list(model.state_names)}, `p` the {count} parameters "
                          f"{list(model.parameters)}; numba checks no bounds in the run, where such a read returns "
                          "whatever memory follows. Index within them (pass other values as parameters).") from err
    except Exception:  # noqa: BLE001, S110 - its other failures at y = 0 (a division by zero) are not this check's
        pass


class DrivenKernels:
    """The generated `module`'s kernels, each wrapped to evaluate `functions` ((function, value slot, count), ...)
    first; its other attributes (data such as ``CONSTRAINT_COUNT``) as they are.  Kernels are wrapped at
    their first look-up (`Method.bound_driver` looks up those its driver takes, then caches the bound
    driver per instance: `driven_kernels` keeps one instance per module and functions)."""

    def __init__(self, module, functions: tuple):
        self._module, self._functions = module, functions

    def __getattr__(self, name):
        with _LOCK:  # (a sweep's threads bind their loops at once: one wrapper per kernel all the same)
            if name in self.__dict__:
                return self.__dict__[name]
            value = getattr(self._module, name)
            for function, slot, count in self._functions:
                value = _wrapped(value, function, slot, count)
            setattr(self, name, value)
            return value


#: {(generated module, functions): DrivenKernels}, for the process (as numba keeps its dispatchers).
_DRIVEN: dict = {}
#: Held while a kernel is wrapped.
_LOCK = threading.RLock()
#: {(kernel, function, slot, count): its wrapper}, for the process: a wrapper is compiled once per kernel and
#: function.
_WRAPPERS: dict = {}
#: {function: it compiled with bounds checking}, for the process (`check_bounds`).
_BOUNDS_CHECKED: dict = {}


def driven_kernels(module, functions: tuple) -> DrivenKernels:
    """The one `DrivenKernels` of `module` with `functions` in this process."""
    key = (module, functions)
    if key not in _DRIVEN:
        _DRIVEN[key] = DrivenKernels(module, functions)
    return _DRIVEN[key]


def _wrapped(kernel, function, slot: int, count: int):
    """`kernel` wrapped to write ``p[slot] = function(t, y, p[:count])`` first: a pointwise kernel ``(t, y, p, ...)``
    before its one call, a row kernel ``(ts, ys, p, outs...)`` (observables, reactions) before each row's;
    anything else (module data, `input_value`) as it is."""
    if not isinstance(kernel, Dispatcher):
        return kernel
    arguments = tuple(inspect.signature(kernel.py_func).parameters)
    if arguments[:3] == ("t", "y", "p"):
        factory = _POINTWISE.get(len(arguments))
    elif arguments[:3] == ("ts", "ys", "p"):
        factory = _ROWS.get(len(arguments))
    else:
        return kernel
    if factory is None:
        raise OptionError(f"Function inputs cannot wrap the kernel {kernel.__name__}{arguments} (no wrapper of "
                          f"{len(arguments)} arguments); give the inputs as tables or laws.")
    key = (kernel, function, slot, count)
    if key not in _WRAPPERS:
        _WRAPPERS[key] = factory(kernel, function, slot, count)
    return _WRAPPERS[key]


# -- the wrappers, by the kernel's arguments (numba compiles closures of a fixed arity) --------------------------


def _pointwise3(kernel, u, slot, count):
    @njit(error_model="numpy", nogil=True)
    def wrapped(t, y, p):
        p[slot] = u(t, y, p[:count])
        return kernel(t, y, p)
    return wrapped


def _pointwise4(kernel, u, slot, count):
    @njit(error_model="numpy", nogil=True)
    def wrapped(t, y, p, out):
        p[slot] = u(t, y, p[:count])
        return kernel(t, y, p, out)
    return wrapped


def _pointwise5(kernel, u, slot, count):
    @njit(error_model="numpy", nogil=True)
    def wrapped(t, y, p, a, b):
        p[slot] = u(t, y, p[:count])
        return kernel(t, y, p, a, b)
    return wrapped


def _rows5(kernel, u, slot, count):
    @njit(error_model="numpy", nogil=True)
    def wrapped(ts, ys, p, a, b):
        for k in range(ts.shape[0]):
            p[slot] = u(ts[k], ys[k], p[:count])
            kernel(ts[k:k + 1], ys[k:k + 1], p, a[k:k + 1], b[k:k + 1])
    return wrapped


def _rows6(kernel, u, slot, count):
    @njit(error_model="numpy", nogil=True)
    def wrapped(ts, ys, p, a, b, c):
        for k in range(ts.shape[0]):
            p[slot] = u(ts[k], ys[k], p[:count])
            kernel(ts[k:k + 1], ys[k:k + 1], p, a[k:k + 1], b[k:k + 1], c[k:k + 1])
    return wrapped


_POINTWISE = {3: _pointwise3, 4: _pointwise4, 5: _pointwise5}
_ROWS = {5: _rows5, 6: _rows6}
