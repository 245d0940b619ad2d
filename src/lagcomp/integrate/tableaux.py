"""Butcher tableaux of the integrators, as validated, read-only data.

The compiled drivers take the coefficient arrays as arguments; :func:`driver_arguments`
returns them in the order the driver expects (for the embedded pairs, those of
`lagcomp.integrate.drivers.embedded.embedded_run`).  An embedded pair is a `Tableau` and a
line of the registry `lagcomp.integrate.methods`: nothing else.

Conventions (Hairer, Norsett & Wanner, *Solving ODEs I*, sec. II.1-II.6):

* ``A`` is the (s, s) strictly lower-triangular stage matrix, ``B`` the (s,)
  weights of the propagated solution and ``C`` the (s,) nodes (row sums of A).
* Error weights (``E`` for DOPRI5, ``E3``/``E5`` for DOP853) have s + 1
  entries: the last multiplies the FSAL stage ``f(t + h, y_new)``.  Each sums
  to zero, since it is a difference of two consistent weight vectors.
* ``P`` (s + 1, m): dense output in powers of the step fraction (DOPRI5, Tsit5,
  BS3), ``y(t + x h) = y + h K^T P [x, x^2, ..., x^m]`` with K including the FSAL row.
* ``A_EXTRA`` (n_extra, s + 1 + n_extra), ``C_EXTRA`` (n_extra,): extra stages
  for DOP853's dense output; ``D`` (m, s + 1 + n_extra) its coefficients.
* ``stiffness_bound``: the h|λ| above which the embedded driver's stiffness test (Hairer's, HNW II,
  sec. IV.2) finds a step at the method's stability limit, a little inside the interval of absolute
  stability on the negative real axis; 0 for no test, which needs the last stage at t + h (c = 1)
  next to the FSAL stage.

DOPRI5 and DOP853 coefficients are scipy's own (``scipy.integrate.RK45`` /
``DOP853`` class attributes, copied into `lagcomp.integrate.dormand_prince` and
checked bitwise against scipy by the tests), so that the drivers reproduce
scipy's step sequence; so are BS3's (``scipy.integrate.RK23``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Optional

import numpy as np

from lagcomp.integrate import dormand_prince as dp

__all__ = ["Tableau", "RK4", "DOPRI5", "DOP853", "TSIT5", "BS3", "driver_arguments", "over_common_denominator"]

#: Absolute tolerance for the consistency checks.  The published rational
#: coefficients are stored as rounded floats, so sums are exact only to a few
#: ulps (observed: < 1e-15 for scipy's tableaux).
_TOL = 1e-14

#: How the embedded driver turns the error weights into the error norm: the RMS norm of one estimate
#: (E), or DOP853's combination of its 5th- and 3rd-order estimates (E5, E3).
ERROR_RMS, ERROR_DOP853 = 0, 1

_ARRAY_FIELDS = ("A", "B", "C", "E", "E3", "E5", "P", "D", "A_EXTRA", "C_EXTRA")


def _frozen_array(value, name: str, ndim: int) -> np.ndarray:
    """Return a read-only float64 copy of ``value``; check its dimension."""
    arr = np.array(value, dtype=np.float64, copy=True)
    if arr.ndim != ndim:
        raise ValueError(f"{name} must be {ndim}-dimensional, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains non-finite values")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Tableau:
    """An explicit Runge-Kutta method given by its coefficients.

    ``order`` is the order of the propagated solution; ``error_order`` the
    order ``q`` of the error estimator (the local error estimate behaves
    like ``h^(q+1)``), which sets the step-control exponent ``-1/(q+1)``.
    It is ``None`` for a method without error estimate (fixed step).

    The arrays are copied to read-only float64 arrays and the invariants
    listed in the module docstring are checked; a violation raises
    ``ValueError``.
    """

    name: str
    order: int
    error_order: Optional[int]
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    E: Optional[np.ndarray] = None
    E3: Optional[np.ndarray] = None
    E5: Optional[np.ndarray] = None
    P: Optional[np.ndarray] = None
    D: Optional[np.ndarray] = None
    A_EXTRA: Optional[np.ndarray] = None
    C_EXTRA: Optional[np.ndarray] = None
    stiffness_bound: float = 0.0

    def __post_init__(self) -> None:
        ndims = {"A": 2, "B": 1, "C": 1, "E": 1, "E3": 1, "E5": 1,
                 "P": 2, "D": 2, "A_EXTRA": 2, "C_EXTRA": 1}
        for name in _ARRAY_FIELDS:
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, _frozen_array(value, name, ndims[name]))
        self._check()

    # -- invariants -------------------------------------------------------

    @property
    def n_stages(self) -> int:
        """Number of stages s of the main method (without the FSAL stage)."""
        return self.B.shape[0]

    def _check(self) -> None:
        if not isinstance(self.order, (int, np.integer)) or self.order < 1:
            raise ValueError(f"{self.name}: order must be a positive integer")
        A, B, C = self.A, self.B, self.C
        s = B.shape[0]
        if s < 1 or A.shape != (s, s) or C.shape != (s,):
            raise ValueError(
                f"{self.name}: inconsistent shapes A{A.shape}, B{B.shape}, C{C.shape}")
        if np.any(np.triu(A) != 0.0):
            raise ValueError(f"{self.name}: A must be strictly lower triangular (explicit method)")
        if np.max(np.abs(A.sum(axis=1) - C)) > _TOL:
            raise ValueError(f"{self.name}: row sums of A must equal C")
        if abs(B.sum() - 1.0) > _TOL:
            raise ValueError(f"{self.name}: sum(B) must be 1")
        if not self.stiffness_bound >= 0.0:
            raise ValueError(f"{self.name}: stiffness_bound must be >= 0")
        if self.stiffness_bound > 0.0 and C[-1] != 1.0:
            raise ValueError(f"{self.name}: the stiffness test compares the last stage with the FSAL stage, both "
                             f"at t + h: it needs C[-1] = 1, got {C[-1]}")

        # Error estimators.
        if (self.E3 is None) != (self.E5 is None):
            raise ValueError(f"{self.name}: E3 and E5 must be given together")
        estimators = [(k, getattr(self, k)) for k in ("E", "E3", "E5")
                      if getattr(self, k) is not None]
        for key, vec in estimators:
            if vec.shape != (s + 1,):
                raise ValueError(
                    f"{self.name}: {key} must have n_stages + 1 = {s + 1} entries "
                    f"(the last for the FSAL stage), got {vec.shape}")
            if abs(vec.sum()) > _TOL:
                raise ValueError(f"{self.name}: sum({key}) must be 0, got {vec.sum():.3e}")
        if estimators:
            if not isinstance(self.error_order, (int, np.integer)) or self.error_order < 1:
                raise ValueError(f"{self.name}: error_order must be a positive integer")
        elif self.error_order is not None:
            raise ValueError(f"{self.name}: error_order given without error weights")

        # DOPRI5-style dense output: continuity at x = 1 needs
        # P.sum(axis=1) == [B, 0] (the interpolant reproduces y_new).
        if self.P is not None:
            P = self.P
            if P.shape[0] != s + 1 or P.shape[1] < 1:
                raise ValueError(f"{self.name}: P must have shape (n_stages + 1, m), got {P.shape}")
            if np.max(np.abs(P.sum(axis=1) - np.append(B, 0.0))) > _TOL:
                raise ValueError(f"{self.name}: rows of P must sum to [B, 0]")

        # DOP853-style dense output with extra stages.
        extra = (self.D, self.A_EXTRA, self.C_EXTRA)
        if any(x is not None for x in extra):
            if any(x is None for x in extra):
                raise ValueError(f"{self.name}: D, A_EXTRA and C_EXTRA must be given together")
            D, AX, CX = extra
            n_extra = CX.shape[0]
            n_all = s + 1 + n_extra
            if AX.shape != (n_extra, n_all) or D.shape[1] != n_all:
                raise ValueError(
                    f"{self.name}: inconsistent dense-output shapes A_EXTRA{AX.shape}, "
                    f"C_EXTRA{CX.shape}, D{D.shape} for {s} stages")
            for k in range(n_extra):
                if np.any(AX[k, s + 1 + k:] != 0.0):
                    raise ValueError(f"{self.name}: A_EXTRA row {k} uses a stage not yet computed")
            if np.max(np.abs(AX.sum(axis=1) - CX)) > _TOL:
                raise ValueError(f"{self.name}: row sums of A_EXTRA must equal C_EXTRA")
            # For f = const the interpolant is linear: D's rows sum to zero
            # (relative to their size: the entries are of order 1e2-1e3).
            if np.any(np.abs(D.sum(axis=1)) > _TOL * np.abs(D).sum(axis=1)):
                raise ValueError(f"{self.name}: rows of D must sum to 0")


def _square(A: np.ndarray) -> np.ndarray:
    """Pad an (s, s-1) stage matrix, as scipy stores RK45's, to (s, s)."""
    A = np.asarray(A, dtype=np.float64)
    s = A.shape[0]
    out = np.zeros((s, s))
    out[:, : A.shape[1]] = A
    return out


