r"""Forward sensitivities: ``simulate(..., sensitivities=...)`` integrates the variational equations with the state.

For y' = f(t, y, p) with y (N,), the sensitivities S = ∂y(t)/∂(y0_c, p_j) of k chosen columns obey

    S' = J(t, y) S (+ ∂f/∂p_j in the column of parameter p_j),   S(0) = e_c (0 for a parameter),

J = ∂f/∂y the model's exact Jacobian (emitted from the symbolic equations: ``rhs_with_jacobian`` writes f and
J in one call) and ∂f/∂p its ``rhs_parameter_jacobian`` (both at once, from one factorization of M or K:
``rhs_with_full_jacobian``).
The run integrates the augmented state (y, S[:, 0], ..., S[:, k-1]) of
N (1 + k) components with the library's embedded Runge-Kutta driver (dop853, dopri5, tsit5, bs3), which
takes as its ``rhs`` a small numba function evaluating f and J S: a closure over the model's kernels,
compiled at the first run that needs it and kept for the process (`_AUGMENTED`), as
`lagcomp.integrate.function_inputs` does for its wrappers.  The model's kernels and the driver are not
compiled again.  Up to `DIRECTIONAL_MAX_COLUMNS` columns the rhs is no closure but one of the module's tangent
kernels (`tangent_kernel`), which the driver calls as it calls ``rhs``: for one column ``rhs_tangent``, or
``rhs_tangent_parameters`` with the parameters' direction at the end of p (``rhs_directional``'s CSE reading
(y, S) and writing (f, J S + ∂f/∂p w) itself); for more ``rhs_tangents`` (``rhs_tangents_parameters`` with
each column's parameter and the scale at the end of p), which computes f, the factors of M (or K) and the
residual's partials once and loops over the columns, a contraction and a substitution each
(`lagcomp.codegen.directional`).  Beyond, the full Jacobians
(`augmented_rhs`, `full_jacobian_rhs`), J (N, N) and ∂f/∂p (N, P) written into work space at the end of the
run's p (the kernels read p only up to their parameters and input tables): a call allocates only what the
kernels do (the factor of M in their LDLᵀ).  Kane modules and systems larger than
`lagcomp.codegen.directional.LARGEST_SYSTEM` have no tangent kernels (unconstrained: nor
``rhs_with_full_jacobian``): the full Jacobians, apart where need be.

Error control (``sensitivity_control``).  The embedded driver's error norm runs over every component of the
state it is given, with one scalar ``rtol``/``atol``, and restricting it to the first N components would
change the driver's signature (an argument every driver call and sweep loop passes).  Both controls come
without that:

* ``"both"`` (the default): the norm covers the state and the sensitivities together (CVODES' ``errconS =
  True``); the steps then differ from a plain run's, the state within the tolerance.
* ``"state"``: the sensitivity columns are integrated scaled by `STATE_ONLY_SCALE` = 2⁻³⁰⁰,
  exactly (a power of two: the linear variational equations commute with it, and every Runge-Kutta sum is
  scaled without rounding), so that their scaled errors ε e_S / atol are ~1e-90 of the threshold (atol > 0
  always) and the norm sees the state only; ``rtol`` and ``atol`` are divided by sqrt(1 + k), which
  undoes the norms' division by the component count N (1 + k) instead of N (the RMS norm of DOPRI5, Tsit5,
  BS3 and DOP853's combined one alike).  The driver then chooses a plain run's steps (up to the rounding
  of that division), and the state columns match a plain run's to rounding.  The sensitivities are
  unscaled exactly on output.  An atol below ~1e-80 times the sensitivities' errors would let the norm
  see them again (as with "both"); sensitivities below ~1e-218 lose precision as subnormal numbers.
  It trusts the steps that resolve the state to resolve S too, which fails where the state is smooth and S is
  not: the rolling disc's steady rolling takes five steps a second and its sensitivities come out 10% wrong
  (`tests/test_constrained_sensitivities.py`).  Hence "both" is the default, and "state" the faster choice for
  a motion whose steps are set by the same dynamics as its perturbations.

Events.  The crossings are located on the state exactly as in a plain run: ``event_values`` reads y's first
N components, and the event rows the driver writes from its dense output hold the whole augmented state, so
S(t*) comes interpolated at the crossing as y(t*) does.  `event_sensitivities` then differentiates the
crossing condition g(t*(w), y(t*(w), w), w) = 0, with the exact partials of the emitted ``event_gradients``:

    dt*/dw = −(∂g/∂y · S(t*) + ∂g/∂w) / (∂g/∂y · f(t*) + ∂g/∂t),     dy(t*)/dw = S(t*) + f(t*) dt*/dw,

∂g/∂w nonzero only for a parameter in g; a grazing crossing (denominator 0) gives inf or nan.

Constrained systems (Lagrange multipliers).  Their ``rhs`` solves the augmented system for (q̈, λ), with the
Baumgarte terms of the run's ``baumgarte=(α, β)``; its emitted Jacobians differentiate that solve exactly
(`lagcomp.codegen.constrained_jacobian` derives them), so S obeys the variational equations of the ODE the run
integrates, everywhere, not of the constrained motion alone.  The sensitivity columns are not projected (nor
is the state: projection is refused).  A consistent perturbation — tangent to the constraint manifold at y0:
a consistent change of the initial state, or a parameter absent from Φ and from Λ q̇ + b — stays tangent,
since the manifold is invariant under the ODE and so its tangent spaces are under the linearised flow; S is
then the sensitivity of the constrained motion.  A column off the manifold (one initial coordinate changed
alone; a parameter of Φ or of Λ q̇ + b, whose change makes y0 inconsistent) is the ODE's response to an
inconsistent start, which `simulate` itself refuses: the residual's change δΦ grows as δΦ(0) + δΦ̇(0) t
without Baumgarte terms and is damped with α, β > 0 — not a motion the constrained system can make.
The reactions' sensitivities follow after the run (`reaction_sensitivities`): dλ/dw =
∂λ/∂y · S + ∂λ/∂p_w, with the module's ``reaction_jacobian``, at each saved row.

Taylor method.  ``method="taylor"`` integrates the same augmented state with the library's Taylor driver, whose
kernel is the model's Taylor program differentiated in forward mode (`lagcomp.integrate.taylor_sensitivities`;
a parameter's column through the partials of the program's scalars).  Its step rule takes a max norm, which the
scaled columns leave alone, so the tolerances are not divided: the state's steps under "state", the steps of
both under "both" (the rule of heyoka's ``var_ode_sys``).

Refused (`OptionError`, docs/errors.md): other methods; located events that read inputs (their module's
``event_gradients`` is a refusing stub, ``EVENT_GRADIENTS_REFUSED`` says why); projection; function inputs
(their ∂u/∂y is unknown); unknown names.  `lagcomp.integrate.sweep` refuses ``sensitivities`` altogether.
"""

