"""sin and cos for the kernels, imported by every generated module.

The kernels print ``sin(x)`` and ``cos(x)`` as calls of `sin` and `cos` below
(``lagcomp.codegen.printer``): Cody–Waite reduction
of x by π/2 in four parts (fdlibm's constants: the first three have 33
significant bits, so k times each is exact for |k| < 2²⁰), then Cephes'
minimax polynomials for sin and cos on [−π/4, π/4] (Cephes ``sin.c``).  The
results are within 2 ulp of libm's, most of them equal (tests/test_trig.py).

Why not libm: an integrator's stages depend on each other, so it waits for
each kernel call to finish, and a libm ``sin`` is an opaque call with
branches on the argument's size.  The polynomial is a few dozen arithmetic
operations that LLVM schedules with the rest of the kernel, and ``sin x`` and
``cos x`` of one argument share the reduction.  On the double pendulum (three
sines and a cosine per ``rhs``) this, with the drivers' view-free stage loop,
brought DOP853 from 1.42x to 1.21x numbalsoda's dop853 (``python -m bench
--only adaptive`` at c6d8e63 and at aed6595).

* `sin`/`cos`: scalar kernels.  For |x| > ``_TRIG_POLY_MAX`` (10⁵) they
  call libm, where the reduction would start to lose accuracy (k·π/2 is
  exact only while |k| < 2²⁰, |x| < 1.6·10⁶), and for non-finite x (NaN).
* `vsin`/`vcos`: the same polynomials without the branch, for the
  batched lane kernels, whose loop over SIMD lanes LLVM vectorizes
  only when it holds no call.  Accurate while |x| < 1.6·10⁶.

Why ``fastmath=False`` on `sin` and `cos`: numba compiles a function called
by another with the caller's fastmath flags unless its own are given
(``flags.inherit_if_not_set("fastmath")``, numba issue #7168), compiles one
version per signature whoever calls next, and caches that version on disk.
The Taylor kernels have ``fastmath={"contract"}``, so sin compiled first by
one of them had FMAs in its polynomials (vfmadd, 18 in its machine code),
sin compiled first by ``rhs`` had none, and every later kernel — of this
process or, through numba's cache, of later ones — got that version: the
double pendulum's trajectories differed in the last bits with the order of
compilation (tests/test_kernel_support_flags.py).  Without contraction the
scalar kernels compute what `vsin` and `vcos` compute inlined into
``rhs_lanes`` (no fastmath), so the batched sweeps stay bitwise equal to the
scalar ones.  `vsin`, `vcos` and `_quadrant` are inlined by numba
(``inline="always"``): compiled as part of their caller, with its flags.
"""

import math

import numpy as np
from numba import njit

# sin(r) = r + r z S(z), cos(r) = 1 − z/2 + z² C(z), z = r², |r| ≤ π/4 (Cephes sin.c)
_SIN_0, _SIN_1, _SIN_2 = 1.58962301576546568060e-10, -2.50507477628578072866e-8, 2.75573136213857245213e-6
_SIN_3, _SIN_4, _SIN_5 = -1.98412698295895385996e-4, 8.33333333332211858878e-3, -1.66666666666666307295e-1
_COS_0, _COS_1, _COS_2 = -1.13585365213876817300e-11, 2.08757008419747316778e-9, -2.75573141792967388112e-7
_COS_3, _COS_4, _COS_5 = 2.48015872888517045348e-5, -1.38888888888730564116e-3, 4.16666666666665929218e-2
# π/2 in four parts, the first three of 33 bits so that k times them is exact (fdlibm's pio2_1, pio2_2,
# pio2_3, pio2_3t): r keeps its relative accuracy even next to a multiple of π/2
_PIO2_1, _PIO2_2 = 1.57079632673412561417e+00, 6.07710050630396597660e-11
_PIO2_3, _PIO2_4 = 2.02226624871116645580e-21, 8.47842766036889956997e-32


@njit(cache=True, error_model="numpy", inline="always")
def _quadrant(x):
    """x = k π/2 + r with |r| ≤ π/4: returns (k mod 4, sin r, cos r)."""
    k = math.floor(x * 0.63661977236758134308 + 0.5)
    r = (((x - k * _PIO2_1) - k * _PIO2_2) - k * _PIO2_3) - k * _PIO2_4
    z = r * r
    s = r + r * z * (((((_SIN_0 * z + _SIN_1) * z + _SIN_2) * z + _SIN_3) * z + _SIN_4) * z + _SIN_5)
    c = 1.0 - 0.5 * z + z * z * (((((_COS_0 * z + _COS_1) * z + _COS_2) * z + _COS_3) * z + _COS_4) * z + _COS_5)
    return np.int64(k) & 3, s, c


@njit(cache=True, error_model="numpy", inline="always")
def vsin(x):
    """sin x, vectorizable (see the module docstring)."""
    q, s, c = _quadrant(x)
    v = c if q & 1 else s
    return -v if q & 2 else v


@njit(cache=True, error_model="numpy", inline="always")
def vcos(x):
    """cos x, vectorizable (see the module docstring)."""
    q, s, c = _quadrant(x)
    v = s if q & 1 else c
    return -v if (q + 1) & 2 else v


#: Above this |x|, `sin` and `cos` call libm (see the module docstring).
_TRIG_POLY_MAX = 1e5


@njit(cache=True, error_model="numpy", fastmath=False)
def sin(x):
    """sin x for the scalar kernels: the polynomial, or libm for huge or non-finite x."""
    if abs(x) <= _TRIG_POLY_MAX:
        return vsin(x)
    return math.sin(x)


@njit(cache=True, error_model="numpy", fastmath=False)
def cos(x):
    """cos x for the scalar kernels: the polynomial, or libm for huge or non-finite x."""
    if abs(x) <= _TRIG_POLY_MAX:
        return vcos(x)
    return math.cos(x)
