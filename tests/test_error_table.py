"""Every row of docs/errors.md, provoked: the exception (or warning) it names, and a message naming the culprit.

`CASES` maps each case of the table to (trigger, culprit): the trigger does
the wrong thing, the culprit is text the message must contain.  The test
reads the table, so a row without a case (or a case without a row) fails.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
import warnings
from dataclasses import replace
from pathlib import Path

import numba
import numpy as np
import pytest
import sympy as sp

import lagcomp as lc
from lagcomp import analysis as an
from lagcomp import cli
from lagcomp.cli_support import models as cli_models
from lagcomp.cli_support import outputs as cli_outputs
from lagcomp.cli_support import run_inputs as cli_inputs
from lagcomp.model import t
from lagcomp.multibody import link_point
from lagcomp.numba_cache import cache_directory

TABLE = Path(__file__).resolve().parent.parent / "docs" / "errors.md"

x, y = lc.coordinates("x y")
m, k, g, l = sp.symbols("m k g l", positive=True)
a, c = sp.symbols("a c")


def _rows() -> dict[str, str]:
    """{case: the 'lagcomp answers' cell} of every table row."""
    rows = {}
    for line in TABLE.read_text(encoding="utf-8").splitlines():
        match = re.match(r"\| `([\w-]+)` \|(.*)\|\s*$", line)
        if match:
            cells = [cell.strip() for cell in re.split(r"(?<!\\)\|", match.group(2))]
            rows[match.group(1)] = cells[1]
    return rows


def _expected(answer: str) -> type:
    """The class the row's 'lagcomp answers' cell names: IntegrationError for run failures (throw=True)."""
    name = "IntegrationError" if answer.startswith("status") else re.match(r"`(\w+)`", answer).group(1)
    return getattr(lc, name)


# -- the systems the triggers use -------------------------------------------------------


def oscillator(**overrides) -> lc.System:
    spec = dict(coordinates=[x], T=m * x.diff(t) ** 2 / 2, V=k * x**2 / 2, name="table_oscillator",
                defaults={"m": 1.0, "k": 1.0}, q0=(1.0,))
    spec.update(overrides)
    return lc.System(**spec)


def plane(**overrides) -> lc.System:
    spec = dict(coordinates=[x, y], T=m * (x.diff(t) ** 2 + y.diff(t) ** 2) / 2, V=m * g * y, name="table_plane")
    spec.update(overrides)
    return lc.System(**spec)


@pytest.fixture(scope="module")
def models(compiled, cache_dir):
    """The models of the run-time rows: examples shared with the other tests, and one that fails on purpose."""
    # M = m (1 − c t) vanishes at t = 1/c; the force a q̇² makes q̇ blow up in finite time
    failing = lc.System([x], T=m * (1 - c * t) * x.diff(t) ** 2 / 2, forces=[a * x.diff(t) ** 2],
                        name="table_failing", defaults={"m": 1.0, "a": 0.0, "c": 0.0}, q0=(0.0,), qd0=(1.0,))
    degenerate = lc.System([x], T=m * x**2 * x.diff(t) ** 2 / 2, name="table_degenerate",
                           events=[lc.Event("origin", x)])
    ball = lc.System([x], T=m * x.diff(t) ** 2 / 2, V=m * g * x, name="table_ball", q0=(1.0,),
                     defaults={"m": 1.0, "g": 9.81, "c": 0.8},
                     events=[lc.Event("bounce", x, direction=-1, reset={x.diff(t): -c * x.diff(t)})])
    blowup = replace(ball, name="table_ball_blowup",
                     events=[lc.Event("bounce", x, direction=-1, reset={x.diff(t): x.diff(t) * sp.exp(1000 * g)})],
                     defaults={"m": 1.0, "g": 9.81, "c": 0.8})
    walled = plane(constraints=[lc.Holonomic("rod", x**2 + y**2 - l**2), lc.Holonomic("wall", x - l)],
                   name="table_walled", defaults={"m": 1.0, "g": 9.81, "l": 1.0}, q0=(1.0, 0.0))
    return {
        "pendulum": compiled("simple_pendulum"),
        "stiff": compiled("stiff_spring_pendulum"),
        "rod": compiled("spherical_pendulum_cartesian"),
        "failing": lc.compile(failing, cache_dir=cache_dir),
        "degenerate": lc.compile(degenerate, cache_dir=cache_dir),
        "bouncer": lc.compile(plane(events=[lc.Contact("floor", y, restitution=c)], name="table_bouncer",
                                    defaults={"m": 1.0, "g": 9.81, "c": 0.5}), cache_dir=cache_dir),
        "walled": lc.compile(walled, cache_dir=cache_dir),
        "ball": lc.compile(ball, cache_dir=cache_dir),
        "blowup": lc.compile(blowup, cache_dir=cache_dir),
        "friction": compiled("rope_friction"),
        "slider": lc.compile(oscillator(V=0, name="table_slider", defaults={"m": 1.0, "g": 9.81, "c": 0.5, "a": 0.3},
                                        events=[lc.Friction("slide", x.diff(t), normal=m * g, static=c, kinetic=a)]),
                             cache_dir=cache_dir),
        # four contacts, four friction elements: 2^4 mode sets each, more than the Taylor method's programs
        "crowd": lc.compile(plane(events=_walls(), name="table_crowd", defaults={"m": 1.0, "g": 9.81}),
                            cache_dir=cache_dir),
        "crowd_slider": lc.compile(plane(events=[lc.Friction(name, v, normal=m * g, static=c, kinetic=a) for name, v in
                                                 (("slide", x.diff(t)), ("drift", y.diff(t)),
                                                  ("skid", x.diff(t) + y.diff(t)), ("spin", x.diff(t) - y.diff(t)))],
                                         name="table_crowd_slider", defaults={"m": 1.0, "g": 9.81, "c": 0.5, "a": 0.3}),
                                   cache_dir=cache_dir),
        # a point sliding on a frictional floor into a wall that leans over it: the wall pushes it into the floor
        "leaning": lc.compile(plane(events=[lc.Contact("floor", y, restitution=0.0),
                                            lc.Contact("wall", 1 - x - y / 2, restitution=0.5),
                                            lc.Friction("ground", x.diff(t), normal="floor", static=0.2)],
                                    name="table_leaning", defaults={"m": 1.0, "g": 9.81}), cache_dir=cache_dir),
        "kane": lc.compile(_kane_slider(), name="table_kane_slider", cache_dir=cache_dir, defaults={"m": 1.0}),
        "kane_across": lc.compile(_kane_slider(across=True), name="table_kane_slider_across", cache_dir=cache_dir,
                                  defaults={"m": 1.0}),
        # a support moved by an input s(t): ẍ_s in the forcing (a linear table is refused for it)
        "driven": lc.compile(oscillator(T=m * (x.diff(t) + lc.Input("s").diff(t)) ** 2 / 2, name="table_driven"),
                             cache_dir=cache_dir),
        # a force u(t) supplied at run time, read without derivatives: what a numba function may give
        "pushed": lc.compile(oscillator(forces=[lc.Input("f")], name="table_pushed"), cache_dir=cache_dir),
        # an event that reads an input: no event partials, so no event-time sensitivities
        "signalled": lc.compile(oscillator(events=[lc.Event("past", x - lc.Input("s"))], name="table_signalled"),
                                cache_dir=cache_dir),
        # a parameter named like the velocity of x: derived correctly, but "x_dot" is ambiguous in a sweep grid
        "clash": lc.compile(oscillator(V=sp.Symbol("x_dot") * x, name="table_clash",
                                       defaults={"m": 1.0, "x_dot": 1.0}), cache_dir=cache_dir),
    }


