"""``rhs_directional`` (lagcomp.codegen.directional): f and J v + (∂f/∂p) w in one kernel, and the sensitivity
runs that use it for few columns (issue 22); ``rhs_with_full_jacobian``, f and [J | ∂f/∂p] from one
factorization, which they use for more columns with a parameter's.

(a) Against the full Jacobians' product J v + Jp w (``rhs_with_jacobian``, ``rhs_parameter_jacobian`` at the
    same state) to rounding, 1e-13 of |J| |v| + |Jp| |w| (the size of the terms the sums add), f against
    ``rhs`` alike, and ``rhs_with_full_jacobian`` against [J | Jp] to 1e-12 of their largest entry:
    hypothesis over directions for the double pendulum and the free axle (Baumgarte gains on,
    a state off the constraint manifold), over random systems with and without constraints (the module as
    plain Python; `RANDOM_TOLERANCE`).  A larger system (n > LARGEST_SYSTEM) has neither kernel.
(b) Against central differences of ``rhs`` along (v, w), extrapolated twice (Richardson), to 1e-10 relative.
(c) Sensitivity runs through the directional path against the full Jacobians' path: as many steps under
    "state" control, the end state to 1e-12 and the end sensitivities to 1e-10 relative.
(d) Names: parameters named like the kernel's locals and arguments.
The tangent kernels (``rhs_tangent``, ``rhs_tangent_parameters``: one column's augmented rhs) with (a): the second
bitwise ``rhs_directional``'s, the first's f too, and its derivative J v to rounding; the kernels of many columns
(``rhs_tangents``, ``rhs_tangents_parameters``) with (a) and against ``rhs_directional`` column by column over
states and columns (hypothesis), to rounding (another CSE).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st
from random_systems import python_kernels, python_model_kernels, random_mechanism

from lagcomp.integrate import sensitivities

#: The directional derivative's error allowed, relative to |J| |v| + |Jp| |w| (the terms' size): rounding.
PRODUCT_TOLERANCE = 1e-13
#: Against extrapolated differences, relative to the largest entry of the derivative.
DIFFERENCE_TOLERANCE = 1e-10
#: f's error against ``rhs`` for the random systems (the derivative's: 100 times it): a constrained one's K can
#: be ill-conditioned, which the Jacobians' rounding and the directional one's share; measured at most 3.5e-14
#: and 1.6e-13 (seed 13289, a particle on a gimbal at a fixed distance from one on a slider), 1e-16 otherwise.
RANDOM_TOLERANCE = 1e-12
GAINS = (0.7, 1.3)


def _product_errors(kernels, y, p, v, w, n_parameters, t=0.3) -> tuple[float, float]:
    """(error of f against ``rhs``, error of the derivative against J v + Jp w), relative as (a) says."""
    N = y.size
    f, J, Jp = np.empty(N), np.empty((N, N)), np.empty((N, n_parameters))
    assert kernels["rhs_with_jacobian"](t, y, p, f, J) == 0
    assert kernels["rhs_parameter_jacobian"](t, y, p, Jp) == 0
    full, both = np.full(N, np.nan), np.full((N, N + n_parameters), np.nan)
    assert kernels["rhs_with_full_jacobian"](t, y, p, full, both) == 0
    assert np.array_equal(full, f)  # (both call rhs)
    assert np.abs(both - np.hstack([J, Jp])).max() <= 1e-12 * max(np.abs(J).max(), np.abs(Jp).max())
    ydot, out = np.full(N, np.nan), np.full(N, np.nan)
    assert kernels["rhs_directional"](t, y, p, v, w, ydot, out) == 0
    size = np.abs(J) @ np.abs(v) + np.abs(Jp) @ np.abs(w[:n_parameters])
    # the tangent kernels: rhs_directional's CSE on (y, v) in one array, w at the end of p (none: dropped)
    tangent = np.full(2 * N, np.nan)
    assert kernels["rhs_tangent_parameters"](t, np.concatenate([y, v]), np.concatenate([p, w]), tangent) == 0
    assert np.array_equal(tangent, np.concatenate([ydot, out]))
    assert kernels["rhs_tangent"](t, np.concatenate([y, v]), p, tangent) == 0
    assert np.array_equal(tangent[:N], ydot)
    state_error = np.max(np.abs(tangent[N:] - J @ v) / np.maximum(np.abs(J) @ np.abs(v), 1e-300))
    columns_f_error, columns_error = _columns_errors(kernels, t, y, p, v, f, J, Jp)
    return (float(max(np.max(np.abs(ydot - f)), columns_f_error) / np.max(np.abs(f))),
            float(max(np.max(np.abs(out - (J @ v + Jp @ w)) / np.maximum(size, 1e-300)), state_error,
                      columns_error)))


def _columns_errors(kernels, t, y, p, v, f, J, Jp) -> tuple[float, float]:
    """The kernels of many columns (``rhs_tangents``, ``rhs_tangents_parameters``) on S = (v, v reversed, −v),
    the third column the last parameter's (scale 0.5; −1 marks the initial-state columns at the end of p), and
    on S's first two columns without parameters: (f's largest error, the columns' error relative to the terms'
    size |J| |S| + 0.5 |∂f/∂p_j|), against ``rhs_with_jacobian`` and ``rhs_parameter_jacobian``."""
    N, P = y.size, Jp.shape[1]
    S, scale = np.stack([v, v[::-1], -v], axis=1), 0.5
    parameters = [-1.0, -1.0, float(P - 1)]
    expected, size = J @ S, np.abs(J) @ np.abs(S)
    if P:
        expected[:, 2] += scale * Jp[:, P - 1]
        size[:, 2] += scale * np.abs(Jp[:, P - 1])
    wide, narrow = np.full(4 * N, np.nan), np.full(3 * N, np.nan)
    assert kernels["rhs_tangents_parameters"](t, np.concatenate([y, S.T.ravel()]),
                                              np.concatenate([p, parameters, [scale]]), wide) == 0
    assert kernels["rhs_tangents"](t, np.concatenate([y, S[:, :2].T.ravel()]), p, narrow) == 0
    f_error = max(np.max(np.abs(wide[:N] - f)), np.max(np.abs(narrow[:N] - f)))
    wide_error = np.abs(wide[N:].reshape(3, N).T - expected) / np.maximum(size, 1e-300)
    narrow_error = np.abs(narrow[N:].reshape(2, N).T - J @ S[:, :2]) / np.maximum(np.abs(J) @ np.abs(S[:, :2]),
                                                                                   1e-300)
    return float(f_error), float(max(wide_error.max(), narrow_error.max()))


def _kernels(model) -> dict:
    return {name: getattr(model.kernels, name) for name in ("rhs", "rhs_with_jacobian", "rhs_parameter_jacobian",
                                                           "rhs_with_full_jacobian", "rhs_directional",
                                                           "rhs_tangent", "rhs_tangent_parameters", "rhs_tangents",
                                                           "rhs_tangents_parameters")}


@pytest.fixture(scope="module", params=["double_pendulum", "free_axle"])
def bundled(request, compiled):
    model = compiled(request.param)
    y = np.random.default_rng(7).uniform(0.2, 1.0, model.state_size)  # off the manifold for the free axle
    return model, y, model.parameter_vector(None, GAINS if model.k else None)


@settings(max_examples=25, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_directional_is_the_jacobians_product(bundled, data):
    model, y, p = bundled
    N, P = model.state_size, len(model.parameters)
    entries = st.floats(-10.0, 10.0, allow_nan=False)
    v = np.array(data.draw(st.lists(entries, min_size=N, max_size=N)))
    w = np.array(data.draw(st.lists(entries, min_size=P, max_size=P)))
    f_error, error = _product_errors(_kernels(model), y, p, v, w, P)
    assert f_error <= 1e-14 and error <= PRODUCT_TOLERANCE, (f_error, error)


@settings(max_examples=25, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_many_columns_are_rhs_directional_column_by_column(bundled, data):
    """``rhs_tangents_parameters`` and ``rhs_tangents`` over states, m = 1 to 4 columns and their parameters
    (−1: none) and scale: f and each column against ``rhs_directional`` along (S[:, c], s e_j), to rounding
    (`PRODUCT_TOLERANCE` of the terms' size |J| |S[:, c]| + s |∂f/∂p_j|)."""
    model, _, p = bundled
    N, P = model.state_size, len(model.parameters)
    y = np.array(data.draw(st.lists(st.floats(0.2, 1.0), min_size=N, max_size=N)))
    m = data.draw(st.integers(1, 4))
    S = np.array(data.draw(st.lists(st.floats(-10.0, 10.0), min_size=N * m, max_size=N * m))).reshape(m, N).T
    parameters = data.draw(st.lists(st.integers(-1, P - 1), min_size=m, max_size=m))
    scale = data.draw(st.sampled_from([1.0, 0.5, 2.0**-300]))
    J, Jp = np.empty((N, N)), np.empty((N, P))
    assert model.kernels.rhs_with_jacobian(0.3, y, p, np.empty(N), J) == 0
    assert model.kernels.rhs_parameter_jacobian(0.3, y, p, Jp) == 0
    out, state_out = np.full(N * (1 + m), np.nan), np.full(N * (1 + m), np.nan)
    Y = np.concatenate([y, S.T.ravel()])
    assert model.kernels.rhs_tangents_parameters(0.3, Y, np.concatenate([p, parameters, [scale]]), out) == 0
    assert model.kernels.rhs_tangents(0.3, Y, p, state_out) == 0
    for c, j in enumerate(parameters):
        w = np.zeros(P)
        if j >= 0:
            w[j] = scale
        ydot, derivative = np.empty(N), np.empty(N)
        assert model.kernels.rhs_directional(0.3, y, p, S[:, c], w, ydot, derivative) == 0
        assert np.abs(out[:N] - ydot).max() <= 1e-14 * np.abs(ydot).max()
        size = np.maximum(np.abs(J) @ np.abs(S[:, c]) + np.abs(Jp) @ np.abs(w), 1e-300)
        assert np.all(np.abs(out[N * (1 + c):N * (2 + c)] - derivative) <= PRODUCT_TOLERANCE * size)
        if j < 0:
            assert np.all(np.abs(state_out[N * (1 + c):N * (2 + c)] - derivative) <= PRODUCT_TOLERANCE * size)
    assert np.array_equal(state_out[:N], out[:N])


def test_directional_agrees_with_extrapolated_differences(bundled):
    """(b): d/dh rhs(t, y + h v, p + h w) at h = 0 by central differences at h, h/2, h/4, h/8, extrapolated twice."""
    model, y, p = bundled
    N, P = model.state_size, len(model.parameters)
    rng = np.random.default_rng(11)
    v, w = rng.normal(size=N), rng.normal(size=P) * p[:P]

    def rhs(h):
        out = np.empty(N)
        assert model.kernels.rhs(0.3, y + h * v, np.concatenate([p[:P] + h * w, p[P:]]), out) == 0
        return out

    d1, d2, d4, d8 = ((rhs(h) - rhs(-h)) / (2 * h) for h in (1e-2 / s for s in (1, 2, 4, 8)))
    r1, r2, r4 = (4 * d2 - d1) / 3, (4 * d4 - d2) / 3, (4 * d8 - d4) / 3
    reference, coarse = (16 * r4 - r2) / 15, (16 * r2 - r1) / 15
    scale = np.abs(reference).max()
    assert np.abs(reference - coarse).max() <= 0.5 * DIFFERENCE_TOLERANCE * scale  # the reference's own error
    ydot, out = np.empty(N), np.empty(N)
    assert model.kernels.rhs_directional(0.3, y, p, v, w, ydot, out) == 0
    assert np.abs(out - reference).max() <= DIFFERENCE_TOLERANCE * scale


@settings(max_examples=8, deadline=None, derandomize=True, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1))
@example(seed=13289)
def test_random_systems_directional_is_the_jacobians_product(seed):
    """Random systems, constrained or not (the module as plain Python, no numba)."""
    from lagcomp.codegen.emit import emit
    from lagcomp.codegen.lower import lower
    from lagcomp.mechanics.lagrange import derive

    mech = random_mechanism(seed, max_bodies=2)
    eom = derive(mech.system)
    module = python_kernels(emit(lower(eom)))
    n, P = eom.n, len(mech.values)
    rng = np.random.default_rng(seed)
    p = np.concatenate([mech.values, GAINS if eom.k else ()])
    y = np.concatenate([mech.q0, mech.qd0]) + rng.normal(0.0, 0.05, 2 * n)
    f_error, error = _product_errors(module, y, p, rng.normal(size=2 * n), rng.normal(size=P), P)
    assert f_error <= RANDOM_TOLERANCE and error <= 100 * RANDOM_TOLERANCE, (mech.description, f_error, error)


