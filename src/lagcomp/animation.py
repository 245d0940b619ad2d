"""Animations of a run: the model's bodies, and points the user names (matplotlib, the ``plots`` extra).

    anim = lc.animate(sol)                      # a system built from lc.Particle / lc.RigidBody
    anim = lc.animate(sol, {"bob1": (l1 * sin(th1), -l1 * cos(th1)), "bob2": (...)},
                      links=[("origin", "bob1"), ("bob1", "bob2")], trace=["bob2"])
    anim.save("run.gif", writer="pillow")      # or animate(..., save="run.gif")
    anim.to_jshtml()                            # an HTML player, in a notebook

Bodies.  A system built from bodies draws itself: its module's ``geometry`` kernel
(`lagcomp.codegen.geometry`) gives each body's position and, for a rigid body, its
orientation, in the axes of the frame the system is described in.  A particle is a
marker; a rigid body a marker at its centre of mass with its axes x, y, z drawn from
it (red, green, blue; ``axes_length``, by default half the motion's extent).  The
picture is 2-D when every body stays in the plane z = 0 and turns only about z
(exactly, at every frame), else 3-D.

Points.  Each point is a tuple of sympy expressions in the model's coordinates (functions
of t, as `lagcomp.coordinates` makes them), its parameters (by name, valued from
``sol.params``) and t, evaluated with numpy (`sympy.lambdify`: this is drawing, not a
kernel).  Tuples of two give a 2-D picture, of three a 3-D one.  A system whose T is
written directly has no bodies: name its points.  Points and bodies may be combined;
`links` and `trace` take the names of both.

Both are evaluated at the frame times t₀ + k·speed/fps, k = 0, 1, ... up to the last
saved time, from the coordinates interpolated *linearly* in t between the solution's
saved rows: save densely enough (``t_eval`` or ``save_every``) that the straight segments
do not show.  ``speed`` is simulated seconds per wall-clock second, so a long run plays
in a short clip.  The axes have equal scales and limits that hold the whole motion.  The
name ``"origin"`` stands for the point at 0 in `links` and `trace` unless a point or
body has that name.
"""

from __future__ import annotations

import numbers
import os
from pathlib import Path

import numpy as np

from lagcomp.animation_bodies import ORIGIN, BodyFrames
from lagcomp.errors import ModelError, OptionError


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


def _check_names(what: str, names, known, unplaced=()) -> None:
    unknown = [n for n in names if n not in known]
    if unknown:
        why = f" ({sorted(set(unknown) & set(unplaced))}: the model does not know where, see " \
            "lagcomp.codegen.geometry)" if set(unknown) & set(unplaced) else ""
        raise OptionError(f"animate: {what} names {unknown}, not a point or a body{why}; the points and bodies are "
                          f"{sorted(known)}.")


def body_frames(sol, times: np.ndarray, needed: bool = True) -> BodyFrames:
    """The bodies of `sol`'s model at `times` (`lagcomp.animation_bodies`), from the interpolated coordinates.

    A Solution without its model's geometry kernel has none to draw: an OptionError when they are `needed`
    (no points named).
    """
    geometry = sol.geometry
    if geometry is None or (geometry.layout and geometry.kernel is None):
        if not needed:
            return BodyFrames({}, {}, ())
        raise OptionError("animate: this Solution carries no model geometry (built by hand, or unpickled): name the "
                          "points to draw, points={'bob': (x, y)}, or animate the run where `simulate` returned it.")
    if not geometry.layout:
        return BodyFrames({}, {}, ())
    return geometry.frames(times, interpolated_coordinates(sol, times))


def default_axes_length(positions: dict[str, np.ndarray]) -> float:
    """Half the largest extent of the drawn positions together with the origin; 1 when nothing moves from 0."""
    every = np.concatenate([*positions.values(), np.zeros((1, next(iter(positions.values())).shape[1]))])
    extent = float(np.max(every.max(axis=0) - every.min(axis=0)))
    return 0.5 * extent if extent > 0 else 1.0


def _dimension(points: dict, bodies: BodyFrames) -> int:
    """2 or 3: the points' own, or for bodies alone 2 when they stay in the plane z = 0 (`BodyFrames.planar`)."""
    planar = bodies.planar()
    if not points:
        return 2 if planar else 3
    d = next(iter(points.values())).shape[1]
    if d == 2 and not planar:
        raise OptionError(f"animate: the points are 2-D but the bodies {sorted(bodies.centres)} leave the plane z = 0 "
                          "or turn out of it: give the points as (x, y, z), or bodies=False.")
    return d