from __future__ import annotations

import sys
import threading
from dataclasses import dataclass

import numpy as np
from numba import njit

from lagcomp.errors import OptionError
from lagcomp.integrate import taylor_sensitivities

#: The groups of columns `sensitivities` may name: every coordinate's initial value, every velocity's
#: (a Kane model's speeds: also "u0"), every parameter.
GROUPS = ("q0", "qd0", "params")
#: The driver that integrates sensitivities (every embedded pair runs on it).
EMBEDDED_DRIVER = "lagcomp.integrate.drivers.embedded:embedded_run"
#: The Taylor method's driver, which integrates them too (`lagcomp.integrate.taylor_sensitivities`).
TAYLOR_DRIVER = "lagcomp.integrate.drivers.taylor:taylor_run"
#: What the step-size control covers (see "Error control" above).
CONTROLS = ("state", "both")
#: The exact scale of the sensitivity columns under ``sensitivity_control="state"``.
STATE_ONLY_SCALE = 2.0 ** -300


@dataclass(frozen=True)
class Columns:
    """The sensitivity columns of a run: initial-state components (indices into y), then parameters (indices
    into `Model.parameters`), and their names (``"q0:theta1"``, ``"qd0:theta1"``, ``"p:m"``)."""

    state: tuple[int, ...]
    parameters: tuple[int, ...]
    names: tuple[str, ...]

    @property
    def k(self) -> int:
        return len(self.state) + len(self.parameters)


