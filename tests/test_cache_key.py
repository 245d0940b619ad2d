"""The cache key of a System changes with every part the kernels depend on, and only with those.

A key that ignored a part (a constraint's expression or kind, the parameter
order, ...) would let two systems of one name share kernels: a silently wrong
model.  The property test changes one part of a System at a time — T, V,
forces, dissipation, each constraint's kind, name and expression, events,
parameter order, frame, bodies, imposed motions — by a random term, and checks
that the key changes and that a cache holding the original's entry serves
nothing under it; it works at the key level (`System.fingerprint`,
`lagcomp.cache.input_key`, `Cache.lookup`), so no example compiles anything.
The parts a run reads from the System itself (defaults, q0, qd0, t_end, an
event's direction and terminal flag) must not change the key, so those
systems share their kernels as intended.  One end-to-end test compiles two
systems of one name that differ only in a constraint into one cache directory
and checks their reactions against Newton's.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import lagcomp as lc
from lagcomp import cache as lagcomp_cache
from lagcomp.cache import KERNEL_LIBRARY, KERNEL_PRODUCERS, Cache, input_key, source_key
from lagcomp.source_digest import hashed_files

t = lc.t
x, y, z = lc.coordinates("x y z")
xd, yd, zd = (q.diff(t) for q in (x, y, z))
m, M, g, l, k, c, b, r, A, W = sp.symbols("m M g l k c b r A Omega")
PARAMETERS = (m, M, g, l, k, c, b, r, A, W)

#: The System every test case changes one part of.  Everything is a plain value so a case can replace one entry.
BASE = {
    "T": M / 2 * zd**2,
    "V": k / 2 * x**2 - A * x * sp.cos(W * t),  # an imposed motion: the support moved along A cos Ωt
    "forces": (0, -c * yd, 0),
    "dissipation": b / 2 * zd**2,
    "constraints": (("Holonomic", "rod", x**2 + y**2 - l**2), ("Nonholonomic", "roll", zd - r * xd)),
    "events": (("cross", x, 0, False), ("top", y - l / 2, 1, True)),
    "parameters": PARAMETERS,
    "frame": ((A * sp.sin(W * t), 0, 0), (0, 0, 0)),  # acceleration, angular velocity of the frame
    "bodies": ((m, (x, y, 0)),),  # particles: mass, position in the frame
}

KINDS = {"Holonomic": lc.Holonomic, "Nonholonomic": lc.Nonholonomic}


def build(spec: dict, **run_options) -> lc.System:
    """A fresh System (fresh sympy, constraint, event, body and frame objects) from `spec`."""
    acceleration, angular_velocity = spec["frame"]
    return lc.System(
        [x, y, z], T=spec["T"], V=spec["V"], forces=spec["forces"], dissipation=spec["dissipation"],
        constraints=[KINDS[kind](name, expr) for kind, name, expr in spec["constraints"]],
        events=[lc.Event(name, expr, direction, terminal) for name, expr, direction, terminal in spec["events"]],
        parameters=spec["parameters"],
        frame=lc.MovingFrame(acceleration=acceleration, angular_velocity=angular_velocity),
        bodies=[lc.Particle(mass, position, name=f"p{i}") for i, (mass, position) in enumerate(spec["bodies"])],
        loads=[lc.Gravity((0, -g, 0))], name="same_name", **run_options)


def key(system: lc.System) -> str:
    return input_key(system.fingerprint(), options={})


# -- the changes ------------------------------------------------------------------------
# Terms by what they may contain: positions only (V, Φ, frames, bodies), anything (T, Q, D, events),
# velocities linearly (a nonholonomic constraint).

POSITION_TERMS = (x, y * z, sp.sin(x), x**2 * y, l * z, sp.cos(W * t), t * y)
ANY_TERMS = POSITION_TERMS + (xd * yd, zd**2, x * zd, sp.sin(y) * xd**2)
VELOCITY_TERMS = (xd, y * zd, sp.cos(x) * yd, zd * l)
TIME_FUNCTIONS = (sp.sin(2 * t), sp.cos(W * t) ** 2, t, sp.exp(-t), sp.cos(3 * W * t))

coefficients = st.fractions(min_value=-5, max_value=5, max_denominator=7).filter(bool).map(sp.Rational)


def _replace(spec, field, value):
    return {**spec, field: value}


def _add_to(field, terms):
    """Add ε·term to the expression `field`."""
    def change(d):
        eps, term = d
        return lambda s: _replace(s, field, s[field] + eps * term)
    return st.tuples(coefficients, st.sampled_from(terms)).map(change)


def _add_to_force(draw_index, terms):
    def change(d):
        i, eps, term = d
        return lambda s: _replace(s, "forces", tuple(Q + eps * term if j == i else Q
                                                     for j, Q in enumerate(s["forces"])))
    return st.tuples(draw_index, coefficients, st.sampled_from(terms)).map(change)


def _change_constraint(i):
    terms = POSITION_TERMS if BASE["constraints"][i][0] == "Holonomic" else VELOCITY_TERMS

    def change(d):
        eps, term = d
        return lambda s: _replace(s, "constraints", tuple(
            (kind, name, expr + eps * term) if j == i else (kind, name, expr) for j, (kind, name, expr) in
            enumerate(s["constraints"])))
    return st.tuples(coefficients, st.sampled_from(terms)).map(change)


def _swap_kind(s):
    """The rod's Φ declared as a Nonholonomic constraint: the same expression, another kind."""
    (_, name, expr), roll = s["constraints"]
    return _replace(s, "constraints", (("Nonholonomic", name, expr), roll))


