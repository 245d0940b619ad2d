"""The matplotlib side of `lagcomp.animation`: a figure of points, body axes, links and traces, and its frames.

Imported only when an animation is made (matplotlib is the optional ``plots``
extra).  The figure has its own Agg canvas and no pyplot, so it works headless
and keeps no global state.

Frames are blitted: the figure is laid out and drawn once without the moving
artists (axes, grid, labels, legend, title: the background, kept as pixels), the
layout is then frozen, and each frame restores the background and draws only the
moving artists (markers, links, traces, body axes and the clock) over it
(`MechanismAnimation.rgba_frames`).  matplotlib's own ``Animation.save`` draws the
whole figure for every frame instead; `lagcomp.animation.save_animation` uses the
blitted frames (bench/bench_animation.py measures both).
"""

from __future__ import annotations

import base64
import io
from collections.abc import Iterator

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
        self._canvas = FigureCanvasAgg(fig)
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
        moving = {"animated": True}
        self.segments = {link: ax.plot(*empty, "-", color="0.3", lw=2.0, zorder=2, **moving)[0] for link in links}
        self.body_axes = {key: ax.plot(*empty, "-", color=AXIS_COLOURS[key[1]], lw=1.5, zorder=2, **moving)[0]
                          for key in self.axis_tips}
        self.markers = {name: ax.plot(*empty, "o", ms=8, label=name, zorder=3, **moving)[0] for name in named}
        colour = {name: line.get_color() for name, line in self.markers.items()}
        self.traces = {name: ax.plot(*empty, lw=0.8, alpha=0.7, color=colour.get(name, "k"), zorder=1, **moving)[0]
                       for name in trace}
        ax.legend(loc="upper right", fontsize="small")
        if "origin" in positions and "origin" not in named:
            ax.plot(*[[0.0]] * d, "k+", ms=8)
        ax.set_title(title)
        self.clock = fig.text(0.01, 0.01, "", fontsize="small", animated=True)
        self._axes = ax
        self._background = self._freeze_layout(fig)
        super().__init__(fig, self.draw, frames=len(times), interval=1000.0 / fps, blit=True, repeat=True)

    def _freeze_layout(self, fig):
        """Lay the figure out and draw its static part once; keep those pixels, and the layout from then on."""
        self._canvas.draw()  # the constrained layout, once; the animated artists are left out of this drawing
        fig.set_layout_engine("none")
        return self._canvas.copy_from_bbox(fig.bbox)

    @property
    def moving_artists(self) -> list:
        """What changes from frame to frame, in drawing order."""
        return [*self.traces.values(), *self.segments.values(), *self.body_axes.values(), *self.markers.values(),
                self.clock]

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
        self.clock.set_text(f"t = {self.frame_times[k]:.2f}")
        return self.moving_artists

    def rgba_frames(self, progress: bool | None = False) -> Iterator[np.ndarray]:
        """Each frame as an RGBA image, shape (height, width, 4) uint8: the background restored and the moving
        artists drawn over it (no layout, no full redraw).  `progress`: a tqdm bar, None for one only on a long
        render (shown after two seconds), True always."""
        from tqdm.auto import tqdm

        figure = self._axes.figure
        frames = range(len(self.frame_times))
        bar = tqdm(frames, desc="animation", unit="frame", disable=progress is False,
                   delay=0.0 if progress else 2.0, leave=False)
        try:
            for k in bar:
                self._canvas.restore_region(self._background)
                for artist in self.draw(k):
                    figure.draw_artist(artist)
                yield np.array(self._canvas.buffer_rgba())  # a copy: the canvas is drawn over next
        finally:
            bar.close()

    def to_jshtml(self, fps=None, embed_frames=True, default_mode=None) -> str:
        """An HTML player of the blitted frames (PNG, embedded): play, pause, step and a slider; what a notebook
        shows for the animation (`_repr_html_`).  `embed_frames` and `default_mode` are matplotlib's, accepted
        for its signature: the frames are always embedded and the clip loops."""
        return player_html(self.rgba_frames(progress=None), fps or self.fps)

    def _repr_html_(self) -> str:
        return self.to_jshtml()


def png_base64(rgba: np.ndarray) -> str:
    """An RGBA image as a base64 PNG."""
    from PIL import Image

    buffer = io.BytesIO()
    Image.fromarray(rgba, "RGBA").save(buffer, format="png", compress_level=1)
    return base64.b64encode(buffer.getvalue()).decode("ascii")


#: The player `player_html` writes: frames as data URLs, a slider, and play / pause / step buttons.
PLAYER = """<div class="lagcomp-player" id="{id}">
<img style="max-width:100%"><br>
<button data-step="-1">&#9664;&#9646;</button><button data-play>&#9654; / &#10074;&#10074;</button><button data-step="1">&#9646;&#9654;</button>
<input type="range" min="0" max="{last}" value="0" style="width:60%"> <span></span>
<script>
(function() {{
  const root = document.getElementById("{id}"), frames = {frames};
  const img = root.querySelector("img"), slider = root.querySelector("input"), label = root.querySelector("span");
  let k = 0, timer = null;
  function show(i) {{ k = (i + frames.length) % frames.length; img.src = frames[k]; slider.value = k;
                      label.textContent = "frame " + (k + 1) + " / " + frames.length; }}
  root.querySelectorAll("button[data-step]").forEach(b => b.onclick = () => show(k + Number(b.dataset.step)));
  root.querySelector("button[data-play]").onclick = () => {{
    if (timer) {{ clearInterval(timer); timer = null; }} else {{ timer = setInterval(() => show(k + 1), {interval}); }} }};
  slider.oninput = () => show(Number(slider.value));
  show(0);
}})();
</script>
</div>
"""


def player_html(frames, fps: float) -> str:
    """The HTML player (`PLAYER`) of RGBA `frames` at `fps`."""
    import json
    import uuid

    urls = [f"data:image/png;base64,{png_base64(frame)}" for frame in frames]
    return PLAYER.format(id=f"lagcomp-{uuid.uuid4().hex}", last=len(urls) - 1,
                         frames=json.dumps(urls), interval=max(round(1000 / fps), 1))
