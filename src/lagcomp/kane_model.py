r"""Compile a ``sympy.physics.mechanics.KanesMethod`` as Kane's equations, and run it.

``lagcomp.compile(km)`` comes here for every KanesMethod.  The equations are
the ones KanesMethod forms (`lagcomp.mechanics.kane`): q̇ = N(q, u, t) from
its kinematic differential equations and M u̇ = F from its mass matrix and
forcing, the differentiated velocity constraints among the rows, over the
state y = (q, u) of length n_q + n_u (n_q and n_u may differ: the Whipple
bicycle of sympy's test_kane3 has 4 coordinates and 6 speeds).  Nothing is
re-derived from the kinetic energy, so velocities set by hand
(``v2pt_theory``, ``set_vel``), rolling contacts and speeds that are not q̇
are all compiled as the user stated them.

A `KaneModel` is a `lagcomp.Model` with these differences:

- ``simulate(t_span, q0, u0, params, **options)``: the initial state is (q0, u0)
  (u0 by speed name order, `speeds`); it must satisfy the configuration
  constraints Φ = 0 and velocity constraints Ψ = 0 to 1e-9 (the equations
  keep Ψ at its initial value), or be projected with ``project_initial=True``
  (least change of q on Φ, then of u on Ψ).  Methods: the Runge-Kutta ones
  (dop853, dopri5, tsit5, bs3, rk4; ``projection=True`` projects after every
  step, the default for rk4) and radau (stiff Kane models: Radau IIA with the
  exact Jacobian ``rhs_jacobian`` of (q̇, u̇); it does not project, and refuses
  ``projection=True``); the others need y = (q, q̇) and refuse with an
  OptionError (`KANE_METHODS`).  No Baumgarte terms.
- Events: ``compile(km, events=[lagcomp.Event(name, g, direction, terminal)])``
  with g in q(t), u(t), q̇ (through the kinematic equations), t and the
  equations' parameters, located on the dense output of the adaptive methods as
  for Lagrange models; in ``Solution.events`` an `EventRecord`'s ``qd`` holds u.
- ``sweep(t_span, grid, q0, u0, ...)``: grids over coordinates, speeds (by
  name) and parameters with any method of `KANE_METHODS`, through the same
  compiled sweep loops as Lagrange models (not ``batched``).
- The `Solution` has ``q``, ``qd`` (q̇ = N(q, u) at each row), ``u`` and
  ``speeds``; ``y`` is (q, u).  ``energy`` is T + V where it can be formed
  (see `lagcomp.mechanics.kane.kane_energy`), else NaN; ``momenta`` are NaN.
  ``reactions`` holds the noncontributing forces of auxiliary speeds by name;
  ``constraint_residual`` the largest |Φ|, |Ψ| over the steps (radau, which
  does not evaluate them as it steps: over the saved rows).  In ``summary``,
  ``qd_min``/``qd_max`` are the ranges of u.
- ``first_order_form``: the `FirstOrderForm` compiled (None for a model from
  `lagcomp.load`), for linearization about steady motions; ``kanes_method``:
  the KanesMethod itself.
"""

from __future__ import annotations

import dataclasses
import hashlib

import numpy as np

from lagcomp.cache import Cache, input_key, load_module
from lagcomp.errors import InitialConditionError, ModelError, OptionError
from lagcomp.integrate.methods import METHODS
from lagcomp.runtime import Model

#: Methods that take any first-order state y (the Runge-Kutta tableaux and radau); the others need y = (q, q̇).
KANE_METHODS = tuple(name for name, m in METHODS.items() if m.any_state)
#: Options `compile(km, ...)` accepts for a KanesMethod.
KANE_OPTIONS = ("name", "parameters", "defaults", "q0", "u0", "t_end", "description", "events")


