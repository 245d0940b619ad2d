"""Symmetric compositions of the Störmer–Verlet step, as validated, read-only data.

A composition advances a step h by Verlet substeps of sizes w_1 h, ..., w_s h
(kick–drift–kick each).  With Σ w_i = 1 and symmetric weights the result is
symmetric, symplectic for separable Hamiltonians H = ½ pᵀM⁻¹p + V(q), and of
even order; the weights below raise it from 2 to 4 and 6.

References
----------
H. Yoshida, "Construction of higher order symplectic integrators",
Phys. Lett. A 150 (1990) 262–268 (the triple jump for order 4; solution A of
his order-6 equations).  E. Hairer, C. Lubich, G. Wanner, *Geometric
Numerical Integration*, 2nd ed., Springer 2006, sec. II.4 and V.3.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Composition", "VERLET", "YOSHIDA4", "YOSHIDA6"]


@dataclass(frozen=True, eq=False)
class Composition:
    """Weights of a symmetric composition of Verlet substeps, and its order."""

    name: str
    order: int
    weights: np.ndarray

    def __post_init__(self):
        w = np.array(self.weights, dtype=np.float64)
        if w.ndim != 1 or w.size == 0:
            raise ValueError(f"{self.name}: weights must be a non-empty 1-D array")
        if abs(w.sum() - 1.0) > 1e-14:
            raise ValueError(f"{self.name}: weights sum to {w.sum()!r}, not 1 (the method would be inconsistent)")
        if not np.allclose(w, w[::-1], rtol=0, atol=1e-15):
            raise ValueError(f"{self.name}: weights are not symmetric (the composition would lose its even order)")
        w.setflags(write=False)
        object.__setattr__(self, "weights", w)

    def driver_arguments(self) -> tuple[np.ndarray, ...]:
        """The arrays `composition_run` takes after its common arguments."""
        return (np.ascontiguousarray(self.weights, dtype=np.float64).copy(),)


def _triple_jump() -> np.ndarray:
    """Order 4: w1 = 1/(2 − 2^(1/3)), w0 = 1 − 2 w1 (the middle substep goes backwards)."""
    w1 = 1.0 / (2.0 - 2.0 ** (1.0 / 3.0))
    return np.array([w1, 1.0 - 2.0 * w1, w1])


def _yoshida6() -> np.ndarray:
    """Order 6, Yoshida's solution A: seven substeps w3 w2 w1 w0 w1 w2 w3.

    Yoshida published 15 digits (−1.17767998417887, 0.235573213359357,
    0.784513610477560), which satisfy the order-6 conditions only to ~1e-14;
    the values below are his solution refined by Newton's method on those
    conditions in 40-digit arithmetic (tests/test_order_conditions.py checks
    them to round-off).
    """
    w1, w2, w3 = -1.1776799841788710069464, 0.2355732133593581336848, 0.7845136104775572638195
    w0 = 1.0 - 2.0 * (w1 + w2 + w3)
    return np.array([w3, w2, w1, w0, w1, w2, w3])


VERLET = Composition("verlet", 2, np.array([1.0]))
YOSHIDA4 = Composition("yoshida4", 4, _triple_jump())
YOSHIDA6 = Composition("yoshida6", 6, _yoshida6())
