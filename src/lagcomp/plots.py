"""Pictures of runs, sweeps and analyses (matplotlib, the ``plots`` extra: ``pip install 'lagcomp[plots]'``).

Every function builds a new `matplotlib.figure.Figure` — without pyplot, so
it works headless and keeps no global state — and returns it: show it in a
notebook by leaving it as a cell's value, or write it with
``fig.savefig("out.png")``.

=========================  ===================================================
`plot_coordinates`         q(t) (and optionally q̇(t)) of a Solution, its
                           resets, impacts and mode switches marked
`plot_energy_error`        |h(t) − h(0)| / |h(0)| of a Solution, log scale
`plot_run`                 the two above stacked (``lagcomp run --plot``)
`plot_phase_portrait`      a Portrait's level curves and separatrices, or a
                           Solution's (q, q̇) trajectory
`plot_poincare`            a Section's points, one colour per trajectory
`plot_sweep`               a Sweep quantity over its grid (map or line)
`plot_lyapunov`            running Lyapunov estimates vs t, log-log
`plot_stability`           eigenvalues of a StabilitySweep vs its parameter:
                           Re λ solid, Im λ dashed, stability changes marked
=========================  ===================================================
"""

from __future__ import annotations

import numpy as np

from lagcomp.errors import OptionError

__all__ = ["plot_coordinates", "plot_energy_error", "plot_run", "plot_phase_portrait", "plot_poincare", "plot_sweep",
           "plot_lyapunov", "plot_stability"]


def _figure(width: float = 7.0, height: float = 4.5):
    try:
        from matplotlib.figure import Figure
    except ImportError as err:
        raise ImportError("lagcomp's plots need matplotlib: pip install 'lagcomp[plots]'.") from err
    return Figure(figsize=(width, height), layout="constrained")


def _require(result, kind: str, function: str):
    """`result` itself when it is a `kind` ("Solution" or "Sweep"), else an OptionError saying what to pass."""
    from lagcomp.integrate.solution import Solution
    from lagcomp.integrate.sweep import Sweep

    wanted = {"Solution": Solution, "Sweep": Sweep}[kind]
    if not isinstance(result, wanted):
        instead = {"Sweep": "plot_sweep(sweep, quantity)", "Solution": "plot_run(sol) or plot_coordinates(sol)"}
        given = type(result).__name__
        hint = f"; for a {given} use {instead[given]}" if given in instead else ""
        raise OptionError(f"{function} draws a {kind} ({'model.simulate' if kind == 'Solution' else 'model.sweep'}'s "
                          f"result), got {given}{hint}.")
    return result


def _sweep_values(sweep, quantity) -> tuple[np.ndarray, str]:
    """(values shaped like the grid, label) of `quantity`: a per-trajectory field of the Sweep named, or an array."""
    import dataclasses

    shape = tuple(sweep.shape)
    if not isinstance(quantity, str):
        values = np.asarray(quantity, dtype=float)
        if values.shape != shape:
            raise OptionError(f"`quantity` must have the grid's shape {shape}, got {values.shape}.")
        return values, "value"
    fields = [f.name for f in dataclasses.fields(sweep)
              if isinstance(getattr(sweep, f.name), np.ndarray) and getattr(sweep, f.name).shape == shape]
    if quantity not in fields:
        import difflib

        names = [f.name for f in dataclasses.fields(sweep)]
        near = difflib.get_close_matches(quantity, names, 1, 0.5)
        why = ("this sweep did not keep it (`output` of model.sweep)" if getattr(sweep, quantity, 0) is None else
               f"did you mean {near[0]!r}? (kept only when `output` of model.sweep asks for it)" if near and
               getattr(sweep, near[0]) is None else f"did you mean {near[0]!r}?" if near else "no such field")
        raise OptionError(f"`quantity` {quantity!r} is no per-trajectory quantity of this sweep ({why}): it has "
                          f"{fields} (or pass an array of the grid's shape {shape}, e.g. sweep.final[..., 0]).")
    return np.asarray(getattr(sweep, quantity), dtype=float), quantity


def _label(name: str) -> str:
    """A coordinate or velocity name as axis text: ``theta_dot`` → ``dθ/dt``-like ``theta'``."""
    return f"{name[:-4]}'" if name.endswith("_dot") else name


def _jumping_events(sol) -> dict:
    """The times (k,) of each event of `sol` that changed the motion: a reset that moved the state, a contact's
    impacts and lift-offs, a friction element's switches between stick and slip."""
    frictions = {switch.friction for switch in getattr(sol, "friction_switches", ())}
    return {name: record.t for name, record in getattr(sol, "events", {}).items()
            if len(record) and (record.impulses is not None or record.jumps or name in frictions)}