def compile_kane(km, cache_dir=None, **options) -> "KaneModel":
    """Compile the KanesMethod `km` (module docstring); `options` as in `KANE_OPTIONS`."""
    from lagcomp.mechanics.kane import auxiliary_reactions, kane_energy, kane_events, kane_form, kane_resets

    unknown = sorted(set(options) - set(KANE_OPTIONS))
    if unknown:
        raise ModelError(f"compile() of a KanesMethod takes the options {list(KANE_OPTIONS)}, not {unknown} "
                         "(the state is (q, u): give initial speeds as u0).")
    form = kane_form(km, options.get("parameters"))
    names, reactions = auxiliary_reactions(km, form)
    energy = kane_energy(km, form)
    events, event_exprs = kane_events(km, form, options.get("events"))
    resets = kane_resets(km, form, events)
    recorded = _run_defaults(form, options, events)
    fingerprint = "\n".join(
        ["kane", recorded["name"], repr(form.coordinate_names), repr(form.speed_names),
         repr([s.name for s in form.parameters]), repr(names)]
        + [f"{role}={_srepr(expr)}" for role, expr in (("N", form.N), ("M", form.M), ("F", form.F),
                                                      ("Phi", form.Phi), ("Psi", form.Psi), ("energy", energy),
                                                      ("reactions", reactions))]
        + [f"event {e.name} {e.direction} {e.terminal}={_srepr(g)}" for e, g in zip(events, event_exprs)]
        + [f"event {e.name} reset {i}={_srepr(v)}" for e, reset in zip(events, resets, strict=True) for i, v in reset]
    )
    cache = Cache(cache_dir)
    key = input_key(fingerprint, options={"kane": 1})
    entry, fresh = cache.lookup(key), False
    if entry is None:
        with cache.lock(key):
            entry = cache.lookup(key)
            if entry is None:
                entry, fresh = _build(cache, key, recorded["name"], form, energy, names, reactions,
                                      tuple(zip((e.name for e in events), event_exprs)), resets), True
    model = KaneModel(None, load_module(entry), entry, from_cache=not fresh, recorded=recorded)
    model.first_order_form, model.kanes_method = form, km
    cache.remember(recorded["name"], key, recorded)
    return model


def _srepr(expr) -> str:
    """A canonical digest of `expr` (sympy's tree, assumptions of symbols included), for the cache key.

    Like ``sympy.srepr`` hashed, but each distinct subexpression is visited once:
    srepr of the bicycle's equations took about 6 s, most of a cache hit's time.
    """
    import sympy as sp

    if expr is None:
        return "None"
    if isinstance(expr, sp.MatrixBase):
        expr = sp.ImmutableMatrix(expr)
    memo: dict = {}

    def digest(node) -> str:
        done = memo.get(node)
        if done is None:
            if node.args:
                text = type(node).__name__ + "(" + ",".join(digest(a) for a in node.args) + ")"
            else:  # an atom: srepr keeps every digit of a Float and a Symbol's assumptions
                text = sp.srepr(node)
            done = memo[node] = hashlib.sha256(text.encode()).hexdigest()[:24]
        return done

    return digest(expr)


def _build(cache, key, name, form, energy, names, reactions, events, resets):
    from lagcomp.codegen.kane import emit_kane

    source, operations = emit_kane(name, form, energy, names, reactions, events, resets)
    metadata = {
        "kane": True, "coordinates": list(form.coordinate_names), "speeds": list(form.speed_names),
        "parameters": [s.name for s in form.parameters], "cyclic": [], "constraints": [], "holonomic": [],
        "separable": False, "holonomic_separable": False, "operations": operations, "taylor_program": None,
        "reaction_names": list(names),
        "residual_labels": [[f"configuration_{i}", "position"] for i in range(form.Phi.rows)]
        + [[f"velocity_{i}", "velocity"] for i in range(form.Psi.rows)],
        "energy": energy is not None,
    }
    return cache.store(key, source, name, metadata)


def _run_defaults(form, options, events=()) -> dict:
    def floats(values, size, what):
        if values is None:
            return None
        values = [float(v) for v in np.atleast_1d(np.asarray(values, dtype=float))]
        if len(values) != size:
            raise InitialConditionError(f"`{what}` needs {size} values, got {len(values)}.")
        return values

    defaults = {str(k): float(v) for k, v in (options.get("defaults") or {}).items()}
    return {
        "name": options.get("name", "kane_model"), "description": options.get("description", ""),
        "defaults": defaults, "q0": floats(options.get("q0"), form.n_q, "q0"),
        "qd0": floats(options.get("u0"), form.n_u, "u0"), "t_end": float(options.get("t_end", 10.0)),
        "events": [[e.name, e.direction, e.terminal, e.changes_state] for e in events],
    }


class KaneKernelMissing(ModelError, AttributeError):
    """A kernel of Lagrange's equations asked of a Kane model's module (an AttributeError too, so that
    ``getattr(kernels, name, default)`` keeps working)."""