def columns(model, requested) -> Columns:
    """The `Columns` `requested` names: a group of `GROUPS` (or "u0"), a state name (`Model.state_names`:
    ``theta1``, ``theta1_dot``), a parameter name, or a column name as `Solution.sensitivity_names` gives
    it (``"q0:theta1"``); a string alone or a sequence of them.  Initial-state columns come first, in state
    order, then parameters in `Model.parameters` order, each once."""
    if isinstance(requested, str):
        requested = (requested,)
    try:
        requested = tuple(requested)
    except TypeError:
        raise OptionError(f"`sensitivities` must be a name or a sequence of names ({', '.join(GROUPS)}, state or "
                          f"parameter names), got {requested!r}.") from None
    n, size = model.n, model.state_size
    state_names = tuple(model.state_names)
    velocity_group = "qd0"
    label = {i: f"{'q0' if i < n else velocity_group}:{state_names[i]}" for i in range(size)}
    by_name = {"q0": range(n), "qd0": range(n, size), "u0": range(n, size)}
    for i in range(size):
        by_name[state_names[i]] = (i,)
        by_name[label[i]] = (i,)
    parameters = {"params": range(len(model.parameters))}
    for j, name in enumerate(model.parameters):
        parameters[name] = parameters[f"p:{name}"] = (j,)
    state, chosen = set(), set()
    for name in requested:
        if not isinstance(name, str) or (name not in by_name and name not in parameters):
            raise OptionError(f"Unknown sensitivity {name!r}: name {', '.join(GROUPS)}, a state component "
                              f"{list(state_names)} or a parameter {list(model.parameters)}.")
        (state if name in by_name else chosen).update(by_name.get(name, parameters.get(name)))
    state, chosen = tuple(sorted(state)), tuple(sorted(chosen))
    if not state and not chosen:
        raise OptionError("`sensitivities` names no column: name q0, qd0, params, state components or parameters.")
    names = tuple(label[i] for i in state) + tuple(f"p:{model.parameters[j]}" for j in chosen)
    return Columns(state, chosen, names)


def check(model, method, options, cols: Columns, original_model) -> None:
    """Refuse what sensitivities cannot run with (see the module docstring); `original_model` is the model
    before `function_inputs.driven` wrapped it (another object when the inputs hold numba functions)."""
    if method.driver == TAYLOR_DRIVER:
        taylor_sensitivities.check(model, cols)
    elif method.driver != EMBEDDED_DRIVER:
        raise OptionError(f"`sensitivities` are integrated by the embedded Runge-Kutta pairs (dop853, dopri5, "
                          f"tsit5, bs3) and the Taylor method; `{method.name}` does not integrate them yet: use "
                          "dop853.")
    located = [e.name for e, action in zip(model.events, options.actions.tolist(), strict=True) if action]
    refused = getattr(model.kernels, "EVENT_GRADIENTS_REFUSED", None)
    if located and refused is not None:
        raise OptionError(f"`sensitivities` with events: the times of {model.name!r}'s events {located} have no "
                          f"sensitivities: its module has no event partials ({refused}); pass events=False.")
    if options.projecting:
        raise OptionError("`sensitivities` with `projection=True`: the projection would move the state and not "
                          "its sensitivities; leave `projection` unset.")
    if model is not original_model:
        raise OptionError("`sensitivities` with inputs given as numba functions: their derivatives ∂u/∂y are "
                          "unknown, so the sensitivities would miss them; give the inputs as tables or laws.")


def scale_for(control) -> float:
    """The factor the sensitivity columns are integrated with under `control` (one of `CONTROLS`)."""
    if control not in CONTROLS:
        raise OptionError(f"`sensitivity_control` must be one of {CONTROLS}, got {control!r}.")
    return STATE_ONLY_SCALE if control == "state" else 1.0


