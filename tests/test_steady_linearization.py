r"""Linearization about steady motions of constrained systems (`lagcomp.analysis.linearize_steady`,
`stability_sweep`), against closed forms derived here, published numbers and sympy's Linearizer.

Closed forms
------------
Sleeping top (pivot O, mass M, centre of mass at distance l on the axis,
transverse moment I1′ = I1 + M l² about O, axial moment I3, spin ω).  With
the axis e₃ ≈ (ξ, η, 1) the angular momentum about O is
H ≈ I3 ω e₃ + I1′ e₃ × ė₃ and gravity's torque is M g l e₃ × (−e_z) =
M g l (−η, ξ, 0).  The horizontal part of dH/dt = torque, to first order:

    I1′ ξ̈ + I3 ω η̇ − M g l ξ = 0,     I1′ η̈ − I3 ω ξ̇ − M g l η = 0,

so (I1′ λ² − M g l)² + (I3 ω λ)² = 0, i.e. I1′ λ² ∓ i I3 ω λ − M g l = 0:

    λ = [± i I3 ω ± √(4 I1′ M g l − I3² ω²)] / (2 I1′),

all on the imaginary axis (stable) iff I3² ω² > 4 I1′ M g l.

Rolling disc (example ``rolling_disc``: mass m, radius r, I1 about a
diameter, I3 about the axis) rolling upright, straight, with spin φ̇ = ω
(ẋ = r ω).  The lean equation at the steady turn of the example's docstring,
linearized (θ ≈ 0, ψ̇ small): (I1 + m r²) θ̈ = m g r θ + (I3 + m r²) ω ψ̇; the
vertical angular momentum about the centre, I1 ψ̇ cos²θ + I3 (φ̇ + ψ̇ sin θ) sin θ
≈ I1 ψ̇ + I3 ω θ, is conserved to first order (the friction force at the
contact has no moment about the vertical through the centre when upright), so
I1 ψ̈ = −I3 ω θ̇.  In the state (θ, ψ̇, θ̇) the eigenvalues are 0 and ±√k,

    k = [m g r − (I3 + m r²) I3 ω² / I1] / (I1 + m r²),

stable iff (I3 + m r²) I3 ω² > m g r I1 — for a uniform thin disc
(I1 = m r²/4, I3 = m r²/2) iff ω² > g / (3 r).

Bead on a hoop turned at the constant rate Ω (``hoop_bead_reaction`` with
ε = 0: φ − Ω t = 0 a rheonomic holonomic constraint): θ̈ = sin θ (g/R +
Ω² cos θ); about cos θ* = −g/(R Ω²) (Ω² > g/R), δθ̈ = −Ω² sin² θ* δθ:
λ = ± i Ω sin θ* = ± i √(Ω² − g²/(R² Ω²)).

Spherical pendulum in Cartesian coordinates hanging at rest: two equal
frequencies √(g/l).  On a conical motion (polar angle θ0 from the downward
vertical, rate Ω² = g/(l cos θ0)) the Cartesian velocity turns, so that point
is not steady in these coordinates: the bob's acceleration toward the axis,
ρ Ω² = g tan θ0, is reported as the residual.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
import sympy.physics.mechanics as me
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp import examples
from lagcomp.mechanics.kane import kane_form
from lagcomp.analysis import (
    consistent_speeds,
    linearize,
    linearize_steady,
    normal_modes,
    stability_sweep,
)

import kane_models  # noqa: E402  (tests/ is on sys.path through conftest's rootdir)
import sympy_models  # noqa: E402

# -- the sleeping top ------------------------------------------------------------------


def sleeping_top() -> lc.System:
    """Heavy symmetric top in Bryant angles (α about x, β about y, then spin φ about the axis): regular upright."""
    alpha, beta, phi = lc.coordinates("alpha beta phi")
    M, l, g, I1, I3 = sp.symbols("M l g I1 I3", positive=True)
    N = sp.physics.vector.ReferenceFrame("N")
    tilted = lc.rotated(N, (alpha, "x"), (beta, "y"), name="K")
    top = lc.rotated(tilted, (phi, "z"), name="B")
    body = lc.RigidBody(M, l * top.z, (I1, I1, I3), top, axes=tilted, name="top")
    return lc.System(coordinates=(alpha, beta, phi), bodies=(body,), loads=(lc.Gravity(-g * N.z),), frame=N,
                     parameters=(M, l, g, I1, I3), name="sleeping_top",
                     defaults={"M": 0.5, "l": 0.05, "g": 9.81, "I1": 5e-4, "I3": 8e-4})


@pytest.fixture(scope="module")
def top():
    return sleeping_top()


def top_eigenvalues(M, l, g, I1, I3, omega):
    J = I1 + M * l**2
    root = np.sqrt(complex(4 * J * M * g * l - (I3 * omega) ** 2))
    return np.array([(s * 1j * I3 * omega + r * root) / (2 * J) for s in (1, -1) for r in (1, -1)])


def same_spectrum(got, want, atol):
    """The two sets of eigenvalues agree, each matched to its nearest (an assignment, not a sort: sorting
    complex numbers whose real parts differ by rounding pairs them wrongly)."""
    from scipy.optimize import linear_sum_assignment

    got, want = np.asarray(got, dtype=complex), np.asarray(want, dtype=complex)
    assert got.shape == want.shape
    rows, cols = linear_sum_assignment(np.abs(got[:, None] - want[None, :]))
    np.testing.assert_allclose(got[rows], want[cols], rtol=0, atol=atol)


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(M=st.floats(0.1, 2.0), l=st.floats(0.01, 0.2), I1=st.floats(1e-4, 1e-2), I3=st.floats(1e-4, 1e-2),
       omega=st.floats(-300.0, 300.0), phi=st.floats(-3.0, 3.0))
def test_sleeping_top_eigenvalues_match_the_closed_form(top, M, l, I1, I3, omega, phi):
    params = dict(M=M, l=l, g=9.81, I1=I1, I3=I3)
    lin = linearize_steady(top, [0.0, 0.0, phi], [0.0, 0.0, omega], params, drop=("phi", "phi_dot"))
    assert lin.states == ("alpha", "beta", "alpha_dot", "beta_dot")
    assert lin.residual == 0.0 and lin.drift == {"phi": omega, "phi_dot": 0.0}
    want = top_eigenvalues(M, l, 9.81, I1, I3, omega)
    # measured: |Δλ| ≤ 5e-15 max(1, |λ|) over 200 random draws
    same_spectrum(lin.eigenvalues, want, atol=1e-10 * max(1.0, float(np.max(np.abs(want)))))
    critical = 4 * (I1 + M * l**2) * M * 9.81 * l - (I3 * omega) ** 2
    if abs(critical) > 1e-3 * (I3 * omega) ** 2:
        assert lin.stable == (critical < 0)


def test_sleeping_top_critical_spin_is_found(top):
    params = {"M": 0.5, "l": 0.05, "g": 9.81, "I1": 5e-4, "I3": 8e-4}
    J = params["I1"] + params["M"] * params["l"] ** 2
    critical = 2 * math.sqrt(J * params["M"] * params["g"] * params["l"]) / params["I3"]  # 51.79 rad/s
    sweep = stability_sweep(top, "phi_dot", np.linspace(0.0, 80.0, 17), [0.0, 0.0, 0.0], None, params,
                            drop=("phi", "phi_dot"))
    assert [(c.becomes, c.crossing) for c in sweep.changes] == [("stable", "marginal")]
    # measured: relative error 3e-14
    assert sweep.changes[0].value == pytest.approx(critical, rel=1e-12, abs=0)
    assert sweep.unstable[0] and not sweep.unstable[-1]


# -- the rolling disc (nonholonomic) -------------------------------------------------


@pytest.fixture(scope="module")
def disc():
    return examples.get("rolling_disc")


DISC_DROP = ("x", "y", "psi", "phi", "phi_dot")


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(omega=st.floats(0.5, 40.0), heading=st.floats(-3.1, 3.1), x=st.floats(-5, 5), spin_angle=st.floats(-3, 3),
       I1=st.floats(1e-3, 1e-2), I3=st.floats(1e-3, 1e-2))
def test_upright_rolling_disc_matches_the_closed_form(disc, omega, heading, x, spin_angle, I1, I3):
    m, r, g = 1.0, 0.1, 9.81
    params = dict(m=m, r=r, I1=I1, I3=I3, g=g)
    q = [x, 0.5, heading, 0.0, spin_angle]
    u = consistent_speeds(disc, q, [0, 0, 0, 0, omega], params, independent=["phi_dot"])
    assert u[0] == pytest.approx(r * omega * math.cos(heading), abs=1e-15)
    lin = linearize_steady(disc, q, u, params, drop=DISC_DROP)
    assert set(lin.states) == {"theta", "psi_dot", "theta_dot"}
    assert set(lin.dependent) == {"x_dot", "y_dot"}
    assert lin.residual <= 1e-14
    k = (m * g * r - (I3 + m * r**2) * I3 * omega**2 / I1) / (I1 + m * r**2)
    root = np.sqrt(complex(k))
    # measured: |Δλ| ≤ 5e-13 max(1, |λ|) over 200 random draws (k is a difference of large terms)
    same_spectrum(lin.eigenvalues, [0.0, root, -root], atol=1e-10 * max(1.0, abs(root)))


def test_the_choice_of_independent_speeds_changes_the_basis_not_the_spectrum(disc):
    """On straight rolling at heading 0.4 only x, y and φ drift, and neither basis depends on them: the two
    reduced matrices are similar (on a steady turn the basis with φ̇ dependent would follow ψ: see below)."""
    q = [0.2, -0.1, 0.4, 0.0, 0.3]
    u = consistent_speeds(disc, q, [0, 0, 0, 0, 9.0], independent=["psi_dot", "theta_dot", "phi_dot"])
    automatic = linearize_steady(disc, q, u)
    chosen = linearize_steady(disc, q, u, independent=["x_dot", "psi_dot", "theta_dot"])
    assert set(automatic.dependent) == {"x_dot", "y_dot"} and set(chosen.dependent) == {"y_dot", "phi_dot"}
    # measured: 8e-17 of the rate scale
    same_spectrum(chosen.eigenvalues, automatic.eigenvalues, atol=1e-11 * automatic.rate_scale)
    # both bases span the same tangent space: each basis vector is a combination of the other's
    P, Q = automatic.basis, chosen.basis
    coefficients, *_ = np.linalg.lstsq(P, Q, rcond=None)
    np.testing.assert_allclose(P @ coefficients, Q, atol=1e-12)


def test_a_basis_that_follows_a_drifting_coordinate_is_refused(disc):
    """On the example's steady turn (ψ drifts), φ̇ dependent makes the kept rates depend on ψ: not ignorable."""
    q = list(disc.q0)
    u = consistent_speeds(disc, q, list(disc.qd0), independent=["psi_dot", "theta_dot", "phi_dot"])
    turning = linearize_steady(disc, q, u, drop=("x", "y", "psi", "phi"))
    assert turning.residual <= 1e-13 and turning.drift["psi"] == pytest.approx(disc.qd0[2])
    with pytest.raises(lc.LinearizationError, match="`psi` is not ignorable"):
        linearize_steady(disc, q, u, independent=["x_dot", "psi_dot", "theta_dot"], drop=("x", "y", "psi", "phi"))


