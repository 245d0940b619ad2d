"""The specialised drivers (`lagcomp.integrate.specialize`): bitwise the library drivers' runs, cached with the model.

A specialised driver is the library driver's own function compiled with one model's kernels as compile-time
callees; these tests hold it to the library driver's results bit for bit (`np.array_equal` of every saved time
and state, and the counters) for every method it covers, check that a later process loads its machine code
from numba's cache without writing into the library's cache files, and that the runs it does not cover are
refused before any work.
"""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import lagcomp as lc
from lagcomp import examples
from lagcomp.integrate import simulate as simulate_module
from lagcomp.integrate import specialize
from lagcomp.integrate.methods import METHODS, get_method

ROOT = Path(__file__).resolve().parent.parent


def _same_run(model, **options):
    """Run `model` with the library driver and with the specialised one; assert the two runs are bitwise equal."""
    library = model.simulate((0.0, 5.0), progress=False, specialize=False, **options)
    special = model.simulate((0.0, 5.0), progress=False, specialize=True, **options)
    assert library.status == special.status == 0
    assert np.array_equal(library.t, special.t)
    assert np.array_equal(library.q, special.q)
    assert np.array_equal(library.qd, special.qd)
    # (nfev is not compared: a run counts one more f evaluation per driver call, and the two tiers' calls are sized
    # from step rates learned per tier)
    assert (library.nsteps, library.nrejected) == (special.nsteps, special.nrejected)
    return library


def test_every_specialisable_method_is_tested_here():
    """The methods the tier covers are the ones the tests below compare (a new one needs its test)."""
    assert set(specialize.SPECIALISABLE) == {"rk4", "dopri5", "dop853", "tsit5", "bs3", "verlet", "yoshida4",
                                             "yoshida6"}


@pytest.mark.parametrize("save_every", [1, 7])
def test_rk4_bitwise(compiled, save_every):
    _same_run(compiled("double_pendulum"), method="rk4", dt=1e-3, save_every=save_every)


@pytest.mark.parametrize("options", [{"rtol": 1e-10, "atol": 1e-10}, {"rtol": 1e-8, "save_every": 5},
                                     {"t_eval": np.linspace(0.0, 5.0, 301)}],
                         ids=["every-step", "save-every", "t-eval"])
def test_dop853_bitwise(compiled, options):
    run = _same_run(compiled("double_pendulum"), method="dop853", **options)
    assert run.nsteps > 100


@pytest.mark.parametrize("method", ["dopri5", "tsit5", "bs3"])
def test_other_embedded_pairs_bitwise(compiled, method):
    """One specialised module serves every embedded pair: the same driver, their tableaux as arguments."""
    _same_run(compiled("double_pendulum"), method=method, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("method", ["verlet", "yoshida4", "yoshida6"])
def test_compositions_bitwise(compiled, method):
    _same_run(compiled("simple_pendulum"), method=method, dt=1e-3)


def test_specialised_module_is_readable_code(compiled):
    """The generated module: a header that says what it is, the library driver and the model's kernels imported,
    one `run` taking the library driver's arguments after the kernels."""
    model = compiled("double_pendulum")
    source = specialize.module_source(model, get_method("rk4"))
    compile(source, "specialised", "exec")
    assert source.startswith('"""The library driver lagcomp.integrate.drivers.fixed_step:runge_kutta_run '
                             "specialised for the model 'double_pendulum'")
    assert "Do not edit." in source and specialize.library_digest() in source
    assert f"from {model.kernels.eager_module.__name__} import rhs\n" in source
    assert "from lagcomp.kernel_support.trivial import project, constraint_residual\n" in source   # (no constraints)
    assert "def run(y, clock, counters, p, projecting, residual_max, t0, dt, n_steps," in source


def test_loaded_from_cache_in_a_new_process(compiled, cache_dir):
    """A second process finds the specialised module and numba's machine code of `run`: no compile."""
    model = compiled("double_pendulum")
    model.simulate((0.0, 0.1), method="rk4", dt=1e-3, specialize=True, progress=False)
    assert specialize.cached(model, get_method("rk4"))
    script = textwrap.dedent(f"""
        import lagcomp as lc
        from lagcomp import examples
        from lagcomp.integrate import specialize
        from lagcomp.integrate.methods import get_method
        model = lc.compile(examples.get("double_pendulum"), cache_dir={str(cache_dir)!r})
        method = get_method("rk4")
        assert specialize.cached(model, method)
        model.simulate((0.0, 0.1), method="rk4", dt=1e-3, specialize=True, progress=False)
        run = specialize.driver(model, method)
        print(sum(run.stats.cache_hits.values()), sum(run.stats.cache_misses.values()))
    """)
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, check=True)
    assert out.stdout.split() == ["1", "0"], out.stdout + out.stderr


