"""Every plot function renders a PNG headless (Agg), and `lagcomp run --plot` writes one.

What the pictures show was checked by eye once (docs/figures/, drawn by
docs/figures/make_figures.py); these tests check that each renders from the
objects it documents, with sensible axes.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from lagcomp import analysis as an  # noqa: E402
from lagcomp import plots  # noqa: E402
from lagcomp.cli import main  # noqa: E402

PNG = b"\x89PNG\r\n\x1a\n"


def _render(fig, path) -> None:
    """Save through the figure's own canvas: no pyplot, no display (Agg for PNG)."""
    fig.savefig(path, dpi=60)
    data = path.read_bytes()
    assert data.startswith(PNG) and len(data) > 5000


@pytest.fixture(scope="module")
def pendulum_run(compiled):
    return compiled("simple_pendulum").simulate((0, 5), rtol=1e-10, atol=1e-10)


def test_time_plots(pendulum_run, tmp_path):
    fig = plots.plot_coordinates(pendulum_run, velocities=True)
    assert len(fig.axes) == 2 and fig.axes[-1].get_xlabel() == "t"
    _render(fig, tmp_path / "coordinates.png")
    fig = plots.plot_energy_error(pendulum_run)
    assert fig.axes[0].get_yscale() == "log"
    _render(fig, tmp_path / "energy.png")
    _render(plots.plot_run(pendulum_run), tmp_path / "run.png")


def test_phase_portrait_plots(compiled, pendulum_run, tmp_path):
    model = compiled("unbalanced_cylinder")
    portrait = an.phase_portrait(model, [0.9, 1.1, 1.5], (-math.pi, math.pi), periodic=True, samples=201)
    fig = plots.plot_phase_portrait(portrait)
    assert fig.axes[0].get_xlabel() == "theta"
    _render(fig, tmp_path / "portrait.png")
    _render(plots.plot_phase_portrait(pendulum_run), tmp_path / "trajectory.png")


def test_poincare_and_sweep_plots(compiled, tmp_path):
    hh = compiled("henon_heiles")
    start = np.array([[0.0, y, 0.0, 0.0] for y in (-0.1, 0.1, 0.3)])
    start, valid = an.on_energy_surface(hh, 1 / 8, start, "x_dot")
    section = an.poincare_section(hh, (0, 300), start, max_points=100, progress=False)
    assert np.all(section.count > 10) and np.all(section.status == 0)
    # on the section x = 0 with ẋ > 0, and on the energy surface
    hits = section.y[0, : section.count[0]]
    np.testing.assert_allclose(hits[:, 0], 0.0, atol=1e-9)
    assert np.all(hits[:, 2] > 0)
    assert [len(p) for p in section.points("y", "y_dot")] == np.minimum(section.count, 100).tolist()
    _render(plots.plot_poincare(section, "y", "y_dot"), tmp_path / "section.png")
    sweep = hh.sweep((0, 20), {"y": np.linspace(-0.2, 0.2, 4), "y_dot": np.linspace(-0.1, 0.1, 3)},
                     qd0=[0.3, 0.0], output="energy", progress=False)
    fig = plots.plot_sweep(sweep)
    assert fig.axes[0].get_xlabel() == "y"
    _render(fig, tmp_path / "sweep.png")
    _render(plots.plot_sweep(sweep, sweep.final[..., 1], cmap="coolwarm", symmetric=True, label="y(20)"),
            tmp_path / "sweep_final.png")


def test_lyapunov_plot(compiled, tmp_path):
    hh = compiled("henon_heiles")
    result = an.lyapunov_exponents(hh, (0, 100), dt=0.05, progress=False)
    _render(plots.plot_lyapunov(result), tmp_path / "lyapunov.png")


def test_cli_run_writes_a_plot(tmp_path, cache_dir, capsys):
    png = tmp_path / "run.png"
    assert main(["--cache-dir", str(cache_dir), "run", "sling", "--t-end", "1", "--quiet", "--plot", str(png)]) == 0
    assert "plotted" in capsys.readouterr().out
    assert png.read_bytes().startswith(PNG)


@pytest.fixture(scope="module")
def bouncing_run(cache_dir):
    """A ball on a contact floor with an apex event (which changes nothing, so it is not marked)."""
    import sympy as sp

    import lagcomp as lc

    x, = lc.coordinates("x")
    g, e = sp.symbols("g e", positive=True)
    model = lc.compile(lc.System([x], T=x.diff(lc.t) ** 2 / 2, V=g * x, name="plotted_ball",
                                 events=[lc.Contact("floor", x, restitution=e),
                                         lc.Event("apex", x.diff(lc.t), direction=-1)],
                                 defaults={"g": 9.81, "e": 0.8}, q0=(1.0,), qd0=(0.0,)), cache_dir=cache_dir)
    return model.simulate((0.0, 3.0), rtol=1e-10, atol=1e-10)


def _marks(ax) -> dict:
    """The vertical event lines of `ax`: {legend label: their x positions}."""
    from matplotlib.collections import LineCollection

    return {c.get_label(): np.array([segment[0, 0] for segment in c.get_segments()])
            for c in ax.collections if isinstance(c, LineCollection)}


def test_plots_mark_a_friction_elements_switches(cache_dir):
    import sympy as sp

    import lagcomp as lc

    x, = lc.coordinates("x")
    k, g, v_b = sp.symbols("k g v_b", positive=True)
    model = lc.compile(lc.System([x], T=x.diff(lc.t) ** 2 / 2, V=k * x**2 / 2, name="plotted_belt",
                                 events=[lc.Friction("belt", x.diff(lc.t) - v_b, normal=g, static=0.6, kinetic=0.4)],
                                 defaults={"k": 4.0, "g": 9.81, "v_b": 0.5}), cache_dir=cache_dir)
    sol = model.simulate((0.0, 6.0), q0=[0.0], qd0=[0.5], rtol=1e-10, atol=1e-10)
    switches = [s.t for s in sol.friction_switches]
    assert len(switches) >= 2
    marks = _marks(plots.plot_run(sol).axes[0])
    assert list(marks) == [f"belt ({len(switches)})"]
    np.testing.assert_array_equal(marks[f"belt ({len(switches)})"], switches)


def test_plots_mark_the_impacts_one_legend_entry_per_event(bouncing_run, pendulum_run, tmp_path):
    impacts = bouncing_run.events["floor"].t
    assert len(impacts) == 6 and len(bouncing_run.events["apex"]) == 6      # t₁ = 0.45, then every 2 e^k v₁/g
    label = f"floor ({len(impacts)})"
    for fig in (plots.plot_run(bouncing_run), plots.plot_coordinates(bouncing_run, velocities=True)):
        top, bottom = fig.axes[:2]
        marks = _marks(top)
        assert list(marks) == [label]                           # the apex changes nothing: not marked
        np.testing.assert_array_equal(marks[label], impacts)
        np.testing.assert_array_equal(next(iter(_marks(bottom).values())), impacts)
        assert [t.get_text() for t in top.get_legend().get_texts()] == ["x", label]
        _render(fig, tmp_path / "marked.png")
    assert _marks(plots.plot_run(bouncing_run, events=False).axes[0]) == {}
    assert _marks(plots.plot_run(pendulum_run).axes[0]) == {}
