"""Long compiles say what they do (issue 24, item 6): the lazy progress rule of runs, for the build stages
and for numba's first compilation.  The delay is set to zero here, so that a small model's
fractions of a second are "long"; derivation is slowed a little so the bar is seen during it."""

from __future__ import annotations

import time

import sympy as sp

import lagcomp as lc
import lagcomp.mechanics.lagrange
import lagcomp.stages
from lagcomp.model import t
from lagcomp.runtime import BUILD_STAGES

x, = lc.coordinates("x")
m, k = sp.symbols("m k", positive=True)


def _system(name):
    return lc.System([x], T=m * x.diff(t) ** 2 / 2, V=k * x**4 / 4, name=name, defaults={"m": 1.0, "k": 1.0},
                     q0=(1.0,))


def _slow_derive(monkeypatch):
    derive = lagcomp.mechanics.lagrange.derive

    def slow(system):
        time.sleep(0.3)
        return derive(system)
    monkeypatch.setattr(lagcomp.mechanics.lagrange, "derive", slow)


def test_build_stages_and_numba_compilation_are_shown_after_the_delay(capsys, tmp_path, monkeypatch):
    monkeypatch.setattr(lagcomp.stages, "PROGRESS_DELAY", 0.0)
    monkeypatch.setattr(lagcomp.stages, "REFRESH_SECONDS", 0.05)
    _slow_derive(monkeypatch)
    model = lc.compile(_system("progress_quartic"), cache_dir=tmp_path)
    shown = capsys.readouterr().err
    assert "compiling progress_quartic" in shown and BUILD_STAGES[0] in shown
    model.simulate((0, 1), method="rk4", dt=0.01)
    shown = capsys.readouterr().err
    assert "numba: compiling the kernels and the rk4 driver" in shown


def test_nothing_is_shown_with_progress_false(capsys, tmp_path, monkeypatch):
    monkeypatch.setattr(lagcomp.stages, "PROGRESS_DELAY", 0.0)
    _slow_derive(monkeypatch)
    model = lc.compile(_system("progress_silent"), cache_dir=tmp_path, progress=False)
    model.simulate((0, 1), method="rk4", dt=0.01, progress=False)
    assert capsys.readouterr().err == ""


def test_stages_report_the_current_one(monkeypatch):
    monkeypatch.setattr(lagcomp.stages, "PROGRESS_DELAY", 0.0)
    with lagcomp.stages.Stages("work", ("one", "two"), progress=True) as stages:
        stages.start("one")
        stages.start("two")
        deadline = time.monotonic() + 5
        while stages.bar is None and time.monotonic() < deadline:
            time.sleep(0.01)
        assert stages.bar is not None and stages.bar.n == 1 and stages.bar.postfix == "two"


def test_numba_stage_only_for_a_dispatcher_not_compiled_yet():
    import numba

    @numba.njit
    def twice(v):
        return 2 * v

    stage = lagcomp.stages.numba_stage(twice, "twice", "preparing", None)
    assert stage is not None and "numba: compiling twice" in stage.names[0]
    assert lagcomp.stages.numba_stage(twice, "twice", "preparing", False) is None
    twice(1.0)
    assert lagcomp.stages.numba_stage(twice, "twice", "preparing", None) is None
