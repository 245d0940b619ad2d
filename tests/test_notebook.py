"""Results in a notebook: `Solution.to_xarray()` and the HTML summaries of Model and Solution (issue 23)."""

from __future__ import annotations

import dataclasses
import html
import sys

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc

xr = pytest.importorskip("xarray")


def _bits(values) -> np.ndarray:
    """The float64 values as their bit patterns: equal arrays of these are equal bit for bit (NaN included)."""
    return np.ascontiguousarray(values, dtype=np.float64).view(np.int64)


def _same_bits(a, b) -> bool:
    return np.shape(a) == np.shape(b) and np.array_equal(_bits(a), _bits(b))


def test_dataset_holds_the_solutions_arrays_bit_for_bit_with_events_and_attrs(compiled):
    model = compiled("henon_heiles")
    sol = model.simulate((0, 20), rtol=1e-10, atol=1e-12)
    ds = sol.to_xarray()
    assert isinstance(ds, xr.Dataset) and ds.sizes["t"] == len(sol.t)
    assert _same_bits(ds["t"].values, sol.t)
    for j, name in enumerate(model.coordinates):
        assert _same_bits(ds[name].values, sol.q[:, j]) and ds[name].dims == ("t",)
        assert _same_bits(ds[f"{name}_dot"].values, sol.qd[:, j])
    assert _same_bits(ds["energy"].values, sol.energy)
    assert "energy_function" not in ds  # h = T + V here: no second copy
    for name, record in sol.events.items():
        assert len(record) > 0
        assert _same_bits(ds[f"event_{name}_t"].values, record.t) and ds[f"event_{name}_t"].dims == (f"event_{name}",)
        assert _same_bits(ds[f"event_{name}_state"].values, np.hstack([record.q, record.qd]))
    assert list(ds["state"].values) == ["x", "y", "x_dot", "y_dot"]
    assert ds.attrs["model"] == "henon_heiles" == sol.model_name
    assert (ds.attrs["method"], ds.attrs["status"], ds.attrs["message"]) == (sol.method, sol.status, sol.message)
    assert (ds.attrs["nfev"], ds.attrs["nsteps"], ds.attrs["record"]) == (sol.nfev, sol.nsteps, "trajectory")
    assert ds.attrs["param_lam"] == sol.params["lam"] == 1.0
    assert ds["x"].attrs["role"] == "coordinate" and ds["x_dot"].attrs["role"] == "velocity"


def test_summary_record_gives_its_kept_rows_and_says_so(compiled):
    model = compiled("henon_heiles")
    full = model.simulate((0, 20))
    summary = model.simulate((0, 20), record="summary")
    ds = summary.to_xarray()
    assert ds.sizes["t"] == 2 and _same_bits(ds["t"].values, full.t[[0, -1]])
    assert _same_bits(ds["y"].values, full.q[[0, -1], 1])
    assert ds.attrs["record"] == "summary" and ds.attrs["summary_rows"] == len(full.t)
    assert ds.attrs["summary_energy_error"] == summary.summary.energy_error
    assert "kept of" in summary._repr_html_()


def test_constrained_model_has_its_reactions_as_variables(compiled):
    model = compiled("hoop_bead_reaction")
    sol = model.simulate((0, 1))
    ds = sol.to_xarray()
    assert model.constraints == ("drive",)
    assert _same_bits(ds["reaction_drive"].values, sol.reactions["drive"])
    assert ds["reaction_drive"].attrs["role"] == "reaction"
    assert ds.attrs["constraint_residual"] == sol.constraint_residual
    page = sol._repr_html_()
    assert "constraint residual" in page and "<code>drive</code>" in page
    assert "<code>drive</code> (holonomic)" in model._repr_html_()


def _kane_pendulum_with_rod_force():
    """A pendulum of length l, speed u = l q̇, with an auxiliary speed along the rod: the rod force R."""
    from sympy.physics import mechanics as me

    q, u, ua, R = me.dynamicsymbols("q u ua R")
    m, length, g = sp.symbols("m l g", positive=True)
    N = me.ReferenceFrame("N")
    pivot = me.Point("O")
    pivot.set_vel(N, 0)
    A = N.orientnew("A", "Axis", [q, N.z])
    P = pivot.locatenew("P", -length * A.y)
    P.set_vel(N, u * A.x + ua * A.y)
    km = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff(me.dynamicsymbols._t) - u / length], u_auxiliary=[ua])
    km.kanes_equations([me.Particle("bob", P, m)], [(P, -m * g * N.y), (P, R * A.y)])
    return km


