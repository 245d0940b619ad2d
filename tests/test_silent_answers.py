"""Issue 36, parts 2 and 3: inputs that were answered silently (or wrongly), or with a raw traceback.

Each test reproduces what a user met, through the public API only, and checks
the answer lagcomp gives now: a refusal naming the culprit, or the right result.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.model import t

x, y = lc.coordinates("x y")
theta = lc.coordinates("theta")[0]
m, k, c, g, l = sp.symbols("m k c g l", positive=True)


def oscillator(**overrides) -> lc.System:
    spec = dict(coordinates=[x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, name="silent_oscillator",
                defaults={"m": 1.0, "k": 1.0}, q0=(1.0,))
    spec.update(overrides)
    return lc.System(**spec)


@pytest.fixture(scope="module")
def model(cache_dir):
    return lc.compile(oscillator(), cache_dir=cache_dir)


# -- 2.1: a Rayleigh function must be a quadratic form in the velocities -----------------


@pytest.mark.parametrize("dissipation", [c * theta**2 / 2, c * theta * theta.diff(t), c * theta.diff(t) ** 4 / 4,
                                         c * theta.diff(t) ** 2 / 2 + c * theta**2 / 2])
def test_dissipation_that_is_no_quadratic_form_in_the_velocities_is_refused(dissipation, tmp_path):
    system = lc.System([theta], T=theta.diff(t) ** 2 / 2, V=-sp.cos(theta), dissipation=dissipation,
                       name="silent_damped")
    with pytest.raises(lc.ModelError, match=r"dissipation function D of 'silent_damped'.*quadratic form"):
        lc.compile(system, cache_dir=tmp_path)


def test_quadratic_dissipation_damps_at_the_rate_it_says(cache_dir):
    """D = c θ̇²/2 with q-dependent coefficients still compiles: θ̈ = −θ − c θ̇ (linear), energy loss rate = −2D."""
    system = lc.System([theta], T=theta.diff(t) ** 2 / 2, V=theta**2 / 2,
                       dissipation=c * (1 + theta**2) * theta.diff(t) ** 2 / 2, name="silent_quadratic_damping")
    model = lc.compile(system, cache_dir=cache_dir)
    out = np.empty(2)
    model.kernels.rhs(0.0, np.array([0.5, 2.0]), model.parameter_vector({"c": 0.3}), out)
    assert out[1] == pytest.approx(-0.5 - 0.3 * (1 + 0.25) * 2.0, rel=1e-15)


# -- 2.6: a cache directory given with ~ ----------------------------------------------


def test_cache_dir_with_tilde_is_the_users_home(tmp_path, monkeypatch):
    home, elsewhere = tmp_path / "home", tmp_path / "cwd"
    home.mkdir(), elsewhere.mkdir()
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(elsewhere)
    system = oscillator(name="silent_tilde")
    lc.compile(system, cache_dir="~/lc-cache")
    assert not (elsewhere / "~").exists()
    assert any((home / "lc-cache" / "modules").glob("silent_tilde*.py"))
    monkeypatch.setenv("LAGCOMP_CACHE_DIR", "~/lc-env-cache")
    lc.compile(system)
    assert not (elsewhere / "~").exists()
    assert any((home / "lc-env-cache" / "modules").glob("silent_tilde*.py"))
    assert lc.load("silent_tilde", cache_dir=Path("~") / "lc-cache").parameters == ("k", "m")


# -- 2.7: booleans are no parameter values ----------------------------------------------


@pytest.mark.parametrize("value", [True, False, np.bool_(True)])
def test_boolean_parameter_values_are_refused(model, value):
    with pytest.raises(lc.ParameterError, match=r"`m`.*boolean"):
        model.simulate((0.0, 0.1), params={"m": value})
    with pytest.raises(lc.ParameterError, match=r"`k`.*boolean"):
        oscillator(defaults={"m": 1.0, "k": value})
    with pytest.raises(lc.ParameterError, match=r"`m`.*boolean"):
        model.fit([0.5, 1.0], [[0.1], [0.2]], {"m": value})


@pytest.mark.parametrize("grid", [{"m": [1.0, True]}, {"m": np.array([True, False])}, {"x": (0.0, np.bool_(False))}])
def test_boolean_grid_values_are_refused(model, grid):
    """A sweep grid of flags (of a parameter or a coordinate) would run m = 1 and m = 0: refused, as in params."""
    (name,) = grid
    with pytest.raises(lc.OptionError, match=rf"Grid values of `{name}`.*boolean"):
        model.sweep((0.0, 0.1), grid)
    with pytest.raises(lc.OptionError, match=r"explicit grid.*boolean"):
        model.sweep((0.0, 0.1), [[1.0, True]], names=["m", "k"])


# -- 2.2: normal modes only about an equilibrium ----------------------------------------


@pytest.mark.parametrize("mass", [1.0, 1e-6, 1e6])
def test_normal_modes_away_from_an_equilibrium_are_refused_with_the_distance(compiled, mass):
    """The pendulum at θ = 1: F = −m g l sin 1 (the message gives it), against the size of the terms
    (`RestForces.force_scale`: |∂F/∂θ| |θ| = m g l cos 1 and the parameters' |∂F/∂p| |p|, each at most |F|): a
    ratio between sin 1/(cos 1 + 3 sin 1) and tan 1, far from the 1e-10 of an equilibrium, whatever m."""
    from lagcomp import analysis as an

    pendulum = compiled("simple_pendulum")
    params = {"m": mass, "l": 1.0, "g": 9.81}
    force = mass * 9.81 * np.sin(1.0)
    with pytest.raises(lc.LinearizationError, match=r"not an equilibrium: max \|F\(q, 0, t\)\| = " + re.escape(f"{force:.3g};")) as info:
        an.normal_modes(pendulum, [1.0], params)
    ratio = float(re.search(r"the worst force is (\S+) times", str(info.value)).group(1))
    assert np.sin(1.0) / (np.cos(1.0) + 3 * np.sin(1.0)) * 0.99 <= ratio <= np.tan(1.0) * 1.01
    assert "find_equilibrium" in str(info.value)
    with pytest.raises(lc.LinearizationError, match="not an equilibrium"):
        an.normal_modes(an.linearize(pendulum, [1.0], params))
    # at the equilibria themselves, rounding aside (sin π ≈ 1.2e-16), the verdicts stand
    assert an.normal_modes(pendulum, [np.pi], params).stability == "unstable"
    assert an.normal_modes(pendulum, [0.0], params).frequencies == pytest.approx([np.sqrt(9.81)], rel=1e-14)


# -- 2.9: a fit that wanders where the model cannot run ----------------------------------


def test_fit_of_an_inseparable_pair_wandering_to_a_singular_mass_says_to_bound_it(cache_dir):
    """A damped free particle identifies c/m only: unbounded, least_squares takes m through 0."""
    system = lc.System([x], T=m * x.diff(t) ** 2 / 2, dissipation=c * x.diff(t) ** 2 / 2, name="silent_pair",
                       defaults={"m": 1.0, "c": 0.3}, q0=(0.0,), qd0=(1.0,))
    model = lc.compile(system, cache_dir=cache_dir)
    times = np.linspace(0.1, 5.0, 30)
    observed = model.simulate((0.0, 5.0), t_eval=times).y[:, 0] + 1e-3 * np.sin(7 * times)
    with pytest.raises(lc.IntegrationError, match=r"trial parameters c=.*m=.*bound the parameters") as info:
        model.fit(times, observed, {"c": 1.0, "m": 0.2})
    assert isinstance(info.value.__cause__, lc.SingularMassMatrixError)
    bounded = model.fit(times, observed, {"c": 1.0, "m": 0.2}, bounds={"m": (0.1, 10.0)}, fixed={})
    assert bounded.estimates["c"] / bounded.estimates["m"] == pytest.approx(0.3, rel=1e-2)


# -- 2.11: stiffness advice the model can follow ------------------------------------------


def _stiffness_messages(run) -> list[str]:
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run()
    return [str(w.message) for w in caught if issubclass(w.category, lc.StiffnessWarning)]


def test_stiffness_advice_does_not_send_a_model_with_contacts_or_function_inputs_to_radau(cache_dir):
    """A heavily damped x (rates −1e4 and −1e−4: stiff) beside a ball over a floor, and pushed by a function."""
    import numba

    damped = dict(T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=m * g * y + k * x**2 / 2,
                  dissipation=c * x.diff(t) ** 2 / 2, defaults={"m": 1.0, "g": 9.81, "k": 1.0, "c": 1e4})
    floor = lc.compile(lc.System([x, y], **damped, events=[lc.Contact("floor", y, restitution=0.5)],
                                 name="silent_stiff_floor", q0=(1.0, 1.0)), cache_dir=cache_dir)
    pushed = lc.compile(lc.System([x, y], **damped, forces=[lc.Input("f"), 0], name="silent_stiff_pushed",
                                  q0=(1.0, 1.0)), cache_dir=cache_dir)
    options = dict(method="dopri5", rtol=1e-6, atol=1e-6)
    (contact,) = _stiffness_messages(lambda: floor.simulate((0.0, 2.0), **options))
    assert 'Use method="radau"' not in contact and "['floor']" in contact and "max_steps" in contact
    with pytest.raises(lc.OptionError):  # what the advice keeps away from
        floor.simulate((0.0, 2.0), method="radau")
    function = numba.njit(lambda t, y, p: 0.0)
    (driven,) = _stiffness_messages(lambda: pushed.simulate((0.0, 2.0), inputs={"f": function}, **options))
    assert 'Use method="radau"' not in driven and "['f']" in driven and "law" in driven
    (swept,) = _stiffness_messages(lambda: pushed.sweep((0.0, 2.0), {"c": [1e4, 2e4]}, inputs={"f": function},
                                                        progress=False, **options))
    assert 'Use method="radau"' not in swept and "['f']" in swept
    # the same model given the input as a table: radau takes it, and the advice says so
    (tabled,) = _stiffness_messages(lambda: pushed.simulate((0.0, 2.0), inputs={"f": 0.0}, **options))
    assert 'Use method="radau"' in tabled
    assert pushed.simulate((0.0, 2.0), inputs={"f": 0.0}, method="radau").status == 0


# -- 2.3: function inputs read only what they are given -----------------------------------


@pytest.fixture(scope="module")
def pushed(cache_dir):
    """m ẍ = −k x + f(t): two parameters, one input."""
    return lc.compile(oscillator(forces=[lc.Input("f")], name="silent_pushed"), cache_dir=cache_dir)


def test_function_input_reading_past_the_parameters_or_the_state_is_refused(pushed):
    import numba

    for function in (numba.njit(lambda t, y, p: p[40]), numba.njit(lambda t, y, p: y[7]),
                     numba.njit(lambda t, y, p: p[2])):
        with pytest.raises(lc.OptionError, match=r"Input `f`.*outside.*`y` holds the 2 values.*`p` the 2 param"):
            pushed.simulate((0.0, 1.0), inputs={"f": function})
        with pytest.raises(lc.OptionError, match=r"Input `f`.*outside"):
            pushed.sweep((0.0, 1.0), {"k": [1.0, 2.0]}, inputs={"f": function}, progress=False)


def test_function_input_sees_the_parameters_in_order_and_the_state(pushed):
    """p is the parameters, in `Model.parameters` order (k, m), and nothing after them; y is (x, ẋ)."""
    import numba

    assert pushed.parameters == ("k", "m")
    cancel = numba.njit(lambda t, y, p: p[0] * y[0])  # f = k x: the spring cancelled, x = 1 + ẋ0 t
    sol = pushed.simulate((0.0, 1.0), qd0=[0.5], inputs={"f": cancel}, params={"k": 3.0}, rtol=1e-12, atol=1e-12)
    assert sol.q[-1, 0] == pytest.approx(1.5, rel=1e-12)
    sizes = numba.njit(lambda t, y, p: 1000.0 * p.size + y.size)  # f = 2002: x = 2002 t²/2 with k = 0, m = 1
    sol = pushed.simulate((0.0, 1e-3), q0=[0.0], inputs={"f": sizes}, params={"k": 0.0}, rtol=1e-12, atol=1e-12)
    assert sol.q[-1, 0] == pytest.approx(2002 * 1e-6 / 2, rel=1e-12)


# -- part 3: what gave a raw traceback -------------------------------------------------------


def test_input_on_a_system_without_parameters_compiles_and_runs(cache_dir):
    """θ̈ = −sin θ + F with F = 0.5 constant: the energy ½θ̇² − cos θ − F θ is conserved."""
    system = lc.System([theta], T=theta.diff(t) ** 2 / 2, V=-sp.cos(theta), forces=[lc.Input("F")],
                       name="silent_no_parameters")
    model = lc.compile(system, cache_dir=cache_dir)
    assert model.parameters == () and model.inputs == ("F",)
    sol = model.simulate((0.0, 3.0), q0=[0.1], inputs={"F": 0.5}, rtol=1e-12, atol=1e-12)
    energy = sol.qd[:, 0] ** 2 / 2 - np.cos(sol.q[:, 0]) - 0.5 * sol.q[:, 0]
    assert sol.status == 0 and np.max(np.abs(energy - energy[0])) < 1e-10


def test_plots_given_the_wrong_result_say_what_they_draw(model):
    pytest.importorskip("matplotlib")
    from lagcomp import plots

    sweep = model.sweep((0.0, 1.0), {"k": [1.0, 2.0]}, progress=False)
    sol = model.simulate((0.0, 1.0))
    with pytest.raises(lc.OptionError, match=r"'energy'.*energy_error") as info:
        plots.plot_sweep(sweep, "energy")
    assert "t_final" in str(info.value)
    with pytest.raises(lc.OptionError, match=r"plot_run draws a Solution.*Sweep.*plot_sweep"):
        plots.plot_run(sweep)
    with pytest.raises(lc.OptionError, match=r"plot_coordinates draws a Solution"):
        plots.plot_coordinates(sweep)
    with pytest.raises(lc.OptionError, match=r"plot_sweep draws a Sweep.*Solution"):
        plots.plot_sweep(sol)
    assert plots.plot_sweep(sweep, "t_final") is not None and plots.plot_run(sol) is not None


def test_saving_into_a_missing_directory_names_it(model, tmp_path):
    sol = model.simulate((0.0, 1.0))
    sweep = model.sweep((0.0, 1.0), {"k": [1.0, 2.0]}, progress=False)
    missing = tmp_path / "nonexistent" / "dir"
    for result in (sol, sweep):
        with pytest.raises(lc.OptionError, match=rf"{missing}.*does not exist"):
            result.save_npz(missing / "run.npz")
        assert not missing.exists()


def test_loading_a_solution_file_as_a_sweep_says_what_it_holds(model, tmp_path):
    sol = model.simulate((0.0, 1.0))
    sol.save_npz(tmp_path / "run.npz")
    with pytest.raises(lc.OptionError, match=r"run\.npz.*not a Sweep.*Solution"):
        lc.Sweep.load_npz(tmp_path / "run.npz")
    np.savez(tmp_path / "other.npz", a=np.zeros(3))
    with pytest.raises(lc.OptionError, match=r"other\.npz.*not a Sweep"):
        lc.Sweep.load_npz(tmp_path / "other.npz")
    model.sweep((0.0, 1.0), {"k": [1.0, 2.0]}, progress=False).save_npz(tmp_path / "sweep.npz")
    assert lc.Sweep.load_npz(tmp_path / "sweep.npz").names == ("k",)


def test_an_event_the_run_has_not_is_named_with_those_it_has(cache_dir):
    ball = lc.compile(oscillator(V=m * g * x, defaults={"m": 1.0, "g": 9.81}, name="silent_ball",
                                 events=[lc.Event("floor", x, direction=-1, terminal=True)]), cache_dir=cache_dir)
    sol = ball.simulate((0.0, 2.0))
    assert len(sol.events["floor"]) == 1
    with pytest.raises(lc.OptionError, match=r"'impact'.*\['floor'\]") as info:
        sol.events["impact"]
    assert isinstance(info.value, KeyError) and "impact" in str(info.value)
    assert sol.events.get("impact") is None and "impact" not in sol.events


# -- part 3: models pickle (multiprocessing, joblib) ----------------------------------------


def test_a_model_pickles_as_its_cache_entry_and_runs_the_same(cache_dir, tmp_path):
    import pickle
    import subprocess
    import sys

    model = lc.compile(oscillator(name="silent_pickled"), cache_dir=cache_dir)
    model.defaults["k"] = 4.0  # run defaults changed after compiling travel too
    again = pickle.loads(pickle.dumps(model))
    assert (again.name, again.cache_key, again.defaults, again.q0) == ("silent_pickled", model.cache_key,
                                                                        {"k": 4.0, "m": 1.0}, (1.0,))
    expected = model.simulate((0.0, 1.0)).y
    assert np.array_equal(again.simulate((0.0, 1.0)).y, expected)
    assert again.system.fingerprint() == model.system.fingerprint()
    # another process: loaded from the cache, no compilation
    (tmp_path / "model.pickle").write_bytes(pickle.dumps(model))
    script = ("import pickle, sys, numpy as np; m = pickle.loads(open(sys.argv[1], 'rb').read()); "
              "np.save(sys.argv[2], m.simulate((0.0, 1.0)).y); print(m.from_cache)")
    env = {**os.environ, "PYTHONPATH": str(Path(lc.__file__).parent.parent)}
    done = subprocess.run([sys.executable, "-c", script, str(tmp_path / "model.pickle"), str(tmp_path / "y.npy")],
                          capture_output=True, text=True, env=env, timeout=600, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split()[-1] == "True" and np.array_equal(np.load(tmp_path / "y.npy"), expected)


def test_an_unpickled_model_whose_entry_is_gone_is_compiled_again_from_its_system(tmp_path):
    import pickle
    import shutil

    first = tmp_path / "first"
    model = lc.compile(oscillator(name="silent_moved"), cache_dir=first)
    blob, loaded = pickle.dumps(model), pickle.dumps(lc.load("silent_moved", cache_dir=first))
    shutil.rmtree(first)
    again = pickle.loads(blob)
    assert again.source_path.exists() and again.cache_key == model.cache_key and not again.from_cache
    with pytest.raises(lc.ModelError, match=r"'silent_moved'.*no System"):
        shutil.rmtree(first)
        pickle.loads(loaded)


# -- part 3: Ctrl-C while numba compiles stops the script ------------------------------------


def test_ctrl_c_during_the_first_compile_raises_keyboard_interrupt(tmp_path):
    """SIGINT while numba compiles the first radau run's Jacobian kernel (sent from numba's own compile event for
    `rhs_jacobian`, so it lands inside that compile whatever the machine's speed; a timer guessed wrong once the
    first compiles got faster): the compile finishes (its machine code kept), then KeyboardInterrupt, not a run
    returned with status 2; the next run compiles nothing and ends normally."""
    import signal
    import time

    from numba.core import event

    class InterruptWhileCompiling(event.Listener):
        sent = False

        def on_start(self, ev):
            dispatcher = ev.data.get("dispatcher")
            if not self.sent and getattr(dispatcher, "__name__", "") == "rhs_jacobian":
                self.sent = True
                os.kill(os.getpid(), signal.SIGINT)

        def on_end(self, ev):
            pass

    model = lc.compile(oscillator(V=k * x**2 / 2 + x**4 / 4, name="silent_interrupted"), cache_dir=tmp_path)
    model.simulate((0.0, 1.0), progress=False)  # compiles what every run's set-up calls
    listener = InterruptWhileCompiling()
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with event.install_listener("numba:compile", listener), pytest.raises(KeyboardInterrupt):
            model.simulate((0.0, 1.0), method="radau", progress=False)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert listener.sent
    started = time.process_time()
    assert model.simulate((0.0, 1.0), method="radau", progress=False).status == 0
    assert time.process_time() - started < 0.2  # compiled, not thrown away (the first compile took a second or more)


# -- 2.10: projection=True saves the states the integrator continues from -------------------


@pytest.mark.parametrize("example", ["spherical_pendulum_cartesian", "four_bar_linkage"])
def test_projected_runs_save_the_projected_states(compiled, example):
    """With projection every accepted state is moved onto Φ = 0 (and Λ q̇ + b = 0) before the next step: the saved
    rows, at the steps and at t_eval points between them (projected too), are on the constraints to rounding."""
    model = compiled(example)
    sol = model.simulate((0.0, 5.0), projection=True)
    assert sol.status == 0 and sol.constraint_residual < 1e-13
    dense = model.simulate((0.0, 5.0), projection=True, t_eval=np.linspace(0.0, 5.0, 51))
    assert dense.status == 0 and dense.constraint_residual < 1e-13
    unprojected = model.simulate((0.0, 5.0))
    assert unprojected.constraint_residual > 1e-10  # (what the projection removes: the steps' drift)
    # the rows at the steps are the same states either way, the t_eval points between them the steps' own
    assert np.array_equal(dense.t, np.linspace(0.0, 5.0, 51))
    assert np.max(np.abs(np.interp(dense.t, sol.t, sol.q[:, 0]) - dense.q[:, 0])) < 0.05


# -- 2.8: periodic orbits that are none, and answers that vary ------------------------------

SIMO_Q = np.array([0.97000436, -0.24308753, -0.97000436, 0.24308753, 0.0, 0.0])
SIMO_QD = np.array([0.466203685, 0.43236573, 0.466203685, 0.43236573, -0.93240737, -0.86473146])
SIMO_PERIOD = 6.32591398
UNIT = {"G": 1.0, "m1": 1.0, "m2": 1.0, "m3": 1.0}


def test_a_fixed_period_that_only_the_equilibrium_has_is_refused(cache_dir):
    """ẍ = −x has periodic orbits of period 2π only; asked for T = 3 the shooting can only close at x = ẋ = 0."""
    from lagcomp import analysis as an

    model = lc.compile(oscillator(name="silent_harmonic"), cache_dir=cache_dir)
    with pytest.raises(lc.OptionError, match=r"no orbit: over the period T = 3 its state moves by .* an equilibrium"):
        an.periodic_orbit(model, [0.5, 0.0], 3.0, fix="period")
    orbit = an.periodic_orbit(model, [0.5, 0.0], 3.0)  # the amplitude held: the period comes out, 2π
    assert orbit.residual < 1e-10 and orbit.period == pytest.approx(2 * np.pi, rel=1e-10)


def _scribbled(rng):
    """Garbage left on the heap: arrays of a solver's sizes, filled with numbers of any size, then freed."""
    junk = [rng.standard_normal(size) * 10.0 ** rng.integers(-300, 300) for size in (13, 14, 182, 169, 26) * 4]
    del junk


