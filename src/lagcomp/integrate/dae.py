"""Constrained systems as index-2 DAEs: the state `radau` integrates instead of projecting.

A constrained Lagrange model, M(q, t) q̈ = F(q, q̇, t) + Λᵀ λ with the velocity constraints
Λ q̇ + b = 0 (all k rows) and the position constraints Φ(q, t) = 0 (the kh holonomic rows Λ_h),
is solved in the stabilised index-2 form of Gear, Gupta and Leimkuhler, with a constant mass matrix:

    z = (q, v, w, λ, μ),  sizes n, n, n, k, kh
    q' = v + Λ_hᵀ μ,   v' = w,   0 = M w − F − Λᵀ λ,   0 = Λ v + b,   0 = Φ

(the generated ``dae_residual`` and ``dae_jacobian`` kernels: the right-hand sides and their exact
Jacobian).  Along a solution μ = 0, w = q̈ and λ are the reactions: the constraints are equations
the integrator solves at every stage, so they hold to the Newton iteration's accuracy without
projection or Baumgarte terms.  q and v are differential components (the first ``2n``), w, λ, μ
algebraic of index 2 (`lagcomp.integrate.drivers.radau` explains how that changes its error
control); Radau IIA converges with order 5 in q and v and order 3 in λ on such systems
(Hairer, Lubich & Roche 1989; Hairer & Wanner II, sec. VII.4).

The rest of lagcomp sees (q, q̇) = (q, v): outputs, events and energies read the first ``2n``
components, reactions are computed from the saved (q, q̇) as for every method.
"""

from __future__ import annotations

import numpy as np

from lagcomp.errors import InitialConditionError, OptionError

#: The tightest rtol `radau` takes for a DAE.  Below it the rounding noise of the constraints (Φ and Λ(q)
#: evaluated at a q known to ulp(|q|)) stops the Newton iteration short of its tolerance: on the four-bar
#: linkage over 10 s, rtol 1e-11 gains less than a factor 2 on 1e-10 (errors 4.9e-10 and 8.6e-10 against dop853
#: at 1e-13 with projection), and 1e-12 fails at t = 6.3 s (`lagcomp.integrate.drivers.radau`, "DAEs").
DAE_RTOL_MIN = 1e-10


def differential_size(model) -> int:
    """Components of the DAE state that are differential, (q, v): the first 2n."""
    return 2 * model.n


def dae_state(model, t0: float, y0: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, int]:
    """The consistent DAE state z0 = (q0, v0, q̈0, λ0, 0) at (t0, y0), y0 = (q0, q̇0) on the constraints,
    and the status of the augmented solve (0, or the pivot j > 0 where [M Λᵀ; Λ 0] is singular: z0 invalid).

    q̈0 and λ0 come from the augmented solve (`rhs`, `reactions`) with the Baumgarte gains (the last two
    entries of `p`) set to 0: on the constraints they change nothing, and the DAE has none.
    """
    n, k = model.n, model.k
    kh = sum(model.holonomic)
    plain = p.copy()
    plain[-2:] = 0.0
    z = np.zeros(3 * n + k + kh)
    z[:2 * n] = y0
    derivative = np.empty(2 * n)
    status = model.kernels.rhs(t0, y0, plain, derivative) or model.kernels.reactions(t0, y0, plain, z[3 * n:3 * n + k])
    z[2 * n:3 * n] = derivative[n:]
    return z, status


def refuse_stabilisation(method: str, model, baumgarte) -> None:
    """Refuse Baumgarte gains for a run that solves `model` as a DAE: its constraints need none."""
    if any(baumgarte):
        raise OptionError(f"`{method}` solves {model.name!r} as a DAE whose constraints hold without stabilisation; "
                          "leave `baumgarte` unset.")


def dae_states(model, t0: float, Y0: np.ndarray, P: np.ndarray, where) -> np.ndarray:
    """`dae_state` of every row of Y0 (with the parameters P's row), shape (rows, 3n + k + kh); `where(i)` names
    row i in the `InitialConditionError` raised when the augmented matrix is singular there."""
    rows = [dae_state(model, t0, y, p) for y, p in zip(Y0, P, strict=True)]
    for i, (_, singular) in enumerate(rows):
        if singular:
            raise InitialConditionError(f"{where(i)}: the augmented matrix [M Λᵀ; Λ 0] of {model.name!r} is singular "
                                        "at the initial state (dependent constraints there, or a zero inertia).")
    return np.array([z for z, _ in rows])
