"""The matplotlib side of `lagcomp.animation`: a figure of points, body axes, links and traces, and its frames.

Imported only when an animation is made (matplotlib is the optional ``plots``
extra).  The figure has its own Agg canvas and no pyplot, so it works headless
and keeps no global state.
"""

from __future__ import annotations

import numpy as np
from matplotlib.animation import FuncAnimation
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

#: Fraction of the motion's extent added on each side of the axes' limits.
MARGIN = 0.08
#: Colours of a body's drawn axes x, y, z.
AXIS_COLOURS = {"x": "tab:red", "y": "tab:green", "z": "tab:blue"}


def _limits(positions: dict[str, np.ndarray], tips: dict) -> tuple[np.ndarray, float]:
    """Centre (d,) and half-width of a cube (square in 2-D) holding every point and axis tip at every frame."""
    every = np.concatenate([*positions.values(), *tips.values()])
    low, high = every.min(axis=0), every.max(axis=0)
    half = max(float(np.max(high - low)) / 2, 1e-9) * (1 + 2 * MARGIN)
    return (low + high) / 2, half


class MechanismAnimation(FuncAnimation):
    """A FuncAnimation of bodies and named points, with what it draws kept readable.

    `named` are the bodies and the user's points (drawn as markers); `positions`
    may hold ``"origin"`` besides, for links and traces.  `axes` are the tips of
    the rigid bodies' axes, by (body, axis label), drawn from the body's position.

    Attributes
    ----------
    frame_times : ndarray, shape (frames,)
        Simulated time of each frame.
    positions : dict of str to ndarray, shape (frames, d)
        Each point's position at each frame (d = 2 or 3), with ``"origin"``
        when a link or trace uses it.
    axis_tips : dict of (str, str) to ndarray, shape (frames, d)
        The end of each drawn body axis, by (body, ``"x"``/``"y"``/``"z"``).
    markers, segments, traces, body_axes : dict
        The artists: one marker line per body and named point, one line per link
        (by the pair of names), one line per traced point, one line per body axis
        (by (body, axis label)) from the body's centre to the axis tip.
    fps : float
        Frames per second of the clip.
    """

    def __init__(self, times, positions, named, *, links, trace, fps, size, dpi, title, axes=None):
        self.frame_times, self.positions, self.fps = times, positions, fps
        self.axis_tips = axes or {}
        d = next(iter(positions.values())).shape[1]
        fig = Figure(figsize=size, dpi=dpi, layout="constrained")
        FigureCanvasAgg(fig)
        ax = fig.add_subplot(projection="3d" if d == 3 else None)
        centre, half = _limits(positions, self.axis_tips)
        for i, axis in enumerate("xyz"[:d]):
            getattr(ax, f"set_{axis}lim")(centre[i] - half, centre[i] + half)
            getattr(ax, f"set_{axis}label")(axis)
        if d == 3:
            ax.set_box_aspect((1, 1, 1))
        else:
            ax.set_aspect("equal")
            ax.grid(alpha=0.3)
        empty = [[]] * d
        self.segments = {link: ax.plot(*empty, "-", color="0.3", lw=2.0, zorder=2)[0] for link in links}
        self.body_axes = {key: ax.plot(*empty, "-", color=AXIS_COLOURS[key[1]], lw=1.5, zorder=2)[0]
                          for key in self.axis_tips}
        self.markers = {name: ax.plot(*empty, "o", ms=8, label=name, zorder=3)[0] for name in named}
        colour = {name: line.get_color() for name, line in self.markers.items()}
        self.traces = {name: ax.plot(*empty, lw=0.8, alpha=0.7, color=colour.get(name, "k"), zorder=1)[0]
                       for name in trace}
        ax.legend(loc="upper right", fontsize="small")
        if "origin" in positions and "origin" not in named:
            ax.plot(*[[0.0]] * d, "k+", ms=8)
        self._title, self._axes = title, ax
        super().__init__(fig, self.draw, frames=len(times), interval=1000.0 / fps, blit=False, repeat=True)

    def _set(self, line, xyz: np.ndarray) -> None:
        """Put the points `xyz` (k, d) on `line`."""
        if xyz.shape[1] == 3:
            line.set_data_3d(xyz[:, 0], xyz[:, 1], xyz[:, 2])
        else:
            line.set_data(xyz[:, 0], xyz[:, 1])

    def draw(self, k: int) -> list:
        """Draw frame `k`: every point and body at `frame_times[k]`, body axes, links, traces up to then."""
        for name, line in self.markers.items():
            self._set(line, self.positions[name][k:k + 1])
        for (a, b), line in self.segments.items():
            self._set(line, np.vstack([self.positions[a][k], self.positions[b][k]]))
        for name, line in self.traces.items():
            self._set(line, self.positions[name][:k + 1])
        for (name, label), line in self.body_axes.items():
            self._set(line, np.vstack([self.positions[name][k], self.axis_tips[name, label][k]]))
        self._axes.set_title(f"{self._title}   t = {self.frame_times[k]:.2f}")
        return [*self.markers.values(), *self.segments.values(), *self.traces.values(), *self.body_axes.values()]