#: Classic 4th-order Runge-Kutta method (Kutta 1901; HNW I, table II.1.2).
RK4 = Tableau(
    name="RK4",
    order=4,
    error_order=None,
    A=[[0.0, 0.0, 0.0, 0.0],
       [0.5, 0.0, 0.0, 0.0],
       [0.0, 0.5, 0.0, 0.0],
       [0.0, 0.0, 1.0, 0.0]],
    B=[1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0],
    C=[0.0, 0.5, 0.5, 1.0],
)

#: Dormand & Prince (1980) 5(4) pair with quartic dense output.
DOPRI5 = Tableau(
    name="DOPRI5",
    order=5,
    error_order=4,
    A=_square(dp.RK45_A),
    B=dp.RK45_B,
    C=dp.RK45_C,
    E=dp.RK45_E,
    P=dp.RK45_P,
    # dopri5.f's 3.25: the real stability interval is (-3.307, 0)
    stiffness_bound=3.25,
)

#: Hairer's DOP853: 8th order, 5th/3rd-order error estimates, 7th-order dense
#: output from three extra stages.
DOP853 = Tableau(
    name="DOP853",
    order=8,
    error_order=7,
    A=dp.DOP853_A,
    B=dp.DOP853_B,
    C=dp.DOP853_C,
    E3=dp.DOP853_E3,
    E5=dp.DOP853_E5,
    D=dp.DOP853_D,
    A_EXTRA=dp.DOP853_A_EXTRA,
    C_EXTRA=dp.DOP853_C_EXTRA,
    # dop853.f's 6.1: the real stability interval is (-6.394, 0)
    stiffness_bound=6.1,
)


