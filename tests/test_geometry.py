"""The ``geometry`` kernel (lagcomp.codegen.geometry) and the animations of bodies drawn from it.

The kernel is checked against sympy.physics.vector evaluated at 40 digits, built independently of
lagcomp's own construction (Euler angles by ``orientnew("Body", ...)``, rotations by hand), at
random states: particles, a rigid body in Euler angles, and a body in a moving frame.  Then the
animations: what the artists hold equals the geometry at the frame times and the closed forms.
"""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest
import sympy as sp
from sympy.physics.vector import Point, ReferenceFrame

import lagcomp as lc
from lagcomp.codegen.geometry import unique_names
from lagcomp.codegen.lower import lower
from lagcomp.mechanics.lagrange import derive

#: Every test here draws frames by hand: its animations are collected quietly when it ends.
pytestmark = pytest.mark.usefixtures("animations_freed_quietly")

th1, th2 = lc.coordinates("theta1 theta2")
m1, m2, l1, l2, g = sp.symbols("m1 m2 l1 l2 g", positive=True)
BOB1 = (l1 * sp.sin(th1), -l1 * sp.cos(th1), 0)
BOB2 = (BOB1[0] + l2 * sp.sin(th2), BOB1[1] - l2 * sp.cos(th2), 0)
#: Few ulps of the size of the values.  Measured: 2 for the particles and the top; 3.9 for the turn indicator,
#: whose imposed angle Ω t (up to 6 rad) is rounded once in float64 before sin and cos (the 40-digit reference
#: multiplies exactly), as any float evaluation of it is.
ULPS = 8


def particle_double_pendulum() -> lc.System:
    """The double pendulum of the examples, built from two particles."""
    return lc.System(
        coordinates=(th1, th2),
        bodies=(lc.Particle(m1, BOB1, name="bob1"), lc.Particle(m2, BOB2, name="bob2")),
        loads=(lc.Gravity((0, -g, 0)),), name="particle_double_pendulum",
        defaults={"m1": 1.0, "m2": 1.0, "l1": 1.0, "l2": 0.7, "g": 9.81}, q0=(1.2, -0.4), qd0=(0.0, 0.5),
    )


@pytest.fixture(scope="module")
def double(cache_dir):
    return lc.compile(particle_double_pendulum(), cache_dir=cache_dir)




def _geometry(model, t, q, params=None) -> np.ndarray:
    """The kernel's output at (t, q), q̇ = 0."""
    out = np.full(model.kernels.GEOMETRY_SIZE, np.nan)
    model.kernels.geometry(t, np.concatenate([q, np.zeros(len(q))]), model.parameter_vector(params), out)
    return out


def _exact(entries, values: dict) -> np.ndarray:
    """`entries` (sympy) at `values` ({symbol or q(t): float}), 40 digits, rounded once to float64."""
    exact = {key: sp.Float(value, 40) for key, value in values.items()}
    return np.array([float(sp.sympify(e).xreplace(exact).evalf(40)) for e in entries])


def _assert_ulps(computed: np.ndarray, exact: np.ndarray) -> None:
    scale = np.max(np.abs(exact))
    assert np.max(np.abs(computed - exact)) <= ULPS * np.spacing(scale), (computed - exact) / np.spacing(scale)


def test_particles_are_where_sympy_puts_them(double, rng):
    N, origin = ReferenceFrame("N"), Point("O")
    P1 = origin.locatenew("P1", l1 * sp.sin(th1) * N.x - l1 * sp.cos(th1) * N.y)
    P2 = P1.locatenew("P2", l2 * sp.sin(th2) * N.x - l2 * sp.cos(th2) * N.y)
    assert double.kernels.GEOMETRY == (("bob1", "particle", 0), ("bob2", "particle", 3))
    params = {"m1": 1.0, "m2": 2.0, "l1": 1.3, "l2": 0.6, "g": 9.81}
    for _ in range(20):
        q = rng.uniform(-np.pi, np.pi, 2)
        values = {th1: q[0], th2: q[1], l1: params["l1"], l2: params["l2"]}
        exact = _exact([*P1.pos_from(origin).to_matrix(N), *P2.pos_from(origin).to_matrix(N)], values)
        _assert_ulps(_geometry(double, 0.0, q, params), exact)