def _mark_events(axes, sol) -> None:
    """Thin vertical lines at the times of the resets, impacts and mode switches of `sol` on each of `axes`, one
    colour per event after the coordinates' colours; the first axes' legend names them (one entry per event)."""
    for j, (name, times) in enumerate(_jumping_events(sol).items()):
        colour = f"C{(len(sol.coordinates) + j) % 10}"
        for a, ax in enumerate(axes):
            ax.vlines(times, 0.0, 1.0, transform=ax.get_xaxis_transform(), colors=colour, linestyles=":",
                      linewidths=0.8, alpha=0.7, zorder=0, label=f"{name} ({len(times)})" if a == 0 else None)


def plot_coordinates(sol, *, velocities: bool = False, events: bool = True, title: str | None = None):
    """Each coordinate q_i(t) of a `Solution` (and q̇_i(t) in a second panel with ``velocities=True``).

    With `events`, the times of the events that changed the motion (resets, a contact's impacts and lift-offs,
    friction's switches) are dotted vertical lines, named in the legend with their count.
    """
    _require(sol, "Solution", "plot_coordinates")
    fig = _figure(7.0, 6.0 if velocities else 4.0)
    axes = fig.subplots(2 if velocities else 1, 1, sharex=True, squeeze=False)[:, 0]
    for i, name in enumerate(sol.coordinates):
        axes[0].plot(sol.t, sol.q[:, i], lw=1.0, label=name)
        if velocities:
            axes[1].plot(sol.t, sol.qd[:, i], lw=1.0, label=_label(f"{name}_dot"))
    if events:
        _mark_events(axes, sol)
    axes[0].set_ylabel("coordinates")
    if velocities:
        axes[1].set_ylabel("velocities")
    for ax in axes:
        ax.legend(loc="upper right", fontsize="small")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("t")
    axes[0].set_title(title or f"{sol.method}: coordinates vs time")
    return fig


def _energy_error_axes(ax, sol, which: str) -> None:
    if which == "balance":
        balance = sol.energy_balance()
        error = np.abs(balance.residual) / balance.scale
        label = "|h(t) − h(0) − ∫P dt| / scale"
    else:
        values = getattr(sol, which)
        scale = abs(values[0]) if values[0] != 0 else 1.0
        error = np.abs(values - values[0]) / scale
        symbol = "h" if which == "energy_function" else "E"
        label = f"|{symbol}(t) − {symbol}(0)| / |{symbol}(0)|"
    positive = error > 0
    floor = float(np.min(error[positive])) / 10 if positive.any() else 1e-17
    ax.semilogy(sol.t, np.maximum(error, floor), lw=0.8)
    ax.set_ylabel(label)
    ax.set_xlabel("t")
    ax.grid(alpha=0.3, which="both")


def plot_energy_error(sol, *, which: str = "energy_function", title: str | None = None):
    """Relative error of the energy function (or ``which="energy"``: T + V; ``which="balance"``: the residual of
    `Solution.energy_balance`, the error of a driven or dissipative run) along a `Solution`, log scale.

    Exact zeros (the initial point) are drawn at a tenth of the smallest
    non-zero error, so the log scale keeps them in view.
    """
    _require(sol, "Solution", "plot_energy_error")
    fig = _figure(7.0, 4.0)
    ax = fig.add_subplot()
    _energy_error_axes(ax, sol, which)
    ax.set_title(title or f"{sol.method}: energy error")
    return fig


def plot_run(sol, *, events: bool = True, title: str | None = None):
    """Coordinates vs time above the energy error: the figure of ``lagcomp run --plot``; with `events`, the
    resets, impacts and mode switches marked on both (as `plot_coordinates` marks them).  Where h is no first
    integral (it drifts by more than `lagcomp.integrate.energy_balance.BALANCE_ABOVE`: forces, dissipation,
    imposed motions) the error drawn is the energy balance's residual."""
    _require(sol, "Solution", "plot_run")
    fig = _figure(7.0, 6.5)
    top, bottom = fig.subplots(2, 1, sharex=True)
    for i, name in enumerate(sol.coordinates):
        top.plot(sol.t, sol.q[:, i], lw=1.0, label=name)
    if events:
        _mark_events((top, bottom), sol)
    top.set_ylabel("coordinates")
    top.legend(loc="upper right", fontsize="small")
    top.grid(alpha=0.3)
    from lagcomp.integrate.energy_balance import balance_or_none

    _energy_error_axes(bottom, sol, "energy_function" if balance_or_none(sol) is None else "balance")
    top.set_title(title or f"{sol.method}, {len(sol.t)} points")
    return fig