def test_library_functions_called_with_kernels_are_uncached_copies():
    """The specialised embedded driver calls copies of the event helpers, themselves calling copies, none cached by
    numba: a cached library helper compiled for a model's kernels would add an entry for them to the library's own
    cache files in every process (the kernels' type is keyed on the dispatcher, which pickles afresh each time)."""
    from numba.core.caching import NullCache

    from lagcomp.integrate.compile_time import uncached_copy
    from lagcomp.integrate.drivers import embedded, events

    copy = uncached_copy(embedded.embedded_run)
    assert isinstance(copy._cache, NullCache) and copy.py_func.__code__ is embedded.embedded_run.py_func.__code__
    for name in ("record_events_between", "restart_brackets", "reset_state", "dense_state"):
        helper = copy.py_func.__globals__[name]
        assert helper is uncached_copy(getattr(events, name)) and isinstance(helper._cache, NullCache)
    called = copy.py_func.__globals__["record_events_between"].py_func.__globals__["event_root"]
    assert called is uncached_copy(events.event_root)
    assert embedded.embedded_run.py_func.__globals__["record_events_between"] is events.record_events_between


def test_not_cached_before_a_run_asks(compiled):
    model = compiled("double_pendulum")
    assert not specialize.cached(model, get_method("taylor"))


@pytest.mark.parametrize("method", sorted(set(METHODS) - set(specialize.SPECIALISABLE) - {"rattle"}))
def test_methods_not_covered_are_refused(compiled, method):
    with pytest.raises(lc.OptionError, match=f"`specialize=True` with method '{method}'"):
        compiled("simple_pendulum").simulate((0.0, 1.0), method=method, dt=None if METHODS[method].adaptive else 0.1,
                                             specialize=True)


def test_rattle_is_refused(compiled):
    """(rattle runs constrained separable models only, which its own check asks for first)"""
    model = compiled("simple_pendulum")
    with pytest.raises(lc.OptionError, match="`specialize=True` with method 'rattle'"):
        specialize.check(get_method("rattle"), model, model)


def test_refusals(compiled):
    model = compiled("double_pendulum")
    with pytest.raises(lc.OptionError, match="`specialize` must be True, False or None"):
        model.simulate((0.0, 1.0), specialize="yes")
    with pytest.raises(lc.OptionError, match="`sensitivities=`"):
        model.simulate((0.0, 1.0), specialize=True, sensitivities=["l1"])


def test_precompile_specialize(compiled, cache_dir, capsys):
    """``lagcomp precompile MODEL --specialize METHOD`` compiles (or loads) the model's specialised driver and says
    which; a method the tier does not cover is refused with the list of those it covers."""
    from lagcomp.cli import main

    model = compiled("simple_pendulum")
    assert main(["--cache-dir", str(cache_dir), "precompile", "simple_pendulum", "--specialize", "verlet"]) == 0
    out = capsys.readouterr().out
    assert "simple_pendulum: verlet driver specialised, " in out
    assert "compiled in" in out or "loaded from numba's cache in" in out
    assert specialize.cached(model, get_method("verlet"))
    assert main(["--cache-dir", str(cache_dir), "precompile", "simple_pendulum", "--specialize-sweep", "verlet"]) == 0
    assert "simple_pendulum: verlet sweep loop specialised, " in capsys.readouterr().out
    assert specialize.cached(model, get_method("verlet"), sweep=True)
    assert main(["--cache-dir", str(cache_dir), "precompile", "simple_pendulum", "--specialize", "radau"]) == 2
    assert "--specialize radau: the specialised drivers cover rk4" in capsys.readouterr().err
    assert main(["--cache-dir", str(cache_dir), "precompile", "--specialize", "rk4"]) == 2
    assert "name the model" in capsys.readouterr().err


