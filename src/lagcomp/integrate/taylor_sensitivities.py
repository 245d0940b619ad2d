"""Sensitivities with the Taylor method: the kernels `taylor_run` takes for the augmented state.

`lagcomp.integrate.sensitivities` integrates y = (x, S[:, 0], ..., S[:, k−1]) (N (1 + k) components).  With
``method="taylor"`` the library driver `taylor_run` runs it unchanged: its kernel is
``taylor_variational_coefficients`` (`lagcomp.codegen.taylor_variational`: the model's Taylor program
differentiated in forward mode), which writes the series of x and of every column of S.  The driver's step
rule takes the max norm of the last two coefficients over all rows; under ``sensitivity_control="state"`` the
columns are integrated times 2⁻³⁰⁰ (exact: the tangent recurrences are linear in them), so the norms, hence
the order, the steps and x itself, are a plain Taylor run's; under ``"both"`` the norms cover S too.  Dense
output, events (located on x, S(t*) from the same series) and the compensated sum cover every row.

The kernel is written from the program stored with the model (no sympy), appended to the model's module
and cached like any module: numba compiles it once per model, then loads it from its disk cache.
"""

from __future__ import annotations

import threading

from lagcomp.errors import OptionError

#: {(generated module, k): the module holding its variational kernel for k columns}, for the process.
_MODULES: dict = {}
_LOCK = threading.Lock()


def check(model, cols) -> None:
    """Refuse what the Taylor method cannot integrate sensitivities of: parameter columns (the program's setup
    scalars are code over the parameters without their partials; use dop853), a model without a program."""
    if model._taylor_program is None:   # (the Taylor method refuses such models before this)
        raise OptionError(f"{model.name!r} has no Taylor program: `sensitivities` with the Taylor method need it.")
    if cols.parameters:
        raise OptionError(
            f"Parameter sensitivities {list(cols.names[len(cols.state):])} with method='taylor': the Taylor "
            "program stores its parameter-dependent scalars as code, without their partials ∂/∂p, so only "
            "initial-state columns (q0, qd0) are integrated by it; use method='dop853' for parameter columns.")


def variational_module(model, k: int):
    """The module of `model`'s kernels with ``taylor_variational_coefficients`` for `k` columns appended (built
    once per process, model and k; on disk in the model's cache root, so that numba compiles the kernel once)."""
    from lagcomp.cache import Cache, load_module, source_key
    from lagcomp.codegen.taylor_variational import variational_module as source_of

    with _LOCK:
        key = (model.kernels, k)
        if key not in _MODULES:
            source = source_of(model.source_path.read_text(encoding="utf-8"), model._taylor_program, k)
            cache = Cache(str(model.source_path.parent.parent))
            entry = cache.store(f"variational-{source_key(source)}", source, model.name, {})
            _MODULES[key] = load_module(entry)
        return _MODULES[key]


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


#: {(generated module, k): TaylorSensitivityKernels}, for the process (`Method.bound_driver` binds once each).
_KERNELS: dict = {}


def taylor_kernels(model, k: int) -> TaylorSensitivityKernels:
    """The one `TaylorSensitivityKernels` of `model`'s module for `k` columns in this process."""
    variational = variational_module(model, k)
    with _LOCK:
        key = (model.kernels, k)
        if key not in _KERNELS:
            _KERNELS[key] = TaylorSensitivityKernels(model.kernels, variational)
        return _KERNELS[key]
