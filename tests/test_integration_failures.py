"""A run that fails part-way stops, keeps every row it computed, and says why (or raises with throw=True).

Each failure is checked three ways: the status, `t_failure` and message of
the returned Solution; the same Solution attached to the `IntegrationError`
that ``throw=True`` raises; and "nothing lost": the rows of the failed run
are exactly the first rows of a run that did not fail there.
"""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.model import t

x, = lc.coordinates("x")
m, a, c = sp.symbols("m a c")


@pytest.fixture(scope="module")
def failing(cache_dir):
    # the same system as docs/errors.md's table test: M = m (1 − c t); the force a q̇² blows q̇ up at t = 1
    system = lc.System([x], T=m * (1 - c * t) * x.diff(t) ** 2 / 2, forces=[a * x.diff(t) ** 2],
                       name="table_failing", defaults={"m": 1.0, "a": 0.0, "c": 0.0}, q0=(0.0,), qd0=(1.0,))
    return lc.compile(system, cache_dir=cache_dir)


def _check_failure(model, status, match, reference=None, **options):
    """Run with and without throw; compare with `reference` (a run that went further) row by row."""
    options.setdefault("progress", False)
    sol = model.simulate(**options)
    assert sol.status == status and not sol.success, sol.message
    assert match in sol.message and f"t = {sol.t_failure:.10g}" in sol.message
    assert sol.t[-1] == sol.t_failure and np.all(np.isfinite(sol.y))
    with pytest.raises(lc.IntegrationError, match=match) as info:
        model.simulate(**options, throw=True)
    raised = info.value.solution
    assert raised.status == status and np.array_equal(raised.y, sol.y) and raised.t_failure == sol.t_failure
    if reference is not None:
        rows = min(len(sol.t) - 1, len(reference.t))  # a failed run's last row: its last good state, saved or not
        assert np.array_equal(sol.t[:rows], reference.t[:rows]) and np.array_equal(sol.y[:rows], reference.y[:rows])
    return sol


def test_non_finite_state(failing):
    params = {"a": 1.0}
    reference = failing.simulate((0, 0.9), params=params, method="rk4", dt=0.01, progress=False)
    sol = _check_failure(failing, -1, "non-finite", reference, t_span=(0, 2), params=params, method="rk4", dt=0.01)
    assert 0.95 < sol.t_failure < 1.05 and len(sol.t) > len(reference.t)


def test_singular_mass_matrix_during_the_run(failing):
    params = {"c": 1.0}
    reference = failing.simulate((0, 0.5), params=params, method="rk4", dt=0.1, progress=False)
    sol = _check_failure(failing, -2, "singular", reference, t_span=(0, 2), params=params, method="rk4", dt=0.1)
    assert 0.5 <= sol.t_failure <= 1.0


def test_step_size_underflow(failing):
    params = {"a": 1.0}
    sol = _check_failure(failing, -3, "step size became too small", t_span=(0, 2), params=params)
    assert abs(sol.t_failure - 1.0) < 1e-6
    # nothing lost: the same run cut short by max_steps has the same rows
    shorter = failing.simulate((0, 2), params=params, max_steps=sol.nsteps - 10, progress=False)
    rows = len(shorter.t) - 1
    assert np.array_equal(shorter.y[:rows], sol.y[:rows])


@pytest.mark.parametrize("save_every", [1, 7])
def test_maximum_number_of_steps(failing, save_every):
    full = failing.simulate((0, 0.999), params={"a": 1.0}, progress=False)
    assert full.nsteps > 20
    sol = _check_failure(failing, -4, "maximum number of steps", full if save_every == 1 else None,
                         t_span=(0, 0.999), params={"a": 1.0}, max_steps=20, save_every=save_every)
    assert sol.nsteps == 20 and sol.t_failure == full.t[20]  # the last good state is kept even if not due
    assert np.array_equal(sol.y[-1], full.y[20])


def test_implicit_stage_equations_not_converging(failing):
    sol = _check_failure(failing, -5, "did not converge", t_span=(0, 0.9), params={"a": 1.0}, method="gauss2", dt=0.3)
    assert sol.t_failure < 0.9


@pytest.mark.parametrize("method, options", [("dop853", dict(rtol=1e-4, atol=1e-4)), ("rk4", dict(dt=0.05))])
def test_constraint_residual_past_its_bound(compiled, method, options):
    model = compiled("spherical_pendulum_cartesian")
    free = model.simulate((0, 10), method=method, projection=False, progress=False, **options)
    bound = free.constraint_residual / 3  # reached part-way through the free run
    sol = _check_failure(model, -6, "max_residual", free, t_span=(0, 10), method=method, projection=False,
                         max_residual=bound, **options)
    assert sol.t_failure < 10 and sol.constraint_residual > bound
    assert f"> max_residual = {bound:g}" in sol.message
    assert set(sol.reactions) == {"rod"} and sol.reactions["rod"].shape == sol.t.shape
    # the bound is only a bound: a run that stays within it is not stopped
    assert model.simulate((0, 10), method=method, projection=False, max_residual=2 * free.constraint_residual,
                          progress=False, **options).success