def animate(sol, points: dict | None = None, *, links=(), trace=(), bodies: bool = True,
            axes_length: float | None = None, fps: float = 30, speed: float = 1.0,
            title: str | None = None, size: tuple[float, float] = (5.0, 5.0), dpi: float = 100,
            save: str | os.PathLike | None = None, progress: bool | None = None):
    """An animation of a `Solution`'s bodies and named points; returns a `MechanismAnimation` (a FuncAnimation).

    Parameters
    ----------
    sol : Solution
        The run; its coordinate names and ``params`` value the expressions.
    points : dict of str to tuple, optional
        ``{name: (x, y)}`` or ``{name: (x, y, z)}``: sympy expressions in the
        coordinates (functions of t), parameters and t (module docstring).
        Needed for a system whose T is written directly, which has no bodies.
    links : iterable of (str, str)
        Pairs of point or body names drawn as segments (rods); ``"origin"`` is 0.
    trace : iterable of str
        Points and bodies whose paths are drawn as they move (a body's centre).
    bodies : bool
        Draw the model's bodies (`lagcomp.Particle`, `lagcomp.RigidBody`): a marker at
        each centre, and a rigid body's axes x, y, z (red, green, blue) from it.  A
        kinematic tree's links (`lagcomp.Tree`) are drawn at their frames' origins, with
        their axes, and a rod from each link's origin to its children's (from ``"origin"``
        for a link on the base).
    axes_length : float, optional
        Length of the drawn body axes, in the model's units of length; by default half
        the largest extent of the motion (`default_axes_length`).
    fps : float
        Frames per second of the clip.
    speed : float
        Simulated seconds per wall-clock second (frames every speed/fps of t).
    title, size, dpi
        The axes' title (default: the method and the time), figure size in inches, resolution.
    save : path, optional
        Also write the clip, the writer chosen from the suffix: ``.gif``
        (pillow), ``.mp4`` (ffmpeg, when installed), ``.html`` (`to_jshtml`).
    progress : bool, optional
        While `save` renders: a progress bar (tqdm) over the frames; None (default) shows one
        only when the rendering lasts more than two seconds, True always, False never.

    Notes
    -----
    The returned animation is a matplotlib ``FuncAnimation`` whose figure is laid out once and
    whose frames are blitted (`lagcomp.animation_artists`).  In a notebook it displays as an
    HTML player (``anim.to_jshtml()``, also its ``_repr_html_``): play, pause, step, a slider.
    """
    if save is not None:
        check_format(save)
    links = [tuple(link) for link in links]
    trace = list(trace)
    if any(len(link) != 2 for link in links):
        raise OptionError(f"animate: links must be pairs of point or body names, got {links}.")
    if axes_length is not None and (isinstance(axes_length, bool) or not isinstance(axes_length, numbers.Real)
                                    or not (np.isfinite(axes_length) and axes_length > 0)):
        raise OptionError(f"animate: axes_length must be a positive number, got {axes_length!r}.")
    times = frame_times(np.asarray(sol.t, dtype=float), fps, speed)
    named = point_positions(sol, points, times) if points is not None else {}
    drawn = body_frames(sol, times, needed=points is None) if bodies else BodyFrames({}, {}, ())
    if not named and not drawn.centres:
        raise OptionError(f"animate: {sol.model_name or 'this model'!r} has no bodies to draw (its T is written "
                          "directly, or bodies=False): name the points, points={'bob': (x, y)}.")
    links += [rod for rod in drawn.skeleton if rod not in links]   # (a tree's links, parent to child)
    clash = sorted(set(named) & set(drawn.centres))
    if clash:
        raise OptionError(f"animate: {clash} name both a point and a body: rename the point.")
    d = _dimension(named, drawn)
    positions = {**{name: centre[:, :d] for name, centre in drawn.centres.items()}, **named}
    known = set(positions) | {ORIGIN}
    _check_names("a link", [n for link in links for n in link], known, drawn.unplaced)
    _check_names("trace", trace, known, drawn.unplaced)
    if ORIGIN not in positions and (any(ORIGIN in link for link in links) or ORIGIN in trace):
        positions[ORIGIN] = np.zeros((len(times), d))
    tips = drawn.axis_tips(axes_length or default_axes_length(positions), d)
    try:
        from lagcomp.animation_artists import MechanismAnimation
    except ImportError as err:
        raise ImportError("lagcomp's animations need matplotlib: pip install 'lagcomp[plots]'.") from err
    anim = MechanismAnimation(times, positions, (*drawn.centres, *named), links=links, trace=trace, axes=tips,
                              fps=fps, size=size, dpi=dpi, title=title or f"{sol.method}")
    if save is not None:
        save_animation(anim, save, progress=progress)
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


