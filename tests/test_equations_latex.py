r"""`model.equations()` and `lagcomp show --latex`: the equations as LaTeX and text (issue 23).

The LaTeX cannot be parsed back here (sympy's `parse_latex` needs antlr), so it is checked three ways:
against equations derived by hand (a pendulum, a rod, a Kane pendulum), against sympy's `latex` of the
tidied M, F, Λ and b under hand-written names, and by matplotlib's mathtext parser (unbalanced braces,
unknown commands).  The text is parsed back with sympy and must equal M q̈ − F − Λᵀλ.  None of this
needs numba: compiling emits the modules, numba compiles a kernel at its first call only.
"""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
import textwrap

import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from sympy.parsing.sympy_parser import parse_expr

import lagcomp as lc
from lagcomp import examples
from lagcomp.cli import main
from lagcomp.codegen.latex import MAX_CHARACTERS, OMITTED, equations_source, lagrange_equations
from lagcomp.equations import Equations
from lagcomp.mechanics.lagrange import derive

mathtext = pytest.importorskip("matplotlib.mathtext")
PARSER = mathtext.MathTextParser("path")


def renders(latex: str) -> None:
    """Raise unless matplotlib's mathtext parses `latex` (math mode, no delimiters).

    mathtext has no environments: the ``cases`` of a Piecewise (sympy's `latex`, which MathJax and amsmath
    render) is parsed as a group, its ``&`` and ``\\`` as spaces, so its braces and commands are still checked.
    """
    assert latex.count(r"\begin{cases}") == latex.count(r"\end{cases}")
    for environment, group in ((r"\begin{cases}", "{"), (r"\end{cases}", "}"), ("&", r"\;"), (r"\\", r"\;")):
        latex = latex.replace(environment, group)
    PARSER.parse(f"${latex}$")


def _rod(name: str = "latex_rod") -> lc.System:
    """A bob on a rod in Cartesian coordinates: m ẍ = 2 x λ, m z̈ = −m g + 2 z λ, Φ = x² + z² − l²."""
    x, z = lc.coordinates("x z")
    m, g, length = sp.symbols("m g l", positive=True)
    return lc.System(coordinates=(x, z), T=m * (x.diff(lc.t) ** 2 + z.diff(lc.t) ** 2) / 2, V=m * g * z,
                     constraints=[lc.Holonomic("rod", x**2 + z**2 - length**2)], name=name,
                     defaults=dict(m=1.0, g=9.81, l=1.0), q0=(1.0, 0.0), qd0=(0.0, 0.0))


def _kane_pendulum():
    """A KanesMethod pendulum with speed u = l q̇: q̇ = u/l, m u̇ = −m g sin q, T + V = m u²/2 − m g l cos q."""
    from sympy.physics import mechanics as me

    q, u = me.dynamicsymbols("q u")
    m, length, g = sp.symbols("m l g", positive=True)
    N = me.ReferenceFrame("N")
    pivot = me.Point("O")
    pivot.set_vel(N, 0)
    A = N.orientnew("A", "Axis", [q, N.z])
    P = pivot.locatenew("P", -length * A.y)
    P.set_vel(N, u * A.x)
    km = me.KanesMethod(N, [q], [u], kd_eqs=[q.diff(me.dynamicsymbols._t) - u / length])
    km.kanes_equations([me.Particle("bob", P, m)], [(P, -m * g * N.y)])
    return km


@pytest.fixture(scope="module")
def models(cache_dir, compiled) -> dict:
    """The compiled pendulum, rod, double pendulum and Kane pendulum (no numba compilation: nothing runs)."""
    return {"pendulum": compiled("simple_pendulum"), "double": compiled("double_pendulum"),
            "rod": lc.compile(_rod(), cache_dir=cache_dir),
            "kane": lc.compile(_kane_pendulum(), cache_dir=cache_dir, name="latex_kane_pendulum",
                               defaults=dict(m=1.0, l=1.0, g=9.81))}


def _tokens(latex: str) -> list[str]:
    return sorted(latex.split())


# -- by hand --------------------------------------------------------------------------------------------------------