def test_reset_events_bitwise(cache_dir):
    """A model whose event resets the state (a bouncing ball): the specialised embedded driver calls the model's own
    ``event_reset`` kernel; its steps, rows and event records are the library driver's, bit for bit."""
    from tests.test_reset_events import _ball

    model = lc.compile(_ball(name="specialised_ball"), cache_dir=cache_dir)
    library = model.simulate((0.0, 3.0), rtol=1e-10, atol=1e-10, progress=False, specialize=False)
    special = model.simulate((0.0, 3.0), rtol=1e-10, atol=1e-10, progress=False, specialize=True)
    assert library.events["impact"].t.size > 5
    assert np.array_equal(library.t, special.t) and np.array_equal(library.q, special.q)
    assert np.array_equal(library.qd, special.qd)
    for field in ("t", "q", "qd", "q_after", "qd_after"):
        assert np.array_equal(getattr(library.events["impact"], field), getattr(special.events["impact"], field))


# -- the automatic tier (``specialize=None``, the default) ----------------------------------------------------------


def _counting_driver(monkeypatch):
    """Make `specialize.driver` hand out its drivers wrapped to count their calls; returns the list of calls."""
    calls, real = [], specialize.driver

    def counted(model, method):
        run = real(model, method)

        def call(*args):
            calls.append(method.name)
            return run(*args)
        return call
    monkeypatch.setattr(specialize, "driver", counted)
    return calls


def _several_calls(monkeypatch):
    """Cut the next run into driver calls of a few dozen steps at first (no step rate learned before)."""
    import weakref

    monkeypatch.setattr(simulate_module, "_STEP_RATES", weakref.WeakKeyDictionary())
    monkeypatch.setattr(simulate_module, "FIRST_BUDGET", 32)


@pytest.mark.parametrize("method, options", [("dop853", {"rtol": 1e-10, "atol": 1e-10}), ("rk4", {"dt": 1e-3})])
def test_automatic_tier_moves_a_long_run_to_a_cached_driver(compiled, monkeypatch, method, options):
    """A run whose rest is estimated to take `AUTO_REMAINING_SECONDS` or more moves between two driver calls to the
    model's specialised driver when numba's cache holds it (not loaded in this process): the run is bitwise the
    library driver's."""
    model, m = compiled("double_pendulum"), get_method(method)
    specialize.prepare(model, m)
    specialize._LOADED.pop(model.kernels, None)           # in the cache, not loaded: as in a new process
    library = model.simulate((0.0, 10.0), method=method, progress=False, specialize=False, **options)
    _several_calls(monkeypatch)
    calls = _counting_driver(monkeypatch)
    monkeypatch.setattr(specialize, "AUTO_REMAINING_SECONDS", 0.0)
    auto = model.simulate((0.0, 10.0), method=method, progress=False, **options)
    assert calls and specialize.loaded(model, m)
    assert np.array_equal(library.t, auto.t) and np.array_equal(library.q, auto.q)
    assert np.array_equal(library.qd, auto.qd)
    assert (library.nsteps, library.nrejected) == (auto.nsteps, auto.nrejected)