def _rename_constraint(s):
    (kind, _, expr), roll = s["constraints"]
    return _replace(s, "constraints", ((kind, "tether", expr), roll))


def _reorder_constraints(s):
    return _replace(s, "constraints", s["constraints"][::-1])


def _drop_constraint(s):
    return _replace(s, "constraints", s["constraints"][:1])


def _change_event(d):
    i, eps, term = d
    return lambda s: _replace(s, "events", tuple(
        (name, expr + eps * term if j == i else expr, direction, terminal)
        for j, (name, expr, direction, terminal) in enumerate(s["events"])))


def _rename_event(s):
    (_, expr, direction, terminal), top = s["events"]
    return _replace(s, "events", (("crossing", expr, direction, terminal), top))


def _add_event(s):
    return _replace(s, "events", s["events"] + (("spin", zd, 0, False),))


def _permute_parameters(permutation):
    return lambda s: _replace(s, "parameters", tuple(s["parameters"][i] for i in permutation))


def _change_frame(d):
    which, axis, eps, f = d
    return lambda s: _replace(s, "frame", tuple(
        tuple(v + eps * f if (w, a) == (which, axis) else v for a, v in enumerate(vec)) for w, vec in
        enumerate(s["frame"])))


def _change_body(d):
    what, eps, term = d

    def change(s):
        (mass, position), = s["bodies"]
        if what == "mass":
            return _replace(s, "bodies", ((mass + eps * M, position),))
        if what == "add":
            return _replace(s, "bodies", ((mass, position), (M, (0, z, 0))))
        axis = int(what)
        moved = tuple(p + eps * term if a == axis else p for a, p in enumerate(position))
        return _replace(s, "bodies", ((mass, moved),))
    return change


def _change_imposed_motion(f):
    return lambda s: _replace(s, "V", s["V"].subs(sp.cos(W * t), f))


_non_identity_permutations = st.permutations(range(len(PARAMETERS))).filter(lambda p: list(p) != sorted(p))