def test_the_pendulum_by_hand(models):
    # T = m l² θ̇²/2, V = −m g l cos θ: d/dt ∂T/∂θ̇ − ∂T/∂θ = m l² θ̈ = −∂V/∂θ = −m g l sin θ
    motion, = models["pendulum"].equations().part("motion")
    assert motion.label == "theta"
    assert _tokens(motion.lhs) == _tokens(r"m l^{2} \ddot{\theta}")  # up to sympy's order of the factors
    assert motion.rhs == r"- g l m \sin{\left(\theta \right)}"
    assert motion.lhs == r"l^{2} m \ddot{\theta}"  # sympy's order, the acceleration last
    assert motion.text == "l**2*m*theta_ddot = -g*l*m*sin(theta)"
    energy = {e.label: e.rhs for e in models["pendulum"].equations().part("energy")}
    assert energy == {"T": r"\frac{l^{2} m \dot{\theta}^{2}}{2}", "V": r"- g l m \cos{\left(\theta \right)}"}


def test_a_constraint_enters_with_its_multiplier(models):
    # Φ = x² + z² − l², Λ = (2x, 2z): m ẍ = 2 x λ_rod, m z̈ = −g m + 2 z λ_rod (F first, then Λᵀλ)
    equations = models["rod"].equations()
    assert [(e.label, e.lhs, e.rhs) for e in equations.part("motion")] == [
        ("x", r"m \ddot{x}", r"2 x \lambda_{rod}"),
        ("z", r"m \ddot{z}", r"- g m + 2 z \lambda_{rod}"),
    ]
    (rod,) = equations.part("constraint")
    assert (rod.label, rod.lhs, rod.rhs) == ("rod", r"- l^{2} + x^{2} + z^{2}", "0")
    assert [e.text for e in equations] == ["m*x_ddot = 2*x*lambda_rod", "m*z_ddot = -g*m + 2*z*lambda_rod",
                                           "-l**2 + x**2 + z**2 = 0", "T = m*(x_dot**2 + z_dot**2)/2", "V = g*m*z"]


def test_a_kane_model_shows_its_kinematics_and_m_udot_equals_f(models):
    # partial velocity of the bob along u is A.x; gravity's component along it is −m g sin q: m u̇ = −g m sin q
    equations = models["kane"].equations()
    (kinematics,) = equations.part("kinematics")
    assert (kinematics.lhs, kinematics.rhs, kinematics.text) == (r"\dot{q}", r"\frac{u}{l}", "q_dot = u/l")
    (motion,) = equations.part("motion")
    assert (motion.label, motion.lhs, motion.rhs) == ("u", r"m \dot{u}", r"- g m \sin{\left(q \right)}")
    (energy,) = equations.part("energy")
    q, u, m, g, length = sp.symbols("q u m g l")
    assert energy.lhs == "T + V"
    assert sp.expand(parse_expr(energy.text.split(" = ")[1], {"q": q, "u": u, "m": m, "g": g, "l": length})
                     - (m * u**2 / 2 - m * g * length * sp.cos(q))) == 0
    assert not equations.part("constraint")


# -- against sympy's rendering of the tidied expressions, and parsed back -------------------------------------------

#: The double pendulum's names written by hand: symbol name -> LaTeX.
DOUBLE = {"theta1": r"\theta_{1}", "theta2": r"\theta_{2}", "theta1_dot": r"\dot{\theta}_{1}",
          "theta2_dot": r"\dot{\theta}_{2}", "theta1_ddot": r"\ddot{\theta}_{1}", "theta2_ddot": r"\ddot{\theta}_{2}"}


def test_the_double_pendulum_is_sympys_latex_of_its_tidied_mass_matrix_and_forcing(models):
    eom = derive(examples.get("double_pendulum"))
    accelerations = [sp.Symbol(f"{q.name}_ddot", commutative=False) for q in eom.q]  # printed after their factor
    names = {s: DOUBLE[s.name] for s in (*eom.q, *eom.qd, *accelerations)}
    lines = models["double"].equations().part("motion")
    for i, line in enumerate(lines):
        assert line.lhs == sp.latex(sum((eom.M[i, j] * a for j, a in enumerate(accelerations)), sp.S.Zero),
                                    symbol_names=names)
        assert line.rhs == sp.latex(eom.F[i], symbol_names=names)
    assert r"\ddot{\theta}_{2}" in lines[0].lhs and r"\dot{\theta}_{2}^{2}" in lines[0].rhs