def test_a_top_in_euler_angles_is_where_sympy_puts_it(compiled, rng):
    model = compiled("symmetric_top")
    psi, theta, phi = lc.coordinates("psi theta phi")
    l = sp.Symbol("l")  # noqa: E741
    N = ReferenceFrame("N")
    B = N.orientnew("B", "Body", (psi, theta, phi), "ZXZ")  # not lagcomp.rotated: sympy's own Euler angles
    C = N.dcm(B)  # columns: B's axes in N
    assert all(sp.simplify(C[:, j] - B_axis.to_matrix(N)) == sp.zeros(3, 1) for j, B_axis in enumerate((B.x, B.y, B.z)))
    assert model.kernels.GEOMETRY == (("top", "rigid", 0),)
    for _ in range(20):
        q = rng.uniform(-np.pi, np.pi, 3)
        values = {psi: q[0], theta: q[1], phi: q[2], l: model.defaults["l"]}
        out = _geometry(model, 0.0, q)
        _assert_ulps(out[:3], _exact(l * B.z.to_matrix(N), values))
        _assert_ulps(out[3:], _exact(list(C), values))  # row-major


def test_a_gyroscope_in_a_turning_aircraft_is_drawn_in_the_aircraft(compiled, rng):
    """turn_indicator: a MovingFrame A turning at ω; the flywheel's axes C = R_x(α + θ) R_y(Ω t) in A's
    components, written here by hand (lagcomp builds them with `rotated`)."""
    model = compiled("turn_indicator")
    theta = lc.coordinates("theta")[0]
    alpha, Omega, time = sp.symbols("alpha Omega t")
    a, b = alpha + theta, Omega * time
    Rx = sp.Matrix([[1, 0, 0], [0, sp.cos(a), -sp.sin(a)], [0, sp.sin(a), sp.cos(a)]])
    Ry = sp.Matrix([[sp.cos(b), 0, sp.sin(b)], [0, 1, 0], [-sp.sin(b), 0, sp.cos(b)]])
    params = {**model.defaults, "Omega": 3.0}  # Ω t of the default Ω = 2000 would measure the rounding of Ω t
    assert model.kernels.GEOMETRY == (("flywheel", "rigid", 0),)
    for _ in range(20):
        q, t = rng.uniform(-np.pi, np.pi, 1), float(rng.uniform(0, 2))
        out = _geometry(model, t, q, params)
        assert out[:3].tolist() == [0.0, 0.0, 0.0]
        values = {theta: q[0], alpha: params["alpha"], Omega: params["Omega"], time: t}
        _assert_ulps(out[3:], _exact(list(Rx * Ry), values))


def _layout(system: lc.System) -> tuple:
    kernel = lower(derive(system)).kernel("geometry")
    return dict((name, value) for name, _, value in kernel.constants)


def test_layout_of_unnamed_unoriented_and_unplaced_bodies():
    (x,) = lc.coordinates("x")
    N, P = ReferenceFrame("N"), Point("P")
    P.set_vel(N, x.diff(lc.t) * N.x)  # a velocity but no position: unplaced
    bodies = [lc.Particle(1, (x, 0, 0)), lc.Particle(1, (0, x, 0)),
              lc.RigidBody(1, (0, 0, x), (1, 1, 1), (0, 0, x.diff(lc.t)), name="wheel"),  # ω as components: centre only
              lc.Particle(1, P, name="ghost"),
              lc.Particle(1, (x + sp.Symbol("d"), 0, 0), name="offset")]  # d: no parameter, lost from T
    system = lc.System([x], bodies=bodies, frame=lc.MovingFrame(axes=N), name="layout")
    assert "d" not in system.parameter_names
    constants = _layout(system)
    assert constants["GEOMETRY"] == (("particle[0]", "particle", 0), ("particle[1]", "particle", 3),
                                     ("wheel", "centre", 6), ("ghost", "unplaced", 9), ("offset", "unplaced", 9))
    assert constants["GEOMETRY_SIZE"] == 9
    assert _layout(lc.System([x], T=x.diff(lc.t) ** 2, name="plain")) == {"GEOMETRY": (), "GEOMETRY_SIZE": 0}
    assert unique_names(["a", "a", "a[1]"]) == ["a[0]", "a[1]_", "a[1]"]


def test_names_like_the_kernels_own_are_the_users(cache_dir):
    """Parameters named like the geometry kernel's arguments and constants, and like its temporaries."""
    (x,) = lc.coordinates("x")
    out, y, size, c0 = sp.symbols("out y GEOMETRY_SIZE _c0", positive=True)
    system = lc.System([x], bodies=[lc.Particle(out, (y * sp.cos(x), size * sp.sin(x), c0 * sp.cos(x)), name="p")],
                       name="geometry_names")
    model = lc.compile(system, cache_dir=cache_dir)
    params = {"out": 1.0, "y": 2.0, "GEOMETRY_SIZE": 3.0, "_c0": 5.0}
    assert np.allclose(_geometry(model, 0.0, np.array([0.3]), params),
                       [2 * np.cos(0.3), 3 * np.sin(0.3), 5 * np.cos(0.3)], rtol=1e-15, atol=0)


