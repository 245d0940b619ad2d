"""Sensitivities with the Taylor method: the kernels `taylor_run` takes for the augmented state.

`lagcomp.integrate.sensitivities` integrates y = (x, S[:, 0], ..., S[:, k−1]) (N (1 + k) components).  With
``method="taylor"`` the library driver `taylor_run` runs it unchanged: its kernel is
``taylor_variational_coefficients`` (`lagcomp.codegen.taylor_variational`: the model's Taylor program
differentiated in forward mode, or `lagcomp.codegen.taylor_jacobian`: from the series of J's entries, whichever
is faster for the model and columns), which writes the series of x and of every column of S.  The driver's step
rule takes the max norm of the last two coefficients over all rows; under ``sensitivity_control="state"`` the
columns are integrated times 2⁻³⁰⁰ (exact: the tangent recurrences are linear in them), so the norms, hence
the order, the steps and x itself, are a plain Taylor run's; under ``"both"`` the norms cover S too.  Dense
output, events (located on x, S(t*) from the same series) and the compensated sum cover every row.

Parameter columns start at zero and grow through the program's parameter-dependent scalars, whose partials the
program stores (`lagcomp.codegen.taylor_variational`).  The kernel is written from the program stored with the
model (no sympy), appended to the model's module and cached like any module: numba compiles it once per model
and choice of columns (k, which parameters, the control's scale), then loads it from its disk cache.
"""

from __future__ import annotations

import threading

from lagcomp.errors import OptionError

#: {(generated module, k, parameter columns, scale): the module holding that variational kernel}, for the process.
_MODULES: dict = {}
_LOCK = threading.Lock()


def check(model, cols) -> None:
    """Refuse what the Taylor method cannot integrate sensitivities of: a model without a program, and
    parameter columns of a program stored without the partials of its scalars (an older build)."""
    program = model._taylor_program
    if program is None:   # (the Taylor method refuses such models before this)
        raise OptionError(f"{model.name!r} has no Taylor program: `sensitivities` with the Taylor method need it.")
    if cols.parameters and not program.get("parameter_partials"):
        raise OptionError(
            f"Parameter sensitivities {list(cols.names[len(cols.state):])} with method='taylor': {model.name!r}'s "
            "Taylor program was stored without the partials ∂/∂p of its scalars (an older build); compile the "
            "model again, or use method='dop853'.")


def variational_module(model, k: int, parameters: tuple[int, ...], scale: float):
    """The module of `model`'s kernels with ``taylor_variational_coefficients`` for `k` columns, the last of them
    those of `parameters`, appended (built once per process and choice; on disk in the model's cache root, so
    that numba compiles each kernel once)."""
    from lagcomp.cache import Cache, load_module, source_key
    from lagcomp.codegen.taylor_variational import variational_module as source_of

    with _LOCK:
        key = (model.kernels, k, parameters, scale)
        if key not in _MODULES:
            source = source_of(model.source_path.read_text(encoding="utf-8"), model._taylor_program, k, parameters,
                               scale, values_import(model))
            cache = Cache(str(model.source_path.parent.parent))
            entry = cache.store(f"variational-{source_key(source)}", source, model.name, {})
            _MODULES[key] = load_module(entry)
        return _MODULES[key]


def values_import(model) -> str | None:
    """The name the variational kernel imports ``taylor_coefficients`` by (its values' coefficients: one numba
    compile per model, not per choice of columns), the module loaded first (`lagcomp.cache.load_module` registers
    it under that name, content-addressed: a module of another program has another name, so the variational
    module's text, hence its cache entry, changes with it); None for a model whose one module holds every kernel
    (a Kane model's: the variational module copies it, ``taylor_coefficients`` included)."""
    entry = model.on_demand_entry("taylor")
    if entry is None:
        return None
    model.kernels.companion.module("taylor")
    return entry.import_name


class TaylorSensitivityKernels:
    """The model's kernels as `taylor_run` takes them (`Method.kernels`) for an augmented state: ``taylor_coefficients``
    the variational kernel of `variational` (a module of `variational_module`), ``TAYLOR_WORK`` its work rows; the
    others (``event_values``, ``TAYLOR_PERIODIC``: they read x's components only) the model's."""

    def __init__(self, module, variational):
        self._module = module
        self.taylor_coefficients = variational.taylor_variational_coefficients
        self.TAYLOR_WORK = variational.VARIATIONAL_WORK

    def __getattr__(self, name):
        return getattr(self._module, name)


#: {(generated module, k, parameter columns, scale): TaylorSensitivityKernels}, for the process
#: (`Method.bound_driver` binds the driver once for each).
_KERNELS: dict = {}


def taylor_kernels(model, cols, scale: float) -> TaylorSensitivityKernels:
    """The one `TaylorSensitivityKernels` of `model`'s module for the columns `cols` and `scale` in this process
    (the initial-state columns are seeded by y; the parameter ones, and so the kernel, depend on which)."""
    key = (model.kernels, cols.k, cols.parameters, scale)
    kernels = _KERNELS.get(key)     # (a short run's look-up: one dict's, no lock)
    if kernels is None:
        variational = variational_module(model, *key[1:])
        with _LOCK:
            kernels = _KERNELS.setdefault(key, TaylorSensitivityKernels(model.kernels, variational))
    return kernels