def test_a_larger_system_takes_the_full_jacobians(cache_dir):
    """n = 7 > LARGEST_SYSTEM: no ``rhs_directional`` nor ``rhs_with_full_jacobian`` is emitted (their sums cost
    every model codegen time), and one column's closure is the full Jacobians'."""
    import lagcomp as lc
    from lagcomp import examples
    from lagcomp.codegen.directional import LARGEST_SYSTEM

    model = lc.compile(examples.get("n_link_pendulum", n=LARGEST_SYSTEM + 1), cache_dir=cache_dir)
    assert not any(hasattr(model.kernels, name) for name in ("rhs_directional", "rhs_with_full_jacobian",
                                                             "rhs_tangent", "rhs_tangent_parameters",
                                                             "rhs_tangents", "rhs_tangents_parameters"))
    cols = sensitivities.columns(model, ("theta1", "m1"))
    kernels = sensitivities.sensitivity_kernels(model.kernels, model.state_size, len(model.parameters), cols, 1.0)
    assert kernels is sensitivities._AUGMENTED[(model.kernels, model.state_size, cols.parameters, 1.0, None)]
    assert sensitivities.tangent_kernel(model.kernels, sensitivities.columns(model, "theta1")) is None


@pytest.mark.parametrize(("name", "columns"), [("double_pendulum", "theta1"), ("double_pendulum", ("theta2", "m2")),
                                               ("double_pendulum", ("theta1", "theta2", "m2")),
                                               ("double_pendulum", ("q0", "qd0")), ("free_axle", "g"),
                                               ("free_axle", ("g", "alpha", "m"))])
