"""Animations of a run from points the user names (matplotlib, the ``plots`` extra).

    anim = lc.animate(sol, {"bob1": (l1 * sin(th1), -l1 * cos(th1)), "bob2": (...)},
                      links=[("origin", "bob1"), ("bob1", "bob2")], trace=["bob2"])
    anim.save("run.gif", writer="pillow")      # or animate(..., save="run.gif")
    anim.to_jshtml()                            # an HTML player, in a notebook

Each point is a tuple of sympy expressions in the model's coordinates (functions
of t, as `lagcomp.coordinates` makes them), its parameters (by name, valued from
``sol.params``) and t.  The expressions are evaluated with numpy (`sympy.lambdify`:
this is drawing, not a kernel) at the frame times t₀ + k·speed/fps, k = 0, 1, ...
up to the last saved time, from the coordinates interpolated *linearly* in t
between the solution's saved rows: save densely enough (``t_eval`` or
``save_every``) that the straight segments do not show.  ``speed`` is simulated
seconds per wall-clock second, so a long run plays in a short clip.  Tuples of
two give a 2-D picture, of three a 3-D one; the axes have equal scales and
limits that hold the whole motion.  The name ``"origin"`` stands for the point
at 0 in `links` and `trace` unless `points` defines it.

Bodies' geometry kernels (positions and orientations of a system's bodies,
without naming points) are not here yet.
"""

from __future__ import annotations

import numbers
import os
from pathlib import Path

import numpy as np

from lagcomp.errors import ModelError, OptionError

ORIGIN = "origin"


def frame_times(t: np.ndarray, fps: float, speed: float) -> np.ndarray:
    """Times of the frames: t[0] + k·speed/fps for k = 0, 1, ... while ≤ t[-1], shape (frames,)."""
    for name, value in (("fps", fps), ("speed", speed)):
        if isinstance(value, bool) or not (isinstance(value, numbers.Real) and np.isfinite(value) and value > 0):
            raise OptionError(f"animate: {name} must be a positive number, got {value!r}.")
    if len(t) < 2 or not t[-1] > t[0]:
        raise OptionError(f"animate: the solution needs at least 2 saved rows spanning some time, got {len(t)} "
                          "(a run with record='summary' keeps only the first and last: record every row).")
    step = speed / fps
    count = int(np.floor((t[-1] - t[0]) / step * (1 + 1e-12))) + 1
    return np.minimum(t[0] + step * np.arange(count), t[-1])


def interpolated_coordinates(sol, times: np.ndarray) -> np.ndarray:
    """The coordinates q at `times`, linear in t between the solution's saved rows, shape (frames, n)."""
    return np.column_stack([np.interp(times, sol.t, sol.q[:, i]) for i in range(sol.q.shape[1])])


def _evaluator(name: str, point, sol):
    """A numpy function of (t, q columns) giving the point's coordinates, and its dimension (2 or 3)."""
    import sympy as sp
    from sympy.core.function import AppliedUndef

    from lagcomp.model import t as time

    if not isinstance(point, (tuple, list)) or len(point) not in (2, 3):
        raise OptionError(f"animate: point {name!r} must be a tuple (x, y) or (x, y, z) of expressions, got {point!r}.")
    exprs = [sp.sympify(part) for part in point]
    if any(expr.has(sp.Derivative) for expr in exprs):
        raise ModelError(f"animate: point {name!r} contains a derivative; points are positions, "
                         "functions of the coordinates, parameters and t only.")
    slots = {c: sp.Dummy(c) for c in sol.coordinates}
    replace, unknown = {}, set()
    for expr in exprs:
        for f in expr.atoms(AppliedUndef):
            if f.func.__name__ in slots and f.args == (time,):
                replace[f] = slots[f.func.__name__]
            else:
                unknown.add(str(f))
    values = {}
    for expr in exprs:
        for s in expr.free_symbols - {time} - set(slots.values()):
            if s.name in sol.params:
                values[s] = float(sol.params[s.name])
            else:
                unknown.add(s.name)
    if unknown:
        raise ModelError(f"animate: point {name!r} uses {sorted(unknown)}, neither coordinate (functions of t: "
                         f"{list(sol.coordinates)}), parameter ({list(sol.params)}) nor t.")
    exprs = [expr.xreplace(replace).xreplace(values) for expr in exprs]
    function = sp.lambdify([time, *slots.values()], exprs, modules="numpy")
    return function, len(exprs)


