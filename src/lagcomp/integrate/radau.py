"""Radau IIA of order 5 as data: the constants of the RADAU5 scheme, derived from the tableau.

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

The values below were computed in 40-digit arithmetic (mpmath) and rounded once to float64;
tests/test_radau_driver.py derives them again from the tableau, bit for bit, and compares them with
scipy's literals.  (Data rather than a derivation at import: mpmath would add ~25 ms to ``import lagcomp``.)
"""

from __future__ import annotations

from dataclasses import dataclass

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


def _frozen(values) -> np.ndarray:
    array = np.array(values, dtype=np.float64)
    array.flags.writeable = False
    return array


#: Radau IIA, 3 stages, order 5, with RADAU5's constants: the 40-digit values rounded once to float64
#: (tests/test_radau_driver.py derives them again and checks every bit).
RADAU5 = RadauIIA(
    "radau5", 5,
    C=_frozen([0.1550510257216822, 0.6449489742783178, 1.0]),
    T=_frozen([[0.09443876248897524, -0.1412552950209542, 0.030029194105147424],
               [0.2502131229653333, 0.20412935229379994, -0.3829421127572619],
               [1.0, 1.0, 0.0]]),
    TI=_frozen([[4.178718591551905, 0.32768282076106237, 0.5233764454994495],
                [-4.178718591551905, -0.32768282076106237, 0.47662355450055044],
                [0.5028726349457868, -2.571926949855605, 0.5960392048282249]]),
    MU=_frozen([3.637834252744496, 2.6810828736277523, -3.0504301992474105]),
    ERROR_WEIGHTS=_frozen([-10.048809399827416, 1.382142733160749, -0.3333333333333333]),
    DENSE_WEIGHTS=_frozen([[10.048809399827416, -25.62959144707664, 15.580782047249224],
                           [-1.382142733160749, 10.296258113743306, -8.914115380582556],
                           [0.3333333333333333, -2.6666666666666665, 3.3333333333333335]]),
)