def test_thin_disc_rolls_upright_stably_above_the_closed_form_spin(disc):
    params = {"m": 1.0, "r": 0.1, "I1": 0.0025, "I3": 0.005, "g": 9.81}  # uniform thin disc
    sweep = stability_sweep(disc, "phi_dot", np.linspace(1.0, 12.0, 12), [0.0] * 5, None, params, drop=DISC_DROP)
    assert [(c.becomes, c.crossing) for c in sweep.changes] == [("stable", "marginal")]
    # ω² = g/(3r); measured relative error 6e-14
    assert sweep.changes[0].value == pytest.approx(math.sqrt(9.81 / 0.3), rel=1e-12, abs=0)


def test_kane_rolling_disc_matches_sympys_linearizer():
    built = sympy_models.kane_rolling_disc()
    km = built["method"]
    km.kanes_equations(km.bodies, km.loads)
    form = kane_form(km, built["parameters"])
    values = {"m": 1.0, "r": 0.1, "I1": 0.0025, "I3": 0.005, "g": 9.81}
    q = [0.3, -0.2, 0.6, 0.0, 1.1]
    u = consistent_speeds(form, q, {"u_psi": 0.0, "u_theta": 0.0, "u_phi": 12.0, "u_x": 0.0, "u_y": 0.0},
                          values, independent=["u_phi"])
    lin = linearize_steady(form, q, u, values)
    t = sp.physics.mechanics.dynamicsymbols._t
    op = {**dict(zip(km.q, q)), **dict(zip(km.u, u)), **{s.diff(t): 0 for s in km.u}}
    A, _, _ = km.linearize(A_and_B=True, op_point=op)
    by_symbol = dict(zip(built["parameters"], (values[str(s)] for s in built["parameters"])))
    reference = np.array(A.xreplace(by_symbol).evalf(), dtype=float)
    assert lin.states == ("x", "y", "psi", "theta", "phi", "u_psi", "u_theta", "u_phi")  # sympy's order
    # measured: max |ΔA| = 4e-15
    np.testing.assert_allclose(lin.A, reference, rtol=0, atol=1e-12)


