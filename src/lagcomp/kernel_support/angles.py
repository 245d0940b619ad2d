"""An angle reduced to [−π, π] with its rounding kept small: what the Taylor method evaluates its series at.

The Taylor drivers (`lagcomp.integrate.drivers.taylor`) and the batched Taylor kernels
(`lagcomp.codegen.taylor_lanes`) evaluate the series of a coordinate that the equations see only
through sin and cos (`lagcomp.codegen.periodic`) at that coordinate reduced to [−π, π]: an angle
that has wound to θ ≈ 500 is stored to ulp(500) = 5.7e-14, and the equations evaluated there
would take in that rounding at every step.
"""

from __future__ import annotations

import numpy as np
from numba import njit

# 2π in three parts: the first two of 31 and 32 significant bits, so that m times them is exact for
# |m| < 2²⁰ (fdlibm's π/2 parts pio2_1, pio2_2, pio2_3, times 4); the third leaves 3.4e-31
_TWO_PI_1, _TWO_PI_2, _TWO_PI_3 = 6.2831853069365025, 2.4308402025215864e-10, 8.089064994844666e-21
#: Up to this |y| `reduced_angle` reduces (|m| < 2²⁰); beyond, y − carry as it is.
REDUCE_MAX = 6.5e6


@njit(cache=True, error_model="numpy", inline="always")
def reduced_angle(y, carry):
    """y − carry − 2πm with m the nearest integer to y/2π, rounded once (|result| ≤ π + 1 ulp).

    y − m·2π₁ is exact (both factors short, and Sterbenz's lemma: the two
    are within a factor 2 when m ≠ 0); the second part is subtracted with
    its rounding error kept (Knuth's TwoSum), then the third part and the
    carry (the Taylor drivers' compensated sum: y stands for y − carry) join
    that small term.  Branch-free apart from the final choice, so that the
    SIMD lanes of the batched Taylor kernels vectorize it as well.
    """
    m = np.floor(y * 0.15915494309189535 + 0.5)
    r = y - m * _TWO_PI_1
    b = m * _TWO_PI_2
    s = r - b
    bb = s - r
    e = (r - (s - bb)) - (b + bb)
    reduced = s + ((e - m * _TWO_PI_3) - carry)
    return reduced if abs(y) < REDUCE_MAX else y - carry
