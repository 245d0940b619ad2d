r"""The ``power`` kernel: the rate of change of the energy function h, term by term (the energy balance).

With L(q, q̇, t) = T − V, the energy function (Jacobi integral) h = q̇·∂L/∂q̇ − L and Lagrange's
equations d/dt ∂L/∂q̇ = ∂L/∂q + Q − ∂D/∂q̇ + Λᵀλ (Q the generalized forces of `System.forces`, inputs
among them, D the Rayleigh function, λ the multipliers of the constraints Λ q̇ + b = 0),

    dh/dt = q̈·∂L/∂q̇ + q̇·d/dt ∂L/∂q̇ − ∂L/∂q·q̇ − ∂L/∂q̇·q̈ − ∂L/∂t
          = Q·q̇ − q̇·∂D/∂q̇ + λ·(Λ q̇) − ∂L/∂t
          = Q·q̇ − 2D − λ·b − ∂L/∂t,

since D = ½ q̇ᵀ C q̇ is a quadratic form (`lagcomp.mechanics.lagrange` refuses any other), so that
q̇·∂D/∂q̇ = 2D, and on the constraints Λ q̇ = −b.  ∂L/∂t is the partial derivative at fixed (q, q̇): the
explicit time of imposed motions, and through an input u(t) in L, u̇ ∂L/∂u + ü ∂L/∂u̇ (the chain rule).
h is the balanced quantity; it is T + V when T is homogeneous quadratic in q̇ (no moving frame, no
imposed motion in T), and otherwise it is not the energy: a rotating hoop's bead conserves h, not T + V.
"""

from __future__ import annotations

import sympy as sp

from lagcomp.codegen.cse import cse_kernel
from lagcomp.codegen.jacobian_blocks import fresh_symbols
from lagcomp.ir import Kernel, ReturnZero
from lagcomp.mechanics.lagrange import EOM, to_plain
from lagcomp.model.system import t

#: The terms of dh/dt the kernel writes, in order (`lagcomp.integrate.energy_balance.EnergyBalance.power`).
TERMS = ("forces", "dissipation", "time", "constraints")


def power_terms(eom: EOM, multipliers) -> list:
    """[Q·q̇, −2D, −∂L/∂t, −λ·b] of `eom` (module docstring), `multipliers` the symbols standing for λ."""
    system = eom.system
    forces = [to_plain(Q, system, eom.q, eom.qd) for Q in system.forces]
    rayleigh = to_plain(system.dissipation, system, eom.q, eom.qd)
    return [
        sp.Add(*(Q * v for Q, v in zip(forces, eom.qd, strict=True))),
        -2 * rayleigh,
        -eom.L.diff(t),
        -sp.Add(*(lam * b for lam, b in zip(multipliers, eom.b, strict=True))),
    ]


def multiplier_symbols(eom: EOM) -> tuple:
    """Symbols standing for the k multipliers λ in `power_terms`, named apart from every symbol of `eom`."""
    taken = {s.name for s in (*eom.q, *eom.qd, *eom.parameters, t)}
    taken |= {s.name for e in (eom.L, *eom.b, *eom.system.forces, eom.system.dissipation) for s in e.free_symbols}
    return fresh_symbols("_lam", eom.k, taken)


def power_kernel(eom: EOM, mapping, loads) -> Kernel:
    """``power(t, y, p, lam, out) -> int``: the four terms of dh/dt (`TERMS`) at y = (q, q̇) into `out` (4,),
    λ = `lam` (k,) the multipliers there (`reactions`; an empty array without constraints).  Returns 0."""
    multipliers = multiplier_symbols(eom)
    mapping = {**mapping, **{s: sp.Symbol(f"_lam{c}", real=True) for c, s in enumerate(multipliers)}}
    loads = loads + tuple((f"_lam{c}", f"lam[{c}]") for c in range(eom.k))
    stores = [(f"out[{i}]", term) for i, term in enumerate(power_terms(eom, multipliers))]
    return cse_kernel(
        "power",
        "The rate of change of the energy function h = q̇·∂L/∂q̇ − L, term by term, into `out` (4,):\n"
        "out[0] = Q·q̇ (generalized forces and inputs), out[1] = −2D (Rayleigh dissipation), out[2] = −∂L/∂t\n"
        "(explicit time: imposed motions, inputs in L), out[3] = −λ·b (work of moving constraints, λ = `lam`).\n"
        "dh/dt is their sum along a motion (lagcomp.codegen.power). Returns 0.",
        ("t", "y", "p", "lam", "out"), stores, mapping, loads, solve=ReturnZero(),
    )