#: Tsitouras' 5(4) pair (Ch. Tsitouras, "Runge-Kutta pairs of order 5(4) satisfying only the first
#: column simplifying assumption", Comput. Math. Appl. 62 (2011) 770-775): 7 stages with FSAL like
#: DOPRI5, with a smaller error constant.  The coefficients are the paper's, computed to 80 digits (as
#: in the tables of DifferentialEquations.jl) and rounded to float64; the dense output of order 4 is
#: the paper's, its factored polynomials b_i(x) expanded in powers of x.  E = b_hat - b, scipy's sign.
#: tests/test_order_conditions.py checks the orders 5, 4 and 4 (dense output) to rounding.
TSIT5 = Tableau(
    name="TSIT5",
    order=5,
    error_order=4,
    A=[[0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
       [0.161, 0.0, 0.0, 0.0, 0.0, 0.0],
       [-0.008480655492356989, 0.335480655492357, 0.0, 0.0, 0.0, 0.0],
       [2.8971530571054935, -6.359448489975075, 4.3622954328695815, 0.0, 0.0, 0.0],
       [5.325864828439257, -11.748883564062828, 7.4955393428898365, -0.09249506636175525, 0.0, 0.0],
       [5.86145544294642, -12.92096931784711, 8.159367898576159, -0.071584973281401, -0.028269050394068383, 0.0]],
    B=[0.09646076681806523, 0.01, 0.4798896504144996, 1.379008574103742, -3.290069515436081, 2.324710524099774],
    C=[0.0, 0.161, 0.327, 0.9, 0.9800255409045097, 1.0],
    E=[-0.0017800110522257714, -0.0008164344596567469, 0.007880878010261995, -0.1447110071732629,
       0.5823571654525552, -0.45808210592918697, 0.015151515151515152],
    P=[[1.0, -2.763706197274826, 2.9132554618219126, -1.0530884977290216],
       [0.0, 0.13169999999999998, -0.2234, 0.1017],
       [0.0, 3.9302962368947516, -5.941033872131505, 2.490627285651253],
       [0.0, -12.411077166933676, 30.33818863028232, -16.548102889244902],
       [0.0, 37.50931341651104, -88.1789048947664, 47.37952196281928],
       [0.0, -27.896526289197286, 65.09189467479366, -34.87065786149661],
       [0.0, 1.5, -4.0, 2.5]],
    # the real stability interval is (-3.507, 0): 3.45 lies as far inside it as dopri5.f's 3.25 inside DOPRI5's
    stiffness_bound=3.45,
)

#: Bogacki & Shampine's 3(2) pair (P. Bogacki, L. F. Shampine, "A 3(2) pair of Runge-Kutta formulas",
#: Appl. Math. Lett. 2 (1989) 321-325) with its cubic Hermite dense output: scipy's RK23, whose
#: float64 values these expressions give bit for bit (checked by tests/test_tableaux.py).
BS3 = Tableau(
    name="BS3",
    order=3,
    error_order=2,
    A=[[0.0, 0.0, 0.0],
       [1 / 2, 0.0, 0.0],
       [0.0, 3 / 4, 0.0]],
    B=[2 / 9, 1 / 3, 4 / 9],
    C=[0.0, 1 / 2, 3 / 4],
    E=[5 / 72, -1 / 12, -1 / 9, 1 / 8],
    P=[[1.0, -4 / 3, 5 / 9],
       [0.0, 1.0, -2 / 3],
       [0.0, 4 / 3, -8 / 9],
       [0.0, -1.0, 1.0]],
)


def driver_arguments(tableau: Tableau) -> tuple:
    """Trailing tableau arguments of the compiled driver for ``tableau``.

    * an embedded pair (error weights present), for
      `lagcomp.integrate.drivers.embedded.embedded_run`: ``(A, B, C, error_weights, error_norm,
      error_exponent, dense_kind, dense_weights, extra_A, extra_C, stiffness_bound)`` with

      - ``error_weights`` (1, s + 1) = [E] and ``error_norm`` ERROR_RMS, or for DOP853 (2, s + 1) =
        [E5, E3] and ERROR_DOP853; ``error_exponent`` = -1 / (error_order + 1);
      - ``dense_kind`` DENSE_POWERS with ``dense_weights`` = Pᵀ (m, s + 1) and no extra stages
        (``extra_A`` (0, s + 1), ``extra_C`` (0,)), or for DOP853 DENSE_CONTD8 with D and its extra
        stages ``A_EXTRA``, ``C_EXTRA``; ``stiffness_bound`` a float (0: no stiffness test);

    * a fixed-step method without error estimate (RK4), for
      `lagcomp.integrate.drivers.fixed_step.runge_kutta_run`: ``(A, C, weights, denominator)``,
      the weights B as `over_common_denominator` writes them.

    The arrays are writable C-contiguous float64 copies (the drivers' signatures name that layout).
    Raises ``ValueError`` for a tableau no driver can use.
    """
    from lagcomp.integrate.drivers.events import DENSE_CONTD8, DENSE_POWERS

    def copy(array) -> np.ndarray:
        return np.ascontiguousarray(array, dtype=np.float64).copy()

    if tableau.E3 is None and tableau.E is None:
        return (copy(tableau.A), copy(tableau.C), *over_common_denominator(tableau.B))
    if tableau.E is not None:
        if tableau.P is None:
            raise ValueError(f"{tableau.name}: the embedded driver needs the dense-output matrix P")
        errors, norm = [tableau.E], ERROR_RMS
        dense, stages = (DENSE_POWERS, tableau.P.T), (np.zeros((0, tableau.n_stages + 1)), np.zeros(0))
    else:
        if tableau.D is None:
            raise ValueError(f"{tableau.name}: the combined E5/E3 error estimate comes with DOP853's dense output D")
        errors, norm = [tableau.E5, tableau.E3], ERROR_DOP853
        dense, stages = (DENSE_CONTD8, tableau.D), (tableau.A_EXTRA, tableau.C_EXTRA)
    return (copy(tableau.A), copy(tableau.B), copy(tableau.C), copy(np.vstack(errors)), norm,
            -1.0 / (tableau.error_order + 1), dense[0], copy(dense[1]), copy(stages[0]), copy(stages[1]),
            float(tableau.stiffness_bound))


#: The largest denominator `over_common_denominator` looks for in a method's weights.
DENOMINATOR_MAX = 1000


def over_common_denominator(weights: np.ndarray) -> tuple[np.ndarray, float]:
    """``(numerators, d)`` with ``weights = numerators / d``: integers over their least common denominator.

    A fixed-step driver forms the new state as ``y + (h / d) * sum_j numerators[j] K[j]``.  When
    every weight is a fraction with a small denominator (the float nearest it, as the tableau
    stores it), the numerators are small integers, which multiply the stages exactly: RK4's
    (1/6, 1/3, 1/3, 1/6) become ``[1, 2, 2, 1]`` over 6, and the driver rounds like the textbook
    formula ``y + h/6 (K1 + 2 K2 + 2 K3 + K4)`` (the golden RK4 trajectories in tests/data fix that
    rounding).  Other weights are returned as they are, over ``d = 1``.  The numerators are a
    writable float64 array, ``d`` a float.
    """
    weights = np.asarray(weights, dtype=np.float64)
    fractions = [Fraction(float(w)).limit_denominator(DENOMINATOR_MAX) for w in weights]
    if any(float(f) != w for f, w in zip(fractions, weights)):
        return weights.copy(), 1.0
    d = math.lcm(*(f.denominator for f in fractions))
    return np.array([float(f * d) for f in fractions]), float(d)