def test_automatic_tier_keeps_short_runs_and_uncached_drivers_on_the_library(cache_dir, monkeypatch):
    """A run estimated to end sooner than `AUTO_REMAINING_SECONDS` stays on the library driver though the specialised
    one is cached; a long run whose specialised driver is not cached stays there too, and compiles nothing."""
    system = examples.get("simple_pendulum")
    model = lc.compile(dataclasses.replace(system, name="auto_tier_pendulum"), cache_dir=cache_dir)
    rk4, verlet = get_method("rk4"), get_method("verlet")
    specialize.prepare(model, verlet)
    specialize._LOADED.pop(model.kernels, None)
    _several_calls(monkeypatch)
    calls = _counting_driver(monkeypatch)
    model.simulate((0.0, 10.0), method="verlet", dt=1e-3, progress=False)   # ~ms: far below one second
    assert calls == [] and not specialize.loaded(model, verlet)
    _several_calls(monkeypatch)
    monkeypatch.setattr(specialize, "AUTO_REMAINING_SECONDS", 0.0)
    model.simulate((0.0, 10.0), method="rk4", dt=1e-3, progress=False)
    assert calls == [] and not specialize.cached(model, rk4)


def test_automatic_tier_starts_with_a_loaded_driver(compiled, monkeypatch):
    """Loaded in this process (an earlier run asked for it), the specialised driver takes every call of a run, however
    short: bitwise the library driver's run."""
    model, m = compiled("double_pendulum"), get_method("dop853")
    model.simulate((0.0, 0.1), progress=False, specialize=True)
    assert specialize.loaded(model, m)
    calls = _counting_driver(monkeypatch)
    specialize._LOADED[model.kernels][m.driver] = specialize.driver(model, m)   # (the counting one)
    library = model.simulate((0.0, 1.0), rtol=1e-10, atol=1e-10, progress=False, specialize=False)
    monkeypatch.setattr(simulate_module, "_bound_drivers", lambda *args, **kwargs: pytest.fail("library driver"))
    auto = model.simulate((0.0, 1.0), rtol=1e-10, atol=1e-10, progress=False)
    assert calls
    assert np.array_equal(library.t, auto.t) and np.array_equal(library.q, auto.q)
    assert np.array_equal(library.qd, auto.qd)


@pytest.mark.parametrize("method, options", [("dop853", {"rtol": 1e-9, "atol": 1e-9}), ("rk4", {"dt": 1e-2})])
def test_automatic_tier_of_a_sweep(compiled, monkeypatch, method, options):
    """A sweep of `sweep.AUTO_TRAJECTORIES` or more trajectories runs the model's specialised sweep loop when numba's
    cache holds it (``lagcomp precompile MODEL --specialize-sweep METHOD``): every output bitwise the library loop's;
    fewer trajectories keep the library loop."""
    from lagcomp.integrate import sweep as sweep_module

    model, m = compiled("double_pendulum"), get_method(method)
    reference = m.sweep
    specialize._LOADED.get(model.kernels, {}).pop(reference, None)
    grid = {"theta1": np.linspace(-2.0, 2.0, 6), "theta2": [0.5, 1.5]}
    run = lambda: model.sweep((0.0, 2.0), grid, method=method, workers=1, progress=False, **options)
    library = run()
    specialize.prepare(model, m, sweep=True)
    specialize._LOADED[model.kernels].pop(reference)      # in the cache, not loaded: as in a new process
    monkeypatch.setattr(sweep_module, "AUTO_TRAJECTORIES", 13)
    run()
    assert not specialize.loaded(model, m, sweep=True)     # 12 trajectories: too few
    monkeypatch.setattr(sweep_module, "AUTO_TRAJECTORIES", 12)
    calls, real = [], specialize.loaded_for

    def counted(kernels, reference):
        loop = real(kernels, reference)
        if loop is None:
            return None

        def call(*args):
            calls.append(reference)
            return loop(*args)
        return call
    monkeypatch.setattr(specialize, "loaded_for", counted)
    auto = run()
    assert specialize.loaded(model, m, sweep=True) and calls      # the chunks ran the specialised loop
    assert (library.status == 0).all()
    for name in ("final", "t_final", "status", "energy_error"):
        assert np.array_equal(getattr(library, name), getattr(auto, name)), name