def _parsed_back(equations: Equations, system: lc.System) -> None:
    """Each text line, parsed by sympy, is M q̈ − F − Λᵀλ (motion) or Φ, Λ q̇ + b (constraints) of `derive`."""
    eom = derive(system)
    names = system.coordinate_names
    qdd = [sp.Symbol(f"{n}_ddot") for n in names]
    lam = [sp.Symbol(f"lambda_{c}") for c in eom.constraint_names]
    local = {s.name: s for s in (*eom.q, *eom.qd, *qdd, *lam, *eom.parameters, lc.t)}
    local.update({f"{n}_dot": v for n, v in zip(names, eom.qd, strict=True)})
    lines = {(e.part, e.label): e.text.split(" = ") for e in equations}

    def difference(key, expected):
        lhs, rhs = lines[key]
        return sp.expand(parse_expr(lhs, local) - parse_expr(rhs, local) - expected)

    for i, name in enumerate(names):
        expected = sum((eom.M[i, j] * qdd[j] for j in range(len(names))), -eom.F[i])
        assert difference(("motion", name), expected - sum(eom.C[k, i] * lam[k] for k in range(eom.k))) == 0
    holonomic = iter(eom.Phi)
    for k, c in enumerate(eom.constraint_names):
        velocity = sum((eom.C[k, i] * v for i, v in enumerate(eom.qd)), eom.b[k])
        expected = next(holonomic) if eom.holonomic[k] else velocity
        assert difference(("constraint", c), expected) == 0
    assert difference(("energy", "T"), sp.Symbol("T") - eom.T) == 0


@pytest.mark.parametrize("name", ["double_pendulum", "rolling_disc", "four_bar_linkage", "hoop_bead_reaction"])
def test_the_text_parsed_back_is_the_derived_equations(name, cache_dir):
    system = examples.get(name)
    _parsed_back(Equations(name, lagrange_equations(derive(system))), system)


def test_every_bundled_example_renders_in_mathtext_and_reads_back_from_its_module_source():
    for name, factory in examples.EXAMPLES.items():
        equations = lagrange_equations(derive(factory()))
        for e in equations:
            renders(e.lhs)
            renders(e.rhs)
        assert _constant(equations_source(equations)) == equations, name


def _constant(source: str) -> tuple:
    """The value of ``EQUATIONS = (...)`` in `source`, read back as Python literals."""
    (assignment,) = [node for node in ast.parse(source).body if isinstance(node, ast.Assign)]
    return ast.literal_eval(assignment.value)


def test_a_side_longer_than_the_cap_is_omitted_with_a_marker():
    (x,) = lc.coordinates("x")
    a = sp.Symbol("a", positive=True)
    system = lc.System(coordinates=(x,), T=x.diff(lc.t) ** 2 / 2, V=sum(a**k * x**k / k for k in range(1, 400)),
                       name="latex_long")
    motion, _, potential = lagrange_equations(derive(system))
    assert (motion.lhs, motion.rhs) == (r"\ddot{x}", OMITTED[0]) and motion.text == f"x_ddot = {OMITTED[1]}"
    assert potential.rhs == OMITTED[0]
    renders(OMITTED[0])
    assert str(MAX_CHARACTERS) in OMITTED[0]


# -- users' names --------------------------------------------------------------------------------------------------

GREEK = ("alpha", "beta", "gamma", "Gamma", "delta", "Delta", "epsilon", "theta", "Theta", "lambda", "lamda", "mu",
         "nu", "xi", "pi", "rho", "sigma", "tau", "phi", "Phi", "chi", "psi", "Psi", "omega", "Omega")
#: Names the modules, Python or LaTeX use themselves (tests/test_names.py has the longer list).
RESERVED = ("k", "i", "y", "p", "out", "for", "in", "range", "lambda_", "x_dot", "q_x", "mom_x", "X0", "_c0", "_u1",
            "dot", "ddot", "frac", "sin", "left", "right", "text", "xbar", "xdot", "a__b", "x_", "l_1_2")
