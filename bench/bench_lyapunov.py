"""What the Lyapunov analysis's tangent dynamics are, how accurate and what they cost, in one process.

    python -m bench.bench_lyapunov [--repeats 3]

`lagcomp.analysis.lyapunov_exponents` integrates Ẇ = J W with J = ∂f/∂x of the canonical equations built from the
model's emitted ``canonical_partials`` kernel (symbolic ∂P/∂q, ∂r/∂q, ∂r/∂q̇ and M: exact, no finite
difference); the only finite difference in the module is `two_trajectory_lyapunov`, a shadow trajectory at
distance d0 (a difference of flows), kept as the Jacobian-free cross-check.  For each of `CASES` this prints:

* the Jacobian: max |J − J_fd| / max |J| against central differences of the canonical field (h = 1e-6) at
  states along the orbit, and the largest |trace J| (exactly 0 for a Hamiltonian flow, so Σλ = 0) next to
  |trace J_fd|, the drift of Σλ a finite-difference Jacobian would bring;
* the spectrum (k = 4): Σλ (0 in exact arithmetic at any time), λ1 + λ4 and λ2, λ3 (0 only as t → ∞);
* the largest exponent by the variational run (k = 1) and by the two-trajectory run (d0 = 1e-9, renormalized
  every 5 steps), and their times (median of `--repeats`) as ratios to the variational k = 1 run.
"""

from __future__ import annotations

import argparse
import math
import time
from functools import partial

import numpy as np

E = 1 / 6


def _start(y0: float) -> tuple[list, list]:
    xd = math.sqrt(2 * E - y0**2 + 2 * y0**3 / 3)
    return [0.0, y0], [xd, 0.0]


def _median_time(run, repeats: int):
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - start)
    return result, float(np.median(times))


def jacobian_check(model, states, h: float = 1e-6) -> dict:
    """Exact canonical Jacobian against central differences of the canonical field at `states` (rows of x)."""
    from lagcomp.integrate.drivers.canonical import canonical_field

    k, p = model.kernels, model.parameter_vector()
    m = 2 * model.n

    def field(x):
        out = np.empty(m)
        canonical_field(k.velocities, k.momentum_rate, 0.0, np.ascontiguousarray(x), p, np.empty(m), out)
        return out

    errors, traces, fd_traces = [], [], []
    for x in states:
        J = model.canonical_jacobian(0.0, x)
        fd = np.stack([(field(x + h * e) - field(x - h * e)) / (2 * h) for e in np.eye(m)], axis=1)
        errors.append(np.abs(J - fd).max() / np.abs(J).max())
        traces.append(abs(np.trace(J)))
        fd_traces.append(abs(np.trace(fd)))
    return dict(error=max(errors), trace=max(traces), fd_trace=max(fd_traces))


#: (example, q0, qd0, dt, t_end): Hénon–Heiles' chaotic orbit at E = 1/6 (tests/test_lyapunov.py), and the double
#: pendulum released from (2, 2) rad (chaotic; its M depends on q, so J's trace is a sum of cancelling terms).
CASES = (("henon_heiles", *_start(-0.1), 0.02, 2000.0), ("double_pendulum", [2.0, 2.0], [0.0, 0.0], 0.005, 500.0))


def measure(repeats: int = 3, cache_dir=None) -> list[dict]:
    import lagcomp as lc
    from lagcomp import analysis as an
    from lagcomp import examples

    rows = []
    for name, q0, qd0, dt, t_end in CASES:
        model = lc.compile(examples.get(name), cache_dir=cache_dir)
        options = dict(dt=dt, progress=False)
        orbit = model.simulate((0.0, 200.0), q0, qd0, rtol=1e-10, atol=1e-10, progress=False)
        picked = np.linspace(0, orbit.t.size - 1, 20, dtype=int)
        states = [model.canonical_state(orbit.q[i], orbit.qd[i]) for i in picked]
        row = dict(model=name, dt=dt, t_end=t_end, jacobian=jacobian_check(model, states))

        runs = (("variational", an.lyapunov_exponents, {}), ("spectrum", an.lyapunov_spectrum, {}),
                ("two-trajectory", an.two_trajectory_lyapunov, dict(d0=1e-9, renorm_every=5)))
        results = {}
        for label, analysis, extra in runs:
            analysis(model, (0.0, 1.0), q0, qd0, **options, **extra)  # numba compiles (or loads) the loop here
            run = partial(analysis, model, (0.0, t_end), q0, qd0, **options, **extra)
            results[label] = _median_time(run, repeats)
        lam = results["spectrum"][0].exponents
        row.update(spectrum=lam, spectrum_sum=float(lam.sum()), pair=float(lam[0] + lam[3]),
                   largest=results["variational"][0].largest, shadow_largest=results["two-trajectory"][0].largest,
                   times={label: t for label, (_, t) in results.items()})
        rows.append(row)
    return rows


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    for r in measure(args.repeats):
        j = r["jacobian"]
        print(f"{r['model']}: RK4 dt = {r['dt']:g}, t in [0, {r['t_end']:g}]")
        print(f"  canonical J (emitted canonical_partials) vs central differences (h = 1e-6): max rel. difference "
              f"{j['error']:.2e}; max |trace J| = {j['trace']:.1e}, max |trace J_fd| = {j['fd_trace']:.1e}")
        print(f"  spectrum {np.array2string(r['spectrum'], precision=5)}: Σλ = {r['spectrum_sum']:.2e}, "
              f"λ1 + λ4 = {r['pair']:.2e}")
        print(f"  largest: variational {r['largest']:.5f}, two-trajectory {r['shadow_largest']:.5f}")
        base = r["times"]["variational"]
        for label, seconds in r["times"].items():
            print(f"  {label:15} {1e3 * seconds:8.1f} ms  {seconds / base:5.2f} × variational k = 1")


if __name__ == "__main__":
    main()
