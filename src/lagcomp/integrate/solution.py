"""The result of a simulation: a frozen record of arrays, status and counters."""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass, field

import numpy as np

from lagcomp.errors import UnknownEventError
from lagcomp.integrate.files import output_path
from lagcomp.integrate.recording import Observed, RunSummary
from lagcomp.integrate.status import MESSAGES  # noqa: F401  (re-exported: a failed run is a status, not an exception)

@dataclass(frozen=True)
class EventRecord:
    """The occurrences of one event: times (k,), and coordinates and velocities (k, n) there, just before it
    (``q``, ``qd``) and just after it (``q_after``, ``qd_after``: the state its reset gave; the same as before
    for an event without a reset; None in a record built without them).  A contact's event (an impact) also
    has ``impulses`` (k, C): the normal impulses of the model's contacts there (`Model.contacts`, in order; 0 for
    a contact that did not take part), from M (q̇⁺ − q̇⁻) = Gᵀ P."""

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    q_after: np.ndarray | None = None
    qd_after: np.ndarray | None = None
    impulses: np.ndarray | None = None

    def __len__(self) -> int:
        return self.t.shape[0]

    @property
    def jumps(self) -> bool:
        """Whether some occurrence changed the state (a reset that moved it)."""
        return self.q_after is not None and not (np.array_equal(self.q, self.q_after)
                                                 and np.array_equal(self.qd, self.qd_after))


class EventRecords(dict):
    """{event name: `EventRecord}` of a run (`Solution.events`): a name the run has no record of is an
    `UnknownEventError` (a KeyError) naming those it has, not a bare KeyError."""

    def __missing__(self, name):
        raise UnknownEventError(f"No event {name!r} in this run: its events are {sorted(self)} (a declared event "
                                "is recorded when the run locates it: not with events=False or a list without it, "
                                "nor by a fixed-step method).")


@dataclass(frozen=True)
class ContactSwitch:
    """A contact's mode switch (`Solution.contact_switches`): at time `t` the contact `contact` closed (`closed`
    True: an impact under pressing ended its bounces, `lagcomp.kernel_support.resting`) or lifted off (False:
    its normal force reached 0)."""

    t: float
    contact: str
    closed: bool


@dataclass(frozen=True)
class FrictionSwitch:
    """A friction element's mode switch (`Solution.friction_switches`, `lagcomp.model.friction.Friction`): at
    time `t` the element `friction` began to stick (`mode` 0: v reached 0 with the force that holds it within
    μs N) or to slip (`mode` ±1, the sign of v from then: its force reached μs |N|, or v reached 0 with a force
    beyond it)."""

    t: float
    friction: str
    mode: int


@dataclass(frozen=True)
class EventSensitivities:
    """The sensitivities of one event's occurrences (`Solution.event_sensitivities`), columns w named by
    `Solution.sensitivity_names`: of its times, t (count, k) = dt*/dw, and of the state there,
    y (count, N, k) = d y(t*)/dw (the total derivative: the crossing moves with w)."""

    t: np.ndarray
    y: np.ndarray

    def __len__(self) -> int:
        return self.t.shape[0]


def _relative_drift(values: np.ndarray) -> float:
    """max |v − v₀| / |v₀| (absolute when v₀ = 0)."""
    scale = abs(values[0]) if values[0] != 0 else 1.0
    return float(np.max(np.abs(values - values[0])) / scale)


