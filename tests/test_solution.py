"""Solution records: export, decimation, chunked output, counters."""

from __future__ import annotations

import numpy as np
import pytest

from lagcomp.integrate import simulate as simulate_module


def test_to_dict_and_npz_round_trip(compiled, tmp_path):
    sol = compiled("simple_pendulum").simulate((0, 1), method="dopri5", rtol=1e-9, atol=1e-12)
    path = tmp_path / "sol.npz"
    sol.save_npz(path)
    data = np.load(path)
    for key, value in sol.to_dict().items():
        np.testing.assert_array_equal(data[key], value)
    assert data["q"].shape == (len(sol.t), 1) and str(data["method"]) == "dopri5"
    assert sol.nfev > sol.nsteps > 0 and sol.success


def test_save_every_bounds_the_output(compiled):
    model = compiled("simple_pendulum")
    full = model.simulate((0, 1), method="rk4", dt=1e-4)
    thinned = model.simulate((0, 1), method="rk4", dt=1e-4, save_every=1000)
    assert len(full.t) == 10_001 and len(thinned.t) == 11
    np.testing.assert_array_equal(thinned.y, full.y[::1000])


def test_long_adaptive_run_spans_many_output_chunks(compiled, monkeypatch):
    model = compiled("simple_pendulum")
    reference = model.simulate((0, 50), method="dopri5", rtol=1e-10, atol=1e-12)
    monkeypatch.setattr(simulate_module, "FIRST_CHUNK", 16)
    monkeypatch.setattr(simulate_module, "MAX_CHUNK", 64)
    chunked = model.simulate((0, 50), method="dopri5", rtol=1e-10, atol=1e-12)
    assert len(reference.t) > 10 * 64
    np.testing.assert_array_equal(chunked.t, reference.t)
    np.testing.assert_array_equal(chunked.y, reference.y)


def test_energy_is_evaluated_by_the_compiled_kernel(compiled):
    model = compiled("simple_pendulum")
    sol = model.simulate((0, 2), method="dop853", rtol=1e-12, atol=1e-12, t_eval=np.linspace(0, 2, 9))
    m, l, g = (model.system.defaults[k] for k in ("m", "l", "g"))
    expected = 0.5 * m * l**2 * sol.qd[:, 0] ** 2 - m * g * l * np.cos(sol.q[:, 0])
    np.testing.assert_allclose(sol.energy, expected, rtol=1e-14)
    np.testing.assert_allclose(sol.energy_function, expected, rtol=1e-14)
    assert sol.energy_drift() < 1e-10


def test_ten_million_steps_in_bounded_memory(compiled):
    import tracemalloc

    model = compiled("simple_pendulum")
    tracemalloc.start()
    sol = model.simulate((0, 100), method="rk4", dt=1e-5, save_every=100_000)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert sol.nsteps == 10_000_000 and len(sol.t) == 101
    assert peak < 2_000_000, f"peak traced memory {peak} bytes"
    assert sol.energy_drift() < 1e-10


def test_invariants_include_cyclic_momenta(compiled):
    model = compiled("spherical_pendulum")
    assert model.cyclic == ("phi",)
    sol = model.simulate((0, 20), method="dop853", rtol=1e-12, atol=1e-12)
    invariants = sol.invariants()
    assert set(invariants) == {"h", "p_phi"}
    values, drift = invariants["p_phi"]
    m, l = model.system.defaults["m"], model.system.defaults["l"]
    np.testing.assert_allclose(values, m * l**2 * np.sin(sol.q[:, 0]) ** 2 * sol.qd[:, 1], rtol=1e-14)
    assert drift < 1e-10 and invariants["h"][1] < 1e-10
    assert sol.momenta.shape == sol.q.shape


@pytest.mark.parametrize("example", ["double_pendulum", "spherical_pendulum", "hoop_bead"])
def test_energies_of_a_kept_trajectory_are_evaluated_on_first_read(compiled, monkeypatch, example):
    """Bitwise what a summary run folds chunk by chunk (`fold_summary`: h the energy or its own kernel, momenta of a
    cyclic coordinate or none); a pickled Solution carries the values, not the model."""
    import pickle

    model = compiled(example)
    monkeypatch.setattr(simulate_module, "FIRST_CHUNK", 16)
    monkeypatch.setattr(simulate_module, "MAX_CHUNK", 64)
    kept = model.simulate((0, 5), rtol=1e-10, atol=1e-12)
    folded = model.simulate((0, 5), rtol=1e-10, atol=1e-12, record="summary")
    assert kept.observed._values is None  # nothing evaluated by the run itself
    assert len(kept.t) > 64
    for name in ("energy", "energy_function", "momenta"):
        ends = getattr(kept, name)[[0, -1]]
        assert ends.tobytes() == getattr(folded, name).tobytes()
    for field in ("rows", "energy_error", "energy_function_error", "momentum_errors"):
        assert getattr(kept.summary, field) == getattr(folded.summary, field)
    for field in ("q_min", "q_max", "qd_min", "qd_max"):
        np.testing.assert_array_equal(getattr(kept.summary, field), getattr(folded.summary, field))
    unevaluated = model.simulate((0, 1))
    again = pickle.loads(pickle.dumps(unevaluated))
    assert unevaluated.observed._values is not None and again.observed._evaluate is None
    np.testing.assert_array_equal(again.energy, unevaluated.energy)
    np.testing.assert_array_equal(again.momenta, unevaluated.momenta)