def _walls() -> list:
    """Four contacts around the unit square of `plane`: 16 mode sets."""
    return [lc.Contact("floor", y, restitution=0.5), lc.Contact("ceiling", 1 - y, restitution=0.5),
            lc.Contact("left", x, restitution=0.5), lc.Contact("right", 1 - x, restitution=0.5)]


def _close_approach(model, points):
    from lagcomp.accuracy import close_approach_states

    return close_approach_states(model, points, 3)


def _simulate(name, **options):
    def run(models):
        t_span = options.pop("t_span", (0.0, 1.0))
        return models[name].simulate(t_span, **options)
    return run


def _fail(name, **options):
    return _simulate(name, throw=True, progress=False, **options)


def _large_taylor_sensitivities(tmp_path):
    """Every state's sensitivity of a 6-link planar chain with method="taylor": a variational kernel of 12 columns
    over a program of 510 operations, which `lagcomp.codegen.taylor_kernel_frame.check_size` refuses."""
    from lagcomp.examples.trees import planar_chain

    model = lc.compile(planar_chain(6), cache_dir=tmp_path, progress=False)
    return model.simulate((0.0, 0.1), [0.1] * model.n, [0.0] * model.n, params=dict.fromkeys(model.parameters, 1.0),
                          method="taylor", sensitivities=("q0", "qd0"), progress=False)


def _cache_case(kind):
    def provoke(models, tmp_path):
        system = oscillator(name="table_cached")
        if kind == "unwritable":
            blocker = tmp_path / "file"
            blocker.write_text("")
            return lc.compile(system, cache_dir=blocker / "cache")
        lc.compile(system, cache_dir=tmp_path)
        if kind == "name record":
            (record,) = (tmp_path / "names").glob("table_cached*.json")
            record.write_text("{")
            return lc.load("table_cached", cache_dir=tmp_path)
        if kind == "numba":
            model = lc.compile(oscillator(name="table_numba"), cache_dir=tmp_path)
            model.simulate((0, 0.1), method="rk4", dt=0.01, progress=False)  # numba writes its cache files
            for data in cache_directory(model.source_path).glob("table_numba*.nbc"):
                data.write_bytes(b"\x80\x05 not a pickle")
            del sys.modules[model.kernels.__name__]  # as a new process: the module runs again, numba reads its files
            return lc.compile(oscillator(name="table_numba"), cache_dir=tmp_path)
        if kind == "corrupt":
            (module,) = (tmp_path / "modules").glob("*.py")
            module.write_text(module.read_text()[:100])
        else:
            (index,) = (tmp_path / "index").glob("*.json")
            record = json.loads(index.read_text())
            index.write_text(json.dumps({**record, "versions": "numba=0.0.1"}))
        return lc.compile(system, cache_dir=tmp_path)
    return provoke


def _plots():
    pytest.importorskip("matplotlib")
    from lagcomp import plots

    return plots


def _sweep(models):
    return models["pendulum"].sweep((0, 1), {"l": [1.0, 2.0]}, progress=False)


def _saved_solution(models, tmp_path):
    models["pendulum"].simulate((0, 1)).save_npz(tmp_path / "run.npz")
    return tmp_path / "run.npz"


def _unpickle_without_entry(tmp_path):
    """A pickled model from `lc.load` (no System), its cache removed before it is unpickled."""
    import pickle
    import shutil

    lc.compile(oscillator(name="table_cached"), cache_dir=tmp_path / "gone")
    blob = pickle.dumps(lc.load("table_cached", cache_dir=tmp_path / "gone"))
    shutil.rmtree(tmp_path / "gone")
    return pickle.loads(blob)


def _cli_args(name, tmp_path, **flags):
    return argparse.Namespace(name=name, arg=None, cached=False, cache_dir=str(tmp_path / "cache"), **flags)


def _cli_model(name, tmp_path):
    return cli_models.resolve(_cli_args(str(name), tmp_path)).model()


def _model_file(tmp_path, text):
    path = tmp_path / "table_model.py"
    path.write_text(text, encoding="utf-8")
    return path


def _cli_input(tmp_path, spec):
    (tmp_path / "push.csv").write_text("time,value\n0,0\n1,1\n", encoding="utf-8")
    return cli_inputs.parse_input(spec, tmp_path)


def _cli_config(tmp_path, text):
    (tmp_path / "run.toml").write_text(text, encoding="utf-8")
    return cli_inputs.read_config(str(tmp_path / "run.toml"))


def _cli_stability_of_cached(models):
    """`lagcomp stability simple_pendulum --cached`: the model the cache holds under that name has no System."""
    cache = str(models["pendulum"].source_path.parents[1])
    return cli.cmd_stability(argparse.Namespace(name="simple_pendulum", arg=None, cached=True, cache_dir=cache,
                                                param="l", range=[1.0, 2.0], num=3, set=None, q=None, u=None,
                                                drop=None, plot=None, config=None))


def _cli_system(name, *arguments):
    """What `lagcomp run NAME --arg ...` builds before anything else."""
    return cli_models.example_system(name, list(arguments))


def _inertia():
    from sympy.physics.vector import ReferenceFrame

    N = ReferenceFrame("N")
    return lc.RigidBody(m, (x, 0, 0), (1, -2, 1), N)