def test_runs_through_either_path_agree(compiled, monkeypatch, name, columns):
    """(c): the same run with the directional path and the full Jacobians' (``rhs_with_full_jacobian`` where a
    parameter's column is among them)."""
    model = compiled(name)
    q0 = None if model.k else (0.5, 0.2)
    runs = {}
    for path, limit in (("directional", {False: 99, True: 99}), ("jacobian", {False: 0, True: 0})):
        monkeypatch.setattr(sensitivities, "DIRECTIONAL_MAX_COLUMNS", limit)
        runs[path] = model.simulate((0.0, 3.0), q0, rtol=1e-11, atol=1e-11, sensitivities=columns,
                                    sensitivity_control="state", progress=False)
    assert {key[-1] is None for key in sensitivities._AUGMENTED if key[0] is model.kernels} == {True, False}
    directional, jacobian = runs["directional"], runs["jacobian"]
    # the steps' sizes come from error estimates ~1e-11, whose rounding differs: the rows' times differ by ~1e-8
    assert directional.status == jacobian.status == 0 and directional.nsteps == jacobian.nsteps
    assert np.abs(directional.y[-1] - jacobian.y[-1]).max() <= 1e-12
    scale = np.abs(jacobian.sensitivities[-1]).max(axis=0)
    assert np.all(np.abs(directional.sensitivities[-1] - jacobian.sensitivities[-1]).max(axis=0) <= 1e-10 * scale)


