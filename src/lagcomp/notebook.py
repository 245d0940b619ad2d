"""Results where notebook users expect them: a Solution as an ``xarray.Dataset``, Models and Solutions as HTML.

`solution_dataset` backs `Solution.to_xarray`; `model_html` and `solution_html` back the ``_repr_html_``
methods Jupyter calls to show a `Model` or a `Solution` as the value of a cell.  The HTML is a compact
table built from strings only: every name, description and message (user text) goes through
`html.escape`, so a description holding ``<b>`` or ``&`` is shown, not interpreted.  Nothing here
needs a dependency beyond numpy; xarray is imported when `solution_dataset` runs.
"""

from __future__ import annotations

import html
import math

import numpy as np

#: Attribute prefix of the parameter values in `solution_dataset` (``param_g``).
PARAM_PREFIX = "param_"


def solution_dataset(solution):
    """`solution` as an ``xarray.Dataset`` along the dimension ``t`` (see `Solution.to_xarray`)."""
    try:
        import xarray as xr
    except ImportError as err:
        raise ImportError("Solution.to_xarray needs xarray: pip install 'lagcomp[xarray]'.") from err
    velocities = [f"{c}_dot" for c in solution.coordinates]
    data = {}
    _add(data, zip(solution.coordinates, solution.q.T, strict=True), "coordinate")
    _add(data, zip(velocities, solution.qd.T, strict=True), "velocity")
    if solution.u is not None:
        _add(data, zip(solution.speeds, solution.u.T, strict=True), "speed")
    energy, energy_function = solution.energy, solution.energy_function
    _add(data, [("energy", energy)], "T + V")
    if not np.array_equal(energy, energy_function, equal_nan=True):
        _add(data, [("energy_function", energy_function)], "energy function h (Jacobi integral)")
    _add(data, ((f"reaction_{name}", values) for name, values in solution.reactions.items()), "reaction")
    state = list(solution.coordinates) + (list(solution.speeds) if solution.u is not None else velocities)
    coords = {"t": ("t", solution.t)}
    for name, record in solution.events.items():
        dim = f"event_{name}"
        _add(data, [(f"{dim}_t", record.t)], f"times of event {name!r}", dim=dim)
        _add(data, [(f"{dim}_state", np.hstack([record.q, record.qd]))], f"state at event {name!r}",
             dim=(dim, "state"))
        if record.q_after is not None:
            _add(data, [(f"{dim}_state_after", np.hstack([record.q_after, record.qd_after]))],
                 f"state just after event {name!r}", dim=(dim, "state"))
    if solution.sensitivities is not None:
        _add(data, [("sensitivities", solution.sensitivities)], "sensitivity ∂y(t)/∂w", dim=("t", "state", "wrt"))
        coords["wrt"] = ("wrt", list(solution.sensitivity_names))
    if solution.reaction_sensitivities is not None:
        _add(data, [("reaction_sensitivities", solution.reaction_sensitivities)], "sensitivity dλ(t)/dw",
             dim=("t", "constraint", "wrt"))
        coords["constraint"] = ("constraint", list(solution.reaction_names))
    if solution.events or solution.sensitivities is not None:
        coords["state"] = ("state", state)
    taken = set(coords) | {d for dims, _, _ in data.values() for d in ((dims,) if isinstance(dims, str) else dims)}
    clashes = sorted(name for name in data if name in taken)
    if clashes:
        raise ValueError(f"Solution.to_xarray: the names {clashes} are both a variable and a dimension of the "
                         f"Dataset (a coordinate named like one of t, state, event_<name>, energy, ...); "
                         f"use Solution.to_dict() instead.")
    return xr.Dataset(data, coords=coords, attrs=_attributes(solution))


def _add(data: dict, named_values, role: str, dim="t") -> None:
    """Put each (name, values) in `data` as a variable along `dim`, refusing a name given twice."""
    for name, values in named_values:
        if name in data:
            raise ValueError(f"Solution.to_xarray: two variables would be named {name!r} (a {role} and a "
                             f"{data[name][2]['role']}); use Solution.to_dict() instead.")
        data[name] = (dim, values, {"role": role})


def _attributes(solution) -> dict:
    """The Dataset's attrs: what ran, how it ended, its counters and parameter values (netCDF-ready types)."""
    attrs = {
        "model": solution.model_name, "method": solution.method, "status": int(solution.status),
        "message": solution.message, "nfev": int(solution.nfev), "nsteps": int(solution.nsteps),
        "nrejected": int(solution.nrejected), "njev": int(solution.njev), "nlu": int(solution.nlu),
        "constraint_residual": float(solution.constraint_residual),
        "record": "summary" if _rows_dropped(solution) else "trajectory",
    }
    if solution.t_failure is not None:
        attrs["t_failure"] = float(solution.t_failure)
    if _rows_dropped(solution):
        summary = solution.summary
        attrs.update(summary_rows=int(summary.rows), summary_energy_error=float(summary.energy_error),
                     summary_energy_function_error=float(summary.energy_function_error))
    attrs.update({f"{PARAM_PREFIX}{name}": float(value) for name, value in solution.params.items()})
    return attrs


