"""Soak tests (slow): many compile-and-simulate cycles in one process, and one 10⁹-step run, in bounded memory.

Memory is the resident set size (/proc/self/status, VmRSS) after a garbage
collection.  numba keeps the machine code of every module it compiled for
the life of the process, so the cycles first compile each system once (the
warm-up) and the bound applies from there to the end: what must not grow is
what a cycle leaves behind (sympy caches, cache entries, solutions, chunks).
"""

from __future__ import annotations

import gc
import math
import time

import numpy as np
import pytest

import lagcomp as lc
from lagcomp import examples
from random_systems import random_mechanism

pytestmark = pytest.mark.slow

MiB = 2**20


def rss() -> int:
    """Resident set size of this process in bytes, after a garbage collection."""
    gc.collect()
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    raise RuntimeError("no VmRSS in /proc/self/status")


def _systems() -> list[tuple[lc.System, np.ndarray, np.ndarray]]:
    """Ten varied systems with consistent initial states: bundled examples and random mechanisms."""
    chosen = []
    for name in ("simple_pendulum", "double_pendulum", "spherical_pendulum_cartesian", "hoop_bead", "henon_heiles"):
        system = examples.get(name)
        chosen.append((system, np.array(system.q0), np.array(system.qd0 or [0.0] * system.n)))
    for seed in (26, 7, 31, 19, 8):
        mech = random_mechanism(seed, max_bodies=2)
        chosen.append((mech.system, mech.q0, mech.qd0))
    return chosen


def test_hundred_compile_and_simulate_cycles_in_bounded_memory(tmp_path):
    systems = _systems()
    rng = np.random.default_rng(2026)
    start, warm, started = rss(), None, time.perf_counter()
    for cycle in range(100):
        system, q0, qd0 = systems[cycle % len(systems)]
        # a fresh cache directory per cycle: every cycle derives, emits and stores the system again
        model = lc.compile(system, cache_dir=tmp_path / f"cycle{cycle}")
        assert not model.from_cache
        params = {name: value * rng.uniform(0.9, 1.1) for name, value in system.defaults.items()}
        sol = model.simulate((0, 1.0), q0=q0, qd0=qd0 * rng.uniform(0.9, 1.1), params=params, method="rk4",
                             dt=1e-3, save_every=10, progress=False, project_initial=True)
        assert sol.success, f"cycle {cycle} ({system.name}): {sol.message}"
        assert np.all(np.isfinite(sol.y)) and len(sol.t) == 101
        del model, sol
        if cycle == 2 * len(systems) - 1:
            warm = rss()  # every system compiled by numba (first pass) and run again (second pass)
    end = rss()
    print(f"\n100 cycles in {time.perf_counter() - started:.0f} s; RSS at start {start / MiB:.0f} MiB, "
          f"after the warm-up (20 cycles) {warm / MiB:.0f} MiB, at the end {end / MiB:.0f} MiB "
          f"(growth over the last 80 cycles {(end - warm) / MiB:+.1f} MiB)")
    assert end - warm < 40 * MiB


def test_billion_steps_in_bounded_memory(compiled):
    model = compiled("simple_pendulum")
    model.simulate((0, 1.0), method="verlet", dt=1e-2, record="summary", progress=False)  # numba compiles first
    before, started = rss(), time.perf_counter()
    sol = model.simulate((0, 1e7), method="verlet", dt=1e-2, record="summary", max_steps=2_000_000_000,
                         progress=False)
    after, elapsed = rss(), time.perf_counter() - started
    print(f"\n1e9 Verlet steps in {elapsed:.0f} s; RSS before {before / MiB:.0f} MiB, after {after / MiB:.0f} MiB "
          f"({(after - before) / MiB:+.1f} MiB); energy error {sol.summary.energy_error:.2e}")
    assert sol.success and sol.nsteps == 1_000_000_000 and sol.summary.rows == 1_000_000_001
    assert len(sol.t) == 2 and math.isclose(sol.t[-1], 1e7)
    assert after - before < 20 * MiB
    assert sol.summary.energy_error < 1e-3  # Verlet at h = 0.01: bounded, no drift