def point_positions(sol, points: dict, times: np.ndarray) -> dict[str, np.ndarray]:
    """Each point's position at `times`, shape (frames, d) with d = 2 or 3 for all points alike."""
    if not isinstance(points, dict) or not points:
        raise OptionError("animate: points must be a non-empty dict {name: (x, y) or (x, y, z)}.")
    q = interpolated_coordinates(sol, times)
    positions, dims = {}, set()
    for name, point in points.items():
        function, d = _evaluator(name, point, sol)
        parts = function(times, *q.T)
        positions[name] = np.column_stack([np.broadcast_to(np.asarray(p, dtype=float), times.shape) for p in parts])
        dims.add(d)
    if len(dims) > 1:
        raise OptionError("animate: every point must have the same number of coordinates (all 2-D or all 3-D), "
                          f"got {({name: len(p) for name, p in points.items()})}.")
    return positions


def _check_names(what: str, names, known) -> None:
    unknown = [n for n in names if n not in known]
    if unknown:
        raise OptionError(f"animate: {what} names {unknown}, not a point; the points are {sorted(known)}.")


def animate(sol, points: dict, *, links=(), trace=(), fps: float = 30, speed: float = 1.0,
            title: str | None = None, size: tuple[float, float] = (5.0, 5.0), dpi: float = 100,
            save: str | os.PathLike | None = None):
    """An animation of named points of a `Solution`; returns a `MechanismAnimation` (a FuncAnimation).

    Parameters
    ----------
    sol : Solution
        The run; its coordinate names and ``params`` value the expressions.
    points : dict of str to tuple
        ``{name: (x, y)}`` or ``{name: (x, y, z)}``: sympy expressions in the
        coordinates (functions of t), parameters and t (module docstring).
    links : iterable of (str, str)
        Pairs of point names drawn as segments (rods); ``"origin"`` is 0.
    trace : iterable of str
        Points whose paths are drawn as they move.
    fps : float
        Frames per second of the clip.
    speed : float
        Simulated seconds per wall-clock second (frames every speed/fps of t).
    title, size, dpi
        The axes' title (default: the method and the time), figure size in inches, resolution.
    save : path, optional
        Also write the clip, the writer chosen from the suffix: ``.gif``
        (pillow), ``.mp4`` (ffmpeg, when installed), ``.html`` (`to_jshtml`).
    """
    if save is not None:
        check_format(save)
    links = [tuple(link) for link in links]
    trace = list(trace)
    if any(len(link) != 2 for link in links):
        raise OptionError(f"animate: links must be pairs of point names, got {links}.")
    times = frame_times(np.asarray(sol.t, dtype=float), fps, speed)
    positions = point_positions(sol, points, times)
    d = next(iter(positions.values())).shape[1]
    known = set(positions) | {ORIGIN}
    _check_names("a link", [n for link in links for n in link], known)
    _check_names("trace", trace, known)
    if ORIGIN not in positions and (any(ORIGIN in link for link in links) or ORIGIN in trace):
        positions[ORIGIN] = np.zeros((len(times), d))
    try:
        from lagcomp.animation_artists import MechanismAnimation
    except ImportError as err:
        raise ImportError("lagcomp's animations need matplotlib: pip install 'lagcomp[plots]'.") from err
    anim = MechanismAnimation(times, positions, tuple(points), links=links, trace=trace, fps=fps, size=size, dpi=dpi,
                              title=title or f"{sol.method}")
    if save is not None:
        save_animation(anim, save)
    return anim