def test_a_state_that_matters_cannot_be_dropped(disc):
    u = consistent_speeds(disc, [0.0] * 5, [0, 0, 0, 0, 10.0], independent=["phi_dot"])
    with pytest.raises(lc.LinearizationError, match="`psi_dot` is not ignorable"):
        linearize_steady(disc, [0.0] * 5, u, drop=DISC_DROP + ("psi_dot",))


def test_a_point_off_the_constraints_is_refused(disc):
    with pytest.raises(lc.InitialConditionError, match="roll_x"):
        linearize_steady(disc, [0.0] * 5, [0, 0, 0, 0, 10.0])


def test_a_wrong_independent_set_is_refused(disc):
    with pytest.raises(lc.LinearizationError, match="only 3"):
        linearize_steady(disc, [0.0] * 5, independent=["x_dot", "y_dot", "psi_dot", "theta_dot"])
    with pytest.raises(lc.LinearizationError, match="Unknown state"):
        linearize_steady(disc, [0.0] * 5, drop=["lean"])


# -- holonomic constraints -------------------------------------------------------------


@pytest.mark.parametrize("Omega", [5.0, 6.0, 9.0])
@pytest.mark.parametrize("t", [0.0, 1.3])
def test_bead_on_a_hoop_turned_at_a_constant_rate(Omega, t):
    system = examples.get("hoop_bead_reaction")
    params = {"m": 0.1, "R": 0.5, "g": 9.81, "Omega": Omega, "epsilon": 0.0}
    theta = math.acos(-9.81 / (0.5 * Omega**2))
    lin = linearize_steady(system, [theta, Omega * t], [0.0, Omega], params, t=t)
    assert lin.states == ("theta", "theta_dot") and lin.dependent == ("phi", "phi_dot")
    assert lin.residual <= 1e-13
    omega = math.sqrt(Omega**2 - (9.81 / (0.5 * Omega)) ** 2)
    # measured: 4e-16 relative
    same_spectrum(lin.eigenvalues, [1j * omega, -1j * omega], atol=1e-12 * omega)
    assert lin.stability == "marginal"