CHANGES = {
    "T": _add_to("T", ANY_TERMS),
    "V": _add_to("V", POSITION_TERMS),
    "forces": _add_to_force(st.integers(0, 2), ANY_TERMS),
    "dissipation": _add_to("dissipation", ANY_TERMS),
    "constraint expression": st.integers(0, 1).flatmap(_change_constraint),
    "constraint kind": st.just(_swap_kind),
    "constraint name": st.just(_rename_constraint),
    "constraint order": st.just(_reorder_constraints),
    "constraint dropped": st.just(_drop_constraint),
    "event expression": st.tuples(st.integers(0, 1), coefficients, st.sampled_from(ANY_TERMS)).map(_change_event),
    "event name": st.just(_rename_event),
    "event added": st.just(_add_event),
    "parameter order": _non_identity_permutations.map(_permute_parameters),
    "frame": st.tuples(st.integers(0, 1), st.integers(0, 1), coefficients, st.sampled_from(TIME_FUNCTIONS)).map(
        _change_frame),
    "bodies": st.tuples(st.sampled_from(["mass", "add", "0", "1", "2"]), coefficients,
                        st.sampled_from(POSITION_TERMS)).map(_change_body),
    "imposed motion": st.sampled_from(TIME_FUNCTIONS).map(_change_imposed_motion),
}


@pytest.fixture(scope="module")
def base_entry(tmp_path_factory):
    """A cache holding an entry for the base System only (a stand-in module: nothing is compiled)."""
    cache = Cache(tmp_path_factory.mktemp("key-cache"))
    base_key = key(build(BASE))
    cache.store(base_key, "# the base system's module\n", "same_name", {"stand_in": True})
    return cache, base_key


def test_the_key_is_a_function_of_the_description(base_entry):
    """Two Systems built separately from one description (fresh sympy and body objects) share their key."""
    cache, base_key = base_entry
    assert key(build(BASE)) == base_key
    assert cache.lookup(base_key).metadata == {"stand_in": True}


@pytest.mark.parametrize("part", sorted(CHANGES))
@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_changing_any_part_changes_the_key(base_entry, part, data):
    cache, base_key = base_entry
    change = data.draw(CHANGES[part], label=part)
    changed = build(change(BASE))
    assert changed.fingerprint() != build(BASE).fingerprint(), part
    assert key(changed) != base_key, part
    assert cache.lookup(key(changed)) is None, part  # the base system's kernels are never served for it


@pytest.mark.parametrize("run_option", [dict(defaults={"m": 2.0}), dict(q0=[0.1, 0.2, 0.3]), dict(qd0=[1, 0, 0]),
                                        dict(t_end=3.0), dict(description="another line")])
def test_run_options_share_the_kernels(run_option):
    assert key(build(BASE, **run_option)) == key(build(BASE))


def test_event_direction_and_terminal_flag_share_the_kernels():
    """The drivers take them at run time, from the System: the compiled event function is the same."""
    (name, expr, _, _), top = BASE["events"]
    flipped = _replace(BASE, "events", ((name, expr, -1, True), top))
    assert key(build(flipped)) == key(build(BASE))


# -- what produced the kernels, and nothing else ------------------------------------------


def test_the_keys_cover_what_produces_the_kernels_and_not_the_drivers():
    """The emitter and kernel_support enter the keys; the drivers (lagcomp.integrate) do not, so a driver
    change recompiles that driver once (numba's own cache) and keeps every model of the cache."""
    package = Path(lc.__file__).parent
    hashed = {path.relative_to(package).as_posix() for path in hashed_files(KERNEL_PRODUCERS)}
    assert {"codegen/emit.py", "codegen/printer.py", "ir.py", "kernel_support/trig.py",
            "kernel_support/linear_solvers.py", "mechanics/lagrange.py", "multibody/aba.py",
            "codegen/tree_lower.py"} <= hashed
    assert not any(name.startswith("integrate/") for name in hashed)
    assert {path.relative_to(package).as_posix() for path in hashed_files(KERNEL_LIBRARY)} >= {
        "kernel_support/trig.py", "kernel_support/linear_solvers.py"}


def test_a_kernel_support_change_renames_the_module_file(monkeypatch):
    """numba stamps a module's machine code on the module file, not on the kernel_support code compiled into
    it: a change there must give the same source another file, whose kernels numba compiles afresh."""
    before = source_key("# a module\n")
    digest = lagcomp_cache.code_digest
    monkeypatch.setattr(lagcomp_cache, "code_digest",
                        lambda parts: "changed" if parts == KERNEL_LIBRARY else digest(parts))
    assert source_key("# a module\n") != before