def test_kane_solution_has_speeds_velocities_and_reactions(cache_dir):
    model = lc.compile(_kane_pendulum_with_rod_force(), cache_dir=cache_dir, name="notebook_kane_pendulum",
                       defaults=dict(m=1.3, l=0.8, g=9.81))
    sol = model.simulate((0, 1.0), q0=[1.0], u0=[0.5])
    ds = sol.to_xarray()
    assert _same_bits(ds["q"].values, sol.q[:, 0])
    assert _same_bits(ds["q_dot"].values, sol.qd[:, 0])  # q̇ = u / l from the kinematic equation
    assert _same_bits(ds["u"].values, sol.u[:, 0]) and ds["u"].attrs["role"] == "speed"
    assert _same_bits(ds["reaction_R"].values, sol.reactions["R"])
    assert ds.attrs["model"] == "notebook_kane_pendulum"
    assert _same_bits(ds["energy"].values, sol.energy)
    page = model._repr_html_()
    assert "KaneModel" in page and "<code>u</code>" in page and "<code>R</code>" in page
    assert "<td><code>u</code></td>" in sol._repr_html_()  # the state table names the speed


def test_user_text_is_escaped_in_the_html(cache_dir):
    (x,) = lc.coordinates("θ")
    k = sp.Symbol("k<1&", positive=True)
    description = "A <b>spring</b> & a mass; 'quoted' \"text\"."
    system = lc.System(coordinates=(x,), T=x.diff(lc.t) ** 2 / 2, V=k * x**2 / 2, name="escaped_spring",
                       description=description, defaults={k: 0.5}, q0=(1.0,), qd0=(0.0,))
    model = lc.compile(system, cache_dir=cache_dir)
    page = model._repr_html_()
    assert html.escape(description) in page and "<b>" not in page
    assert "<code>k&lt;1&amp;</code> = 0.5" in page and "<code>θ</code>" in page
    sol = model.simulate((0, 0.5), method="rk4", dt=0.01)
    sol = dataclasses.replace(sol, message="done <script>alert(1)</script>")
    page = sol._repr_html_()
    assert "<script>" not in page and "&lt;script&gt;" in page
    assert sol.to_xarray().attrs["param_k<1&"] == 0.5


def test_names_given_twice_are_refused(compiled):
    sol = compiled("henon_heiles").simulate((0, 1), events=False)
    with pytest.raises(ValueError, match="'x_dot'"):  # coordinates x and x_dot: the velocity of x is x_dot too
        dataclasses.replace(sol, coordinates=("x", "x_dot")).to_xarray()
    with pytest.raises(ValueError, match=r"\['t'\]"):  # a coordinate named t
        dataclasses.replace(sol, coordinates=("t", "y")).to_xarray()


def test_missing_xarray_says_how_to_install_it(compiled, monkeypatch):
    sol = compiled("henon_heiles").simulate((0, 1))
    monkeypatch.setitem(sys.modules, "xarray", None)
    with pytest.raises(ImportError, match=r"Solution.to_xarray needs xarray: pip install 'lagcomp\[xarray\]'"):
        sol.to_xarray()
    assert "henon_heiles" in sol._repr_html_()  # the HTML needs nothing beyond numpy


def test_energy_function_is_a_variable_where_it_differs_from_t_plus_v(compiled):
    """A Solution whose h differs from T + V (as under imposed motions), built from a run by replacing its values."""
    from lagcomp.integrate.recording import Observed

    sol = compiled("henon_heiles").simulate((0, 1), events=False)
    energy, h, momenta, summary = sol.observed.values()
    shifted = dataclasses.replace(sol, observed=Observed(values=(energy, h + 0.25, momenta, summary)))
    ds = shifted.to_xarray()
    assert _same_bits(ds["energy_function"].values, h + 0.25) and _same_bits(ds["energy"].values, energy)