def test_cartesian_spherical_pendulum_hanging_and_on_a_cone():
    system = examples.get("spherical_pendulum_cartesian")
    params = {"m": 1.0, "l": 1.0, "g": 9.81}
    hanging = linearize_steady(system, [0.0, 0.0, -1.0], [0.0, 0.0, 0.0], params)
    assert set(hanging.dependent) == {"z", "z_dot"} and hanging.residual == 0.0
    w = math.sqrt(9.81)
    same_spectrum(hanging.eigenvalues, [1j * w, 1j * w, -1j * w, -1j * w], atol=1e-10)  # measured: 0
    theta0 = 0.7
    rho, Omega = math.sin(theta0), math.sqrt(9.81 / math.cos(theta0))
    cone = linearize_steady(system, [rho, 0.0, -math.cos(theta0)], [0.0, rho * Omega, 0.0], params)
    assert cone.residual == pytest.approx(9.81 * math.tan(theta0), rel=1e-12, abs=0)


# -- non-smooth equations (sympy's derivatives, DiracDelta away from kinks) -----------


def test_sliding_rope_with_coulomb_friction():
    """While sliding (ẋ > 0): ẍ = (g(1 + f)/L)(x − l0), so λ = ±√(g(1 + f)/L); at rest sign(ẋ) has a kink."""
    system = examples.get("rope_friction")
    lin = linearize_steady(system, [0.4], [0.5], {"f": 0.3})
    rate = math.sqrt(9.81 * 1.3 / 1.0)
    # measured: 0 (both entries exact in binary to the last bit here)
    same_spectrum(lin.eigenvalues, [rate, -rate], atol=1e-13 * rate)
    with pytest.raises(lc.LinearizationError, match="x_dot = 0 is a kink"):
        linearize_steady(system, [0.4], [0.0])