@dataclass(frozen=True)
class Solution:
    """A trajectory saved at times `t`.

    Attributes
    ----------
    t : ndarray, shape (m,)
        Saved times.
    q, qd : ndarray, shape (m, n)
        Coordinates and velocities at those times.
    energy : ndarray, shape (m,)
        Total mechanical energy T + V, evaluated by the compiled kernel
        (with `energy_function`, `momenta` and `summary`: when first read,
        see `observed`).
    energy_function : ndarray, shape (m,)
        Energy function h (Jacobi integral), conserved for time-independent
        conservative systems even when T + V is not (imposed motions).
    momenta : ndarray, shape (m, n)
        Conjugate momenta ∂L/∂q̇ at the saved times.
    cyclic : tuple of str
        The model's cyclic coordinates, whose momenta are conserved
        (without constraints acting along them).
    status : int
        0 when the end of the span was reached, 1 when a terminal event
        stopped the run, 2 when Ctrl-C did, negative on failure (`MESSAGES`).
    message : str
        What happened, with the time of failure if any.
    t_failure : float or None
        Time of the last good state when the run failed.
    nfev, nsteps, nrejected : int
        Right-hand-side evaluations, accepted steps and rejected steps.
    njev, nlu : int
        Jacobian evaluations and LU factorizations of the iteration matrices
        (``radau``; scipy's ``njev`` and ``nlu``); 0 for the other methods.
    method : str
        The integration method used.
    coordinates : tuple of str
        Coordinate names, the column order of `q` and `qd`.
    params : dict
        Parameter values used, by name.
    reactions : dict of str to ndarray, shape (m,)
        Multiplier λ_k of each constraint along the run, by name: the
        generalized force it exerts along its row Λ_k (empty without constraints).
    constraint_residual : float
        Largest constraint residual seen (|Φ| for holonomic constraints and
        |Λ q̇ + b| for all), over every step taken; 0.0 without constraints.
    projected_initial_state : ndarray, shape (2n,), or None
        The state the run started from when ``project_initial=True`` moved the
        given one onto the constraints.
    events : dict of str to EventRecord
        Each declared event's occurrences, by name (empty records when the
        method does not locate events or they were switched off).
    u : ndarray, shape (m, n_u), or None
        Kane models (`lagcomp.kane_model`): the generalized speeds, whose names
        are `speeds`; `qd` then holds q̇ from the kinematic equations.
    speeds : tuple of str
        Names of the columns of `u` (empty for Lagrange models).
    model_name : str
        Name of the model that ran ("" for a Solution built by hand).
    geometry : lagcomp.animation_bodies.BodyGeometry or None
        The model's ``geometry`` kernel with the run's parameters, which `animate` draws the
        bodies with (None for a Solution built by hand; a pickled one keeps no kernel).
    sensitivities : ndarray, shape (m, N, k), or None
        With ``simulate(..., sensitivities=...)``: ∂y(t)/∂w at each saved time for the k
        columns w named by `sensitivity_names` (initial-state components and parameters);
        rows of axis 1 are the state components of `state_names` (N = 2n, or n + n_u for
        a Kane model).  None without.  See `lagcomp.integrate.sensitivities`.
    sensitivity_names : tuple of str
        The columns of `sensitivities`: ``"q0:<coordinate>"``, ``"qd0:<state name>"`` (a
        velocity's ``<coordinate>_dot``, or a Kane model's speed) and ``"p:<parameter>"``.
    event_sensitivities : dict
        With sensitivities and located events: {event name: `EventSensitivities`}, the
        sensitivities of each occurrence's time and of the state there; empty without.
    reaction_sensitivities : ndarray, shape (m, K, k), or None
        With sensitivities, for a model with Lagrange multipliers: dλ/dw at each saved time,
        rows the constraints of `reaction_names`, columns the `sensitivity_names` (exact
        partials of λ times the sensitivities, `lagcomp.integrate.sensitivities.reaction_sensitivities`).
        None without sensitivities or multipliers (a Kane model's auxiliary reactions have none).
    contact_switches : tuple of ContactSwitch
        The contacts' closings and lift-offs, in time order (empty without contacts).  A lift-off is
        also an occurrence of the contact's event (in `events`, with no jump and zero impulse); a closing
        is the impact it ends with.
    contact_forces : ndarray, shape (m, C), or None
        The contacts' normal forces at the saved times (`Model.contacts`' order), 0 while a contact is
        open; at a switch's time the first row is before it, a second row at that time after it.  None
        for a model without contact modes (Kane models) or without contacts.
    friction_switches : tuple of FrictionSwitch
        The friction elements' switches between stick and slip, in time order (empty without friction); each
        is also an occurrence of the element's event (in `events`, no jump).
    friction_forces : ndarray, shape (m, F), or None
        The friction elements' forces (`Model.frictions`' order) along v at the saved times (in the units of the
        force conjugate to v's coordinate): while sticking the multiplier that holds v = 0, while slipping
        −μk |N| sign v.  None without friction.
    power_source : lagcomp.integrate.energy_balance.PowerSource or None
        The run's kernels and parameters, which `energy_balance` evaluates the power with (None for a
        Solution built by hand; a pickled one keeps none).
    summary : RunSummary or None
        Running reductions over every saved row (`lagcomp.integrate.recording`):
        the largest energy errors, coordinate ranges.  With
        ``record="summary"`` the arrays above hold only the first and last rows.
    observed : Observed
        Holds `energy`, `energy_function`, `momenta` and `summary`.  A run
        keeping every row evaluates them on first read, once (numba compiles
        the ``observables`` kernel then, not before the run's first result);
        ``record="summary"`` evaluated them during the run.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    observed: Observed = field(repr=False, compare=False)
    cyclic: tuple
    status: int
    message: str
    t_failure: float | None
    nfev: int
    nsteps: int
    nrejected: int
    method: str
    coordinates: tuple
    params: dict = field(default_factory=dict)
    reactions: dict = field(default_factory=dict)
    constraint_residual: float = 0.0
    projected_initial_state: np.ndarray | None = None
    events: dict = field(default_factory=dict)
    u: np.ndarray | None = None
    speeds: tuple = ()
    njev: int = 0
    nlu: int = 0
    model_name: str = ""
    geometry: object = field(default=None, repr=False, compare=False)
    sensitivities: np.ndarray | None = field(default=None, repr=False)
    sensitivity_names: tuple = ()
    event_sensitivities: dict = field(default_factory=dict, repr=False)
    reaction_sensitivities: np.ndarray | None = field(default=None, repr=False)
    contact_switches: tuple = ()
    contact_forces: np.ndarray | None = field(default=None, repr=False)
    friction_switches: tuple = ()
    friction_forces: np.ndarray | None = field(default=None, repr=False)
    power_source: object = field(default=None, repr=False, compare=False)

    def __post_init__(self):
        if not isinstance(self.events, EventRecords):
            object.__setattr__(self, "events", EventRecords(self.events))

    @classmethod
    def of_run(cls, **values) -> Solution:
        """``Solution(**values)`` built without the frozen dataclass's ``__init__``, to the same object: its fields
        in order, the defaults of those not given, then `__post_init__`.  ``__init__`` sets the 33 fields one
        ``object.__setattr__`` at a time, some 10 µs, a tenth of a short run's fixed cost; `simulate` builds
        every run's Solution here."""
        fields = dict(_TEMPLATE)        # (every field, in order: updated in place, the order stays)
        fields.update(values)
        if len(fields) != len(_TEMPLATE) or not values.keys() >= _REQUIRED:
            raise TypeError(f"Solution.of_run: unknown field(s) {sorted(values.keys() - _TEMPLATE.keys())} or "
                            f"missing {sorted(_REQUIRED - values.keys())}")
        for name, factory in _FACTORIES:
            if name not in values:
                fields[name] = factory()
        solution = object.__new__(cls)
        solution.__dict__.update(fields)
        solution.__post_init__()
        return solution

    @property
    def success(self) -> bool:
        """The run reached the end of its span or a terminal event."""
        return self.status in (0, 1)

    @property
    def energy(self) -> np.ndarray:
        return self.observed.values()[0]

    @property
    def energy_function(self) -> np.ndarray:
        return self.observed.values()[1]

    @property
    def momenta(self) -> np.ndarray:
        return self.observed.values()[2]

    @property
    def summary(self) -> RunSummary:
        return self.observed.values()[3]

    @property
    def reaction_names(self) -> tuple[str, ...]:
        """The constraints, in the order of the rows of each `reaction_sensitivities` matrix (`reactions`' keys)."""
        return tuple(self.reactions)

    @property
    def state_names(self) -> tuple[str, ...]:
        """Names of the columns of `y` (and the rows of each `sensitivities` matrix): the coordinates, then
        ``<coordinate>_dot`` (a Kane model: its speeds)."""
        velocities = self.speeds if self.u is not None else tuple(f"{c}_dot" for c in self.coordinates)
        return tuple(self.coordinates) + tuple(velocities)

    @property
    def y(self) -> np.ndarray:
        """The state at each saved time: (q, q̇), shape (m, 2n); (q, u) for Kane models."""
        return np.hstack([self.q, self.qd if self.u is None else self.u])

    def energy_drift(self, which: str = "energy") -> float:
        """Largest relative deviation of `energy` (or `energy_function`) from its initial value."""
        return _relative_drift(getattr(self, which))

    def energy_balance(self):
        """h(t) − h(0) against the work of the forces, dissipation, imposed motions and moving constraints.

        The energy function h (T + V when T is homogeneous quadratic in q̇) changes at the rate
        dh/dt = Q·q̇ − 2D − ∂L/∂t − λ·b; the residual h(t) − h(0) − ∫ dh/dt dt (less the jumps at resets) is
        the integration error, where `energy_drift` means nothing for a driven or damped run.  The integral
        is taken along the saved rows (quintic Hermite interpolation, 4-point Gauss, O(Δ⁷) per interval);
        ``quadrature_error`` estimates the rows' share: save them densely (``t_eval``) where it matters.

        Returns
        -------
        lagcomp.integrate.energy_balance.EnergyBalance
            ``change``, ``work`` by term, ``jumps``, ``residual`` (m,) and ``max_residual``,
            ``relative_residual``.

        Raises
        ------
        ModelError
            For a Kane model, a model with contacts or friction elements, a ``record="summary"`` run, or a
            Solution that keeps no kernels (pickled, built by hand).
        """
        from lagcomp.integrate.energy_balance import energy_balance

        return energy_balance(self)

    def invariants(self) -> dict[str, tuple[np.ndarray, float]]:
        """The candidate conserved quantities along the run, with their largest relative drift.

        Returns ``{name: (values, drift)}`` for the energy function ``h``
        (conserved when L has no explicit t and no forces act) and the momentum
        ``p_<name>`` of each cyclic coordinate.  Whether a quantity is really
        conserved depends on the system; the drift tells.
        """
        found = {"h": self.energy_function}
        found.update({f"p_{c}": self.momenta[:, self.coordinates.index(c)] for c in self.cyclic})
        return {name: (values, _relative_drift(values)) for name, values in found.items()}

    def to_dict(self) -> dict:
        """Arrays and scalars as a dict of numpy arrays (what `save_npz` writes)."""
        return {
            "t": self.t, "q": self.q, "qd": self.qd,
            **({"u": self.u, "speeds": np.asarray(self.speeds)} if self.u is not None else {}),
            "energy": self.energy, "energy_function": self.energy_function, "momenta": self.momenta,
            "status": np.asarray(self.status), "message": np.asarray(self.message),
            "t_failure": np.asarray(np.nan if self.t_failure is None else self.t_failure),
            "nfev": np.asarray(self.nfev), "nsteps": np.asarray(self.nsteps),
            "nrejected": np.asarray(self.nrejected), "njev": np.asarray(self.njev), "nlu": np.asarray(self.nlu),
            "method": np.asarray(self.method), "coordinates": np.asarray(self.coordinates),
            "param_names": np.asarray(list(self.params)),
            "param_values": np.asarray(list(self.params.values()), dtype=float),
            "constraint_residual": np.asarray(self.constraint_residual),
            **{f"reaction_{name}": values for name, values in self.reactions.items()},
            **{f"event_{name}_{part}": getattr(record, part)
               for name, record in self.events.items() for part in ("t", "q", "qd", "q_after", "qd_after", "impulses")
               if getattr(record, part) is not None},
            **({"sensitivities": self.sensitivities, "sensitivity_names": np.asarray(self.sensitivity_names)}
               if self.sensitivities is not None else {}),
            **({"reaction_sensitivities": self.reaction_sensitivities}
               if self.reaction_sensitivities is not None else {}),
            **({"contact_forces": self.contact_forces,
                "contact_switch_t": np.array([s.t for s in self.contact_switches], dtype=float),
                "contact_switch_contact": np.array([s.contact for s in self.contact_switches], dtype=str),
                "contact_switch_closed": np.array([s.closed for s in self.contact_switches], dtype=bool)}
               if self.contact_forces is not None else {}),
            **({"friction_forces": self.friction_forces,
                "friction_switch_t": np.array([s.t for s in self.friction_switches], dtype=float),
                "friction_switch_friction": np.array([s.friction for s in self.friction_switches], dtype=str),
                "friction_switch_mode": np.array([s.mode for s in self.friction_switches], dtype=np.int64)}
               if self.friction_forces is not None else {}),
        }

    def to_xarray(self):
        """The run as an ``xarray.Dataset`` along the dimension (and coordinate) ``t``, for notebooks.

        Data variables, each of shape (m,) along ``t``: one per coordinate (its name), one per velocity
        (``<coordinate>_dot``, q̇; for a Kane model from its kinematic equations), a Kane model's speeds
        (their names), ``energy`` (T + V), ``energy_function`` (h, only where it differs from T + V) and
        ``reaction_<constraint>`` for each constraint's multiplier (a Kane model's auxiliary reactions by
        name).  Each variable's ``attrs["role"]`` says which it is.  Each event ``<name>`` has its own
        dimension ``event_<name>`` (its occurrences): ``event_<name>_t``, ``event_<name>_state`` and
        ``event_<name>_state_after`` (the state after it: its reset's)
        (occurrences × ``state``, the coordinates then the velocities, or the speeds of a Kane model).
        A run with sensitivities adds ``sensitivities`` with dims (``t``, ``state``, ``wrt``), ``wrt`` the
        `sensitivity_names`, and for a model with multipliers ``reaction_sensitivities`` with dims (``t``,
        ``constraint``, ``wrt``), ``constraint`` the `reaction_names`.

        ``attrs``: ``model`` (its name), ``method``, ``status``, ``message``, ``nfev``, ``nsteps``,
        ``nrejected``, ``njev``, ``nlu``, ``constraint_residual``, ``t_failure`` (failed runs only),
        ``record`` and one ``param_<name>`` per parameter value.  lagcomp models carry no units, so
        the Dataset has none.

        A ``record="summary"`` run kept only its first and last rows: the Dataset holds those two rows
        (``attrs["record"] == "summary"``) and the summary's row count and energy errors as
        ``summary_rows``, ``summary_energy_error`` and ``summary_energy_function_error``.

        The values are the Solution's arrays themselves (bit for bit).  A name given twice (a coordinate
        named ``x_dot`` beside one named ``x``, or one named ``t``) is a ValueError: use `to_dict` then.
        Needs xarray (``pip install 'lagcomp[xarray]'``).
        """
        from lagcomp.notebook import solution_dataset

        return solution_dataset(self)

    def _repr_html_(self) -> str:
        """A compact HTML summary for Jupyter (`lagcomp.notebook.solution_html`)."""
        from lagcomp.notebook import solution_html

        return solution_html(self)

    def animate(self, points: dict | None = None, **options):
        """An animation of this run's bodies and named points: `lagcomp.animation.animate` (matplotlib)."""
        from lagcomp.animation import animate

        return animate(self, points, **options)

    def save_npz(self, path: str | os.PathLike) -> None:
        """Write `to_dict()` to a compressed .npz file (numpy adds ``.npz`` to a name without it); a directory
        that does not exist is an OptionError."""
        np.savez_compressed(output_path(path, "Solution.save_npz"), **self.to_dict())

    def __repr__(self) -> str:
        return (
            f"Solution(method={self.method!r}, status={self.status}, points={len(self.t)}, "
            f"t=[{self.t[0]:g}, {self.t[-1]:g}], nsteps={self.nsteps}, nfev={self.nfev})"
        )


#: Every field of `Solution` in order, with its default (None for the fields without one and those with a factory):
#: `Solution.of_run`'s starting point; the fields without a default, and those whose default is made per Solution.
_TEMPLATE = {spec.name: None if spec.default is dataclasses.MISSING else spec.default
             for spec in dataclasses.fields(Solution)}
_REQUIRED = frozenset(spec.name for spec in dataclasses.fields(Solution)
                      if spec.default is dataclasses.MISSING and spec.default_factory is dataclasses.MISSING)
_FACTORIES = tuple((spec.name, spec.default_factory) for spec in dataclasses.fields(Solution)
                   if spec.default_factory is not dataclasses.MISSING)
