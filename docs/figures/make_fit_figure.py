"""Draw ``fit.png``: the README's fit of a damped double pendulum to noisy angles (`Model.fit`).

    PYTHONPATH=src python docs/figures/make_fit_figure.py [docs/figures]

(needs matplotlib; some twenty seconds, most of it compiling the model once).  The same system, data and
start as the README's section "Fitting" and `tests/test_fit.py`.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import sympy as sp

import lagcomp as lc


def damped_double_pendulum() -> lc.System:
    """The double pendulum with viscous joints, D = c1 θ̇1²/2 + c2 (θ̇2 − θ̇1)²/2."""
    th1, th2 = lc.coordinates("theta1 theta2")
    m1, m2, l1, l2, g, c1, c2 = sp.symbols("m1 m2 l1 l2 g c1 c2", positive=True)
    x1, y1 = l1 * sp.sin(th1), -l1 * sp.cos(th1)
    x2, y2 = x1 + l2 * sp.sin(th2), y1 - l2 * sp.cos(th2)
    T = m1 * (x1.diff(lc.t) ** 2 + y1.diff(lc.t) ** 2) / 2 + m2 * (x2.diff(lc.t) ** 2 + y2.diff(lc.t) ** 2) / 2
    return lc.System([th1, th2], T=T, V=g * (m1 * y1 + m2 * y2), name="damped_double_pendulum",
                     dissipation=c1 * th1.diff(lc.t) ** 2 / 2 + c2 * (th2.diff(lc.t) - th1.diff(lc.t)) ** 2 / 2,
                     defaults=dict(m1=1.0, m2=1.0, l1=1.0, l2=1.0, g=9.81, c1=0.1, c2=0.1), q0=(1.0, 0.5))


def main(directory: Path) -> None:
    directory.mkdir(parents=True, exist_ok=True)
    model = lc.compile(damped_double_pendulum())
    true = dict(c1=0.3, c2=0.2, m2=0.8, l2=0.7)
    t = np.linspace(0.0, 10.0, 201)
    exact = model.simulate((0, 10), params=true, t_eval=t, rtol=1e-12, atol=1e-12).q
    data = exact + 1e-3 * np.random.default_rng(22).standard_normal(exact.shape)
    fit = model.fit(t, data, {"c1": 0.39, "c2": 0.15, "m2": 1.0, "l2": 0.56}, sigma=1e-3)
    print(fit.estimates, fit.standard_errors, f"nfev {fit.nfev}, njev {fit.njev}")
    fit.plot().savefig(directory / "fit.png", dpi=110)
    print(f"wrote {directory / 'fit.png'}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parent)
