"""Gauss–Legendre collocation methods (implicit Runge–Kutta), as validated, read-only data.

The s-stage Gauss–Legendre method collocates at the zeros of the shifted
Legendre polynomial of degree s; it has order 2s, is symmetric, and is
symplectic for every Hamiltonian system (HLW, *Geometric Numerical
Integration*, sec. II.1.3 and VI.4).  lagcomp applies it to the canonical
equations in x = (q, p), so it is symplectic for any Lagrangian, separable
or not.

References
----------
J. C. Butcher, "Implicit Runge-Kutta processes", Math. Comp. 18 (1964) 50–64.
E. Hairer, C. Lubich, G. Wanner, *Geometric Numerical Integration*, 2nd ed.,
Springer 2006, Table II.1.1 (the coefficients below).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Collocation", "GAUSS1", "GAUSS2", "GAUSS3"]


@dataclass(frozen=True, eq=False)
class Collocation:
    """An implicit Runge–Kutta method: full stage matrix A, weights B, nodes C."""

    name: str
    order: int
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray

    def __post_init__(self):
        A, B, C = (np.array(v, dtype=np.float64) for v in (self.A, self.B, self.C))
        s = B.size
        if A.shape != (s, s) or C.shape != (s,):
            raise ValueError(f"{self.name}: A must be ({s}, {s}) and C ({s},) for {s} weights")
        if abs(B.sum() - 1.0) > 1e-14:
            raise ValueError(f"{self.name}: weights sum to {B.sum()!r}, not 1")
        if not np.allclose(A.sum(axis=1), C, rtol=0, atol=1e-14):
            raise ValueError(f"{self.name}: row sums of A differ from the nodes C")
        # order 2s needs B·C^(k-1) = 1/k for k = 1..2s (the quadrature is exact to degree 2s − 1)
        for k in range(1, self.order + 1):
            if abs(B @ C ** (k - 1) - 1.0 / k) > 1e-14:
                raise ValueError(f"{self.name}: quadrature condition of degree {k - 1} fails")
        for name, value in (("A", A), ("B", B), ("C", C)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    @property
    def extrapolation(self) -> np.ndarray:
        """E (s, s): the previous step's stage derivatives K_j give the next step's first guess Σ_j E_ij K_j.

        The collocation polynomial's derivative interpolates K_j at the nodes
        c_j; E_ij = ℓ_j(1 + c_i) evaluates its Lagrange basis at the next
        step's nodes (same step size), a guess accurate to O(h^s) that saves
        fixed-point sweeps.
        """
        C = self.C
        s = C.size
        E = np.ones((s, s))
        for i in range(s):
            for j in range(s):
                for m in range(s):
                    if m != j:
                        E[i, j] *= (1.0 + C[i] - C[m]) / (C[j] - C[m])
        return E

    def driver_arguments(self) -> tuple[np.ndarray, ...]:
        """The arrays `collocation_run` takes: A, B, C and the extrapolation matrix E."""
        return tuple(np.ascontiguousarray(v, dtype=np.float64).copy() for v in (self.A, self.B, self.C, self.extrapolation))


_r3, _r15 = math.sqrt(3.0), math.sqrt(15.0)

GAUSS1 = Collocation("gauss1", 2, [[0.5]], [1.0], [0.5])  # the implicit midpoint rule
GAUSS2 = Collocation(
    "gauss2", 4,
    [[0.25, 0.25 - _r3 / 6], [0.25 + _r3 / 6, 0.25]],
    [0.5, 0.5],
    [0.5 - _r3 / 6, 0.5 + _r3 / 6],
)
GAUSS3 = Collocation(
    "gauss3", 6,
    [[5 / 36, 2 / 9 - _r15 / 15, 5 / 36 - _r15 / 30],
     [5 / 36 + _r15 / 24, 2 / 9, 5 / 36 - _r15 / 24],
     [5 / 36 + _r15 / 30, 2 / 9 + _r15 / 15, 5 / 36]],
    [5 / 18, 4 / 9, 5 / 18],
    [0.5 - _r15 / 10, 0.5, 0.5 + _r15 / 10],
)
