"""Print sympy expressions as numba-friendly Python scalar code.

Symbols print as their names (the IR has already renamed them to locals).
Scalar math goes through the `math` module (numba lowers it to LLVM
intrinsics), except sin and cos, which call `sin` and `cos` of
`lagcomp.kernel_support.trig` (polynomials, faster than libm's calls), which
the generated module imports.
Integer powers keep an int literal exponent (``x**2``), which numba expands
into multiplications at compile time (a float exponent would call `pow`,
20-40 ns); half-integer powers become a square root times an integer power
(``r**(-3/2)`` is ``1.0/(r*math.sqrt(r))``: through pow, Kepler's RK4 ran at
a third of a hand-written loop); rationals print as float literals.
"""

from __future__ import annotations

import sympy as sp
from sympy.printing.pycode import PythonCodePrinter


class KernelPrinter(PythonCodePrinter):
    """`PythonCodePrinter` with float literals, int-literal powers, `math.sqrt`, kernel_support's sin/cos."""

    sin_name, cos_name = "sin", "cos"

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

    def _print_sin(self, expr):
        return f"{self.sin_name}({self._print(expr.args[0])})"

    def _print_cos(self, expr):
        return f"{self.cos_name}({self._print(expr.args[0])})"

    def _print_sign(self, expr):
        return f"np.sign({self._print(expr.args[0])})"

    def _print_Pow(self, expr, rational=False):
        base, exp = expr.args
        b = self.parenthesize(base, sp.printing.precedence.PRECEDENCE["Mul"] + 1)
        if exp.is_Integer:  # an int literal: numba unrolls it into multiplications
            k = int(exp)
            return f"{b}**{k}" if k > 0 else (f"1.0/{b}" if k == -1 else f"1.0/{b}**{-k}")
        if exp.is_Rational and exp.q == 2:  # b**(k/2) = b**((|k|-1)/2) * sqrt(b): no call to pow
            root = f"math.sqrt({self._print(base)})"
            m = (abs(int(exp.p)) - 1) // 2
            if m == 0:
                return root if exp > 0 else f"1.0/{root}"
            magnitude = f"({b}{'' if m == 1 else f'**{m}'}*{root})"  # parenthesized: a Mul prints it as a divisor
            return magnitude if exp > 0 else f"1.0/{magnitude}"
        return f"{b}**{self._print(exp)}"


class LanePrinter(KernelPrinter):
    """`KernelPrinter` for code that runs across SIMD lanes: sin and cos call ``vsin``/``vcos``
    (`lagcomp.kernel_support.trig`), the polynomials without ``sin``'s branch to libm, so that LLVM
    can vectorize the loop (a call keeps it scalar)."""

    sin_name, cos_name = "vsin", "vcos"


#: One printer of each kind, reused: building a printer costs more than printing a small expression.
_PRINTERS = {False: KernelPrinter(), True: LanePrinter()}


def to_code(expr: sp.Expr, lanes: bool = False) -> str:
    """The Python source of a scalar expression (`lanes`: for a loop over SIMD lanes)."""
    return _PRINTERS[lanes].doprint(expr)