# -- unconstrained: the same as `linearize` ------------------------------------------


@pytest.mark.parametrize("name, q, params", [
    ("double_pendulum", [0.0, 0.0], None),
    ("double_pendulum", [math.pi, 0.0], None),
    ("hoop_bead", [math.acos(-9.81 / (0.5 * 36.0))], {"epsilon": 0.0}),
])
def test_unconstrained_equilibria_agree_with_linearize(compiled, name, q, params):
    model = compiled(name)
    old = linearize(model, q, params)
    new = linearize_steady(model, q, None, params)
    n = len(q)
    companion = np.block([[np.zeros((n, n)), np.eye(n)],
                          [-np.linalg.solve(old.M, old.K), -np.linalg.solve(old.M, old.C)]])
    # measured: 1e-15 relative
    np.testing.assert_allclose(new.A, companion, rtol=0, atol=1e-12 * np.max(np.abs(companion)))
    same_spectrum(new.eigenvalues, normal_modes(old).eigenvalues, atol=1e-10 * new.rate_scale)


# -- the Whipple bicycle (KanesMethod, holonomic + nonholonomic) ---------------------

#: Meijaard et al. (2007), Table 2: eigenvalues of the benchmark bicycle at v = 0 and 5 m/s, weave and capsize speeds.
PUBLISHED = {
    0.0: [3.13164324790656, -3.13164324790656, 5.53094371765393, -5.53094371765393],
    5.0: [-0.32286642900409, -0.77534188219585 + 4.46486771378823j, -0.77534188219585 - 4.46486771378823j,
          -14.07838969279820],
}
WEAVE, CAPSIZE = 4.29238253634111, 6.02426201538837


@pytest.fixture(scope="module")
def bike(whipple_bicycle):
    """sympy's test_kane3 KanesMethod as `lc.compile` compiles it (conftest's session fixture)."""
    _, model = whipple_bicycle
    return model


def running(v: float) -> dict:
    return {"u": {"u2": 0.0, "u3": v / kane_models.RAD_REAR, "u5": 0.0, "u1": 0.0, "u4": 0.0, "u6": v / kane_models.RAD_FRONT}}


@pytest.mark.parametrize("v", sorted(PUBLISHED))
def test_bicycle_eigenvalues_are_the_published_ones(bike, v):
    lin = linearize_steady(bike, [0.0] * 4, running(v)["u"], kane_models.BENCHMARK, drop=("q1", "u3"))
    assert lin.states == ("q2", "q5", "u2", "u5")  # lean, steer and their rates
    assert set(lin.dependent) == {"q4", "u1", "u4", "u6"}
    assert lin.residual <= 1e-13
    np.testing.assert_allclose(lin.dropped_eigenvalues, 0.0, atol=1e-12)  # yaw and rear-wheel rate: cyclic
    # measured: 1e-14 (v = 0), 4.4e-14 (v = 5)
    same_spectrum(lin.eigenvalues, PUBLISHED[v], atol=1e-10)