def _cartesian_bob(coordinates: tuple[str, ...]) -> dict:
    """A bob whose coordinates are its position (x, y[, z]), on a rod from the origin."""
    from lagcomp.model import coordinates as functions

    return dict(points={"bob": functions(" ".join(coordinates))}, links=[("origin", "bob")], trace=["bob"])


def body_drawing(sol) -> dict:
    """What ``lagcomp animate`` draws of a bundled example built from bodies, besides the bodies: a rod from the
    origin (the examples' pivot) to each body, and its path (`animate`'s ``links`` and ``trace``); of a kinematic
    tree, the paths of its last links (its rods `animate` draws itself)."""
    names = [name for name, kind, _ in sol.geometry.layout if kind != "unplaced"]
    parents = sol.geometry.parents
    if parents:     # a tree: `animate` draws its rods; the paths of its last links (those no link hangs from)
        return dict(links=[], trace=[name for name, _ in parents if all(name != p for _, p in parents)])
    return dict(links=[(ORIGIN, name) for name in names], trace=names)


#: What ``lagcomp animate NAME`` draws for the bundled examples with an obvious picture and no bodies: example
#: name → function of the model's coordinate names giving `animate`'s ``points``, ``links`` and ``trace``.
#: The examples built from bodies draw themselves (`body_drawing`).
EXAMPLE_DRAWINGS = {
    "simple_pendulum": _chain,
    "double_pendulum": _chain,
    "n_link_pendulum": _chain,
    "spherical_pendulum": _spherical,
    "spherical_pendulum_cartesian": _cartesian_bob,
}


#: File suffixes `save_animation` writes.
FORMATS = (".gif", ".mp4", ".html")


def check_format(path: str | os.PathLike) -> Path:
    """`path` as a Path when its suffix is one of `FORMATS`; else an OptionError (before any work is done)."""
    path = Path(path)
    if path.suffix.lower() not in FORMATS:
        raise OptionError(f"animate: cannot tell the format of {str(path)!r}: give a .gif, .mp4 or .html file.")
    return path


def save_animation(anim, path: str | os.PathLike, progress: bool | None = None) -> Path:
    """Write `anim` to `path`, the format from the suffix: .gif (Pillow) and .html (`to_jshtml`'s player) from
    the blitted frames (`MechanismAnimation.rgba_frames`), .mp4 through matplotlib's ffmpeg writer (which draws
    the whole figure per frame).  `progress`: a tqdm bar over the frames, as in `animate`."""
    from matplotlib import animation as mpl_animation

    path = check_format(path)
    suffix = path.suffix.lower()
    if suffix == ".gif":
        from PIL import Image

        images = [Image.fromarray(frame[..., :3]) for frame in anim.rgba_frames(progress)]
        # one palette, from the first frame (every colour drawn is in it: the legend holds the markers'): quicker
        # than a palette per frame, and a smaller file
        palette = images[0].quantize(colors=255, method=Image.Quantize.MEDIANCUT)
        frames = [image.quantize(palette=palette, dither=Image.Dither.NONE) for image in images]
        frames[0].save(path, save_all=True, append_images=frames[1:], duration=int(1000 / anim.fps), loop=0)
    elif suffix == ".mp4":
        if not mpl_animation.writers.is_available("ffmpeg"):
            raise OptionError(f"animate: saving {path.name} needs ffmpeg on the PATH; save a .gif or .html instead.")
        anim.save(path, writer=mpl_animation.FFMpegWriter(fps=anim.fps))
    else:
        from lagcomp.animation_artists import player_html

        path.write_text(player_html(anim.rgba_frames(progress), anim.fps), encoding="utf-8")
    return path
