"""Radau IIA of order 5 as data: the constants of the RADAU5 scheme, derived from the tableau at import.

The three-stage Radau IIA method collocates at the zeros c of the Radau polynomial
d²/dx² (x² (x - 1)³) (c = (4 ∓ √6)/10, 1); its stage matrix A (a_ij = ∫₀^{c_i} l_j, l_j the Lagrange
basis on c) has weights b = A's last row (stiffly accurate) and order 5.  Hairer & Wanner's RADAU5
(*Solving Ordinary Differential Equations II*, 2nd ed., 1996, sec. IV.8) solves the stage equations
Z = h (A ⊗ I) F(y + Z) in the variables W = (T⁻¹ ⊗ I) Z, where A⁻¹ = T Λ T⁻¹ with

* γ, the real eigenvalue of A⁻¹, and α ± iβ, the complex pair (β > 0);
* T's columns: the eigenvector of γ and the real and imaginary parts of the eigenvector of α + iβ,
  each scaled so that its last component is 1 (Hairer's normalisation, so T's last row is
  (1, 1, 0); scipy's ``T`` and ``TI`` are the same matrices: tests/test_radau_driver.py checks).

Then one real n×n system with (γ/h I − J) and one complex one with ((α − iβ)/h I − J) make a
simplified Newton step (`MU_REAL` = γ, `MU_COMPLEX` = α − iβ: W₁ + iW₂ satisfies
(α − iβ)/h (W₁ + iW₂) = (T⁻¹F)₁ + i (T⁻¹F)₂).

The embedded error estimate (HNW IV.8, eq. (8.19)-(8.20)): ŷ₁ − y₁ = γ₀ h f(t₀, y₀) + Σ (b̂_i − b_i) h F_i
with γ₀ = 1/γ and b̂ the weights of order 3 with the extra node 0 (Σ b̂ = 1 − γ₀, Σ b̂ c = 1/2,
Σ b̂ c² = 1/3); with h F = A⁻¹ Z it is γ₀ (h f₀ + E·Z) for `ERROR_WEIGHTS` E = γ (b̂ − b) A⁻¹, and the
driver filters it as (γ/h I − J)⁻¹ (f₀ + E·Z / h) (the same as (I − h γ₀ J)⁻¹ (ŷ₁ − y₁)).

Dense output: the collocation polynomial u(t + x h) = y + Σ_k Q_k x^(k+1) (k = 0, 1, 2) through
y + Z_i at x = c_i, i.e. Q = V⁻¹ Z with V_ik = c_i^(k+1); `DENSE_WEIGHTS` P = (V⁻¹)ᵀ gives
Q_k = Σ_i P_ik Z_i.

Everything is computed in 40-digit arithmetic (mpmath) and rounded once to float64.
"""

from __future__ import annotations

from dataclasses import dataclass

import mpmath
import numpy as np

__all__ = ["RadauIIA", "RADAU5"]


@dataclass(frozen=True, eq=False)
class RadauIIA:
    """The constants the Radau driver takes (`lagcomp.integrate.drivers.radau`), as float64 arrays."""

    name: str
    order: int
    #: Nodes c (3,).
    C: np.ndarray
    #: T and T⁻¹ (3, 3).
    T: np.ndarray
    TI: np.ndarray
    #: [γ, Re(α − iβ), Im(α − iβ)]: the shifts of the real and the complex iteration matrix (times 1/h).
    MU: np.ndarray
    #: E (3,): the error estimate's weights on Z.
    ERROR_WEIGHTS: np.ndarray
    #: P (3, 3): Q_k = Σ_i P[i, k] Z_i.
    DENSE_WEIGHTS: np.ndarray

    def driver_arguments(self) -> tuple:
        """The arrays after the driver protocol's arguments: C, T, TI, MU, ERROR_WEIGHTS, DENSE_WEIGHTS, as
        writable copies (the driver's signature names writable C-contiguous arrays; these are read-only)."""
        return tuple(a.copy() for a in (self.C, self.T, self.TI, self.MU, self.ERROR_WEIGHTS, self.DENSE_WEIGHTS))


def _derive() -> RadauIIA:
    """The constants of RADAU5 from the Radau IIA tableau (see the module docstring)."""
    with mpmath.workdps(40):
        s6 = mpmath.sqrt(6)
        c = [(4 - s6) / 10, (4 + s6) / 10, mpmath.mpf(1)]
        a = mpmath.matrix(3, 3)
        for j in range(3):
            others = [c[m] for m in range(3) if m != j]
            scale = (c[j] - others[0]) * (c[j] - others[1])
            # l_j(x) = (x - c_m)(x - c_n)/scale = (x² - (c_m + c_n) x + c_m c_n)/scale, integrated from 0
            for i in range(3):
                x = c[i]
                a[i, j] = (x ** 3 / 3 - (others[0] + others[1]) * x ** 2 / 2 + others[0] * others[1] * x) / scale
        a_inv = a ** -1
        values, vectors = mpmath.eig(a_inv)
        real = min(range(3), key=lambda k: abs(mpmath.im(values[k])))
        pair = max(range(3), key=lambda k: mpmath.im(values[k]))
        gamma = mpmath.re(values[real])
        v_real = [mpmath.re(vectors[i, real] / vectors[2, real]) for i in range(3)]
        v_pair = [vectors[i, pair] / vectors[2, pair] for i in range(3)]
        t = mpmath.matrix([[v_real[i], mpmath.re(v_pair[i]), mpmath.im(v_pair[i])] for i in range(3)])
        ti = t ** -1
        mu_complex = mpmath.conj(values[pair])
        vander = mpmath.matrix([[1, 1, 1], c, [ci ** 2 for ci in c]])
        b_hat = vander ** -1 * mpmath.matrix([1 - 1 / gamma, mpmath.mpf(1) / 2, mpmath.mpf(1) / 3])
        error = [gamma * sum((b_hat[k] - a[2, k]) * a_inv[k, j] for k in range(3)) for j in range(3)]
        powers = mpmath.matrix([[ci ** (k + 1) for k in range(3)] for ci in c])
        dense = (powers ** -1).T

        def floats(m, rows, cols=None):
            if cols is None:
                return np.array([float(m[i]) for i in range(rows)])
            return np.array([[float(m[i, j]) for j in range(cols)] for i in range(rows)])

        return RadauIIA(
            "radau5", 5, C=floats(c, 3), T=floats(t, 3, 3), TI=floats(ti, 3, 3),
            MU=np.array([float(gamma), float(mpmath.re(mu_complex)), float(mpmath.im(mu_complex))]),
            ERROR_WEIGHTS=floats(error, 3), DENSE_WEIGHTS=floats(dense, 3, 3),
        )


#: Radau IIA, 3 stages, order 5, with RADAU5's constants.
RADAU5 = _derive()
for array in (RADAU5.C, RADAU5.T, RADAU5.TI, RADAU5.MU, RADAU5.ERROR_WEIGHTS, RADAU5.DENSE_WEIGHTS):
    array.flags.writeable = False
