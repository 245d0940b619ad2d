"""`lagcomp.animate`: the drawn points are the solution's (read back from the artists), and the clip saves.

Frames are few (fps 5, ~2 s of motion) so the GIF and HTML writers stay quick.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest
import sympy as sp

pytest.importorskip("matplotlib")


import lagcomp as lc  # noqa: E402
from lagcomp.animation import frame_times  # noqa: E402

#: Every test here draws frames by hand: its animations are collected quietly when it ends.
pytestmark = pytest.mark.usefixtures("animations_freed_quietly")

th1, th2 = lc.coordinates("theta1 theta2")
l1, l2 = sp.symbols("l1 l2", positive=True)
BOB1 = (l1 * sp.sin(th1), -l1 * sp.cos(th1))
BOB2 = (BOB1[0] + l2 * sp.sin(th2), BOB1[1] - l2 * sp.cos(th2))
RODS = [("origin", "bob1"), ("bob1", "bob2")]


@pytest.fixture(scope="module")
def double_run(compiled):
    return compiled("double_pendulum").simulate((0, 2), t_eval=np.linspace(0, 2, 201))




@pytest.fixture
def double_anim(double_run):
    return lc.animate(double_run, {"bob1": BOB1, "bob2": BOB2}, links=RODS, trace=["bob2"], fps=5, dpi=40)


def _at(sol, times, column):
    return np.interp(times, sol.t, sol.q[:, column])


def test_frames_are_every_speed_over_fps_seconds_of_the_run(double_run):
    assert np.allclose(frame_times(double_run.t, 5, 1.0), np.arange(11) * 0.2, rtol=0, atol=1e-15)
    assert np.allclose(frame_times(double_run.t, np.int64(5), np.float32(4.0)), [0.0, 0.8, 1.6], rtol=0, atol=1e-15)


def test_double_pendulum_draws_the_bobs_where_the_solution_puts_them(double_run, double_anim):
    p = double_run.params
    for k in (0, 3, len(double_anim.frame_times) - 1):
        double_anim.draw(k)
        t = double_anim.frame_times[k]
        a, b = _at(double_run, t, 0), _at(double_run, t, 1)
        x1, y1 = p["l1"] * np.sin(a), -p["l1"] * np.cos(a)
        x2, y2 = x1 + p["l2"] * np.sin(b), y1 - p["l2"] * np.cos(b)
        for name, expected in (("bob1", (x1, y1)), ("bob2", (x2, y2))):
            drawn = np.array(double_anim.markers[name].get_data(), dtype=float)[:, 0]
            assert np.max(np.abs(drawn - expected)) < 1e-12
        rod = np.array(double_anim.segments[("bob1", "bob2")].get_data(), dtype=float)
        assert np.max(np.abs(rod - [[x1, x2], [y1, y2]])) < 1e-12
        assert np.array(double_anim.segments[("origin", "bob1")].get_data())[:, 0].tolist() == [0.0, 0.0]
        assert len(double_anim.traces["bob2"].get_data()[0]) == k + 1
    assert double_anim.frame_times[0] == 0.0 and abs(double_anim.frame_times[-1] - 2.0) < 1e-12


def test_sol_animate_is_lc_animate(double_run):
    anim = double_run.animate({"bob1": BOB1}, fps=2, speed=2.0)
    assert len(anim.frame_times) == 3 and set(anim.markers) == {"bob1"} and anim.segments == {}


def test_spherical_pendulum_in_3d(compiled):
    sol = compiled("spherical_pendulum_cartesian").simulate((0, 1), t_eval=np.linspace(0, 1, 101))
    x, y, z = lc.coordinates("x y z")
    anim = lc.animate(sol, {"bob": (x, y, z)}, links=[("origin", "bob")], fps=5, dpi=40)
    assert anim.markers["bob"].axes.name == "3d"
    for k in range(len(anim.frame_times)):
        anim.draw(k)
        expected = [_at(sol, anim.frame_times[k], i) for i in range(3)]
        drawn = np.array(anim.markers["bob"].get_data_3d(), dtype=float)[:, 0]
        assert np.max(np.abs(drawn - expected)) < 1e-12


def test_points_may_use_t_and_constants(double_run):
    t = lc.t
    anim = lc.animate(double_run, {"cart": (sp.sin(t), 0), "bob": BOB1}, fps=5, dpi=40)
    anim.draw(4)
    assert np.allclose(anim.markers["cart"].get_data(), [[np.sin(0.8)], [0.0]], rtol=0, atol=1e-15)


def test_saves_a_gif_with_pillow(double_anim, tmp_path):
    path = tmp_path / "run.gif"
    from lagcomp.animation import save_animation

    save_animation(double_anim, path)
    assert path.read_bytes().startswith(b"GIF8")
    double_anim.save(tmp_path / "again.gif", writer="pillow")
    assert (tmp_path / "again.gif").read_bytes().startswith(b"GIF8")


def test_html_player_holds_every_frame(double_run, tmp_path):
    anim = lc.animate(double_run, {"bob1": BOB1}, fps=2, dpi=30, save=tmp_path / "run.html")
    html = anim.to_jshtml()
    assert "<script" in html and html.count("data:image/png;base64") == len(anim.frame_times) == 5
    assert (tmp_path / "run.html").read_text().count("data:image/png;base64") == 5


@pytest.mark.parametrize("points, options, error, match", [
    ({"bob": (l1 * sp.sin(th1), sp.Symbol("zeta"))}, {}, lc.ModelError, r"\['zeta'\]"),
    ({"bob": (lc.coordinates("phi")[0], 0)}, {}, lc.ModelError, r"phi\(t\)"),
    ({"bob": (th1.diff(lc.t), 0)}, {}, lc.ModelError, "derivative"),
    ({"bob": (th1,)}, {}, lc.OptionError, r"\(x, y\) or \(x, y, z\)"),
    ({"bob": (th1, th2, 0, 0)}, {}, lc.OptionError, r"\(x, y\) or \(x, y, z\)"),
    ({"a": (th1, th2), "b": (th1, th2, 0)}, {}, lc.OptionError, "same number of coordinates"),
    ({}, {}, lc.OptionError, "non-empty dict"),
    ({"bob": BOB1}, {"links": [("origin", "bob3")]}, lc.OptionError, r"\['bob3'\], not a point"),
    ({"bob": BOB1}, {"links": [("bob",)]}, lc.OptionError, "pairs"),
    ({"bob": BOB1}, {"trace": ["bob2"]}, lc.OptionError, r"\['bob2'\], not a point"),
    ({"bob": BOB1}, {"fps": 0}, lc.OptionError, "fps must be a positive number"),
    ({"bob": BOB1}, {"speed": float("nan")}, lc.OptionError, "speed must be a positive number"),
    ({"bob": BOB1}, {"speed": True}, lc.OptionError, "speed must be a positive number"),
    ({"bob": BOB1}, {"save": "run.avi"}, lc.OptionError, r"\.gif, \.mp4 or \.html"),
])
def test_errors_name_the_culprit(double_run, points, options, error, match, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(error, match=match):
        lc.animate(double_run, points, fps=options.pop("fps", 1), dpi=30, **options)


def test_a_solution_of_one_row_is_refused(compiled):
    sol = compiled("double_pendulum").simulate((0, 1), record="summary")
    one = type(sol)(**{**{f: getattr(sol, f) for f in sol.__dataclass_fields__}, "t": sol.t[:1], "q": sol.q[:1]})
    with pytest.raises(lc.OptionError, match="at least 2 saved rows"):
        one.animate({"bob": BOB1})


def test_mp4_without_ffmpeg_says_so(double_anim, tmp_path, monkeypatch):
    from matplotlib import animation as mpl_animation

    from lagcomp.animation import save_animation

    monkeypatch.setattr(mpl_animation.writers, "is_available", lambda name: False)
    with pytest.raises(lc.OptionError, match="needs ffmpeg"):
        save_animation(double_anim, tmp_path / "run.mp4")


def test_without_matplotlib_the_message_says_how_to_install(double_run, monkeypatch):
    monkeypatch.delitem(sys.modules, "lagcomp.animation_artists", raising=False)
    monkeypatch.setitem(sys.modules, "matplotlib.animation", None)
    with pytest.raises(ImportError, match=r"pip install 'lagcomp\[plots\]'"):
        lc.animate(double_run, {"bob": BOB1})


def test_example_drawings_put_the_bobs_on_their_rods(compiled):
    from lagcomp.animation import EXAMPLE_DRAWINGS, point_positions

    chain = EXAMPLE_DRAWINGS["n_link_pendulum"](("theta1", "theta2", "theta3"))
    assert chain["links"] == [("origin", "bob1"), ("bob1", "bob2"), ("bob2", "bob3")] and chain["trace"] == ["bob3"]
    model = compiled("spherical_pendulum")
    sol = model.simulate((0, 1), t_eval=np.linspace(0, 1, 11))
    drawing = EXAMPLE_DRAWINGS["spherical_pendulum"](model.coordinates)
    bob = point_positions(sol, drawing["points"], sol.t)["bob"]
    assert bob.shape == (11, 3) and np.max(np.abs(np.linalg.norm(bob, axis=1) - sol.params["l"])) < 1e-14


def test_a_named_point_of_the_symmetric_top_is_drawn_on_its_body(compiled):
    """The top's centre of mass named by hand, G = l K.z, where its geometry kernel draws the body."""
    psi, theta, _ = lc.coordinates("psi theta phi")
    l = sp.Symbol("l")  # noqa: E741  (the example's name)
    G = (l * sp.sin(theta) * sp.sin(psi), -l * sp.cos(psi) * sp.sin(theta), l * sp.cos(theta))
    sol = compiled("symmetric_top").simulate((0, 0.5), t_eval=np.linspace(0, 0.5, 51))
    anim = lc.animate(sol, {"G": G}, links=[("origin", "G")], trace=["top"], fps=20, dpi=30)
    for k in (0, 5, 10):
        anim.draw(k)
        drawn = {name: np.array(anim.markers[name].get_data_3d(), dtype=float)[:, 0] for name in ("G", "top")}
        assert np.max(np.abs(drawn["G"] - drawn["top"])) < 1e-12


def test_cli_animates_an_example(cache_dir, tmp_path, capsys):
    from lagcomp.cli import main

    gif = tmp_path / "double.gif"
    args = ["--cache-dir", str(cache_dir), "animate", "double_pendulum", "-o", str(gif), "--t-end", "1", "--fps", "4"]
    assert main(args) == 0 and gif.read_bytes().startswith(b"GIF8")
    assert "5 frames of t in [0, 1] at 4 fps" in capsys.readouterr().out


@pytest.mark.parametrize("name, output, message", [
    ("hoop_bead", "run.gif", "lagcomp animate draws"),
    ("double_pendulum", "run.avi", r"give a .gif, .mp4 or .html file"),
])
def test_cli_refuses_before_running(name, output, message, cache_dir, tmp_path, capsys):
    from lagcomp.cli import main

    assert main(["--cache-dir", str(cache_dir), "animate", name, "-o", str(tmp_path / output)]) == 2
    assert message in capsys.readouterr().err