def test_the_kane_form_itself_is_linearized_like_the_compiled_model(whipple_bicycle):
    """`linearize_steady` takes the `FirstOrderForm` of `lagcomp.mechanics.kane.kane_form` as well as a Model."""
    km, model = whipple_bicycle
    form = kane_form(km, model.first_order_form.parameters)
    lin = linearize_steady(form, [0.0] * 4, running(5.0)["u"], kane_models.BENCHMARK, drop=("q1", "u3"))
    same_spectrum(lin.eigenvalues, PUBLISHED[5.0], atol=1e-10)


def test_bicycle_state_matrix_matches_sympys_linearization(bike):
    """test_kane3's `Res`: the lean/steer rows of KanesMethod.linearize, printed to 15 digits."""
    for v in range(6):
        lin = linearize_steady(bike, [0.0] * 4, running(float(v))["u"], kane_models.BENCHMARK, drop=("q1", "u3"))
        res = np.array([[0, 0, 1.0, 0], [0, 0, 0, 1.0],
                        [9.48977444677355, -0.891197738059089 * v**2 - 0.571523173729245,
                         -0.105522449805691 * v, -0.330515398992311 * v],
                        [11.7194768719633, -1.97171508499972 * v**2 + 30.9087533932407,
                         3.67680523332152 * v, -3.08486552743311 * v]])
        # measured: 8e-14 (test_kane3 asserts 1e-12; its Res is printed to 15 digits)
        np.testing.assert_allclose(lin.A, res, rtol=0, atol=1e-12)


def test_bicycle_weave_and_capsize_speeds(bike):
    sweep = stability_sweep(bike, running, np.linspace(0.0, 10.0, 21), [0.0] * 4, None, kane_models.BENCHMARK,
                            drop=("q1", "u3"), label="v")
    assert [(c.becomes, c.crossing) for c in sweep.changes] == [("stable", "transversal"),
                                                                ("unstable", "transversal")]
    # measured: 4e-15
    np.testing.assert_allclose([c.value for c in sweep.changes], [WEAVE, CAPSIZE], rtol=0, atol=1e-10)
    # the same through the rear wheel's rate, the front wheel's completed by the constraints
    by_wheel = stability_sweep(bike, "u3", np.linspace(0.0, 10.0, 21) / kane_models.RAD_REAR, [0.0] * 4,
                               running(0.0)["u"], kane_models.BENCHMARK, drop=("q1", "u3"))
    np.testing.assert_allclose([c.value * kane_models.RAD_REAR for c in by_wheel.changes], [WEAVE, CAPSIZE],
                               rtol=0, atol=1e-10)
    assert sweep.parameter == "v" and sweep.unstable[0] and not sweep.unstable[10] and sweep.unstable[-1]


def test_stability_plot(bike, tmp_path):
    pytest.importorskip("matplotlib")
    from lagcomp.plots import plot_stability

    sweep = stability_sweep(bike, running, np.linspace(0.0, 10.0, 11), [0.0] * 4, None, kane_models.BENCHMARK,
                            drop=("q1", "u3"), label="v")
    fig = plot_stability(sweep)
    ax = fig.axes[0]
    assert ax.get_xlabel() == "v"
    # per eigenvalue: Re solid and |Im| dashed; plus the two legend proxies
    styles = [line.get_linestyle() for line in ax.get_lines() if line.get_xydata().shape[0] == 11]
    assert styles.count("-") == 4 and styles.count("--") == 4
    fig.savefig(tmp_path / "bicycle.png", dpi=60)
    assert (tmp_path / "bicycle.png").read_bytes().startswith(b"\x89PNG")


def test_cli_stability_finds_the_hoop_beads_critical_rate(capsys, tmp_path):
    """The bottom of a hoop turned at Ω becomes unstable at Ω² = g/R (δθ̈ = (Ω² − g/R) δθ there)."""
    pytest.importorskip("matplotlib")
    from lagcomp.cli import main

    argv = ["--cache-dir", str(tmp_path), "stability", "hoop_bead", "--param", "Omega", "--range", "1", "8",
            "--num", "8", "--set", "epsilon=0", "--q", str(math.pi), "--plot", str(tmp_path / "hoop.png")]
    assert main(argv) == 0
    out = capsys.readouterr().out
    line = next(row for row in out.splitlines() if row.startswith("becomes unstable at Omega = "))
    # measured: 1e-13 relative (printed to 12 digits)
    assert float(line.split("= ")[1].split()[0]) == pytest.approx(math.sqrt(9.81 / 0.5), rel=1e-11, abs=0)
    assert (tmp_path / "hoop.png").exists()