class KaneKernels:
    """A Kane model's generated module, answering for the kernels of (q, q̇) it does not have.

    Code written for Lagrange models (the analysis functions: equilibria,
    linearization at rest, Lyapunov exponents, sections) reaches for kernels
    such as ``forcing`` or ``rest_partials``; they get a ModelError saying why
    instead of an AttributeError about a generated module's name.
    """

    def __init__(self, module, name: str):
        self._module, self._name = module, name

    def __getattr__(self, kernel: str):
        try:
            return getattr(self._module, kernel)
        except AttributeError:
            raise KaneKernelMissing(
                f"{self._name!r} is a Kane model (state (q, u)): its module has no `{kernel}`, a kernel of Lagrange's "
                f"equations in (q, q̇). Kane models simulate and sweep with {', '.join(KANE_METHODS)}; linearize them "
                "with lagcomp.analysis.linearize_steady (steady motions and equilibria, constraints included), or "
                "use `model.first_order_form` and `model.rhs`."
            ) from None


def _lagrange_only(what: str):
    """A method of `Model` that needs the state (q, q̇): on a Kane model it refuses with a ModelError."""
    def refuse(self, *args, **kwargs):
        raise ModelError(f"`{what}` needs the state (q, q̇) of Lagrange's equations; {self.name!r} is a Kane "
                         "model with state (q, u).")
    refuse.__name__ = what
    return refuse


