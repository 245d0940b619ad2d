r"""Parameter identification: ``Model.fit`` fits parameters to measured trajectories by least squares.

For experiments e with data times t_e (m_e,), measured state components ``observe`` (K of them, rows of
y = (q, q̇)) and observations d_e (m_e, K), the residual of the unknowns θ (parameters) is

    r(θ) = ((y_e(t_e; θ)[:, observe] − d_e) / σ) flattened and stacked over the experiments,

σ a scalar or one value per observable (θ may include components of each experiment's initial state,
``fit_initial``), and its Jacobian ∂r/∂θ = S[:, observe, :] / σ comes from the same
run: ``simulate(..., t_eval=t_e, sensitivities=<the fitted parameters>)`` integrates the variational
equations with the state (`lagcomp.integrate.sensitivities`), so J is exact up to the run's tolerance, not a
finite difference.  `scipy.optimize.least_squares` (trust-region reflective, bounds allowed) calls the
residual and the Jacobian separately at the same θ; `_Runs` keeps the last θ's runs so that each pair costs
one run per experiment.

The covariance of the estimates is (JᵀJ)⁻¹ with J the weighted Jacobian at the optimum: the covariance of a
linearised model with independent Gaussian noise of standard deviations σ.  Without `sigma` (σ = 1), it is
scaled by the reduced χ², s² = Σr² / (m − P), the usual estimate of an unknown common noise variance.

Refused (`OptionError`, docs/errors.md): unknown or repeated parameter names, observations whose shape
differs from (len(t), len(observe)), non-finite data, times that do not increase, a run that cannot carry
sensitivities (a method without them: the run's own refusal); a run failing at some trial parameters, or
refused at them (a mass through zero: `SingularMassMatrixError`, the cause), raises `IntegrationError`
naming them and advising bounds.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from lagcomp.errors import IntegrationError, OptionError, ParameterError, SingularMassMatrixError
from lagcomp.names import by_name


@dataclass(frozen=True)
class Experiment:
    """One measured run: data times `t` (m,), starting at or after the run's start `t0`, observations (m, K)
    of the `observe` components, and the initial state y0 = (q0, q̇0) (2n,) (in a `FitResult`: with the fitted
    initial components at their estimates)."""

    t: np.ndarray
    observations: np.ndarray
    y0: np.ndarray
    t0: float


@dataclass(frozen=True)
class FitResult:
    """What `Model.fit` found.

    Attributes
    ----------
    estimates : dict
        The fitted parameters by name, then the fitted initial-state components (`fit_initial`) named as
        `Solution.sensitivity_names` names them (``"q0:theta1"``, ``"qd0:theta1_dot"``), with ``[e]``
        appended for experiment e when there are several.
    covariance : ndarray, shape (P, P)
        Covariance of the estimates, in `names` order: (JᵀJ)⁻¹ of the σ-weighted Jacobian at the optimum,
        scaled by the reduced χ² when no `sigma` was given (`sigma_given`).  NaN if J is rank-deficient
        (parameters that the data cannot tell apart).
    standard_errors : dict
        Square roots of the covariance's diagonal, by name.
    residuals : list of ndarray
        Per experiment, model − data at the data times, shape (m_e, K) (unweighted, units of the state).
    cost : float
        ½ Σ r² of the weighted residuals at the optimum.
    nfev, njev : int
        Residual and Jacobian evaluations of least_squares (each pair of them at one θ costs one run per
        experiment).
    success : bool
    message : str
        least_squares' verdict.
    names : tuple of str
        The unknowns (parameters, then initial-state components), the order of `covariance`'s rows.
    observe : tuple of str
        The measured state components.
    sigma_given : bool
        Whether `sigma` weighted the residuals (else the covariance is scaled by the reduced χ²).
    experiments : tuple of Experiment
        The data fitted, each with its initial state at the estimates (what `plot` runs).
    """

    estimates: dict
    covariance: np.ndarray
    standard_errors: dict
    residuals: list
    cost: float
    nfev: int
    njev: int
    success: bool
    message: str
    names: tuple
    observe: tuple
    sigma_given: bool
    experiments: tuple = field(repr=False)
    _model: object = field(repr=False)
    _fixed: dict = field(repr=False)
    _run_options: dict = field(repr=False)

    @property
    def correlation(self) -> np.ndarray:
        """The covariance normalised to unit diagonal, (P, P)."""
        scale = np.sqrt(np.diag(self.covariance))
        return self.covariance / np.outer(scale, scale)

    def plot(self, points: int = 400):
        """Fit against data: one panel per observed component, the data as dots and the fitted model's run
        (at the estimates, `points` times per experiment) as lines, one colour per experiment; a Figure."""
        from lagcomp.plots import _figure, _label

        fig = _figure(7.0, 2.2 * len(self.observe) + 0.8)
        axes = fig.subplots(len(self.observe), 1, sharex=True, squeeze=False)[:, 0]
        params = {**self._fixed, **{name: self.estimates[name] for name in self._model.parameters
                                     if name in self.estimates}}
        n = self._model.n
        columns = _state_indices(self._model, self.observe)
        for e, experiment in enumerate(self.experiments):
            dense = np.linspace(experiment.t0, experiment.t[-1], points)
            sol = self._model.simulate((experiment.t0, experiment.t[-1]), experiment.y0[:n], experiment.y0[n:], params,
                                       t_eval=dense, **self._run_options)
            for k, axis in enumerate(axes):
                colour = f"C{e}"
                axis.plot(experiment.t, experiment.observations[:, k], ".", color=colour, markersize=3,
                          label=f"data {e}" if len(self.experiments) > 1 else "data")
                axis.plot(sol.t, sol.y[:, columns[k]], "-", color=colour, linewidth=1.0,
                          label=f"fit {e}" if len(self.experiments) > 1 else "fit")
        for axis, name in zip(axes, self.observe, strict=True):
            axis.set_ylabel(_label(name))
        axes[0].legend(loc="best", fontsize="small")
        axes[-1].set_xlabel("t")
        estimates = ", ".join(f"{name} = {self.estimates[name]:.4g} ± {self.standard_errors[name]:.2g}"
                              for name in self.names)
        axes[0].set_title(estimates, fontsize="small")
        return fig


def fit(model, t=None, observations=None, params0: Mapping | None = None, *, observe=None, fixed=None,
        bounds=None, q0=None, qd0=None, t0=0.0, sigma=None, experiments=None, fit_initial=(), method="dop853",
        rtol=1e-10, atol=None, max_nfev=None, **least_squares_options) -> FitResult:
    """Fit `params0`'s parameters of `model` to observations; see `lagcomp.Model.fit`."""
    from scipy.optimize import least_squares

    initial = _fit_initial(model, fit_initial)
    parameters, x0 = _unknowns(model, params0, bool(initial))
    fixed = _fixed(model, fixed, parameters)
    observe = _observed(model, observe)
    experiments = _experiments(model, t, observations, q0, qd0, t0, experiments, len(observe))
    data_scale = 1.0 if sigma is not None else _data_scale(experiments)
    weights = _weights(sigma, len(observe)) * data_scale
    atol = default_atol(rtol, experiments) if atol is None else atol
    run_options = dict(method=method, rtol=rtol, atol=atol, events=False, progress=False)
    runs = _Runs(model, parameters, initial, fixed, observe, experiments, weights, run_options)
    names = runs.names
    x0 = np.concatenate([x0] + [experiment.y0[list(initial)] for experiment in experiments])
    lower, upper = _bounds(bounds, names, x0)
    try:  # the run's refusals (a method without sensitivities) before least_squares starts
        runs.evaluate(x0)
    except OptionError as err:
        raise OptionError(f"`fit` integrates the sensitivities of the unknowns {list(names)}, and the run "
                          f"refuses: {err}") from err
    # the unknowns in units of their starting values (1 where that is 0): scipy's gtol tests J^T r unscaled, in
    # the unknowns' units, and stopped a fit of k ~ 6e9 (a spring in other units) where it started
    unit = np.where(np.abs(x0) > 0.0, np.abs(x0), 1.0)
    result = least_squares(lambda u: runs.residual(u * unit), x0 / unit, jac=lambda u: runs.jacobian(u * unit) * unit,
                           bounds=(lower / unit, upper / unit), x_scale="jac", max_nfev=max_nfev,
                           **least_squares_options)
    result.x = result.x * unit
    residuals, jacobian = runs.evaluate(result.x)
    covariance = _covariance(jacobian, residuals, sigma is not None)
    estimates = dict(zip(names, map(float, result.x), strict=True))
    return FitResult(
        estimates=estimates, covariance=covariance,
        standard_errors=dict(zip(names, map(float, np.sqrt(np.diag(covariance))), strict=True)),
        residuals=runs.unweighted(result.x), cost=float(0.5 * residuals @ residuals) * data_scale**2, nfev=int(result.nfev),
        njev=int(result.njev or 0), success=bool(result.success), message=str(result.message), names=names,
        observe=observe, sigma_given=sigma is not None, experiments=runs.fitted_experiments(result.x), _model=model,
        _fixed=fixed, _run_options=runs.run_options)