def test_cli_stability_reports_an_unknown_parameter(capsys):
    from lagcomp.cli import main

    assert main(["stability", "hoop_bead", "--param", "spin", "--range", "0", "1"]) == 2
    assert "Unknown sweep parameter 'spin'" in capsys.readouterr().err


# -- LagrangesMethod models with constraints: lc.compile(lm) + linearize_steady against sympy's Linearizer ----------


def _sympy_state_matrix(lm, q_ind, qd_ind, q_dep, qd_dep, point: dict, values: dict) -> np.ndarray:
    """sympy's reduced A (``LagrangesMethod.linearize(..., A_and_B=True)``, states [q_ind, qd_ind]) at `point`,
    a steady motion: accelerations zero, the multipliers from ``solve_multipliers`` there."""
    t = me.dynamicsymbols._t
    op = dict(point)
    op.update({q.diff(t, 2): 0 for q in lm.q})
    op.update(lm.solve_multipliers(op_point=[op, values]))
    A = lm.linearize(q_ind=q_ind, qd_ind=qd_ind, q_dep=q_dep, qd_dep=qd_dep, op_point=[op, values], A_and_B=True)[0]
    return np.array(A.evalf(30).tolist(), dtype=float)


def test_lagranges_method_conical_pendulum_matches_sympys_linearizer(cache_dir):
    r"""A spherical pendulum in (θ, φ, r) with the holonomic constraint r − L = 0, on its conical motion
    (θ = θ0, φ̇ = Ω with Ω² = g / (L cos θ0)): r and ṙ dependent, as sympy's Linearizer is told.

    Zero eigenvalues, twice: φ is cyclic (its column of A is zero: the cone turned about the vertical is
    the same motion), and φ̇'s direction is the family of conical motions at other θ0 (p_φ conserved: a
    neighbouring steady motion, not a restoring mode). The nutation pair is ±iω, ω² = Ω² (1 + 3 cos² θ0).
    (Coordinates in the order (θ, φ, r) so that sympy's permutation of [q_ind, q_dep] is the identity:
    with (r, θ, φ) sympy 1.14's Linearizer takes the transposed permutation matrix of that 3-cycle and
    raises NonInvertibleMatrixError.)
    """
    r, th, ph = me.dynamicsymbols("r theta phi")
    m, g, L = sp.symbols("m g L", positive=True)
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", r * (sp.sin(th) * sp.cos(ph) * N.x + sp.sin(th) * sp.sin(ph) * N.y - sp.cos(th) * N.z))
    P.set_vel(N, P.pos_from(O).dt(N))
    lm = me.LagrangesMethod(me.Lagrangian(N, me.Particle("bob", P, m)), [th, ph, r], hol_coneqs=[r - L],
                            forcelist=[(P, -m * g * N.z)], frame=N)
    lm.form_lagranges_equations()
    values = {"m": 1.3, "g": 9.81, "L": 0.8}
    theta0, phi0 = 0.6, 0.4
    Omega = math.sqrt(values["g"] / (values["L"] * math.cos(theta0)))
    model = lc.compile(lm, cache_dir=cache_dir, name="lm_conical_pendulum", defaults=values)
    q, u = [theta0, phi0, values["L"]], [0.0, Omega, 0.0]
    lin = linearize_steady(model, q, u, independent=["theta", "phi", "theta_dot", "phi_dot"])
    assert lin.states == ("theta", "phi", "theta_dot", "phi_dot") and lin.dependent == ("r", "r_dot")
    t = me.dynamicsymbols._t
    point = {**dict(zip(lm.q, q)), **dict(zip([c.diff(t) for c in lm.q], u))}
    reference = _sympy_state_matrix(lm, [th, ph], [th.diff(t), ph.diff(t)], [r], [r.diff(t)], point,
                                    {sp.Symbol(k, positive=True): v for k, v in values.items()})
    # measured: max |ΔA| = 3.6e-15 (|A| up to 11.3)
    np.testing.assert_allclose(lin.A, reference, rtol=0, atol=1e-12)
    omega = Omega * math.sqrt(1 + 3 * math.cos(theta0) ** 2)
    assert np.sort(np.abs(lin.eigenvalues.imag)) == pytest.approx([0, 0, omega, omega], abs=1e-12)
    np.testing.assert_allclose(np.sort(np.abs(np.linalg.eigvals(reference))), [0, 0, omega, omega], atol=1e-12)
    assert np.max(np.abs(lin.eigenvalues.real)) < 1e-12
    steady = linearize_steady(model, q, u, drop=["phi"])  # the cyclic φ dropped: a steady motion, residual 0
    assert steady.states == ("theta", "theta_dot", "phi_dot") and steady.residual < 1e-13  # measured 1.1e-15
    assert steady.drift == {"phi": pytest.approx(Omega, rel=1e-15, abs=0)} and steady.stability == "marginal"