def driver_tolerances(rtol: float, atol: float, cols: Columns, scale: float, method=None) -> tuple[float, float]:
    """The (rtol, atol) the driver gets: divided by sqrt(1 + k) for state-only control (see the docstring); the
    Taylor method's as given (its step rule takes a max norm over the rows, which the scaled columns leave
    alone)."""
    if scale == 1.0 or (method is not None and method.driver == TAYLOR_DRIVER):
        return rtol, atol
    shrink = float(np.sqrt(1.0 + cols.k))
    return rtol / shrink, atol / shrink


def initial_state(y0: np.ndarray, cols: Columns, scale: float) -> np.ndarray:
    """(y0, scale S(0)) flat, N (1 + k): unit columns for the initial-state components, zero for parameters."""
    n = y0.size
    augmented = np.zeros(n * (1 + cols.k))
    augmented[:n] = y0
    for c, i in enumerate(cols.state):
        augmented[n * (1 + c) + i] = scale
    return augmented


def run_parameters(p: np.ndarray, model, cols: Columns, scale: float = 1.0) -> np.ndarray:
    """p followed by the work space of the run's rhs: for one column through a tangent kernel (`tangent_kernel`),
    the direction w (P,) of ``rhs_tangent_parameters`` (`scale` e_j for parameter j's column, else 0); for more,
    each column's parameter index (−1 for an initial-state column) and `scale` (``rhs_tangents_parameters``);
    else the floats `augmented_rhs` writes J and ∂f/∂p into (see `work_size`)."""
    if tangent_kernel(model.kernels, cols) is None:
        return np.concatenate([p, np.zeros(work_size(model.state_size, len(model.parameters), cols))])
    if cols.k == 1:
        direction = np.zeros(len(model.parameters))
        direction[list(cols.parameters)] = scale
        return np.concatenate([p, direction])
    return np.concatenate([p, [-1.0] * len(cols.state), np.array(cols.parameters, dtype=float), [scale]])


def work_size(n: int, n_parameters: int, cols: Columns) -> int:
    """Floats at the end of p that `augmented_rhs` uses: J (n, n) last, before it ∂f/∂p (n, P) if asked
    (`full_jacobian_rhs`: [J | ∂f/∂p] (n, n + P) in the same floats)."""
    return n * n + (n * n_parameters if cols.parameters else 0)


class SensitivityKernels:
    """The generated `module`'s kernels with ``rhs`` replaced by `augmented_rhs` for `cols`; the others
    (``project``, ``constraint_residual``, ``event_values``: no-ops here, or reading y's first N components)
    as they are.  One instance per module and columns (`sensitivity_kernels`), so that `Method.bound_driver`
    binds the driver once."""

    def __init__(self, module, rhs):
        self._module, self.rhs = module, rhs

    def __getattr__(self, name):
        return getattr(self._module, name)


#: The most columns whose derivatives the run takes from the module's tangent kernels (one column: ``rhs_tangent``;
#: more: ``rhs_tangents``, the shared part once and a loop over the columns; `tangent_kernel`) rather than from
#: the full Jacobians (`augmented_rhs`, `full_jacobian_rhs`), without and with a parameter's column among them:
#: every k, since the tangent kernels cost 0.34-0.72 of the full Jacobians' path at every k measured
#: (``python -m bench.bench_sensitivities --calls``, ns per call of the augmented rhs, full / tangent kernels,
#: double pendulum, 5-link, free axle): k = 1 150 / 54, 426 / 169, 1152 / 542; k = 2 156 / 66, 461 / 178,
#: 1195 / 658; k = 2n 170 / 72, 760 / 320, 1518 / 1095; a parameter's and 2n initial-state columns 216 / 88,
#: 974 / 380, 2012 / 1177.  A value below 2n + P forces the full Jacobians above it (the bench, the tests).
DIRECTIONAL_MAX_COLUMNS = {False: sys.maxsize, True: sys.maxsize}

#: {(generated module, n, parameter columns, scale, tangent kernel or None): SensitivityKernels}, for the process.
_AUGMENTED: dict = {}
_LOCK = threading.Lock()