def default_atol(rtol: float, experiments) -> float:
    """The runs' atol when none is given: rtol times the largest |component| of the experiments' initial states
    (rtol itself when they are all 0), so that the runs are as accurate in any units: a fixed atol = rtol, in the
    state's units, was 1e-7 of a state in millimetres against 1e-10 in metres at the default rtol, and the fitted
    parameters moved by that much."""
    size = max(float(np.max(np.abs(experiment.y0), initial=0.0)) for experiment in experiments)
    return rtol * size if size > 0.0 else rtol


class _Runs:
    """The residual and Jacobian of the unknowns θ, both from one run per experiment, the last θ's kept (the
    key: θ's bytes) so that least_squares' separate ``fun`` and ``jac`` calls at one θ cost one run."""

    def __init__(self, model, parameters, initial, fixed, observe, experiments, weights, run_options):
        self.model, self.parameters, self.initial, self.fixed = model, parameters, initial, fixed
        self.experiments, self.weights, self.run_options = experiments, weights, run_options
        self.columns = _state_indices(model, observe)
        labels = [_initial_label(model, i) for i in initial]
        suffixes = [""] if len(experiments) == 1 else [f"[{e}]" for e in range(len(experiments))]
        self.names = parameters + tuple(label + suffix for suffix in suffixes for label in labels)
        # the run's sensitivity columns: initial-state components first, then parameters (`Columns`)
        self.requested = tuple(model.state_names[i] for i in initial) + parameters
        self.order = labels + [f"p:{name}" for name in parameters]
        self._key, self._value = None, None

    def fitted_experiments(self, x) -> tuple[Experiment, ...]:
        """The experiments with their fitted initial components at `x`'s values."""
        return tuple(dataclasses.replace(experiment, y0=self._initial_state(x, e))
                     for e, experiment in enumerate(self.experiments))

    def _initial_state(self, x, e: int) -> np.ndarray:
        y0 = self.experiments[e].y0.copy()
        start = len(self.parameters) + e * len(self.initial)
        y0[list(self.initial)] = x[start:start + len(self.initial)]
        return y0

    def evaluate(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(r (M,), J (M, P)) at θ = x, M = Σ m_e K."""
        key = np.asarray(x, dtype=float).tobytes()
        if key != self._key:
            parts = [self._run(x, e) for e in range(len(self.experiments))]
            self._value = (np.concatenate([r for r, _, _ in parts]), np.concatenate([j for _, j, _ in parts]))
            self._unweighted = [d for _, _, d in parts]
            self._key = key
        return self._value

    def residual(self, x):
        return self.evaluate(x)[0]

    def jacobian(self, x):
        return self.evaluate(x)[1]

    def unweighted(self, x) -> list:
        self.evaluate(x)
        return self._unweighted

    def _run(self, x, e: int):
        experiment, n, p = self.experiments[e], self.model.n, len(self.parameters)
        params = {**self.fixed, **dict(zip(self.parameters, map(float, x[:p]), strict=True))}
        y0 = self._initial_state(x, e)
        shown = ", ".join(f"{name}={value:.17g}" for name, value in zip(self.names, x, strict=True))
        try:  # trial values where the model cannot start (a mass through zero, a restitution above 1)
            sol = self.model.simulate((experiment.t0, float(experiment.t[-1])), y0[:n], y0[n:], params,
                                      t_eval=experiment.t, sensitivities=self.requested, **self.run_options)
        except (SingularMassMatrixError, ParameterError) as err:
            raise IntegrationError(f"The fit's run failed at the trial parameters {shown}, which the model "
                                   f"refuses ({err}); bound the parameters (`bounds=`) to where the model runs, "
                                   "or start closer.") from err
        if not sol.success or sol.t.size != experiment.t.size:
            raise IntegrationError(f"The fit's run failed at the trial parameters {shown} (status {sol.status}: "
                                   f"{sol.message}); bound the parameters (`bounds=`) or start closer.", sol)
        difference = sol.y[:, self.columns] - experiment.observations  # (m, K)
        order = [sol.sensitivity_names.index(label) for label in self.order]
        sensitivities = sol.sensitivities[:, self.columns, :][:, :, order] / self.weights[None, :, None]  # (m, K, k)
        residual = (difference / self.weights).ravel()
        jacobian = np.zeros((residual.size, len(self.names)))
        k_initial = len(self.initial)
        jacobian[:, :p] = sensitivities[:, :, k_initial:].reshape(residual.size, p)
        start = p + e * k_initial
        jacobian[:, start:start + k_initial] = sensitivities[:, :, :k_initial].reshape(residual.size, k_initial)
        return residual, jacobian, difference


def _covariance(jacobian: np.ndarray, residuals: np.ndarray, sigma_given: bool) -> np.ndarray:
    """(JᵀJ)⁻¹ by the SVD of J, times the reduced χ² without `sigma`; NaN where J is rank-deficient."""
    _, singular, vt = np.linalg.svd(jacobian, full_matrices=False)
    size = jacobian.shape[1]
    if singular[-1] <= np.finfo(float).eps * max(jacobian.shape) * singular[0]:
        return np.full((size, size), np.nan)
    covariance = (vt.T / singular**2) @ vt
    if not sigma_given:
        dof = residuals.size - size
        covariance *= (residuals @ residuals) / dof if dof > 0 else np.nan
    return covariance


def _unknowns(model, params0, initial: bool) -> tuple[tuple[str, ...], np.ndarray]:
    """The fitted parameters' names and starting values (none when only initial components are fitted)."""
    if params0 is None and initial:
        return (), np.zeros(0)
    if not isinstance(params0, Mapping) or not (params0 or initial):
        raise OptionError("`params0` must be a dict of the parameters to fit and their starting values, "
                          f"e.g. {{{model.parameters[0]!r}: 1.0}}, got {params0!r}." if model.parameters else
                          f"{model.name!r} has no parameters to fit.")
    params0 = by_name(params0, "params0", model.parameters)
    unknown = [name for name in params0 if name not in model.parameters]
    if unknown:
        raise OptionError(f"`params0` names unknown parameters {unknown}; {model.name!r} has {list(model.parameters)}.")
    names = tuple(params0)
    x0 = np.array([params0[name] for name in names], dtype=float)
    if not np.all(np.isfinite(x0)):
        raise OptionError(f"`params0` holds non-finite starting values: {dict(params0)}.")
    return names, x0


def _fit_initial(model, fit_initial) -> tuple[int, ...]:
    """The indices into y of the initial-state components `fit_initial` names (state names), in state order."""
    fit_initial = (fit_initial,) if isinstance(fit_initial, str) else tuple(fit_initial or ())
    names = list(model.state_names)
    unknown = [name for name in fit_initial if name not in names]
    if unknown:
        raise OptionError(f"`fit_initial` names unknown state components {unknown}; {model.name!r} has {names}.")
    return tuple(sorted({names.index(name) for name in fit_initial}))


def _initial_label(model, i: int) -> str:
    """The name of y0's component i as `Solution.sensitivity_names` gives it: ``q0:theta1``, ``qd0:theta1_dot``."""
    return f"{'q0' if i < model.n else 'qd0'}:{model.state_names[i]}"


def _fixed(model, fixed, names) -> dict:
    fixed = dict(fixed or {})
    unknown = [name for name in fixed if name not in model.parameters]
    if unknown:
        raise OptionError(f"`fixed` names unknown parameters {unknown}; {model.name!r} has {list(model.parameters)}.")
    both = [name for name in fixed if name in names]
    if both:
        raise OptionError(f"Parameters {both} are both fitted (`params0`) and `fixed`: give each in one of them.")
    return fixed


def _observed(model, observe) -> tuple[str, ...]:
    if observe is None:
        return tuple(model.coordinates)
    observe = (observe,) if isinstance(observe, str) else tuple(observe)
    _state_indices(model, observe)
    if not observe or len(set(observe)) != len(observe):
        raise OptionError(f"`observe` must name each measured state component once, got {list(observe)}.")
    return observe


def _state_indices(model, observe) -> list[int]:
    names = list(model.state_names)
    unknown = [name for name in observe if name not in names]
    if unknown:
        raise OptionError(f"`observe` names unknown state components {unknown}; {model.name!r} has {names}.")
    return [names.index(name) for name in observe]


def _experiments(model, t, observations, q0, qd0, t0, experiments, width: int) -> tuple[Experiment, ...]:
    """The experiments as `Experiment`s, checked: `experiments` is a list of (t, observations, q0, qd0)
    replacing the single one of `t`, `observations`, `q0`, `qd0`."""
    if experiments is None:
        given = [(t, observations, q0, qd0)]
    else:
        if t is not None or observations is not None:
            raise OptionError("Give either `t` and `observations` or `experiments` (a list of (t, observations, "
                              "q0, qd0)), not both.")
        given = list(experiments)
        if not given:
            raise OptionError("`experiments` is empty.")
    checked = []
    for e, entry in enumerate(given):
        try:
            times, data, start_q, start_qd = entry
        except (TypeError, ValueError):
            raise OptionError(f"Experiment {e} must be (t, observations, q0, qd0), got {entry!r}.") from None
        label = "" if experiments is None else f"experiment {e}: "
        times = np.asarray(times, dtype=float)
        data = np.asarray(data, dtype=float)
        if data.ndim == 1 and width == 1:
            data = data[:, None]
        if times.ndim != 1 or times.size < 1 or data.shape != (times.size, width):
            raise OptionError(f"{label}observations of shape {data.shape} for {times.shape} times and {width} "
                              f"observed components: need (len(t), len(observe)) = ({times.size}, {width}).")
        if not (np.all(np.isfinite(times)) and np.all(np.isfinite(data))):
            raise OptionError(f"{label}the data hold non-finite values (NaN or inf) in "
                              f"{'`t`' if not np.all(np.isfinite(times)) else '`observations`'}: drop those rows.")
        if np.any(np.diff(times) <= 0) or times[0] < t0 or times[-1] <= t0:
            raise OptionError(f"{label}the times must increase strictly from t0 = {t0} on, and end after it.")
        checked.append(Experiment(times, data, model.initial_state(start_q, start_qd), float(t0)))
    return tuple(checked)


def _data_scale(experiments) -> float:
    """The largest |observation| of the experiments (1 when all are 0): without `sigma` the residuals are divided
    by it, one number for all, which moves neither the optimum nor the covariance (scaled by the reduced χ²) but
    makes least_squares' tolerances (gtol on J^T r, in the data's units squared) relative: in millimetres its
    gradient test stopped the fit with k 2e-5 off."""
    size = max(float(np.max(np.abs(experiment.observations), initial=0.0)) for experiment in experiments)
    return size if size > 0.0 and np.isfinite(size) else 1.0


def _weights(sigma, width: int) -> np.ndarray:
    """σ per observed component, (K,): ones without `sigma`."""
    values = np.asarray(1.0 if sigma is None else sigma, dtype=float)
    if (values.ndim > 1 or values.size not in (1, width) or not np.all(np.isfinite(values))
            or np.any(values <= 0)):
        raise OptionError(f"`sigma` must be a positive number or one per observed component ({width}), got {sigma!r}.")
    return np.broadcast_to(values.reshape(-1), (width,)).copy()


def _bounds(bounds, names, x0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) (P,) from `bounds`: None, or {name: (low, high)} for some of the fitted parameters, which
    must hold the starting values `x0`."""
    lower, upper = np.full(len(names), -np.inf), np.full(len(names), np.inf)
    names = list(names)
    if bounds is not None and not isinstance(bounds, Mapping):
        raise OptionError(f"`bounds` must be a dict {{name: (low, high)}} of fitted parameters, got {bounds!r}.")
    for name, (low, high) in (bounds or {}).items():
        if name not in names:
            raise OptionError(f"`bounds` names {name!r}, which is not fitted ({list(names)}).")
        lower[names.index(name)], upper[names.index(name)] = low, high
    outside = [name for name, low, high, start in zip(names, lower, upper, x0, strict=True)
               if not low <= start <= high or not low < high]
    if outside:
        raise OptionError(f"`params0` of {outside} lies outside its `bounds` (or the bounds are empty): start "
                          "inside them.")
    return lower, upper