def test_the_figure_eight_from_a_rough_guess_is_the_same_whatever_the_heap(compiled):
    """Simó's state with positions 10 % too far out and velocities 10 % too slow (tests/test_periodic.py): the same
    orbit, bit for bit, with different garbage on the heap before each solve (MINPACK's lm read some of it)."""
    from lagcomp import analysis as an

    bodies = compiled("pythagorean_three_body")
    guess = np.concatenate([1.1 * SIMO_Q, 0.9 * SIMO_QD])
    rng = np.random.default_rng(7)
    found = set()
    for _ in range(8):
        _scribbled(rng)
        orbit = an.periodic_orbit(bodies, guess, SIMO_PERIOD, fix="period", params=UNIT)
        found.add(orbit.y0.tobytes())
    assert len(found) == 1 and orbit.residual < 1e-10


def test_the_figure_eight_from_both_10_percent_too_large_is_no_answer_in_disguise(compiled):
    """Positions and velocities both 10 % too large: once a "stable periodic orbit" of bodies 1e6 apart moving at
    1e-11; now either the figure eight (its energy) or a refusal, never a degenerate motion."""
    from lagcomp import analysis as an

    bodies = compiled("pythagorean_three_body")
    try:
        orbit = an.periodic_orbit(bodies, np.concatenate([1.1 * SIMO_Q, 1.1 * SIMO_QD]), SIMO_PERIOD, fix="period",
                                  params=UNIT)
    except lc.OptionError as refusal:
        assert "did not converge" in str(refusal) or "no orbit" in str(refusal)
    else:
        energy = bodies.energy(SIMO_Q, SIMO_QD, params=UNIT)
        assert bodies.energy(orbit.y0[:6], orbit.y0[6:], params=UNIT) == pytest.approx(energy, abs=1e-6)
        assert np.abs(orbit.y0[6:]).max() > 0.1
