"""Property tests: random mechanical systems derived by lagcomp agree with sympy.physics.mechanics.

Each example is a random tree of particles and rigid bodies with random
joints, parameters and holonomic constraints (`random_systems`), derived
twice: by lagcomp and by sympy's LagrangesMethod.  At random states near a
consistent configuration, q̈ and the multipliers λ must agree to 1e-10
(norm-wise: max |a − b| ≤ 1e-10 · max(max |b|, 1)), both from lagcomp's
derived equations and from its emitted kernels.  The kernels run as plain
Python here (`random_systems.python_kernels`: the emitted module with njit
a no-op), so most examples cost no numba compilation; one system is
compiled by numba, its rhs kernel stepped by scipy's DOP853, and the
energy function must be conserved along the run (the systems are
conservative: gravity and scleronomic constraints).

The default run tries a few systems of at most two bodies; the slow profile
(``pytest -m slow tests/test_properties.py``) tries 200 of up to three
bodies, with an energy check (scipy's DOP853 over the emitted rhs) on each.
Seeds are drawn by hypothesis with ``derandomize=True``, so runs repeat.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, reject, settings
from hypothesis import strategies as st

import lagcomp as lc
from random_systems import lagcomp_functions, python_kernels, random_mechanism, reference_functions

TOLERANCE = 1e-10
SEEDS = st.integers(0, 2**32 - 1)


def _error(a, b) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return float(np.max(np.abs(a - b), initial=0.0) / max(np.max(np.abs(b), initial=0.0), 1.0))


def _states(mech, count=4):
    rng = np.random.default_rng(mech.seed ^ 0x5EED)
    n = len(mech.q0)
    yield mech.q0, mech.qd0
    for _ in range(count - 1):
        yield mech.q0 + rng.uniform(-0.3, 0.3, n), rng.uniform(-2.0, 2.0, n)


def _kernel_vector(mech, eom) -> np.ndarray:
    """The kernels' p: parameter values, then the Baumgarte gains (0, 0) of constrained systems."""
    return np.concatenate([mech.values, np.zeros(2 if eom.k else 0)])


def check_agreement(mech, kernels=True) -> dict:
    """Compare q̈ and λ of sympy's derivation with lagcomp's derivation (and emitted kernels) at random states."""
    from lagcomp.codegen.emit import emit
    from lagcomp.codegen.lower import lower

    reference = reference_functions(mech)
    eom, derived = lagcomp_functions(mech)
    module = python_kernels(emit(lower(eom))) if kernels else None
    p, n, worst = _kernel_vector(mech, eom), eom.n, 0.0
    for q, qd in _states(mech):
        qdd_ref, lam_ref = reference(q, qd)
        qdd, lam = derived(q, qd)
        worst = max(worst, _error(qdd, qdd_ref), _error(lam, lam_ref))
        if module is not None:
            y, out = np.concatenate([q, qd]), np.empty(2 * n)
            assert module["rhs"](0.0, y, p, out) == 0
            worst = max(worst, _error(out[n:], qdd_ref), _error(out[:n], qd))
            if eom.k:
                reactions = np.empty(eom.k)
                assert module["reactions"](0.0, y, p, reactions) == 0
                worst = max(worst, _error(reactions, lam_ref))
    assert worst <= TOLERANCE, f"{mech.description}: q̈/λ disagree by {worst:.3g}"
    return dict(eom=eom, module=module, p=p, worst=worst)


def check_energy_with_python_kernels(mech, module, p, t_end=1.0) -> float:
    """The energy function along scipy's DOP853 run of the emitted rhs (as Python)."""
    from scipy.integrate import solve_ivp

    n = len(mech.q0)

    def f(t, y):
        out = np.empty(2 * n)
        assert module["rhs"](t, y, p, out) == 0
        return out
    y0 = np.concatenate([mech.q0, mech.qd0])
    sol = solve_ivp(f, (0.0, t_end), y0, method="DOP853", rtol=1e-11, atol=1e-11)
    if not sol.success:  # only where the coordinates themselves are singular (a gimbal's pole): M degenerates
        M = np.empty((n, n))
        module["mass_matrix"](sol.t[-1], sol.y[:, -1], p, M)
        assert np.linalg.cond(M) > 1e6, f"{mech.description}: {sol.message} at t = {sol.t[-1]}, M regular"
        reject()
    h = [module["energy_function"](0.0, y, p) for y in sol.y.T]
    drift = float(np.max(np.abs(np.array(h) - h[0])) / max(abs(h[0]), 1.0))
    assert drift < 1e-7, f"{mech.description}: energy function drifts by {drift:.3g}"
    return drift


@settings(max_examples=4, deadline=None, derandomize=True, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=SEEDS)
def test_random_systems_agree_with_sympy_mechanics(seed):
    check_agreement(random_mechanism(seed, max_bodies=2))


@pytest.mark.parametrize("seed", [31])  # a 3-D particle on a revolute joint carrying a body on a slider, on a plane
def test_compiled_random_system_agrees_and_conserves_energy(seed, cache_dir):
    from scipy.integrate import solve_ivp

    mech = random_mechanism(seed)
    assert mech.system.constraints and not mech.planar
    reference = reference_functions(mech)
    model = lc.compile(mech.system, cache_dir=cache_dir)
    p = model.parameter_vector()
    for q, qd in _states(mech):
        y = np.concatenate([q, qd])
        qdd_ref, lam_ref = reference(q, qd)
        assert _error(model.rhs(0.0, y)[model.n:], qdd_ref) <= TOLERANCE
        assert _error(list(model.reactions(0.0, y).values()), lam_ref) <= TOLERANCE

    def f(t, y):  # the numba rhs kernel, stepped by scipy's DOP853 (lagcomp's own driver costs ~15 s to compile)
        out = np.empty(2 * model.n)
        assert model.kernels.rhs(t, y, p, out) == 0
        return out
    run = solve_ivp(f, (0.0, 2.0), np.concatenate([mech.q0, mech.qd0]), method="DOP853", rtol=1e-11, atol=1e-11)
    assert run.success
    energy_function = python_kernels(model.source_path.read_text())["energy_function"]
    h = np.array([energy_function(0.0, y, p) for y in run.y.T])
    assert np.max(np.abs(h - h[0])) < 1e-8 * max(abs(h[0]), 1.0)


@pytest.mark.slow
@settings(max_examples=200, deadline=None, derandomize=True, database=None, phases=[Phase.generate],
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(seed=SEEDS)
def test_many_random_systems(seed):
    mech = random_mechanism(seed)
    checked = check_agreement(mech)
    drift = check_energy_with_python_kernels(mech, checked["module"], checked["p"])
    print(f"{mech.description}: q̈/λ agree to {checked['worst']:.1e}, energy drift {drift:.1e}")  # shown with -s