NAMES = st.one_of(
    st.sampled_from(GREEK + RESERVED),
    st.builds(lambda base, digits, sub: base + digits + sub,
              st.sampled_from(GREEK + tuple("abcxyzABXZ")), st.sampled_from(("", "1", "2", "12", "0")),
              st.sampled_from(("", "_1", "_a", "_theta", "_x_y", "_max"))),
)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(names=st.lists(NAMES, min_size=5, max_size=5, unique=True).filter(lambda names: "t" not in names))
def test_any_coordinate_and_parameter_names_render(names):
    first, second, mass, stiffness, constraint = names
    x, z = lc.coordinates(f"{first} {second}")
    m, k = sp.Symbol(mass, positive=True), sp.Symbol(stiffness, positive=True)
    rolling = constraint if constraint.isidentifier() else "c"
    system = lc.System(coordinates=(x, z), T=m * (x.diff(lc.t) ** 2 + z.diff(lc.t) ** 2) / 2,
                       V=k * sp.cos(x) * z**2, constraints=[lc.Nonholonomic(rolling, x.diff(lc.t) - k * z)],
                       parameters=(m, k), name="latex_names")
    equations = lagrange_equations(derive(system))
    for e in equations:
        renders(e.lhs)
        renders(e.rhs)
    assert _constant(equations_source(equations)) == equations
    motion = [e for e in equations if e.part == "motion"]
    assert [e.label for e in motion] == [first, second]
    assert r"\ddot{" in motion[0].lhs and sp.latex(sp.Symbol(f"lambda_{rolling}")) in motion[0].rhs


# -- from the cache without sympy, the command line, the result object ---------------------------------------------

LOAD_PROBE = textwrap.dedent(
    """
    import json, sys
    import lagcomp as lc

    equations = lc.load("latex_rod", cache_dir=sys.argv[1]).equations()
    print(json.dumps({"sympy_imported": "sympy" in sys.modules, "equations": equations.equations,
                      "latex": equations.latex}))
    """
)


def test_a_model_loaded_without_sympy_has_the_same_equations(models, cache_dir):
    env = {k: v for k, v in os.environ.items() if k != "LAGCOMP_CACHE_DIR"}
    out = subprocess.run([sys.executable, "-c", LOAD_PROBE, str(cache_dir)], capture_output=True, text=True,
                         env=env, check=True)
    loaded = json.loads(out.stdout.strip().splitlines()[-1])
    equations = models["rod"].equations()
    assert loaded == {"sympy_imported": False, "equations": [list(e) for e in equations],
                      "latex": equations.latex}


def test_show_latex_prints_the_align_environment(models, cache_dir, capsys):
    for name, model in (("simple_pendulum", models["pendulum"]), ("latex_rod", models["rod"]),
                        ("latex_kane_pendulum", models["kane"])):
        assert main(["--cache-dir", str(cache_dir), "show", name, "--latex"]) == 0
        out = capsys.readouterr().out
        assert out == model.equations().latex + "\n"
        assert out.startswith("\\begin{align*}\n") and out.endswith("\\end{align*}\n")
    assert main(["--cache-dir", str(cache_dir), "show", "latex_rod", "--latex"]) == 0
    assert r"m \ddot{x} &= 2 x \lambda_{rod} \\" in capsys.readouterr().out.splitlines()


def test_show_of_a_users_model_prints_its_equations_as_text(models, cache_dir, capsys):
    assert main(["--cache-dir", str(cache_dir), "show", "latex_rod"]) == 0
    out = capsys.readouterr().out
    assert "Equations of motion:\n  m*x_ddot = 2*x*lambda_rod\n" in out and "Constraints:\n  -l**2" in out


def test_the_result_renders_in_jupyter_and_as_text(models):
    equations = models["rod"].equations()
    latex = equations._repr_latex_()
    assert latex.startswith("$$\\begin{aligned}\n") and latex.endswith("\\end{aligned}$$")
    assert equations.lines[0] == r"m \ddot{x} &= 2 x \lambda_{rod}" and len(equations) == 5
    assert str(equations).splitlines()[:3] == ["Equations of 'latex_rod'", "", "Equations of motion:"]
    assert repr(equations) == "Equations('latex_rod': 2 motion, 1 constraint, 2 energy)"
    assert "model.equations()" in models["rod"]._repr_html_()
    with pytest.raises(ValueError, match="part"):
        equations.part("kinetic")