def run_kernels(model, method, cols: Columns, scale: float):
    """The kernels `method`'s driver takes for the augmented state: the Taylor method's variational kernel
    (`lagcomp.integrate.taylor_sensitivities`), or the embedded pairs' `augmented_rhs` (`sensitivity_kernels`)."""
    if method.driver == TAYLOR_DRIVER:
        return taylor_sensitivities.taylor_kernels(model, cols, scale)
    return sensitivity_kernels(model.kernels, model.state_size, len(model.parameters), cols, scale)


def tangent_kernel(module, cols: Columns):
    """The kernel of `module` that is the whole augmented rhs of the columns `cols`, or None (the full
    Jacobians): up to `DIRECTIONAL_MAX_COLUMNS` columns, for one ``rhs_tangent`` (an initial-state column) or
    ``rhs_tangent_parameters`` (a parameter's, its direction at the end of p: `run_parameters`), for more
    ``rhs_tangents`` or ``rhs_tangents_parameters`` (each column's parameter and the scale at the end of p), which
    the driver calls itself.  A closure over ``rhs_directional`` cost twice as much per call, measured on the
    double pendulum through the drivers' function type: 104 ns against 54 (65 with a parameter's), ``rhs`` 37;
    its views of y and out, its loop over columns, the seven arrays of each call (see
    `lagcomp.codegen.directional.tangent_kernels`).  One column keeps its own kernels: ``rhs_tangents`` at k = 1
    costs 64 ns against 54, 166 against 167, 591 against 531 (double pendulum, 5-link, free axle; with a
    parameter's 70 / 65, 197 / 230, 631 / 559)."""
    if cols.k > DIRECTIONAL_MAX_COLUMNS[bool(cols.parameters)]:
        return None
    name = ("rhs_tangent" if cols.k == 1 else "rhs_tangents") + ("_parameters" if cols.parameters else "")
    return getattr(module, name, None)  # (Kane modules, and modules generated before the kernel, have none)


def sensitivity_kernels(module, n: int, n_parameters: int, cols: Columns, scale: float) -> SensitivityKernels:
    """The one `SensitivityKernels` of `module` for `cols` and `scale` in this process (the full Jacobians'
    closure compiled at first use; none with a tangent kernel: `tangent_kernel`)."""
    tangent = tangent_kernel(module, cols)
    key = (module, n, cols.parameters, scale, tangent)  # (initial-state columns: y's size)
    with _LOCK:
        if key not in _AUGMENTED:
            if tangent is not None:
                rhs = tangent
            elif cols.parameters and hasattr(module, "rhs_with_full_jacobian"):
                rhs = full_jacobian_rhs(module.rhs_with_full_jacobian, n, n_parameters, cols.parameters, scale)
            else:
                parameter_jacobian = module.rhs_parameter_jacobian if cols.parameters else None
                rhs = augmented_rhs(module.rhs_with_jacobian, parameter_jacobian, n, n_parameters, cols.parameters,
                                    scale)
            _AUGMENTED[key] = SensitivityKernels(module, rhs)
        return _AUGMENTED[key]