def test_lagranges_method_sleigh_matches_sympys_linearizer_and_its_closed_form(cache_dir):
    r"""The Chaplygin sleigh as a LagrangesMethod with a nonholonomic constraint (the knife edge at P:
    −ẋ sin θ + ẏ cos θ = 0, ẏ dependent), sliding straight along its blade at speed v0 with heading θ0.

    Closed form (test_kane_interop's sleigh, v the speed along the blade, ω = θ̇): v̇ = a ω²,
    ω̇ = −m a v ω / J with J = I + m a²; about ω = 0 the only nonzero eigenvalue is −m a v0 / J (yaw rate
    decays with the centre of mass ahead of the blade). The four zero eigenvalues: x, y and θ, because a
    straight slide shifted or turned is again one (their columns have no restoring entry), and v, because
    a slide at another speed is again one (v̇ = a ω² is of second order in ω).
    """
    x, y, th = me.dynamicsymbols("x y theta")
    m, I, a = sp.symbols("m I a", positive=True)
    N = me.ReferenceFrame("N")
    B = N.orientnew("B", "Axis", [th, N.z])
    O = me.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x + y * N.y)
    G = P.locatenew("G", a * B.x)
    body = me.RigidBody("sleigh", G, B, m, (me.inertia(B, 0, 0, I), G))
    t = me.dynamicsymbols._t
    knife = -x.diff(t) * sp.sin(th) + y.diff(t) * sp.cos(th)
    lm = me.LagrangesMethod(me.Lagrangian(N, body), [x, y, th], nonhol_coneqs=[knife], bodies=[body], frame=N)
    lm.form_lagranges_equations()
    values = {"m": 2.0, "I": 0.3, "a": 0.4}
    model = lc.compile(lm, cache_dir=cache_dir, name="lm_chaplygin_sleigh", defaults=values)
    v0, theta0 = 1.5, 0.3
    q, u = [0.7, -0.2, theta0], [v0 * math.cos(theta0), v0 * math.sin(theta0), 0.0]
    lin = linearize_steady(model, q, u, independent=["x", "y", "theta", "x_dot", "theta_dot"])
    assert lin.dependent == ("y_dot",)
    point = {**dict(zip(lm.q, q)), **dict(zip([c.diff(t) for c in lm.q], u))}
    reference = _sympy_state_matrix(lm, [x, y, th], [x.diff(t), th.diff(t)], [], [y.diff(t)], point,
                                    {sp.Symbol(k, positive=True): v for k, v in values.items()})
    # measured: max |ΔA| = 8.9e-16 (|A| up to 1.9)
    np.testing.assert_allclose(lin.A, reference, rtol=0, atol=1e-12)
    J = values["I"] + values["m"] * values["a"] ** 2
    decay = -values["m"] * values["a"] * v0 / J
    assert lin.eigenvalues[-1] == pytest.approx(decay, rel=1e-13, abs=0) and np.all(np.abs(lin.eigenvalues[:-1]) < 1e-12)
    assert np.sort(np.linalg.eigvals(reference).real)[0] == pytest.approx(decay, rel=1e-13, abs=0)