class KaneModel(Model):
    """A compiled KanesMethod: state (q, u) (module docstring)."""

    first_order_form = None
    kanes_method = None

    def __init__(self, system, kernels, entry, from_cache: bool, recorded: dict | None = None):
        super().__init__(system, kernels, entry, from_cache, recorded)
        self.kernels = KaneKernels(kernels, self.name)
        self.speeds = tuple(entry.metadata["speeds"])
        self.reaction_names = tuple(entry.metadata["reaction_names"])
        self._residual_labels = tuple(tuple(pair) for pair in entry.metadata["residual_labels"])
        self.energy_available = bool(entry.metadata["energy"])
        self.u0 = self.qd0

    @property
    def state_size(self) -> int:
        return len(self.coordinates) + len(self.speeds)

    @property
    def state_names(self) -> tuple[str, ...]:
        """Labels of the state y = (q, u): the coordinates, then the speeds."""
        return self.coordinates + self.speeds

    @property
    def residual_labels(self) -> tuple[tuple[str, str], ...]:
        """(name, level) of Φ's rows ("position"), then Ψ's ("velocity")."""
        return self._residual_labels

    def __repr__(self) -> str:
        return (f"KaneModel({self.name!r}, n_q={self.n}, n_u={len(self.speeds)}, parameters={self.parameters}, "
                f"from {'cache' if self.from_cache else 'fresh build'}: {self.source_path})")

    def parameter_vector(self, params=None, baumgarte=(0.0, 0.0), inputs=None, span=None) -> np.ndarray:
        if tuple(baumgarte) != (0.0, 0.0):
            raise OptionError("`baumgarte` does not apply to a Kane model: its equations hold the velocity "
                              "constraints among their rows; use projection=True or a tighter tolerance.")
        return super().parameter_vector(params, inputs=inputs)  # (a Kane model has no inputs: refused if given)

    def initial_state(self, q0=None, u0=None) -> np.ndarray:
        """y = (q0, u0), defaults from `compile`'s q0/u0 (u0 = 0 when none), checked."""
        parts = []
        for what, given, default, names in (("q0", q0, self.q0, self.coordinates), ("u0", u0, self.u0, self.speeds)):
            values = given if given is not None else default
            if values is None:
                if what == "q0":
                    raise InitialConditionError(f"`q0` is required: {self.name!r} has no default initial coordinates.")
                values = [0.0] * len(names)
            values = np.atleast_1d(np.asarray(values, dtype=float))
            if values.shape != (len(names),) or not np.all(np.isfinite(values)):
                raise InitialConditionError(f"`{what}` must be {len(names)} finite number(s), one per "
                                            f"{'coordinate' if what == 'q0' else 'speed'} {list(names)}, "
                                            f"got {values.tolist()}.")
            parts.append(values)
        return np.concatenate(parts)

    def rhs(self, t: float, y, params=None) -> np.ndarray:
        """dy/dt = (q̇, u̇) at one state y = (q, u)."""
        y = self._vector(y, self.state_size, "y")
        out = np.empty(self.state_size)
        status = self.kernels.rhs(float(t), y, self.parameter_vector(params), out)
        if status:
            raise self._singular_mass_matrix(t, y, status)
        return out

    def constraint_residuals(self, t: float, y, params=None) -> dict[str, float]:
        """Φ and Ψ at one state y = (q, u), by name."""
        y = self._vector(y, self.state_size, "y")
        out = np.empty(len(self.residual_labels))
        self.kernels.constraint_residuals(float(t), y, self.parameter_vector(params), out)
        return dict(zip((name for name, _ in self.residual_labels), out.tolist()))

    def energy(self, q, u, t: float = 0.0, params=None) -> float:
        """T + V at (q, u); NaN when it could not be formed (`energy_available`)."""
        y = np.concatenate([self._vector(q, self.n, "q"), self._vector(u, len(self.speeds), "u")])
        return float(self.kernels.energy(float(t), y, self.parameter_vector(params)))

    mass_matrix = _lagrange_only("mass_matrix")
    forcing = _lagrange_only("forcing")
    momenta = _lagrange_only("momenta")
    energy_function = _lagrange_only("energy_function")
    hamiltonian = _lagrange_only("hamiltonian")
    canonical_jacobian = _lagrange_only("canonical_jacobian")

    def reactions(self, t: float, y, params=None) -> dict[str, float]:
        """The noncontributing forces of the auxiliary speeds at one state y = (q, u), by name."""
        if not self.reaction_names:
            return {}
        y = self._vector(y, self.state_size, "y")
        out = np.empty(len(self.reaction_names))
        status = self.kernels.reactions(float(t), y, self.parameter_vector(params), out)
        if status:
            raise self._singular_mass_matrix(t, y, status)
        return dict(zip(self.reaction_names, out.tolist()))

    def simulate(self, t_span, q0=None, u0=None, params=None, **options):
        """Integrate from (q0, u0); see the module docstring and `lagcomp.Model.simulate` for the options."""
        from lagcomp.integrate.simulate import simulate

        if options.pop("qd0", None) is not None:  # (None: what `lagcomp run` passes when --qd0 is not given)
            raise InitialConditionError(f"{self.name!r} is a Kane model: give its initial speeds as `u0` "
                                        f"(speeds {list(self.speeds)}; --u0 on the command line), not `qd0`.")
        solution = simulate(self, t_span, q0, u0, params, **options)
        return self._completed(solution)

    def _completed(self, solution):
        """The Solution with q̇ from the kinematic equations, u by name, the auxiliary reactions and, from a
        method that does not evaluate the constraints as it steps (radau), their residual over the saved rows."""
        n, p = self.n, np.array([solution.params[k] for k in self.parameters], dtype=float)
        ts, u = solution.t, solution.qd
        y = np.ascontiguousarray(np.hstack([solution.q, u]))
        qd = np.empty((ts.size, n))
        self.kernels.kinematics_along(ts, y, p, qd)
        reactions = {}
        if self.reaction_names:
            values = np.full((ts.size, len(self.reaction_names)), np.nan)
            self.kernels.reactions_along(ts, y, p, values)
            reactions = {name: values[:, j].copy() for j, name in enumerate(self.reaction_names)}
        residual = solution.constraint_residual
        if self.residual_labels and not METHODS[solution.method].checks_residual:
            rows = [self.kernels.constraint_residual(t, row, p) for t, row in zip(ts.tolist(), y, strict=True)]
            residual = float(np.max(rows, initial=residual))    # (NaN if a row's is)
        return dataclasses.replace(solution, qd=qd, u=u, speeds=self.speeds, reactions=reactions,
                                   constraint_residual=residual)

    def sweep(self, t_span, grid, q0=None, u0=None, **options):
        """Integrate every point of `grid` (see `lagcomp.Model.sweep`), the state being (q, u).

        Grid names are coordinates, speeds (initial u) and parameters; `q0`,
        `u0` and `params` give what is not swept.  Methods of `KANE_METHODS`,
        one trajectory per thread (no ``batched``); ``Sweep.final`` and
        ``dense`` hold (q, u), ``Sweep.speeds`` names the speeds.
        """
        from lagcomp.integrate.sweep import sweep

        if options.pop("qd0", None) is not None:  # (None: what `lagcomp sweep` passes when --qd0 is not given)
            raise InitialConditionError(f"{self.name!r} is a Kane model: give its initial speeds as `u0` "
                                        f"(speeds {list(self.speeds)}), not `qd0`.")
        return sweep(self, t_span, grid, q0=q0, qd0=u0, **options)
