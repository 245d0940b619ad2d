"""`lagcomp run` lists the occurrences of the events that change the state (issue 21): each impact's time, the
contacts' impulses and the velocities before → after; a long list shows its first few, the count left out, and
its last.  References: the bouncing ball's closed form (t₁ = √(2 h₀/g), v₁ = √(2 g h₀), P = m (1 + e) v₁) and
Newton's cradle of three equal balls (q̇⁺ = (−1/3, 2/3, 2/3), impulses 4/3 and 2/3)."""

from __future__ import annotations

import math

import pytest
import sympy as sp

import lagcomp as lc
from lagcomp.cli import main
from lagcomp.event_report import FIRST_SHOWN

t = lc.t
M, G, E, H0 = 2.0, 9.81, 0.9, 1.0


@pytest.fixture(scope="module")
def models(cache_dir):
    """A ball on a contact floor (with an apex event, which changes nothing), a ball whose floor is a reset event,
    and Newton's cradle, compiled under the names the command line takes."""
    x, = lc.coordinates("x")
    m, g, e = sp.symbols("m g e", positive=True)
    lc.compile(lc.System([x], T=m * x.diff(t) ** 2 / 2, V=m * g * x, name="cli_contact_ball",
                         events=[lc.Contact("floor", x, restitution=e), lc.Event("apex", x.diff(t), direction=-1)],
                         defaults={"m": M, "g": G, "e": E}, q0=(H0,), qd0=(0.0,)), cache_dir=cache_dir)
    lc.compile(lc.System([x], T=x.diff(t) ** 2 / 2, V=g * x, name="cli_reset_ball",
                         events=[lc.Event("bounce", x, direction=-1, reset={x.diff(t): -e * x.diff(t)})],
                         defaults={"g": G, "e": E}, q0=(H0,), qd0=(0.0,)), cache_dir=cache_dir)
    x1, x2, x3 = lc.coordinates("x1 x2 x3")
    T = (x1.diff(t) ** 2 + x2.diff(t) ** 2 + x3.diff(t) ** 2) / 2
    lc.compile(lc.System([x1, x2, x3], T=T, events=[lc.Contact("c12", x2 - x1 - 1), lc.Contact("c23", x3 - x2 - 1)],
                         name="cli_cradle", q0=(-0.5, 1.0, 2.0), qd0=(1.0, 0.0, 0.0)), cache_dir=cache_dir)
    k, v_b = sp.symbols("k v_b", positive=True)
    lc.compile(lc.System([x], T=x.diff(t) ** 2 / 2, V=k * x**2 / 2, name="cli_belt", q0=(0.0,), qd0=(0.5,),
                         events=[lc.Friction("belt", x.diff(t) - v_b, normal=g, static=0.6, kinetic=0.4)],
                         defaults={"k": 4.0, "g": G, "v_b": 0.5}), cache_dir=cache_dir)
    return str(cache_dir)


def _run(cache, name, t_end, capsys, *options) -> list[str]:
    code = main(["--cache-dir", cache, "run", name, "--t-end", str(t_end), "--quiet", *options])
    out = capsys.readouterr().out
    assert code == 0, out
    return out.splitlines()


def test_a_bouncing_balls_impacts_are_listed_first_few_then_the_last(models, capsys):
    lines = _run(models, "cli_contact_ball", 6.0, capsys)
    start = next(i for i, line in enumerate(lines) if line.startswith("event       floor:"))
    count = int(lines[start].split(": ")[1].split()[0])
    assert count > FIRST_SHOWN + 2 and lines[start].endswith("(impacts)")
    listed = lines[start + 1:start + FIRST_SHOWN + 3]
    assert [line.split()[0] for line in listed] == [*(f"#{k}" for k in range(1, FIRST_SHOWN + 1)), "...", f"#{count}"]
    assert listed[FIRST_SHOWN].strip() == f"... {count - FIRST_SHOWN - 1} more ..."
    assert lines[start + FIRST_SHOWN + 3].startswith("event       apex:")   # the apex changes nothing: one line
    v1 = math.sqrt(2 * G * H0)
    first = listed[0].split()
    assert float(first[3]) == pytest.approx(math.sqrt(2 * H0 / G), rel=1e-9)
    assert first[4:7] == ["impulse", "floor", f"{M * (1 + E) * v1:.6g}"]
    assert first[7] == "x_dot" and float(first[8]) == pytest.approx(-v1, rel=1e-7)
    assert float(first[10]) == pytest.approx(E * v1, rel=1e-7)
    rows = [line for line in listed if line.split()[0].startswith("#")]
    assert len({line.index("impulse") for line in rows}) == 1 and len({line.index("x_dot") for line in rows}) == 1


def test_the_impact_that_closes_the_floor_says_so(models, capsys):
    """Past t∞ = t₁ (1 + 2 e/(1 − e)) = 8.58 the ball rests: the last impact closes the floor."""
    lines = _run(models, "cli_contact_ball", 10.0, capsys)
    start = next(i for i, line in enumerate(lines) if line.startswith("event       floor:"))
    listed = lines[start + 1:start + FIRST_SHOWN + 3]
    assert listed[-1].endswith("floor closes")
    assert not any("closes" in line or "lifts off" in line for line in listed[:-1])


def test_the_belt_oscillators_switches_are_listed(models, capsys):
    """Stuck on the belt from x = 0 it breaks away at k x = μs g (t = μs g/(k v_b)) slipping slower than the belt,
    then sticks again when ẋ = v_b (design: tests/test_friction.py's closed form)."""
    lines = _run(models, "cli_belt", 5.0, capsys)
    start = next(i for i, line in enumerate(lines) if line.startswith("event       belt:"))
    first, second = lines[start + 1].split(), lines[start + 2].split()
    assert first[0] == "#1" and lines[start + 1].endswith("belt slips (v < 0)")
    assert float(first[3]) == pytest.approx(0.6 * G / (4.0 * 0.5), rel=1e-9)
    assert second[0] == "#2" and lines[start + 2].endswith("belt sticks")


def test_a_reset_events_jumps_are_listed_without_impulses(models, capsys, tmp_path):
    lines = _run(models, "cli_reset_ball", 1.0, capsys, "--plot", str(tmp_path / "ball.png"))
    assert f"plotted     {tmp_path / 'ball.png'} (coordinates and energy error vs time; resets and impacts marked)" \
        in lines
    start = next(i for i, line in enumerate(lines) if line.startswith("event       bounce:"))
    assert lines[start].endswith("(each resets the state)") and " 1 occurrence(s) at t = 0.4515236" in lines[start]
    row = lines[start + 1].split()
    assert row[0] == "#1" and "impulse" not in row and row[4] == "x_dot"


def test_newtons_cradle_shows_both_impulses_of_its_simultaneous_impact(models, capsys):
    lines = _run(models, "cli_cradle", 2.0, capsys)
    start = next(i for i, line in enumerate(lines) if line.startswith("event       c12:"))
    row = lines[start + 1]
    assert "impulse c12 1.33333, c23 0.666667" in row
    assert "x1_dot 1 → -0.33333333, x2_dot 0 → 0.66666667, x3_dot 0 → 0.66666667" in row
    assert lines[start + 2] == "event       c23: 0 occurrence(s)"
