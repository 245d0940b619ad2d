"""The command line and the committed `generated/` modules."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from lagcomp import examples
from lagcomp.cli import main
from lagcomp.codegen.bundled import bundled_sources

GENERATED = Path(__file__).resolve().parents[1] / "generated"


def test_generated_modules_are_current():
    sources = bundled_sources()
    stale = [name for name, text in sources.items()
             if not (GENERATED / name).exists() or (GENERATED / name).read_text(encoding="utf-8") != text]
    assert not stale, f"stale files in generated/: {stale}; regenerate with `lagcomp generate generated/`"
    assert sorted(p.relative_to(GENERATED).as_posix() for p in GENERATED.rglob("*.py")) == sorted(sources)


def test_list_names_every_example(capsys):
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    for name in examples.EXAMPLES:
        assert name in out


def test_run_prints_a_summary_and_saves(capsys, tmp_path, cache_dir):
    out_file = tmp_path / "run.npz"
    code = main(["--cache-dir", str(cache_dir), "run", "sling", "--t-end", "1.5", "--param", "omega=3",
                 "--q0", "0.2", "--out", str(out_file)])
    out = capsys.readouterr().out
    assert code == 0
    assert "status 0" in out and "steps" in out and "max relative drift" in out
    data = np.load(out_file)
    assert data["t"][-1] == 1.5
    np.testing.assert_allclose(data["q"][-1, 0], 0.2 * np.cosh(3 * 1.5), rtol=1e-8)
    assert list(data["param_names"]) == ["m", "omega"] and data["param_values"][1] == 3.0


def test_run_rk4_with_decimation(capsys, cache_dir, tmp_path):
    out_file = tmp_path / "rk4.npz"
    code = main(["--cache-dir", str(cache_dir), "run", "simple_pendulum", "--method", "rk4", "--dt", "0.001",
                 "--t-end", "2", "--save-every", "100", "--out", str(out_file)])
    assert code == 0 and "status 0" in capsys.readouterr().out
    data = np.load(out_file)
    np.testing.assert_allclose(data["t"], np.linspace(0, 2, 21), atol=1e-12)


def test_bad_input_is_a_message_not_a_traceback(capsys, cache_dir):
    assert main(["--cache-dir", str(cache_dir), "run", "no_such_system"]) == 2
    assert "no_such_system" in capsys.readouterr().err
    assert main(["--cache-dir", str(cache_dir), "run", "sling", "--param", "omega=-"]) == 2
    assert main(["--cache-dir", str(cache_dir), "run", "sling", "--param", "mass=2"]) == 2
    assert "Unknown parameter" in capsys.readouterr().err


def test_show_prints_equations_and_module_path(capsys, cache_dir):
    assert main(["--cache-dir", str(cache_dir), "show", "hoop_bead"]) == 0
    out = capsys.readouterr().out
    assert "parameters  p  = (m, R, g, Omega, epsilon)" in out
    assert "M =" in out and "F =" in out and "generated module:" in out


def test_example_arguments(capsys, cache_dir):
    assert main(["--cache-dir", str(cache_dir), "show", "n_link_pendulum", "--arg", "n=2"]) == 0
    assert "theta2" in capsys.readouterr().out


def test_show_derives_once_on_a_cache_miss(capsys, tmp_path, monkeypatch):
    import lagcomp.mechanics.lagrange as lagrange

    calls = []
    original = lagrange.derive
    monkeypatch.setattr(lagrange, "derive", lambda system: calls.append(system.name) or original(system))
    assert main(["--cache-dir", str(tmp_path), "show", "sling"]) == 0
    assert calls == ["sling"]


def test_sweep_over_a_coordinate_and_a_parameter_follows_cosh(capsys, tmp_path, cache_dir):
    """The sling, ρ'' = ω²ρ from rest: ρ(t) = ρ0 cosh(ωt) at every grid point."""
    from lagcomp.integrate.sweep import Sweep

    out_file = tmp_path / "sweep.npz"
    code = main(["--cache-dir", str(cache_dir), "sweep", "sling", "--grid", "rho=0.1:0.3:3", "--param", "omega=1:3:3",
                 "--param", "m=2", "--t-end", "1.5", "--output", "max-energy-error", "--quiet", "--out", str(out_file)])
    out = capsys.readouterr().out
    assert code == 0
    assert "9 trajectories over rho (3 values), omega (3 values)" in out and "status      0: 9" in out
    sweep = Sweep.load_npz(out_file)
    rho0, omega = np.meshgrid(sweep.axes["rho"], sweep.axes["omega"], indexing="ij")
    np.testing.assert_allclose(sweep.final[..., 0], rho0 * np.cosh(omega * 1.5), rtol=1e-8)
    np.testing.assert_array_equal(sweep.t_final, 1.5)


def test_sweep_options_are_checked_with_a_message(capsys, cache_dir):
    for argv, message in [
        (["sweep", "sling"], "Nothing to sweep"),
        (["sweep", "sling", "--grid", "rho=0:1:0"], "LO:HI:N"),
        (["sweep", "sling", "--grid", "rho=0:1:2", "--output", "every=10"], "times=N"),
        (["sweep", "sling", "--grid", "rho=0:1:2", "--method", "rk4", "--output", "times=3"], "every=K"),
        (["sweep", "sling", "--grid", "rho=0:1:2", "--output", "nonsense"], "choose final"),
        (["sweep", "sling", "--grid", "nope=0:1:2"], "nope"),
    ]:
        assert main(["--cache-dir", str(cache_dir), *argv]) == 2, argv
        assert message in capsys.readouterr().err, argv


def test_run_and_sweep_a_users_model_by_the_name_it_was_compiled_under(capsys, tmp_path):
    """x'' = −(k/m) x from x0 = 1: x(t) = cos(√(k/m) t)."""
    import sympy as sp

    import lagcomp as lc

    x, = lc.coordinates("x")
    m, k = sp.symbols("m k", positive=True)
    lc.compile(lc.System([x], T=m * x.diff(lc.t) ** 2 / 2, V=k * x**2 / 2, name="my_oscillator",
                         defaults={"m": 1.0, "k": 4.0}, q0=(1.0,)), cache_dir=tmp_path)
    assert main(["--cache-dir", str(tmp_path), "run", "my_oscillator", "--t-end", "1.0"]) == 0
    out = capsys.readouterr().out
    final = float(out.split("final       x=")[1].split()[0])
    assert abs(final - np.cos(2.0)) < 1e-7
    assert main(["--cache-dir", str(tmp_path), "sweep", "my_oscillator", "--param", "k=1:9:3", "--t-end", "1.0",
                 "--quiet"]) == 0
    assert "3 trajectories over k (3 values)" in capsys.readouterr().out
    assert main(["--cache-dir", str(tmp_path), "run", "not_a_model"]) == 2
    assert "nor the name of a model compiled with lagcomp.compile()" in capsys.readouterr().err


def test_run_a_kane_model_from_its_initial_speeds(capsys, tmp_path):
    """A KanesMethod spring x' = w, m w' = −k x compiled under a name: `--u0` sets w(0), so from x = 0,
    x(t) = (w0/ω) sin ωt with ω = √(k/m) = 2. `--qd0` is refused for it, and `--u0` for a Lagrange model."""
    import sympy as sp
    import sympy.physics.mechanics as me

    import lagcomp as lc

    x, w = me.dynamicsymbols("x w")
    m, k = sp.symbols("m k", positive=True)
    N = me.ReferenceFrame("N")
    P = me.Point("P")
    P.set_vel(N, w * N.x)
    km = me.KanesMethod(N, [x], [w], kd_eqs=[x.diff(me.dynamicsymbols._t) - w])
    km.kanes_equations([me.Particle("p", P, m)], [(P, -k * x * N.x)])
    lc.compile(km, cache_dir=tmp_path, name="kane_spring", defaults={"m": 1.0, "k": 4.0}, q0=[0.0])
    argv = ["--cache-dir", str(tmp_path), "run", "kane_spring", "--t-end", "1.0", "--quiet"]
    assert main([*argv, "--u0", "0.8"]) == 0
    final = float(capsys.readouterr().out.split("final       x=")[1].split()[0])
    assert abs(final - 0.4 * np.sin(2.0)) < 5e-9  # measured 7.3e-10: the 8 digits printed (the run's own error 4.4e-12)
    assert main([*argv, "--u0", "0.8", "--method", "radau"]) == 0    # radau takes Kane models too
    final = float(capsys.readouterr().out.split("final       x=")[1].split()[0])
    assert abs(final - 0.4 * np.sin(2.0)) < 5e-9
    assert main([*argv, "--qd0", "0.8"]) == 2
    assert "give its initial speeds as `u0` (speeds ['w']; --u0 on the command line)" in capsys.readouterr().err
    lc.compile(lc.System([x], T=m * x.diff(lc.t) ** 2 / 2, V=k * x**2 / 2, name="lagrange_spring",
                         defaults={"m": 1.0, "k": 4.0}, q0=(0.0,)), cache_dir=tmp_path)
    assert main(["--cache-dir", str(tmp_path), "run", "lagrange_spring", "--u0", "0.8", "--quiet"]) == 2
    assert "is a Lagrange model: give its initial velocities as `qd0` (--qd0" in capsys.readouterr().err


def test_method_choices_are_the_registrys(capsys):
    """`run` and `sweep` offer every method of the registry (tsit5 and bs3 with the others), no list of their own."""
    import pytest

    from lagcomp.integrate.methods import METHODS

    for command in ("run", "sweep"):
        with pytest.raises(SystemExit):
            main([command, "double_pendulum", "--method", "no_such_method"])
        message = capsys.readouterr().err
        assert all(f"'{name}'" in message for name in METHODS) and "'tsit5'" in message and "'bs3'" in message
def test_precompile_compiles_every_library_driver_of_the_registry(capsys, monkeypatch):
    """Every `Method.driver` / `Method.sweep` in the library is imported (compiled, or loaded from numba's
    cache) and reported with its time, then the hooks models share (`lagcomp.kernel_support.trivial`); a
    registry entry stands in for a driver family still to move."""
    import dataclasses

    from lagcomp.cli import library_drivers
    from lagcomp.integrate import methods

    stand_in = dataclasses.replace(methods.METHODS["rk4"], name="stand_in", sweep=None,
                                   driver="lagcomp.integrate.drivers.sweep_rows:fold_rows")
    monkeypatch.setitem(methods.METHODS, "stand_in", stand_in)
    references = library_drivers()
    assert stand_in.driver in references and len(references) == len(set(references))
    modules = list(dict.fromkeys(reference.partition(":")[0] for reference in references))
    assert main(["precompile"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert len(out) == len(modules) + 2 and out[-1].startswith(f"{len(references)} library drivers ready in ")
    assert out[-2].startswith("lagcomp.kernel_support.trivial and events.unchanged_state (") and out[-2].endswith(" s")
    for i, (line, module) in enumerate(zip(out, modules), 1):
        assert line.startswith(f"[{i}/{len(modules)}] {module} (") and line.endswith(" s")
        assert "compiled in" in line or "loaded from numba's cache in" in line
    assert "sweep_rows (fold_rows): " in "\n".join(out)