KEYS_PROBE = (
    "from lagcomp import examples; from lagcomp.cache import input_key, source_key; "
    "print(input_key(examples.get('simple_pendulum').fingerprint(), {}), source_key('# a module'))"
)


def _keys_of_a_copy(tmp_path, name, edit=None):
    """The probe's keys computed by a copy of the lagcomp package, with `edit` (a file of it) changed."""
    copy = tmp_path / name
    shutil.copytree(Path(lc.__file__).parent, copy / "lagcomp", ignore=shutil.ignore_patterns("__pycache__"))
    if edit is not None:
        with open(copy / "lagcomp" / edit, "a", encoding="utf-8") as f:
            f.write("\n# an edit\n")
    env = {**os.environ, "PYTHONPATH": str(copy)}
    out = subprocess.run([sys.executable, "-c", KEYS_PROBE], capture_output=True, text=True, env=env, check=True)
    return out.stdout.split()


def test_a_driver_change_keeps_the_keys_and_an_emitter_change_does_not(tmp_path):
    """Edited drivers (lagcomp.integrate) serve the models already cached; an edited emitter does not."""
    original = _keys_of_a_copy(tmp_path, "original")
    assert _keys_of_a_copy(tmp_path, "driver", edit="integrate/methods.py") == original
    emitter = _keys_of_a_copy(tmp_path, "emitter", edit="codegen/emit.py")
    assert emitter[0] != original[0] and emitter[1] == original[1]
    support = _keys_of_a_copy(tmp_path, "support", edit="kernel_support/trig.py")
    assert support[0] != original[0] and support[1] != original[1]


# -- end to end ---------------------------------------------------------------------------


def _bob(rod):
    """A particle on a rod in the vertical plane, gravity along −y: the rod written as Φ = `rod`."""
    px, py = lc.coordinates("px py")
    mass, gravity = sp.symbols("m g")
    return lc.System([px, py], T=mass / 2 * (px.diff(t) ** 2 + py.diff(t) ** 2), V=mass * gravity * py,
                     constraints=[lc.Holonomic("rod", rod(px, py))], name="bob_on_a_rod",
                     defaults={"m": 2.0, "g": 9.81})


def test_same_named_systems_differing_in_a_constraint_get_their_own_reactions(tmp_path):
    """Φ = r² − 1 and Φ = (r² − 1)/2 describe one motion with λ in the ratio 1 : 2 (Λ = ∇Φ halves).

    Newton: at rest at r = (0.6, −0.8) the rod pulls with N = m g 0.8 toward the pivot, and N r = −λ ∇Φ,
    so λ = −N/2 for Φ = r² − 1 (|∇Φ| = 2) and −N for (r² − 1)/2.  Compiled one after the other into
    one cache under one name, each gets its own λ; compiled again, each is served its own entry.
    """
    state = np.array([0.6, -0.8, 0.0, 0.0])
    tension = 2.0 * 9.81 * 0.8
    whole = _bob(lambda px, py: px**2 + py**2 - 1)
    half = _bob(lambda px, py: (px**2 + py**2 - 1) / 2)
    first = lc.compile(whole, cache_dir=tmp_path)
    second = lc.compile(half, cache_dir=tmp_path)
    assert not first.from_cache and not second.from_cache
    expected = {first: -tension / 2, second: -tension}
    for model, lam in expected.items():
        assert model.reactions(0.0, state)["rod"] == pytest.approx(lam, rel=1e-14, abs=0)  # measured: exact
    np.testing.assert_allclose(first.rhs(0.0, state), second.rhs(0.0, state), rtol=1e-15, atol=1e-15)
    for system, lam in ((whole, -tension / 2), (half, -tension)):
        again = lc.compile(system, cache_dir=tmp_path)
        assert again.from_cache
        assert again.reactions(0.0, state)["rod"] == pytest.approx(lam, rel=1e-14, abs=0)