# -- animations -----------------------------------------------------------------------------------


def _at(sol, times, column):
    return np.interp(times, sol.t, sol.q[:, column])


@pytest.fixture(scope="module")
def top_run(compiled):
    return compiled("symmetric_top").simulate((0, 0.5), t_eval=np.linspace(0, 0.5, 51))


def test_the_top_is_drawn_where_its_geometry_and_euler_angles_put_it(compiled, top_run):
    pytest.importorskip("matplotlib")
    model, sol = compiled("symmetric_top"), top_run
    anim = lc.animate(sol, fps=20, dpi=30, axes_length=0.03)
    assert set(anim.markers) == {"top"} and set(anim.body_axes) == {("top", a) for a in "xyz"}
    assert anim.markers["top"].axes.name == "3d"
    l = sol.params["l"]  # noqa: E741
    for k in range(len(anim.frame_times)):
        anim.draw(k)
        t = anim.frame_times[k]
        q = np.array([_at(sol, t, i) for i in range(3)])
        geometry = _geometry(model, t, q)
        centre = np.array(anim.markers["top"].get_data_3d(), dtype=float)[:, 0]
        axes = {a: np.array(anim.body_axes["top", a].get_data_3d(), dtype=float).T for a in "xyz"}
        assert np.max(np.abs(centre - geometry[:3])) < 1e-12
        for j, a in enumerate("xyz"):
            assert np.max(np.abs(axes[a] - [geometry[:3], geometry[:3] + 0.03 * geometry[3 + j::3]])) < 1e-12
        (sp_, cp), (st, ct), (sf, cf) = ((np.sin(v), np.cos(v)) for v in q)
        axis = np.array([st * sp_, -st * cp, ct])  # the symmetry axis from Euler angles ψ, θ
        assert np.max(np.abs(centre - l * axis)) < 1e-12
        assert np.max(np.abs(axes["z"][1] - (l + 0.03) * axis)) < 1e-12
        spin_x = np.array([cp * cf - sp_ * ct * sf, sp_ * cf + cp * ct * sf, st * sf])  # the body's x: it spins
        assert np.max(np.abs(axes["x"][1] - (l * axis + 0.03 * spin_x))) < 1e-12


def test_default_axes_are_half_the_motions_extent(top_run):
    pytest.importorskip("matplotlib")
    anim = lc.animate(top_run, links=[("origin", "top")], trace=["top"], fps=10, dpi=30)
    every = np.vstack([anim.positions["top"], np.zeros((1, 3))])
    length = 0.5 * np.max(every.max(axis=0) - every.min(axis=0))
    tip = anim.axis_tips["top", "z"] - anim.positions["top"]
    assert np.allclose(np.linalg.norm(tip, axis=1), length, rtol=1e-14, atol=0)
    anim.draw(3)
    assert len(anim.traces["top"].get_data_3d()[0]) == 4


def test_the_particle_double_pendulum_is_drawn_flat_where_its_bobs_are(double):
    pytest.importorskip("matplotlib")
    sol = double.simulate((0, 2), t_eval=np.linspace(0, 2, 201))
    anim = sol.animate(links=[("origin", "bob1"), ("bob1", "bob2")], trace=["bob2"], fps=5, dpi=30)
    assert anim.markers["bob1"].axes.name == "rectilinear" and anim.body_axes == {}
    p = sol.params
    for k in range(len(anim.frame_times)):
        anim.draw(k)
        a, b = _at(sol, anim.frame_times[k], 0), _at(sol, anim.frame_times[k], 1)
        x1, y1 = p["l1"] * np.sin(a), -p["l1"] * np.cos(a)
        x2, y2 = x1 + p["l2"] * np.sin(b), y1 - p["l2"] * np.cos(b)
        for name, expected in (("bob1", (x1, y1)), ("bob2", (x2, y2))):
            assert np.max(np.abs(np.array(anim.markers[name].get_data(), dtype=float)[:, 0] - expected)) < 1e-12
        rod = np.array(anim.segments[("bob1", "bob2")].get_data(), dtype=float)
        assert np.max(np.abs(rod - [[x1, x2], [y1, y2]])) < 1e-12