def _lagranges_method_without_frame():
    import sympy.physics.mechanics as me

    return lc.compile(me.LagrangesMethod(m * x.diff(t) ** 2 / 2, [x], forcelist=[(me.Point("P"), me.ReferenceFrame("N").x)]))


def me_function(name):
    """A function of time (``dynamicsymbols(name)``)."""
    import sympy.physics.mechanics as me

    return me.dynamicsymbols(name)


def _rolling_disc_by_hand():
    """A LagrangesMethod whose disc centre's velocity comes from a contact point set at rest (v2pt_theory)."""
    import sympy.physics.mechanics as me

    N = me.ReferenceFrame("N")
    D = N.orientnew("D", "Axis", [-x, N.z])
    C = me.Point("C")
    C.set_vel(N, 0)
    G = C.locatenew("G", l * N.y)
    G.v2pt_theory(C, N, D)
    disc = me.RigidBody("disc", G, D, m, (me.inertia(D, 1, 1, 2), G))
    return lc.compile(me.LagrangesMethod(me.Lagrangian(N, disc), [x], bodies=[disc], frame=N))


def _kane_slider(formed=True, force=None, across=False):
    """x' = w, a particle pushed along N.x by `force` (default none); KanesMethod, equations formed or not.
    `across`: a second speed v along N.y, held at 0 by a velocity constraint (v dependent)."""
    import sympy.physics.mechanics as me

    w, v = me.dynamicsymbols("w v")
    N = me.ReferenceFrame("N")
    P = me.Point("P")
    P.set_vel(N, w * N.x + (v * N.y if across else 0))
    constraint = dict(u_dependent=[v], velocity_constraints=[v]) if across else {}
    km = me.KanesMethod(N, [x], [w], kd_eqs=[x.diff(t) - w], **constraint)
    if formed:
        km.kanes_equations([me.Particle("p", P, m)], [(P, force * N.x)] if force is not None else [])
    return km


def _on_demand_without_equations(tmp_path):
    """A loaded model whose entry keeps no equations, asked for its Jacobian (an on-demand kernel)."""
    from lagcomp import runtime

    lc.compile(oscillator(), cache_dir=tmp_path)
    for kept in (tmp_path / "equations").glob("*.pickle"):
        kept.unlink()
    runtime._NAMESPACES.clear()     # (as in a new process)
    lc.load(oscillator().name, cache_dir=tmp_path).jacobian(0.0, [0.1, 0.0])


def _planar_loop(directions: str) -> lc.Tree:
    """Two rods hinged about z at (0, 0) and (1, 0), their ends pinned together by a cut joint."""
    rod = {"mass": m, "com": (l / 2, 0, 0), "inertia": (0, m * l**2 / 12, m * l**2 / 12)}
    return lc.Tree([lc.Link("left", lc.Revolute("q1"), **rod), lc.Link("right", lc.Revolute("q2", origin=(1, 0, 0)),
                                                                          **rod)],
                   name="tree_loop", defaults={"m": 1.0, "l": 1.0},
                   loops=[lc.Loop("pin", ("left", (l, 0, 0)), ("right", (l, 0, 0)), directions=directions)])


def _from_urdf(tmp_path, kind: str):
    """lc.from_urdf of a two-link URDF whose one joint, 'base', is of `kind` (a skip without yourdfpy)."""
    pytest.importorskip("yourdfpy")
    inertial = '<inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial>'
    path = tmp_path / "bot.urdf"
    path.write_text(f'<robot name="bot"><link name="ground"/><link name="arm">{inertial}</link><joint name="base" '
                    f'type="{kind}"><parent link="ground"/><child link="arm"/></joint></robot>', encoding="utf-8")
    lc.from_urdf(path)


def _points_of_a_loaded_model(tmp_path):
    """A body's point as an output of the linearization of a model from `lc.load` (no System kept)."""
    lc.compile(oscillator(), cache_dir=tmp_path)
    an.linearize(lc.load(oscillator().name, cache_dir=tmp_path), [0.0], outputs=["bob.x"])


def _tree_batched_sweep(tmp_path):
    """A batched sweep of a kinematic tree with a closed loop: its lanes evaluate the articulated-body rhs only, and
    the loop's motion is an augmented solve (a tree without loops, contacts or friction has them:
    tests/test_multibody_lanes.py)."""
    model = lc.compile(_planar_loop("x"), cache_dir=tmp_path)
    model.sweep((0, 0.1), {"m": [1.0, 2.0]}, q0=[np.pi / 3, 2 * np.pi / 3], qd0=[0.0, 0.0], method="rk4", dt=0.01,
                batched=True)


def _tree_steady(tmp_path):
    """linearize_steady on a model compiled from a kinematic tree: it reduces a System's symbolic equations."""
    tree = lc.Tree([lc.Link("rod", lc.Revolute("q"), mass=m, com=(l, 0, 0), inertia=(0, 0, 0))], gravity=(0, -g, 0),
                   name="tree_rod", defaults={"m": 1.0, "l": 1.0, "g": 9.81})
    an.linearize_steady(lc.compile(tree, cache_dir=tmp_path), [0.1], [0.0])