def augmented_rhs(rhs_with_jacobian, parameter_jacobian, n: int, n_parameters: int,
                  parameter_columns: tuple[int, ...], scale: float):
    """``rhs(t, y, p, out) -> int`` of the augmented state y = (x, S[:, 0], ..., S[:, k-1]) (column blocks of
    n, each times `scale`): out = (f(x), J S[:, c] + scale ∂f/∂p_j for the parameter columns).  Returns the
    kernels' status (0, or the singular pivot).  f and J come from one call of the module's
    ``rhs_with_jacobian`` (f computed once, bitwise ``rhs``'s); J sits in the last n² floats of p, ∂f/∂p
    (n, n_parameters) before it.  The parameter columns are the last; the initial-state ones before them are
    as many as y's size says, so that one closure serves every choice of them (it compiles once per module,
    in ~0.8 s)."""
    k_parameters = len(parameter_columns)
    columns_p = np.array(parameter_columns, dtype=np.int64)
    jacobian_size = n * n
    if parameter_jacobian is None:
        @njit(error_model="numpy", nogil=True)
        def state_rhs(t, y, p, out):
            end = p.shape[0]
            J = p[end - jacobian_size:].reshape((n, n))
            status = rhs_with_jacobian(t, y[:n], p, out[:n], J)
            if status != 0:
                return status
            _multiply(J, y, out, n, y.shape[0] // n - 1)
            return 0
        return state_rhs

    parameter_size = n * n_parameters

    @njit(error_model="numpy", nogil=True)
    def full_rhs(t, y, p, out):
        end = p.shape[0]
        J = p[end - jacobian_size:].reshape((n, n))
        status = rhs_with_jacobian(t, y[:n], p, out[:n], J)
        if status != 0:
            return status
        k = y.shape[0] // n - 1
        _multiply(J, y, out, n, k)
        Jp = p[end - jacobian_size - parameter_size:end - jacobian_size].reshape((n, n_parameters))
        status = parameter_jacobian(t, y[:n], p, Jp)
        if status != 0:
            return status
        for c in range(k_parameters):
            base = n * (1 + k - k_parameters + c)
            j = columns_p[c]
            for i in range(n):
                out[base + i] += scale * Jp[i, j]
        return 0
    return full_rhs


def full_jacobian_rhs(rhs_with_full_jacobian, n: int, n_parameters: int, parameter_columns: tuple[int, ...],
                      scale: float):
    """`augmented_rhs` with parameter columns from one call of the module's ``rhs_with_full_jacobian``: f and
    [J | ∂f/∂p] (n, n + n_parameters) written into the work space at the end of p, from one solve for f and one
    factorization of M (K) for both, where ``rhs_with_jacobian`` and ``rhs_parameter_jacobian`` take two each."""
    k_parameters = len(parameter_columns)
    columns_p = n + np.array(parameter_columns, dtype=np.int64)
    width = n + n_parameters

    @njit(error_model="numpy", nogil=True)
    def full_rhs(t, y, p, out):
        end = p.shape[0]
        jacobians = p[end - n * width:].reshape((n, width))
        status = rhs_with_full_jacobian(t, y[:n], p, out[:n], jacobians)
        if status != 0:
            return status
        k = y.shape[0] // n - 1
        _multiply(jacobians[:, :n], y, out, n, k)
        for c in range(k_parameters):
            base = n * (1 + k - k_parameters + c)
            j = columns_p[c]
            for i in range(n):
                out[base + i] += scale * jacobians[i, j]
        return 0
    return full_rhs


@njit(cache=True, error_model="numpy", nogil=True)
def _multiply(J, y, out, n, k):
    """out[n (1 + c) + i] = sum_j J[i, j] y[n (1 + c) + j] for the k columns c: J S, column block by block."""
    for c in range(k):
        base = n * (1 + c)
        for i in range(n):
            acc = 0.0
            for j in range(n):
                acc += J[i, j] * y[base + j]
            out[base + i] = acc


class SensitivityRecorder:
    """A `lagcomp.integrate.recording.Recorder` of the state (the first `n` columns of the augmented rows),
    keeping the sensitivity columns beside it: every row, or with ``record="summary"`` the first and last
    (the rows the summary keeps of the state)."""

    def __init__(self, recorder, n: int, k: int, scale: float):
        self.recorder, self.n, self.k, self.unscale = recorder, n, k, 1.0 / scale
        self.parts: list[np.ndarray] = []

    def add(self, ts: np.ndarray, ys: np.ndarray, reused: bool = True) -> None:
        """`Recorder.add` of the state's columns; the sensitivities' columns copied."""
        if ts.shape[0] == 0:
            return
        self.recorder.add(ts, ys[:, :self.n], reused)
        rows = ys[:, self.n:].copy()
        if self.recorder.keep:
            self.parts.append(rows)
        else:  # the first row ever, and the last so far
            self.parts = [self.parts[0] if self.parts else rows[:1], rows[-1:]]

    @property
    def rows(self) -> int:
        return self.recorder.rows

    @property
    def last(self):
        return self.recorder.last

    def sensitivities(self) -> np.ndarray:
        """(m, N, k) along the rows the state's recorder returns."""
        rows = np.concatenate(self.parts) * self.unscale     # (exact: a power of two)
        if not self.recorder.keep and self.recorder.rows == 1:
            rows = rows[:1]
        return rows.reshape(rows.shape[0], self.k, self.n).transpose(0, 2, 1).copy()


def event_sensitivities(model, p: np.ndarray, cols: Columns, scale: float, event_parts) -> dict:
    """{event name: `EventSensitivities`} of a sensitivity run's located events (see "Events" above).

    `event_parts` are the run's event rows as `simulate` collects them: (times (m,), augmented states
    (m, N (1 + k)) with the columns scaled by `scale`, event indices (m,)) per driver call.  `p` is the run's
    parameter vector without the work space.  A row whose ``rhs`` fails (a singular mass matrix there) is nan.
    """
    from lagcomp.integrate.solution import EventSensitivities

    if not model.events:    # (what follows on empty arrays takes 30 µs: a sixth of a short run's fixed cost)
        return {}
    n, k, kernels = model.state_size, cols.k, model.kernels
    if event_parts:
        times, rows, which = (np.concatenate(column) for column in zip(*event_parts, strict=True))
    else:
        times, rows, which = np.empty(0), np.empty((0, n * (1 + k))), np.empty(0, dtype=np.int64)
    m = times.size
    S = rows[:, n:].reshape(m, k, n).transpose(0, 2, 1) * (1.0 / scale)   # (m, N, k); exact: a power of two
    f, gradients = np.full((m, n), np.nan), np.empty((len(model.events), n + 1 + len(model.parameters)))
    g = np.empty((m, gradients.shape[1]))
    for r in range(m):   # the kernels at each crossing (a failing rhs leaves its row nan)
        x = rows[r, :n].copy()
        if kernels.rhs(times[r], x, p, f[r]) != 0:
            f[r] = np.nan
        kernels.event_gradients(times[r], x, p, gradients)
        g[r] = gradients[which[r]]
    numerator = np.einsum("rj,rjc->rc", g[:, :n], S)
    numerator[:, len(cols.state):] += g[:, n + 1 + np.array(cols.parameters, dtype=np.int64)]
    with np.errstate(divide="ignore", invalid="ignore"):
        dt = -numerator / (np.einsum("rj,rj->r", g[:, :n], f) + g[:, n])[:, None]
    dy = S + f[:, :, None] * dt[:, None, :]
    return {event.name: EventSensitivities(t=dt[which == e], y=dy[which == e])
            for e, event in enumerate(model.events)}


def reaction_sensitivities(model, ts: np.ndarray, ys: np.ndarray, p: np.ndarray, S: np.ndarray,
                           cols: Columns) -> np.ndarray | None:
    """dλ/dw, (m, K, k), of a constrained model's multipliers at the saved rows (ts (m,), ys (m, N)) from the
    state's sensitivities S (m, N, k): ∂λ/∂y · S, plus ∂λ/∂p_j in the column of parameter p_j, with the
    module's exact ``reaction_jacobian`` (K, N + P).  None for a model without it (no multipliers, or a Kane
    model's auxiliary reactions); a row where the augmented matrix is singular is nan.  `p` is the run's
    parameter vector without the work space."""
    if not model.k:     # no multipliers (and no companion of the Jacobians to build for nothing)
        return None
    kernel = getattr(model.kernels, "reaction_jacobian", None)
    if kernel is None:
        return None
    m, n = ts.size, model.state_size
    jacobian = np.empty((model.k, n + len(model.parameters)))
    out = np.full((m, model.k, cols.k), np.nan)
    parameters = n + np.array(cols.parameters, dtype=np.int64)
    for r in range(m):
        if kernel(ts[r], ys[r], p, jacobian) == 0:
            out[r] = jacobian[:, :n] @ S[r]
            out[r, :, len(cols.state):] += jacobian[:, parameters]
    return out