def test_default_choice_of_path(compiled):
    """Every k takes the tangent kernels (`DIRECTIONAL_MAX_COLUMNS`), which the run passes to the driver itself:
    one column its own kernel, with its direction at the end of p; more ``rhs_tangents``, with each column's
    parameter (−1: none) and the scale at the end of p."""
    limit = sensitivities.DIRECTIONAL_MAX_COLUMNS
    model = compiled("double_pendulum")
    assert min(limit.values()) >= model.state_size + len(model.parameters)
    kernels, P = model.kernels, len(model.parameters)
    p = model.parameter_vector(None)
    for requested, kernel, tail in (("theta1", kernels.rhs_tangent, np.zeros(P)),
                                    ("m2", kernels.rhs_tangent_parameters, 0.5 * np.eye(P)[1]),
                                    (("q0", "qd0"), kernels.rhs_tangents, [-1.0] * 4 + [0.5]),
                                    (("theta1", "m2", "g"), kernels.rhs_tangents_parameters, [-1.0, 1.0, 4.0, 0.5])):
        cols = sensitivities.columns(model, requested)
        assert sensitivities.sensitivity_kernels(kernels, model.state_size, P, cols, 0.5).rhs is kernel
        run_p = sensitivities.run_parameters(p, model, cols, 0.5)
        assert np.array_equal(run_p[:p.size], p) and np.array_equal(run_p[p.size:], tail)


@pytest.mark.parametrize("names", [("_dy0", "_dp0", "_g0"), ("v", "w", "_direction"), ("_dx0", "_dx1", "ydot")])
@pytest.mark.parametrize("constrained", [False, True])
def test_parameters_named_like_the_kernels_locals(cache_dir, names, constrained):
    """A pendulum (a rod's constraint, or a spring's V) whose mass, gravity and length are named like the kernel's
    locals, arguments and fresh symbols (`_dx<j>`): the kernel still gives the Jacobians' product."""
    import sympy as sp

    import lagcomp as lc

    x, z = lc.coordinates("x z")
    mass, gravity, length = (sp.Symbol(name, positive=True) for name in names)
    T = mass * (x.diff(lc.t) ** 2 + z.diff(lc.t) ** 2) / 2
    if constrained:
        system = lc.System(coordinates=(x, z), T=T, V=mass * gravity * z, parameters=(mass, gravity, length),
                           constraints=[lc.Holonomic("rod", x**2 + z**2 - length**2)], name="directional_named_rod")
    else:
        system = lc.System(coordinates=(x, z), T=T, V=mass * gravity * z + (sp.sqrt(x**2 + z**2) - length) ** 2,
                           parameters=(mass, gravity, length), name="directional_named_spring")
    model = lc.compile(system, cache_dir=cache_dir)
    module = python_model_kernels(model)
    y, p = np.array([0.6, -0.7, 0.4, 0.3]), np.array([1.5, 9.75, 1.25, *(GAINS if constrained else ())])
    f_error, error = _product_errors(module, y, p, np.array([0.3, -1.1, 0.7, 2.0]), np.array([0.5, -0.25, 1.5]), 3)
    assert f_error <= 1e-14 and error <= PRODUCT_TOLERANCE, (f_error, error)