CASES = {
    # the description: System(...) and compile
    "undeclared-symbol": (lambda: oscillator(V=k * x**2 / 2 + sp.Symbol("stray") * x, parameters=(m, k)), "stray"),
    "undeclared-function": (lambda: oscillator(V=k * (x - sp.Function("phi")(t)) ** 2), "phi(t)"),
    "input-name-clash": (lambda: oscillator(forces=[lc.Input("k")]), "['k']"),
    "input-law-with-velocities-in-T": (
        lambda: oscillator(T=(m + lc.Input("lift", law=c * x.diff(t))) * x.diff(t) ** 2 / 2), "lift"),
    "input-missing": (_simulate("driven"), "['s']"),
    "input-unknown": (_simulate("driven", inputs={"s": 0.0, "r": 0.0}), "['r']"),
    "input-times-not-increasing": (_simulate("driven", inputs={"s": ([0.0, 1.0, 0.5, 2.0], [0.0] * 4)}), "times[1]"),
    "input-not-finite": (_simulate("driven", inputs={"s": ([0.0, 1.0, 2.0], [0.0, math.nan, 0.0])}), "`s`"),
    "input-length-mismatch": (_simulate("driven", inputs={"s": ([0.0, 1.0, 2.0], [0.0, 0.0])}), "3 times but 2"),
    "input-does-not-cover-run": (_simulate("driven", inputs={"s": ([0.0, 0.5], [0.0, 0.0])}), "[0.0, 0.5]"),
    "input-linear-needs-acceleration": (
        _simulate("driven", inputs={"s": lc.Tabulated([0.0, 2.0], [0.0, 1.0], kind="linear")}), "`s`"),
    "input-with-taylor": (_simulate("driven", inputs={"s": 0.0}, method="taylor"), "inputs supplied at run time"),
    "input-function-not-numba": (_simulate("pushed", inputs={"f": lambda t, y, p: 0.0}), "@numba.njit"),
    "input-function-signature": (_simulate("pushed", inputs={"f": numba.njit(lambda t, y: t)}),
                                 "u(t: float64, y: float64[::1], p: float64[::1]) -> float64"),
    "input-function-reads-outside": (_simulate("pushed", inputs={"f": numba.njit(lambda t, y, p: p[40])}),
                                     "Input `f`"),
    "input-function-needs-derivative": (_simulate("driven", inputs={"s": numba.njit(lambda t, y, p: t)}),
                                        "derivative of order 2"),
    "input-function-with-radau": (_simulate("pushed", inputs={"f": numba.njit(lambda t, y, p: 0.0)}, method="radau"),
                                  "['f']"),
    "input-function-on-dask": (lambda models: models["pushed"].sweep(
        (0.0, 1.0), {"x": [0.0]}, inputs={"f": numba.njit(lambda t, y, p: 0.0)}, client=object()), "['f']"),
    "input-one-state-evaluation": (lambda models: models["driven"].rhs(0.0, [0.0, 0.0]), "['s']"),
    "inputs-without-inputs": (_simulate("pendulum", inputs={"s": 0.0}), "has no inputs"),
    "plain-symbol-coordinate": (lambda: lc.System([sp.Symbol("q")], T=sp.Symbol("q") ** 2, name="bad"), "Coordinate q"),
    "repeated-coordinate": (lambda: lc.System([x, x], T=m * x.diff(t) ** 2), "(x(t), x(t))"),
    "bad-system-name": (lambda: oscillator(name="double-pendulum"), "'double-pendulum'"),
    "not-an-expression": (lambda: oscillator(T=[m]), "`T` must be a sympy expression"),
    "expression-is-a-string": (lambda: oscillator(events=[lc.Event("hit", "x - 1")]),
                               "Event `hit`: the expression is the string 'x - 1'"),
    "complex-or-infinite-expression": (lambda: oscillator(V=sp.I * k * x**2), "V contains the imaginary unit"),
    "coordinates-not-a-sequence": (lambda: lc.System("x", T=m * x.diff(t) ** 2), "`coordinates`"),
    "field-not-a-sequence": (lambda: plane(constraints=lc.Holonomic("floor", y)), "`constraints` must be a sequence"),
    "bad-t-end": (lambda: oscillator(t_end=-1.0), "`t_end`"),
    "defaults-not-a-mapping": (lambda: oscillator(defaults=[1.0, 2.0]), "`defaults`"),
    "no-kinetic-energy": (lambda: oscillator(T=0), "'table_oscillator' has no kinetic energy"),
    "T-not-quadratic": (lambda: lc.compile(oscillator(T=m * x.diff(t) ** 4)), "kinetic energy T"),
    "accelerations-in-expressions": (lambda: lc.compile(oscillator(events=[lc.Event("e", x.diff(t, 2))])),
                                     "Derivative(x(t), (t, 2))"),
    "velocity-dependent-potential": (lambda: lc.compile(oscillator(V=k * x * x.diff(t))), "potential V"),
    "non-smooth-T": (lambda: lc.compile(oscillator(T=sp.Piecewise((m, x > 0), (2 * m, True)) * x.diff(t) ** 2 / 2)),
                     "T of 'table_oscillator' contains Piecewise"),
    "non-smooth-constraint": (lambda: lc.compile(plane(constraints=[lc.Holonomic("kink", sp.Abs(x) - y)])),
                              "constraint `kink`"),
    "dissipation-not-quadratic": (lambda: lc.compile(oscillator(dissipation=c * x**2 / 2)), "table_oscillator"),
    "jump-in-potential": (lambda: lc.compile(oscillator(V=k * sp.Heaviside(x))), "Heaviside(x)"),
    "zero-inertia-coordinate": (lambda: lc.compile(plane(T=m * x.diff(t) ** 2 / 2)), "`y`"),
    "singular-mass-matrix": (lambda: lc.compile(plane(T=m * (x.diff(t) + y.diff(t)) ** 2 / 2)), "x, y"),
    "negative-kinetic-energy": (lambda: lc.compile(oscillator(T=-m * x.diff(t) ** 2 / 2)), "negative eigenvalue"),
    "redundant-constraints": (lambda: lc.compile(plane(constraints=[lc.Holonomic("one", x - y),
                                                                    lc.Holonomic("two", 2 * x - 2 * y)])),
                              "['one', 'two']"),
    "holonomic-with-velocities": (lambda: plane(constraints=[lc.Holonomic("c", x.diff(t) - y)]), "`c`"),
    "nonholonomic-not-linear": (lambda: lc.compile(plane(constraints=[lc.Nonholonomic("c", x.diff(t) ** 2 - y)])),
                                "`c`"),
    "bad-constraint-name": (lambda: lc.Holonomic("a rod", x), "'a rod'"),
    "repeated-constraint-names": (lambda: plane(constraints=[lc.Holonomic("c", x), lc.Holonomic("c", y)]), "['c']"),
    "forces-wrong-length": (lambda: oscillator(forces=[1, 2]), "`forces` has 2 entries"),
    "forces-unknown-coordinate": (lambda: oscillator(forces={y: 1}), "y(t)"),
    "parameter-not-a-symbol": (lambda: oscillator(parameters=(m, k, 3)), "Parameter 3"),
    "symbol-named-t": (lambda: oscillator(V=k * x**2 / 2 + sp.Symbol("t", real=True) * x),
                       "symbol named t (Symbol('t', real=True))"),
    "same-name-symbols": (lambda: oscillator(V=(k + sp.Symbol("k")) * x**2 / 2, defaults={}), "['k']"),
    "event-undeclared-symbol": (lambda: oscillator(events=[lc.Event("hit", x - sp.Symbol("wall"))], parameters=(m, k)),
                                "wall appear in 'table_oscillator' (first in event hit)"),
    "event-bad-direction": (lambda: lc.Event("hit", x, direction=2), "got 2"),
    "reset-terminal": (lambda: lc.Event("hit", x, terminal=True, reset={x.diff(t): 0}), "terminal"),
    "reset-not-a-state": (lambda: lc.Event("hit", x, reset={x.diff(t, 2): 0}), "Derivative(x(t), (t, 2))"),
    "reset-unknown-coordinate": (lambda: oscillator(events=[lc.Event("hit", x, reset={y.diff(t): 0})]), "y(t)"),
    "reset-undeclared-symbol": (lambda: oscillator(parameters=(m, k), events=[
        lc.Event("hit", x, reset={x.diff(t): -a * x.diff(t)})]), "event hit reset"),
    "reset-reads-input": (lambda: oscillator(events=[lc.Event("hit", x, reset={x.diff(t): lc.Input("s")})]),
                          "s(t)"),
    "resets-method": (_simulate("ball", method="rk4", dt=0.01), "['bounce']"),
    "resets-with-sensitivities": (_simulate("ball", sensitivities="q0"), "saltation"),
    "resets-batched-sweep": (lambda models: models["ball"].sweep((0.0, 1.0), {"c": [0.5, 0.6]}, batched=True,
                                                                 progress=False), "batched"),
    "reset-non-finite": (_fail("blowup"), "reset"),
    "events-accumulated": (_fail("ball", t_span=(0.0, 6.0)), "accumulate"),
    "reset-gone-through": (_simulate("ball", params={"c": 0.0}), "lc.Contact"),
    "simultaneous-frictional-impact": (_fail("leaning", t_span=(0.0, 0.5), q0=[0.0, 0.0], qd0=[3.0, 0.0]),
                                       "sliding friction element"),
    "contact-restitution-out-of-range": (lambda: lc.Contact("floor", x, restitution=1.5), "`floor`"),
    "contact-gap-with-velocities": (lambda: lc.Contact("floor", x + x.diff(t)), "`floor`"),
    "contact-unknown-coordinate": (lambda: oscillator(events=[lc.Contact("floor", x - sp.Function("w")(t))]),
                                   "w(t)"),
    "contact-on-kanes-method": (lambda: lc.compile(_kane_slider(), events=[lc.Contact("wall", x)]), "`wall`"),
    "friction-coefficient-out-of-range": (lambda: lc.Friction("slide", x.diff(t), normal=m * g, static=-0.1),
                                          "`slide`"),
    "friction-velocity-not-linear": (lambda: lc.compile(oscillator(events=[
        lc.Friction("slide", x.diff(t) ** 3, normal=m * g, static=0.5)])), "`slide`"),
    "friction-unknown-contact": (lambda: plane(events=[lc.Contact("floor", y), lc.Friction(
        "slide", x.diff(t), normal="ground", static=0.5)]), "'ground'"),
    "default-unknown-parameter": (lambda: oscillator(defaults={"mass": 1.0}), "['mass']"),
    "default-not-a-number": (lambda: oscillator(defaults={"m": "heavy", "k": 1.0}), "`m`"),
    "default-initial-values": (lambda: oscillator(q0=("one",)), "`q0`"),
    "not-a-system": (lambda: lc.compile("double_pendulum"), "got str"),
    "inertia-not-positive": (_inertia, "inertia"),
    "velocity-set-by-hand": (_rolling_disc_by_hand, "point G: its velocity in N was set by hand"),
    "tree-joint-coordinates": (lambda: lc.Tree([lc.Link("ball", lc.Spherical(("a", "b")), mass=1.0)]),
                               "Spherical('a', 'b'): needs 3 coordinates"),
    "tree-parent-not-listed": (lambda: lc.Tree([lc.Link("arm", lc.Revolute("q"), parent="base", mass=1.0)]),
                               "'base'"),
    "tree-kernel-not-available": (_tree_batched_sweep, ("`rhs_lanes` (batched sweeps) is not available for the "
                                                       "kinematic tree 'tree_loop' yet: its motion has closed loops "
                                                       "['pin']")),
    "tree-no-lagrangian": (_tree_steady, "linearize_steady"),
    "tree-loop-unknown-link": (lambda: lc.Tree(_planar_loop("xy").links, loops=[
        lc.Loop("pin", ("left", (1, 0, 0)), ("rihgt", (1, 0, 0)))]), "'rihgt'"),
    "tree-loop-idle-direction": (lambda tmp_path: lc.compile(_planar_loop("xyz"), cache_dir=tmp_path), "'pin_z'"),
    "tree-point-not-placed": (lambda: link_point([lc.Link("arm", lc.Revolute("q"), mass=1.0)], "amr", (1, 0, 0)),
                              "'amr'"),
    "urdf-joint-not-available": (lambda tmp_path: _from_urdf(tmp_path, "ball"),
                                 "joint 'base' has the unknown type 'ball'"),
    "urdf-not-a-tree": (lambda tmp_path: _from_urdf(tmp_path, "fixed"), "nothing in 'bot' moves"),
    "kane-equations-not-formed": (lambda: lc.compile(_kane_slider(formed=False)), "kanes_equations"),
    "kane-specified-function": (lambda: lc.compile(_kane_slider(force=me_function("F"))), "F(t)"),
    "kane-method-not-applicable": (_simulate("kane", q0=[0.0], method="gauss2", dt=0.1), "`gauss2`"),
    "kane-radau-projection": (_simulate("kane_across", q0=[0.0], method="radau", projection=True),
                              "`radau` does not project"),
    "kane-initial-velocities": (_simulate("kane", q0=[0.0], qd0=[1.0]), "`u0`"),
    "lagrange-initial-speeds": (_simulate("pendulum", u0=[1.0]), "'simple_pendulum' is a Lagrange model"),
    "kane-event-unknown-symbol": (lambda: lc.compile(_kane_slider(), events=[lc.Event("wall", x - sp.Symbol("w0"))]),
                                  "Event `wall` holds ['w0']"),
    "kane-batched-sweep": (lambda models: models["kane"].sweep((0, 1), {"m": [1.0]}, q0=[0.0], batched=True),
                           "'table_kane_slider' is a Kane model"),
    "kane-no-lagrangian": (lambda models: an.conserved_quantities(models["kane"]),
                           "'table_kane_slider' is a Kane model"),
    # a run's inputs: Model.simulate
    "unknown-parameter": (_simulate("pendulum", params={"mass": 1.0}), "['mass']"),
    "missing-parameter": (lambda models: models["degenerate"].simulate((0, 1), q0=[1.0], params={}), "['m']"),
    "non-finite-parameter": (_simulate("pendulum", params={"g": math.inf}), "`g` is inf"),
    "parameter-boolean": (_simulate("pendulum", params={"m": np.bool_(True)}), "`m`"),
    "parameter-not-a-number": (_simulate("pendulum", params={"l": [1.0, 2.0]}), "`l`"),
    "params-not-a-mapping": (_simulate("pendulum", params=[1.0, 1.0, 9.81]), "`params`"),
    "params-keys-not-names": (_simulate("pendulum", params={3: 1.0}), "`params` keys"),
    "initial-wrong-length": (_simulate("pendulum", q0=[1.0, 2.0]), "`q0` has 2 value(s)"),
    "initial-wrong-shape": (_simulate("pendulum", qd0=[[0.0]]), "`qd0` has shape (1, 1)"),
    "initial-not-finite": (_simulate("pendulum", qd0=[math.nan]), "`qd0`"),
    "initial-not-a-number": (_simulate("pendulum", q0=["up"]), "`q0`"),
    "kernel-state-wrong-size": (lambda models: models["pendulum"].rhs(0.0, [1.0, 0.0, 0.0]), "`y` must have shape (2,)"),
    "initial-missing": (lambda models: models["degenerate"].simulate((0, 1), params={"m": 1.0}), "`q0` is required"),
    "inconsistent-initial-conditions": (_simulate("rod", q0=[1.0, 0.0, -1.0]), "constraint `rod` at position level"),
    "contact-gap-negative-at-start": (_simulate("bouncer", q0=[0.0, -0.1]), "`floor`"),
    "energy-balance-refused": (lambda models: models["bouncer"].simulate((0.0, 1.0), q0=[0.0, 1.0]).energy_balance(),
                               "'table_bouncer'"),
    "contact-restitution-parameter-out-of-range": (_simulate("bouncer", q0=[0.0, 1.0], params={"c": 2.0}),
                                                   "`floor`"),
    "friction-coefficient-parameter-out-of-range": (_simulate("slider", q0=[0.0], qd0=[1.0], params={"a": 0.9}),
                                                    "`slide`"),
    "friction-with-taylor": (_simulate("crowd_slider", q0=[0.5, 0.5], qd0=[1.0, 0.0], method="taylor"),
                             "['slide', 'drift', 'skid', 'spin']"),
    "contacts-method": (_simulate("bouncer", q0=[0.0, 1.0], method="rk4", dt=0.01), "use dopri5, dop853"),
    "contacts-left-out": (_simulate("slider", q0=[0.0], qd0=[1.0], events=False), "['slide']"),
    "contact-closed-at-start-with-taylor": (_simulate("crowd", q0=[0.5, 0.0], method="taylor"),
                                            "['floor'] start closed"),
    "singular-at-initial-state": (_simulate("degenerate", q0=[0.0], params={"m": 1.0}, method="rk4", dt=0.1), "x=0"),
    "parameter-makes-M-singular": (_simulate("pendulum", params={"m": 0.0}), "['m'] are zero"),
    "redundant-constraints-at-initial-state": (_simulate("walled", method="rk4", dt=0.01), "['wall']"),
    "bad-time-span": (_simulate("pendulum", t_span=(1.0, 0.0)), "`t_span`"),
    "bad-step": (_simulate("pendulum", method="rk4", dt=-0.1), "`dt`"),
    "missing-step": (_simulate("pendulum", method="rk4"), "`dt`"),
    "step-with-adaptive-method": (_simulate("pendulum", dt=0.1), "`dt`"),
    "bad-tolerance": (_simulate("pendulum", atol=math.nan), "`atol`"),
    "tolerance-out-of-range": (_simulate("pendulum", rtol=1e-16), "`rtol` = 1e-16"),
    "atol-shape": (_simulate("pendulum", atol=[1e-9, 1e-9, 1e-9]), "`atol` has shape (3,)"),
    "atol-component-not-positive": (_simulate("pendulum", atol=[1e-9, -1e-9]), "`atol[1]` (theta_dot)"),
    "atol-mapping-incomplete": (_simulate("pendulum", atol={"phi": (1e-9, 1e-9)}), "missing: ['theta']"),
    "lyapunov-scale": (lambda models: an.two_trajectory_lyapunov(models["pendulum"], (0.0, 1.0), scale=[1.0, 0.0],
                                                                 progress=False), "`scale` must hold 2"),
    "batched-taylor-atol": (lambda models: models["pendulum"].sweep((0, 1), {"l": [1.0, 2.0]}, method="taylor",
                                                                   batched=True, atol=[1e-9, 1e-8], progress=False),
                            "`atol`"),
    "bad-step-bounds": (_simulate("pendulum", first_step=0.0), "`first_step`"),
    "bad-save-every": (_simulate("pendulum", save_every=1.5), "`save_every`"),
    "bad-max-steps": (_simulate("pendulum", method="rk4", dt=1e-3, max_steps=10), "`max_steps`"),
    "bad-t-eval": (_simulate("pendulum", t_eval=[0.5, 2.0]), "`t_eval`"),
    "unknown-method": (_simulate("pendulum", method="euler"), "'euler'"),
    "method-not-applicable": (_simulate("rod", method="verlet", dt=0.1), "`verlet`"),
    "rattle-not-applicable": (_simulate("pendulum", method="rattle", dt=0.1), "`rattle` integrates constrained systems"),
    "radau-constrained-options": (_simulate("rod", method="radau", projection=True), "without projection"),
    "radau-dae-tolerance": (_simulate("rod", method="radau", rtol=1e-12), "rtol = 1e-12 asked"),
    "sensitivities-method": (_simulate("pendulum", method="rk4", dt=0.1, sensitivities="q0"), "`rk4`"),
    "taylor-sensitivities-too-large": (_large_taylor_sensitivities, "`taylor_variational_coefficients` for 12"),
    "sensitivities-with-events": (_simulate("signalled", inputs={"s": 0.5}, sensitivities="q0"), "['past']"),
    "sensitivities-function-input": (_simulate("pushed", inputs={"f": numba.njit(lambda t, y, p: 0.0)},
                                               sensitivities="q0"), "numba functions"),
    "sensitivities-unknown-name": (_simulate("pendulum", sensitivities=("q0", "theta0")), "'theta0'"),
    "sensitivity-control-unknown": (_simulate("pendulum", sensitivities="q0", sensitivity_control="all"), "'all'"),
    "sensitivities-in-sweep": (lambda models: models["pendulum"].sweep((0.0, 1.0), {"theta": [0.1]},
                                                                      sensitivities="q0"), "a sweep"),
    "fit-start-boolean": (lambda models: models["pendulum"].fit([0.5, 1.0], [[0.1], [0.2]], {"l": True}), "`l`"),
    "fit-unknown-parameter": (lambda models: models["pendulum"].fit([0.5, 1.0], [[0.1], [0.2]], {"mass": 1.0}),
                              "['mass']"),
    "fit-data-shape": (lambda models: models["pendulum"].fit([0.5, 1.0], [[0.1, 0.2]], {"l": 1.0}), "(1, 2)"),
    "fit-non-finite-data": (lambda models: models["pendulum"].fit([0.5, 1.0], [math.nan, 0.2], {"l": 1.0}),
                            "`observations`"),
    "fit-start-outside-bounds": (lambda models: models["pendulum"].fit([0.5, 1.0], [0.1, 0.2], {"l": 2.0},
                                                                       bounds={"l": (0.5, 1.5)}), "['l']"),
    "fit-run-failed": (lambda models: models["failing"].fit([0.25, 0.5, 0.75, 1.0], [0.0, 0.2, 0.4, 0.6], {"c": 2.0}),
                       "c=2"),
    "fit-without-sensitivities": (lambda models: models["pendulum"].fit([0.5, 1.0], [0.1, 0.2], {"l": 1.0},
                                                                        method="radau"), "['l']"),
    "taylor-not-applicable": (_simulate("friction", method="taylor"), "`taylor` cannot integrate 'rope_friction'"),
    "unknown-implicit-solver": (_simulate("pendulum", method="gauss2", dt=0.1, implicit_solver="broyden"), "broyden"),
    "bad-record": (_simulate("pendulum", record="everything"), "`record`"),
    "specialize-method": (_simulate("pendulum", method="radau", specialize=True), "`specialize=True` with method 'radau'"),
    "bad-specialize": (_simulate("pendulum", specialize="always"), "`specialize`"),
    "unknown-event": (_simulate("pendulum", events=["apex"]), "['apex']"),
    "events-with-fixed-step": (_simulate("degenerate", q0=[1.0], params={"m": 1.0}, method="rk4", dt=0.1, events=True),
                               "rk4"),
    "bad-baumgarte": (_simulate("rod", baumgarte=(-1.0, 0.0)), "`baumgarte`"),
    "bad-max-residual": (_simulate("rod", max_residual=-1.0), "`max_residual`"),
    "run-too-large-for-memory": (_simulate("pendulum", t_span=(0, 10), method="rk4", dt=1e-7), "record=\"summary\""),
    "bad-memory-limit": (_simulate("pendulum", memory_limit="lots"), "`memory_limit`"),
    "ambiguous-sweep-name": (lambda models: models["clash"].sweep((0, 1), {"x_dot": [0.0, 1.0]}), "['x_dot']"),
    "unknown-option": (_simulate("pendulum", save_evry=10), "did you mean `save_every`?"),
    "sweep-too-large-for-memory": (lambda models: models["pendulum"].sweep((0, 1), {"theta": np.zeros(10**5),
                                                                                    "l": np.ones(10**5)}),
                                   "10,000,000,000 trajectories"),
    "sweep-grid-not-numbers": (lambda models: models["pendulum"].sweep((0, 1), {"theta": ["up", "down"]}),
                               "Grid values of `theta`"),
    "sweep-grid-boolean": (lambda models: models["pendulum"].sweep((0, 1), {"l": [1.0, True]}), "Grid values of `l`"),
    # a run that fails part-way (throw=True; the statuses are tested in test_integration_failures.py)
    "non-finite-state": (_fail("failing", t_span=(0, 2), params={"a": 1.0}, method="rk4", dt=0.01), "non-finite"),
    "singular-during-run": (_fail("failing", t_span=(0, 2), params={"c": 1.0}, method="rk4", dt=0.1), "singular"),
    "step-size-underflow": (_fail("failing", t_span=(0, 2), params={"a": 1.0}), "step size became too small"),
    "max-steps-reached": (_fail("pendulum", max_steps=3), "maximum number of steps"),
    "stiff-problem": (_simulate("stiff", method="dopri5", rtol=1e-6, atol=1e-6), 'method="radau"'),
    "implicit-not-converged": (_fail("failing", t_span=(0, 0.9), params={"a": 1.0}, method="gauss2", dt=0.3),
                               "did not converge"),
    "rattle-not-converged": (_fail("rod", method="rattle", dt=0.3), "did not converge"),
    "constraint-drift": (_fail("rod", rtol=1e-4, atol=1e-4, max_residual=1e-6), "max_residual = 1e-06"),
    "memory-limit-reached": (_fail("pendulum", t_span=(0, 1000), memory_limit=10_000), "`memory_limit`"),
    # the cache
    "corrupt-cache-entry": (_cache_case("corrupt"), "sha256"),
    "stale-cache-entry": (_cache_case("stale"), "another lagcomp or numba version"),
    "unwritable-cache": (_cache_case("unwritable"), "cannot write its cache"),
    "unpickle-without-entry": (lambda models, tmp_path: _unpickle_without_entry(tmp_path), "'table_cached'"),
    "load-unknown-name": (lambda models, tmp_path: lc.load("never_compiled", cache_dir=tmp_path), "'never_compiled'"),
    "on-demand-without-equations": (lambda tmp_path: _on_demand_without_equations(tmp_path), "`rhs_jacobian`"),
    "linearize-constrained": (lambda models: an.linearize(models["rod"], [0.0, 0.0, -1.0]), "linearize_steady"),
    "periodic-constrained": (lambda models: an.periodic_orbit(models["rod"], np.zeros(6), 1.0),
                             "'spherical_pendulum_cartesian'"),
    "periodic-guess-size": (lambda models: an.periodic_orbit(models["pendulum"], [1.0], 2.0), "2 numbers"),
    "periodic-no-convergence": (lambda models: an.periodic_orbit(models["pendulum"], [1.0, 0.0], 2.0,
                                                                 max_iterations=1), "did not converge"),
    "modes-not-at-equilibrium": (lambda models: an.normal_modes(models["pendulum"], [1.0]), "theta=1"),
    "periodic-degenerate": (lambda models: an.periodic_orbit(models["pendulum"], [0.1, 0.0], 1.0, fix="period"),
                            "no orbit"),
    "steady-off-constraints": (lambda models: an.linearize_steady(models["rod"], [0.0, 0.0, -2.0]), "residual"),
    "steady-singular-point": (lambda: an.linearize_steady(lc.System([x], T=m * x**2 * x.diff(t) ** 2 / 2,
                                                                    name="table_degenerate"), [0.0], None, {"m": 1.0}),
                              "singular"),
    "linearize-inputs-missing": (lambda models: an.linearize_steady(models["pushed"], [0.0]), "inputs={'f'"),
    "state-space-unknown-point": (lambda models: an.linearize(models["pendulum"], [0.0], outputs=["pole.x"]),
                                  "'pole.x'"),
    "state-space-points-need-system": (_points_of_a_loaded_model, "'table_oscillator'"),
    "state-space-input-derivatives": (
        lambda models: an.linearize(models["driven"], [0.0], inputs={"s": 0.0}).state_space(), "['s']"),
    "steady-unknown-state": (lambda models: an.linearize_steady(models["rod"], [0.0, 0.0, -1.0], drop=["w"]), "['w']"),
    "steady-too-many-independent": (lambda models: an.linearize_steady(models["rod"], [0.0, 0.0, -1.0],
                                                                      independent=["x", "y", "z"]), "['x', 'y', 'z']"),
    "steady-singular-dependent": (lambda models: an.linearize_steady(models["rod"], [0.0, 0.0, -1.0],
                                                                    independent=["x", "z"]), "['y']"),
    "steady-drop-not-ignorable": (lambda models: an.linearize_steady(models["rod"], [0.0, 0.0, -1.0], drop=["x"]),
                                  "`x`"),
    "steady-at-a-kink": (lambda models: an.linearize_steady(models["friction"], [0.5], [0.0]), "x_dot = 0"),
    "sweep-unknown-parameter": (lambda models: an.stability_sweep(models["rod"], "mass", [1.0, 2.0], [0.0, 0.0, -1.0]),
                                "'mass'"),
    "accuracy-bad-states": (lambda models: lc.kernel_accuracy(models["pendulum"], [[0.1, 0.2, 0.3]]), "shape (m, 2)"),
    "accuracy-needs-system": (lambda models: lc.kernel_accuracy(models["kane"]), "KanesMethod"),
    "accuracy-unknown-point": (lambda models: _close_approach(models["rod"], [("x", "w")]), "'w'"),
    "bad-cache-dir": (lambda: lc.compile(oscillator(), cache_dir=5), "`cache_dir`"),
    "corrupt-name-record": (_cache_case("name record"), "was corrupt"),
    "unreadable-numba-cache": (_cache_case("numba"), "unreadable and removed"),
    "cli-unknown-example-argument": (lambda: _cli_system("n_link_pendulum", "m=3"), "the example 'n_link_pendulum' takes"),
    "cli-unwritable-output": (lambda tmp_path: cli_outputs.check_writable(str(tmp_path / "nonexistent" / "x.npz"), "--out"),
                              "does not exist"),
    "plot-wrong-result": (lambda models: _plots().plot_run(_sweep(models)), "plot_run draws a Solution"),
    "plot-unknown-quantity": (lambda models: _plots().plot_sweep(_sweep(models), "energy"), "'energy'"),
    "save-missing-directory": (lambda models, tmp_path: models["pendulum"].simulate((0, 1)).save_npz(
        tmp_path / "nonexistent" / "run.npz"), "nonexistent"),
    "load-not-a-sweep": (lambda models, tmp_path: lc.Sweep.load_npz(_saved_solution(models, tmp_path)), "run.npz"),
    "event-not-in-run": (lambda models: models["ball"].simulate((0, 1)).events["impact"], "'impact'"),
    "cli-unknown-model": (lambda tmp_path: _cli_model("no_such_model", tmp_path), "neither a bundled example"),
    "cli-model-file": (lambda tmp_path: _cli_model(_model_file(tmp_path, "raise RuntimeError('broken model')"),
                                                   tmp_path), "raised RuntimeError: broken model"),
    "cli-model-not-in-file": (lambda tmp_path: _cli_model(_model_file(tmp_path, "answer = 42"), tmp_path),
                              "defines no System"),
    "cli-output-format": (lambda tmp_path: cli_outputs.check_result_path(str(tmp_path / "run.txt")),
                          "use .npz (numpy), .csv (a table) or .nc"),
    "cli-input-signal": (lambda tmp_path: _cli_input(tmp_path, "F=push.csv:force"), "no column 'force'"),
    "cli-missing-input": (lambda models: cli_inputs.check_inputs(models["driven"], {}), "--input s="),
    "cli-config-file": (lambda tmp_path: _cli_config(tmp_path, "q0 = [1.0]\nparameters = {}\n"),
                        "unknown key(s) ['parameters']"),
    "cli-stability-needs-system": (_cli_stability_of_cached, "path/to/model.py"),
    "animate-no-bodies": (lambda models: lc.animate(models["pendulum"].simulate((0, 1))), "'simple_pendulum'"),
    "animate-no-geometry": (lambda models: replace(models["pendulum"].simulate((0, 1)), geometry=None).animate(),
                            "no model geometry"),
    "animate-unknown-name": (lambda models: lc.animate(models["pendulum"].simulate((0, 1)),
                                                       {"bob": (lc.coordinates("theta")[0], 0)}, trace=["rod"]),
                             "['rod'], not a point or a body"),
}


def test_every_row_has_a_case_and_every_case_a_row():
    rows = _rows()
    assert len(rows) > 60
    assert sorted(set(rows) - set(CASES)) == [] and sorted(set(CASES) - set(rows)) == []


@pytest.mark.parametrize("case", sorted(_rows()))
def test_row(case, models, tmp_path):
    expected = _expected(_rows()[case])
    trigger, culprit = CASES[case]
    arguments = {"models": models, "tmp_path": tmp_path}
    names = trigger.__code__.co_varnames[: trigger.__code__.co_argcount]
    call = lambda: trigger(*(arguments[name] for name in names))
    if issubclass(expected, Warning):
        with pytest.warns(expected) as record:
            call()
        messages = [str(w.message) for w in record if issubclass(w.category, expected)]
        assert any(culprit in message for message in messages), messages
        return
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", lc.CacheWarning)
        with pytest.raises(expected) as info:
            call()
    assert type(info.value).__name__ == expected.__name__ or expected is lc.IntegrationError
    assert culprit in str(info.value), str(info.value)
    assert not isinstance(info.value, (sp.SympifyError,)) and type(info.value).__module__.startswith("lagcomp")