def _rows_dropped(solution) -> bool:
    """Whether the run kept only its first and last rows (``record="summary"``, more rows than it kept)."""
    return solution.summary.rows > len(solution.t)


# -- HTML --------------------------------------------------------------------------------------------------

def _text(value) -> str:
    return html.escape(str(value))


def _number(value) -> str:
    return "n/a" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:.6g}"


def _names(names) -> str:
    return ", ".join(f"<code>{_text(n)}</code>" for n in names) or "none"


def _table(title: str, rows) -> str:
    """A two-column table: `title` (HTML) as caption, then one (label, HTML value) pair per row."""
    body = "".join(f"<tr><th style='text-align:left'>{_text(label)}</th><td style='text-align:left'>{value}</td></tr>"
                   for label, value in rows)
    return f"<table><caption style='text-align:left'>{title}</caption>{body}</table>"


def model_html(model) -> str:
    """A Model (or KaneModel) as an HTML table: what it is, its inputs, constraints, events and methods, and where
    its equations are (`Model.equations`, which Jupyter renders as LaTeX: not repeated here)."""
    from lagcomp.benchmark import applicable_methods

    kane = hasattr(model, "speeds")
    parameters = ", ".join(
        f"<code>{_text(p)}</code> = {_number(model.defaults[p])}" if p in model.defaults else f"<code>{_text(p)}</code>"
        for p in model.parameters) or "none"
    if kane:
        constraints = ", ".join(f"<code>{_text(name)}</code> ({_text(level)})"
                                for name, level in model.residual_labels) or "none"
    else:
        constraints = ", ".join(f"<code>{_text(name)}</code> ({'holonomic' if holonomic else 'nonholonomic'})"
                                for name, holonomic in zip(model.constraints, model.holonomic, strict=True)) or "none"
    events = ", ".join(f"<code>{_text(e.name)}</code> (direction {e.direction:+d}{', terminal' if e.terminal else ''})"
                       for e in model.events) or "none"
    rows = [("description", _text(model.description or "")), ("coordinates", _names(model.coordinates))]
    if kane:
        rows += [("speeds", _names(model.speeds))]
        if model.reaction_names:
            rows += [("reactions", _names(model.reaction_names))]
    rows += [("parameters (defaults)", parameters)]
    if getattr(model, "inputs", ()):  # signals supplied at run time (lagcomp.Input), with the derivative read
        rows += [("inputs", ", ".join(f"<code>{_text(name)}</code> (up to d{order}/dt{order})" if order > 0
                                      else f"<code>{_text(name)}</code>"
                                      for name, order in zip(model.inputs, model.input_orders, strict=True)))]
    rows += [("constraints", constraints), ("events", events),
             ("methods", _names(m.name for m in applicable_methods(model))),
             ("equations", "<code>model.equations()</code> (LaTeX, rendered as math in a cell)"),
             ("kernels", f"<code>{_text(model.source_path)}</code> "
                         f"({'from the cache' if model.from_cache else 'fresh build'})")]
    title = f"<strong>{type(model).__name__}</strong> <code>{_text(model.name)}</code>"
    return _table(title, rows)


def solution_html(solution) -> str:
    """A Solution as an HTML table: how the run ended, its counters, drifts and first and last states.

    The drifts come from `Solution.summary`: for a kept trajectory, reading it evaluates the energies on first
    read (numba compiles the ``observables`` kernel then, 0.4 s for a double pendulum), once.
    """
    t = solution.t
    counters = ", ".join(f"{name} {getattr(solution, name)}" for name in ("nsteps", "nfev", "nrejected", "njev", "nlu"))
    rows = [("method", f"<code>{_text(solution.method)}</code>"),
            ("status", f"{solution.status}: {_text(solution.message)}"),
            ("t", f"[{_number(float(t[0]))}, {_number(float(t[-1]))}], {len(t)} points"
                  + (f" kept of {solution.summary.rows} (record='summary')" if _rows_dropped(solution) else "")),
            ("counters", counters),
            ("energy drift", f"{_number(solution.summary.energy_error)} (T + V), "
                             f"{_number(solution.summary.energy_function_error)} (h); max |E − E₀| / |E₀|")]
    if solution.reactions or solution.constraint_residual:
        rows += [("constraint residual", _number(solution.constraint_residual)),
                 ("reactions", _names(solution.reactions))]
    names = list(solution.coordinates) + (list(solution.speeds) if solution.u is not None
                                          else [f"{c}_dot" for c in solution.coordinates])
    first, last = solution.y[0], solution.y[-1]
    state = "".join(f"<tr><td><code>{_text(n)}</code></td><td>{_number(float(a))}</td><td>{_number(float(b))}</td></tr>"
                    for n, a, b in zip(names, first, last, strict=True))
    rows += [("state", f"<table><tr><th></th><th>first</th><th>last</th></tr>{state}</table>")]
    model = f" <code>{_text(solution.model_name)}</code>" if solution.model_name else ""
    return _table(f"<strong>Solution</strong>{model}", rows)
