"""Print sympy expressions as numba-friendly Python scalar code.

Symbols print as their names (the IR has already renamed them to locals).
Scalar math goes through the `math` module (numba lowers it to LLVM
intrinsics).  Integer powers keep an int literal exponent (``x**2``), which
numba expands into multiplications at compile time (a float exponent would
call `pow`); square roots become `math.sqrt`, rationals float literals.
"""

from __future__ import annotations

import sympy as sp
from sympy.printing.pycode import PythonCodePrinter


class KernelPrinter(PythonCodePrinter):
    """`PythonCodePrinter` with float literals, int-literal powers and `math.sqrt`."""

    def __init__(self):
        super().__init__({"fully_qualified_modules": True, "standard": "python3", "order": "none"})

    def _print_Symbol(self, expr):
        return expr.name

    def _print_Rational(self, expr):
        return repr(float(expr.p) / float(expr.q))

    def _print_Half(self, expr):
        return "0.5"

    def _print_Integer(self, expr):
        return f"{int(expr)}.0"

    def _print_sign(self, expr):
        return f"np.sign({self._print(expr.args[0])})"

    def _print_Pow(self, expr, rational=False):
        base, exp = expr.args
        b = self.parenthesize(base, sp.printing.precedence.PRECEDENCE["Mul"] + 1)
        if exp.is_Integer:  # an int literal: numba unrolls it into multiplications
            k = int(exp)
            return f"{b}**{k}" if k > 0 else (f"1.0/{b}" if k == -1 else f"1.0/{b}**{-k}")
        if exp == sp.S.Half:
            return f"math.sqrt({self._print(base)})"
        if exp == -sp.S.Half:
            return f"1.0/math.sqrt({self._print(base)})"
        return f"{b}**{self._print(exp)}"


class LanePrinter(KernelPrinter):
    """`KernelPrinter` for code that runs across SIMD lanes: sin and cos call the template's
    polynomial ``_vsin``/``_vcos`` (``templates/lanes.py``), which LLVM can vectorize, where
    ``math.sin`` is an opaque libm call that keeps the loop scalar."""

    def _print_sin(self, expr):
        return f"_vsin({self._print(expr.args[0])})"

    def _print_cos(self, expr):
        return f"_vcos({self._print(expr.args[0])})"


#: One printer of each kind, reused: building a printer costs more than printing a small expression.
_PRINTERS = {False: KernelPrinter(), True: LanePrinter()}


def to_code(expr: sp.Expr, lanes: bool = False) -> str:
    """The Python source of a scalar expression (`lanes`: for a loop over SIMD lanes)."""
    return _PRINTERS[lanes].doprint(expr)