def _chain(coordinates: tuple[str, ...]) -> dict:
    """Bobs on rods hung from the origin in a plane: rod ``l<i>`` at angle ``theta<i>`` from the downward vertical."""
    import sympy as sp

    from lagcomp.model import coordinates as functions

    x = y = sp.S.Zero
    points = {}
    for name, angle in zip(coordinates, functions(" ".join(coordinates)), strict=True):
        length = sp.Symbol("l" + name.removeprefix("theta"))
        x, y = x + length * sp.sin(angle), y - length * sp.cos(angle)
        points[f"bob{name.removeprefix('theta')}"] = (x, y)
    names = ["origin", *points]
    return dict(points=points, links=list(zip(names[:-1], names[1:], strict=True)), trace=[names[-1]])


def _spherical(coordinates: tuple[str, ...]) -> dict:
    """The bob of a spherical pendulum in angles (θ from the downward vertical, azimuth φ) on a rod of length l."""
    import sympy as sp

    from lagcomp.model import coordinates as functions

    theta, phi = functions(" ".join(coordinates))
    l = sp.Symbol("l")  # noqa: E741  (the examples' name)
    bob = (l * sp.sin(theta) * sp.cos(phi), l * sp.sin(theta) * sp.sin(phi), -l * sp.cos(theta))
    return dict(points={"bob": bob}, links=[("origin", "bob")], trace=["bob"])


def _top_axis(coordinates: tuple[str, ...]) -> dict:
    """The centre of mass G = l K.z of a top in z–x–z Euler angles (ψ, θ, φ): its axis, precessing and nutating."""
    import sympy as sp

    from lagcomp.model import coordinates as functions

    psi, theta, _ = functions(" ".join(coordinates))
    l = sp.Symbol("l")  # noqa: E741  (the example's name)
    centre = (l * sp.sin(theta) * sp.sin(psi), -l * sp.sin(theta) * sp.cos(psi), l * sp.cos(theta))
    return dict(points={"G": centre}, links=[("origin", "G")], trace=["G"])


def _cartesian_bob(coordinates: tuple[str, ...]) -> dict:
    """A bob whose coordinates are its position (x, y[, z]), on a rod from the origin."""
    from lagcomp.model import coordinates as functions

    return dict(points={"bob": functions(" ".join(coordinates))}, links=[("origin", "bob")], trace=["bob"])


#: What ``lagcomp animate NAME`` draws for the bundled examples with an obvious picture: example name →
#: function of the model's coordinate names giving `animate`'s ``points``, ``links`` and ``trace``.
EXAMPLE_DRAWINGS = {
    "simple_pendulum": _chain,
    "double_pendulum": _chain,
    "n_link_pendulum": _chain,
    "spherical_pendulum": _spherical,
    "spherical_pendulum_cartesian": _cartesian_bob,
    "symmetric_top": _top_axis,
}


#: File suffixes `save_animation` writes.
FORMATS = (".gif", ".mp4", ".html")


def check_format(path: str | os.PathLike) -> Path:
    """`path` as a Path when its suffix is one of `FORMATS`; else an OptionError (before any work is done)."""
    path = Path(path)
    if path.suffix.lower() not in FORMATS:
        raise OptionError(f"animate: cannot tell the format of {str(path)!r}: give a .gif, .mp4 or .html file.")
    return path


def save_animation(anim, path: str | os.PathLike) -> Path:
    """Write `anim` to `path`, the writer chosen from the suffix (.gif pillow, .mp4 ffmpeg, .html player)."""
    from matplotlib import animation as mpl_animation

    path = check_format(path)
    suffix = path.suffix.lower()
    if suffix == ".gif":
        anim.save(path, writer=mpl_animation.PillowWriter(fps=anim.fps))
    elif suffix == ".mp4":
        if not mpl_animation.writers.is_available("ffmpeg"):
            raise OptionError(f"animate: saving {path.name} needs ffmpeg on the PATH; save a .gif or .html instead.")
        anim.save(path, writer=mpl_animation.FFMpegWriter(fps=anim.fps))
    else:
        path.write_text(anim.to_jshtml(fps=anim.fps), encoding="utf-8")
    return path
