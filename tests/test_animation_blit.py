"""Fast animations (issue 37, part 3): the layout fixed once, frames blitted (no full redraw), what they show
is the run, files and the notebook player hold every frame, a progress bar on request."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

pytest.importorskip("matplotlib")

import lagcomp as lc

pytestmark = pytest.mark.usefixtures("animations_freed_quietly")

th1, th2 = lc.coordinates("theta1 theta2")
l1, l2 = sp.symbols("l1 l2", positive=True)
BOB1 = (l1 * sp.sin(th1), -l1 * sp.cos(th1))
BOB2 = (BOB1[0] + l2 * sp.sin(th2), BOB1[1] - l2 * sp.cos(th2))


@pytest.fixture(scope="module")
def run(compiled):
    return compiled("double_pendulum").simulate((0, 2), t_eval=np.linspace(0, 2, 201))


@pytest.fixture
def anim(run):
    return lc.animate(run, {"bob1": BOB1, "bob2": BOB2}, links=[("origin", "bob1"), ("bob1", "bob2")],
                      trace=["bob2"], fps=5, dpi=50)


def test_frames_are_blitted_with_the_layout_fixed(anim, monkeypatch):
    from matplotlib.figure import Figure

    position = anim._axes.get_position().bounds
    draws = []
    original = Figure.draw
    monkeypatch.setattr(Figure, "draw", lambda self, renderer: draws.append(1) or original(self, renderer))
    frames = list(anim.rgba_frames())
    assert draws == []  # no frame drew the whole figure
    assert len(frames) == len(anim.frame_times) == 11
    assert {frame.shape for frame in frames} == {(250, 250, 4)} and frames[0].dtype == np.uint8
    assert anim._axes.get_position().bounds == position
    from matplotlib.layout_engine import ConstrainedLayoutEngine

    assert not isinstance(anim._axes.figure.get_layout_engine(), ConstrainedLayoutEngine)  # laid out once
    assert not np.array_equal(frames[0], frames[-1])


def test_each_frame_shows_the_bobs_where_the_run_puts_them(anim, run):
    """The pixel under each bob's centre (the solution's position through the axes' transform) has its
    marker's colour, in every frame: the blitted pictures are the run's."""
    from matplotlib.colors import to_rgba

    height = anim._axes.figure.bbox.height
    for k, frame in enumerate(anim.rgba_frames()):
        t = anim.frame_times[k]
        a, b = (np.interp(t, run.t, run.q[:, i]) for i in (0, 1))
        x1, y1 = np.sin(a), -np.cos(a)
        for name, (x, y) in (("bob1", (x1, y1)), ("bob2", (x1 + np.sin(b), y1 - np.cos(b)))):
            px, py = anim._axes.transData.transform((x, y))
            pixel = frame[int(height - py), int(px)]
            colour = np.array(to_rgba(anim.markers[name].get_color())) * 255
            assert np.max(np.abs(pixel.astype(float) - colour)) <= 2, (k, name, pixel, colour)


def test_a_3d_run_is_blitted_too(compiled):
    sol = compiled("symmetric_top").simulate((0, 1), t_eval=np.linspace(0, 1, 11))
    anim = lc.animate(sol, fps=5, dpi=40)
    assert anim._axes.name == "3d"
    frames = list(anim.rgba_frames())
    assert len(frames) == 6 and not np.array_equal(frames[1], frames[4])


def test_the_gif_holds_every_frame_and_the_notebook_shows_a_player(anim, tmp_path):
    from PIL import Image, ImageSequence

    from lagcomp.animation import save_animation

    path = save_animation(anim, tmp_path / "run.gif", progress=False)
    with Image.open(path) as gif:
        assert sum(1 for _ in ImageSequence.Iterator(gif)) == 11
        assert gif.info["duration"] == 200  # 5 frames per second
    html = anim._repr_html_()
    assert html.count("data:image/png;base64") == 11 and "setInterval" in html and 'type="range"' in html


def test_a_progress_bar_when_asked(anim, tmp_path, capsys):
    from lagcomp.animation import save_animation

    save_animation(anim, tmp_path / "run.html", progress=True)
    err = capsys.readouterr().err
    assert "animation:" in err and "/11 [" in err
    save_animation(anim, tmp_path / "quiet.html", progress=False)
    assert capsys.readouterr().err == ""