def plot_phase_portrait(portrait, *, title: str | None = None):
    """Level curves ±q̇(q, E) of a `Portrait` (separatrices dashed), or the (q, q̇) path of a 1-DoF `Solution`."""
    fig = _figure(7.0, 5.0)
    ax = fig.add_subplot()
    if hasattr(portrait, "energies"):
        import matplotlib as mpl

        colours = mpl.colormaps["viridis"](np.linspace(0.0, 0.9, max(len(portrait.energies), 1)))
        for j, (E, regime, colour) in enumerate(zip(portrait.energies, portrait.regimes, colours)):
            q, qd = portrait.curve(j)
            ax.plot(q, qd, color=colour, lw=1.2, label=f"E = {E:.4g} ({regime})")
            ax.plot(q, -qd, color=colour, lw=1.2)
        for j, E in enumerate(portrait.separatrices):
            q, qd = portrait.curve(j, separatrix=True)
            ax.plot(q, qd, "r--", lw=1.0, label=f"separatrix E = {E:.4g}")
            ax.plot(q, -qd, "r--", lw=1.0)
        a, b = portrait.q[0], portrait.q[-1]
        shifts = (-(b - a), 0.0, b - a) if portrait.periodic else (0.0,)
        for e, stable in zip(portrait.equilibria, portrait.stable):
            for q in (e.q[0] + s for s in shifts if a - 1e-9 <= e.q[0] + s <= b + 1e-9):
                ax.plot(q, 0.0, "o", color="k" if stable else "r", mfc="k" if stable else "w", ms=6)
        name = portrait.coordinate
        ax.legend(loc="upper right", fontsize="x-small")
    else:
        if portrait.q.shape[1] != 1:
            raise OptionError("A phase portrait from a Solution needs one coordinate; pass a Portrait instead.")
        name = portrait.coordinates[0]
        ax.plot(portrait.q[:, 0], portrait.qd[:, 0], lw=0.8)
    ax.set_xlabel(name)
    ax.set_ylabel(_label(f"{name}_dot"))
    ax.grid(alpha=0.3)
    ax.set_title(title or "phase portrait")
    return fig


def plot_poincare(section, x: str, y: str, *, title: str | None = None, size: float = 1.0):
    """The crossings of a `Section` projected on the state components `x`, `y`: one colour per trajectory."""
    import matplotlib as mpl

    fig = _figure(6.5, 6.0)
    ax = fig.add_subplot()
    points = section.points(x, y)
    colours = mpl.colormaps["turbo"](np.linspace(0.05, 0.95, max(len(points), 1)))
    for pts, colour in zip(points, colours):
        ax.scatter(pts[:, 0], pts[:, 1], s=size, color=colour, linewidths=0)
    ax.set_xlabel(_label(x))
    ax.set_ylabel(_label(y))
    ax.set_title(title or f"Poincaré section `{section.event}`: {len(points)} trajectories")
    ax.grid(alpha=0.3)
    return fig


def plot_sweep(sweep, quantity="energy_error", *, label: str | None = None, log: bool | None = None,
               cmap: str = "viridis", symmetric: bool = False, title: str | None = None):
    """A per-trajectory quantity of a `Sweep` over its grid: a map for two swept names, a line for one.

    `quantity` is an attribute name of the Sweep (``"energy_error"``,
    ``"t_final"``, ``"nsteps"``, ...) or an array shaped like the grid (e.g.
    a final coordinate, ``sweep.final[..., 0]``).  ``log`` (default: for
    positive data spanning over two decades) uses a logarithmic colour scale;
    ``symmetric`` centres a linear one on zero (with a diverging `cmap`).
    """
    from matplotlib.colors import LogNorm, Normalize

    values, name = _sweep_values(_require(sweep, "Sweep", "plot_sweep"), quantity)
    if name == "energy_error" and getattr(sweep, "energy_balance", False):
        name = "energy balance residual"        # (h − h(0) − ∫P dt, relative: a system that is not conservative)
    label = label or name
    finite = values[np.isfinite(values)]
    if log is None:
        log = finite.size > 0 and finite.min() > 0 and finite.max() > 100 * finite.min()
    fig = _figure(7.0, 5.0)
    ax = fig.add_subplot()
    if sweep.combine == "product" and len(sweep.names) == 2:
        xs, ys = (sweep.axes[name] for name in sweep.names)
        norm = None
        if log and finite.size:
            norm = LogNorm(vmin=finite.min(), vmax=finite.max())
        elif symmetric and finite.size:
            norm = Normalize(vmin=-np.abs(finite).max(), vmax=np.abs(finite).max())
        mesh = ax.pcolormesh(xs, ys, values.T, shading="nearest", norm=norm, cmap=cmap)
        fig.colorbar(mesh, ax=ax, label=label)
        ax.set_xlabel(_label(sweep.names[0]))
        ax.set_ylabel(_label(sweep.names[1]))
    elif len(sweep.names) >= 1 and values.ndim == 1:
        xs = sweep.axes[sweep.names[0]]
        order = np.argsort(xs)
        ax.plot(xs[order], values[order], ".-", lw=0.8)
        if log:
            ax.set_yscale("log")
        ax.set_xlabel(_label(sweep.names[0]))
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    else:
        raise OptionError(f"plot_sweep draws grids of one or two swept names; this one has {list(sweep.names)}.")
    ax.set_title(title or f"sweep ({sweep.method}): {label}")
    return fig