def test_points_and_bodies_together(double):
    pytest.importorskip("matplotlib")
    sol = double.simulate((0, 1), t_eval=np.linspace(0, 1, 11))
    mid = tuple((a + b) / 2 for a, b in zip(BOB1[:2], BOB2[:2], strict=True))
    anim = lc.animate(sol, {"middle": mid}, links=[("bob1", "middle")], fps=5, dpi=30)
    assert list(anim.markers) == ["bob1", "bob2", "middle"]
    anim.draw(4)
    drawn = {name: np.array(anim.markers[name].get_data(), dtype=float)[:, 0] for name in anim.markers}
    assert np.max(np.abs(drawn["middle"] - (drawn["bob1"] + drawn["bob2"]) / 2)) < 1e-15


def test_saves_a_gif_of_the_top_from_the_command_line(cache_dir, tmp_path, capsys):
    pytest.importorskip("matplotlib")
    from lagcomp.animation import EXAMPLE_DRAWINGS
    from lagcomp.cli import main

    assert "symmetric_top" not in EXAMPLE_DRAWINGS  # drawn from its geometry
    gif = tmp_path / "top.gif"
    args = ["--cache-dir", str(cache_dir), "animate", "symmetric_top", "-o", str(gif), "--t-end", "0.3", "--fps", "10"]
    assert main(args) == 0 and gif.read_bytes().startswith(b"GIF8")
    assert "4 frames of t in [0, 0.3] at 10 fps" in capsys.readouterr().out


@pytest.mark.parametrize("points, options, match", [
    (None, {"links": [("top", "bob")]}, r"\['bob'\], not a point or a body"),
    (None, {"trace": ["G"]}, r"\['G'\], not a point or a body"),
    ({"top": (0, 0, 0)}, {}, r"\['top'\] name both a point and a body"),
    (None, {"axes_length": 0.0}, "axes_length must be a positive number"),
    (None, {"axes_length": True}, "axes_length must be a positive number"),
    (None, {"bodies": False}, "has no bodies to draw"),
    ({"p": lc.coordinates("psi theta")}, {}, "the points are 2-D but the bodies"),
])
def test_errors_name_the_culprit(top_run, points, options, match):
    pytest.importorskip("matplotlib")
    with pytest.raises(lc.OptionError, match=match):
        lc.animate(top_run, points, fps=5, dpi=30, **options)


def test_a_system_without_bodies_needs_points(compiled):
    sol = compiled("double_pendulum").simulate((0, 1), t_eval=np.linspace(0, 1, 11))
    with pytest.raises(lc.OptionError, match="'double_pendulum' has no bodies to draw"):
        sol.animate()


def test_a_pickled_solution_keeps_no_kernel(top_run):
    assert copy.deepcopy(top_run).geometry.kernel is top_run.geometry.kernel is not None
    again = pickle.loads(pickle.dumps(top_run))
    assert again.geometry.layout == top_run.geometry.layout and again.geometry.kernel is None
    with pytest.raises(lc.OptionError, match="carries no model geometry"):
        again.animate()


def test_a_kane_model_has_an_empty_geometry(cache_dir):
    """Kane modules define the no-op kernel (GEOMETRY = (), size 0): its runs are drawn from named points."""
    from sympy.physics import mechanics as me

    q, u = me.dynamicsymbols("q u")
    k = sp.Symbol("k", positive=True)
    N, P = me.ReferenceFrame("N"), me.Point("P")
    P.set_vel(N, u * N.x)
    km = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff(lc.t) - u])
    km.kanes_equations([me.Particle("p", P, 1)], [(P, -k * q * N.x)])
    model = lc.compile(km, name="geometry_kane_slider", cache_dir=cache_dir, defaults={"k": 1.0})
    assert model.kernels.GEOMETRY == () and model.kernels.GEOMETRY_SIZE == 0
    sol = model.simulate((0, 1), q0=[1.0], t_eval=np.linspace(0, 1, 11))
    assert sol.geometry.layout == ()
    with pytest.raises(lc.OptionError, match="has no bodies to draw"):
        sol.animate()


def test_an_unplaced_body_is_not_drawn_and_a_link_to_it_says_why(double):
    from dataclasses import replace

    from lagcomp.animation_bodies import BodyGeometry

    sol = double.simulate((0, 1), t_eval=np.linspace(0, 1, 11))
    layout = (*sol.geometry.layout, ("ghost", "unplaced", 6))
    with_ghost = replace(sol, geometry=BodyGeometry(layout, 6, sol.geometry.p, sol.geometry.kernel))
    pytest.importorskip("matplotlib")
    assert list(lc.animate(with_ghost, fps=5, dpi=30).markers) == ["bob1", "bob2"]
    with pytest.raises(lc.OptionError, match=r"\['ghost'\]: the model does not know where"):
        lc.animate(with_ghost, links=[("bob1", "ghost")], fps=5, dpi=30)