def plot_lyapunov(*results, labels=None, reference: bool = True, title: str | None = None):
    """Running Lyapunov estimates vs t (log-log) of one or more `Lyapunov` results.

    Negative or zero estimates are left out of the log scale.  With
    ``reference``, the curve log(t)/t (the decay of a regular orbit's
    estimate) is drawn dotted for comparison.
    """
    fig = _figure(7.0, 4.5)
    ax = fig.add_subplot()
    labels = labels or [f"{r.method}" for r in results]
    t_max = 0.0
    for r, (result, label) in enumerate(zip(results, labels)):
        style = ("-", "--", "-.", (0, (5, 1, 1, 1)))[r % 4]  # curves that coincide stay visible
        for j in range(result.history.shape[1]):
            values = result.history[:, j]
            keep = values > 0
            ax.loglog(result.t[keep], values[keep], lw=1.4, ls=style,
                      label=label if result.history.shape[1] == 1 else f"{label} λ{j + 1}")
        t_max = max(t_max, float(result.t[-1]) if len(result.t) else 0.0)
    if reference and t_max > 0:
        t = np.geomspace(max(t_max / 1e3, 3.0), t_max, 100)
        ax.loglog(t, np.log(t) / t, "k:", lw=1.0, label="log(t)/t")
    ax.set_xlabel("t")
    ax.set_ylabel("running estimate of λ")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize="small")
    ax.set_title(title or "Lyapunov exponent estimates")
    return fig


def plot_stability(sweep, *, title: str | None = None):
    """Eigenvalues of a `StabilitySweep` against its parameter, drawn as the bicycle literature draws them.

    Each followed eigenvalue keeps one colour: its real part solid, its
    imaginary part dashed where it is not zero (|Im λ|: a conjugate pair
    shares one dashed curve).  Stability changes are dotted vertical lines,
    and the ranges where no Re λ > 0 are shaded.
    """
    fig = _figure(7.0, 4.5)
    ax = fig.add_subplot()
    x, values = sweep.values, sweep.eigenvalues
    scale = max(float(np.max(np.abs(values), initial=0.0)), 1e-300)
    for j in range(values.shape[1]):
        colour = f"C{j % 10}"
        ax.plot(x, values[:, j].real, "-", color=colour, lw=1.4)
        imag = np.abs(values[:, j].imag)
        ax.plot(x, np.where(imag > 1e-9 * scale, imag, np.nan), "--", color=colour, lw=1.0)
    ax.axhline(0.0, color="k", lw=0.6)
    edges = [x[0], *(c.value for c in sweep.changes), x[-1]]
    for left, right in zip(edges[:-1], edges[1:]):
        middle = np.searchsorted(x, 0.5 * (left + right))
        if not sweep.unstable[min(middle, len(x) - 1)]:
            ax.axvspan(left, right, color="0.9", zorder=0)
    for change in sweep.changes:
        ax.axvline(change.value, color="k", ls=":", lw=1.0)
        ax.annotate(f"{change.value:.4g}", (change.value, 1.0), xycoords=("data", "axes fraction"),
                    ha="left", va="top", fontsize="small")
    ax.plot([], [], "k-", label="Re λ")
    ax.plot([], [], "k--", label="|Im λ|")
    ax.legend(fontsize="small", loc="lower left")
    ax.set_xlabel(_label(sweep.parameter))
    ax.set_ylabel("eigenvalues λ")
    ax.grid(alpha=0.3)
    ax.set_title(title or f"eigenvalues vs {sweep.parameter} (shaded: stable)")
    return fig
