"""Impulses of simultaneous frictionless impacts with Newton's restitution law.

At an impact the velocities jump and the positions do not.  With M the mass
matrix, G the c × n matrix whose rows are the gradients ∂g_i/∂q of the gaps
of the c closed contacts, and their normal velocities v = G q̇ + ∂g/∂t, the
contacts push with impulses P ≥ 0 along Gᵀ:

    M (q̇⁺ − q̇⁻) = Gᵀ P    so    v⁺ = v⁻ + W P,    W = G M⁻¹ Gᵀ

(W is the Delassus matrix: symmetric, positive definite when the contacts
are independent).  Newton's law for each contact, written so that it also
decides which contacts push (Glocker & Pfeiffer's complementarity form):

    w = v⁺ + e v⁻ ≥ 0,    P ≥ 0,    w_i P_i = 0,

a contact either pushes and leaves with v⁺ = −e v⁻, or does not push and
separates no slower than that.  Substituting v⁺ gives the linear
complementarity problem LCP(W, (1 + e) v⁻): w = W P + (1 + e) v⁻.  For one
contact its solution is P = −(1 + e) v⁻ / W when v⁻ < 0, so v⁺ = −e v⁻.

The problem is solved by Murty's least-index principal pivoting (K. G.
Murty, *Linear Complementarity, Linear and Nonlinear Programming*, 1988,
sec. 4.2): guess which contacts push, solve W_AA P_A = −q_A on them, and flip
the first contact (lowest index) that violates a sign condition.  For a
positive definite W it ends, in exact arithmetic, at the unique solution;
the iterations are bounded (2^c + c) so rounding cannot make it cycle.

The kinetic energy changes by ΔT = ½ Pᵀ (v⁺ + v⁻) for gaps that do not
depend on t (M-weighted algebra from the jump above): with e = 1 that is
½ Pᵀ w = 0 by complementarity, energy is conserved exactly, also for
simultaneous impacts; with e < 1 it is ½ (1 − e) Pᵀ v⁻, a loss as long as the
contacts that push were approaching.

With holonomic constraints (a System's, a tree's loops) M⁻¹ becomes the constrained response
K = M⁻¹ − M⁻¹Aᵀ (A M⁻¹ Aᵀ)⁻¹ A M⁻¹ (A the constraint matrix): the jump is K Gᵀ P, W = G K Gᵀ, and the
constraints' velocities are kept (`lagcomp.kernel_support.constrained_response` derives it; the
``constrained_`` entry points take A).

These are helpers of the emitted ``event_reset`` kernels: numba compiles them
into the kernel that calls them.  They allocate small work arrays: impacts are
rare events, not the inner loop.
"""

import numpy as np
from numba import njit

from lagcomp.kernel_support.constrained_response import response_columns
from lagcomp.kernel_support.linear_solvers import ldlt_solve
from lagcomp.kernel_support.symbol_calls import called_by_symbol

#: Impacts solved: the complementarity problem's solution was found.
IMPACT_SOLVED = 0
#: W_AA of a guessed set of pushing contacts is singular: the contacts are not independent.
IMPACT_DEPENDENT_CONTACTS = -1
#: The pivoting did not settle within its bound (a Delassus matrix that is not positive definite).
IMPACT_NOT_SETTLED = -2
#: M is not positive definite.
IMPACT_SINGULAR_MASS = -3
#: Simultaneous impacts gave a normal impulse to a contact that presses a sliding friction element: the tangential
#: impulse Coulomb's law would add there is not solved (`lagcomp.kernel_support.resting.pressed_contact_event`).
IMPACT_FRICTION_UNSOLVED = -4


@njit(cache=True, error_model="numpy", fastmath=False)
def solve_on_set(W, q, pushing, z):
    """P_A = −W_AA⁻¹ q_A on the contacts flagged in `pushing`, 0 elsewhere, into z; False if W_AA is singular."""
    c = q.shape[0]
    index = np.empty(c, dtype=np.int64)
    m = 0
    for i in range(c):
        if pushing[i]:
            index[m] = i
            m += 1
    block = np.empty((m, m))
    rhs = np.empty(m)
    for a in range(m):
        rhs[a] = -q[index[a]]
        for b in range(m):
            block[a, b] = W[index[a], index[b]]
    solution = np.empty(m)
    if m > 0 and ldlt_solve(block, rhs, solution, 0) != 0:
        return False
    for i in range(c):
        z[i] = 0.0
    for a in range(m):
        z[index[a]] = solution[a]
    return True


@njit(cache=True, error_model="numpy", fastmath=False)
def solve_lcp(W, q, z, w):
    """Solve w = W z + q, z ≥ 0, w ≥ 0, zᵢ wᵢ = 0 for a symmetric positive definite W, shape (c, c).

    Writes z and w; returns `IMPACT_SOLVED` or a negative status.  A sign
    condition counts as violated below −8 ε times the problem's scale, so
    that rounding does not flip a contact back and forth.
    """
    c = q.shape[0]
    scale = 0.0
    for i in range(c):
        scale = max(scale, abs(q[i]))
    w_tolerance = 8.0 * 2.220446049250313e-16 * scale
    pushing = np.zeros(c, dtype=np.bool_)
    for i in range(c):
        pushing[i] = q[i] < 0.0
    for _ in range(2 ** min(c, 30) + c):
        if not solve_on_set(W, q, pushing, z):
            return IMPACT_DEPENDENT_CONTACTS
        z_scale = 0.0
        for i in range(c):
            z_scale = max(z_scale, abs(z[i]))
        z_tolerance = 8.0 * 2.220446049250313e-16 * z_scale
        for i in range(c):
            s = q[i]
            for j in range(c):
                s += W[i, j] * z[j]
            w[i] = 0.0 if pushing[i] else s
        flip = -1
        for i in range(c):
            if (pushing[i] and z[i] < -z_tolerance) or (not pushing[i] and w[i] < -w_tolerance):
                flip = i
                break
        if flip < 0:
            for i in range(c):
                z[i] = max(z[i], 0.0)
            return IMPACT_SOLVED
        pushing[flip] = not pushing[flip]
    return IMPACT_NOT_SETTLED


@njit(cache=True, error_model="numpy", fastmath=False)
def impact_velocities(M, G, v_minus, restitution, qd, impulses):
    """`constrained_impact_velocities` without constraints: K = M⁻¹."""
    return constrained_impact_velocities(M, np.empty((0, M.shape[0])), G, v_minus, restitution, qd, impulses)


@njit(cache=True, error_model="numpy", fastmath=False)
def constrained_impact_velocities(M, A, G, v_minus, restitution, qd, impulses):
    """Apply the impacts of the closed contacts to the velocities ``qd`` (n) in place; impulses into ``impulses``.

    M (n, n): the mass matrix (lower triangle read, not modified).  G (c, n):
    the closed contacts' gap gradients ∂g/∂q.  v_minus (c): their normal
    velocities before the impact, G q̇⁻ + ∂g/∂t (negative: approaching).
    restitution (c): Newton's coefficients e in [0, 1].  Impulses are in the
    units of the gaps' conjugate forces times time (N s for a gap in metres),
    ≥ 0, zero for a contact that does not push.  A (k, n): the constraint matrix
    Λ of a constrained system (k = 0 without): the jump is K Gᵀ P, W = G K Gᵀ
    (`lagcomp.kernel_support.constrained_response`), which keeps Λ q̇ + b.
    Returns `IMPACT_SOLVED` or a negative status (the velocities are then
    unchanged).
    """
    n = M.shape[0]
    c = G.shape[0]
    factor = np.empty((n, n))
    for i in range(n):
        for j in range(i + 1):
            factor[i, j] = M[i, j]
    minv_gt = np.empty((n, c))                  # M⁻¹ Gᵀ (K Gᵀ), column per contact
    for i in range(n):
        for a in range(c):
            minv_gt[i, a] = G[a, i]
    if response_columns(factor, A, minv_gt) != 0:
        return IMPACT_SINGULAR_MASS
    delassus = np.empty((c, c))
    for a in range(c):
        for b in range(c):
            s = 0.0
            for i in range(n):
                s += G[a, i] * minv_gt[i, b]
            delassus[a, b] = s
    for a in range(c):
        if not delassus[a, a] > 0.0:             # a gap that does not depend on q (or NaN)
            return IMPACT_DEPENDENT_CONTACTS
    q = np.empty(c)
    for a in range(c):
        q[a] = (1.0 + restitution[a]) * v_minus[a]
    w = np.empty(c)
    status = solve_lcp(delassus, q, impulses, w)
    if status != IMPACT_SOLVED:
        return status
    for i in range(n):
        s = 0.0
        for a in range(c):
            s += minv_gt[i, a] * impulses[a]
        qd[i] += s
    return IMPACT_SOLVED


#: A contact other than the one whose event fired takes part in an impact when its gap is at most this times
#: Σ_j |∂g/∂q_j| (|q_j| + 1): touching to rounding, on a scale of the coordinates or of 1 unit, whichever is
#: larger (balls at rest in a row; an angle near 0).
CLOSED_GAP = 1e-12


@njit(cache=True, error_model="numpy", fastmath=False)
def touching(gap, gradients, row, q):
    """Whether a contact of gap `gap` and gradient ``gradients[row]`` (∂g/∂q) counts as touching at q:
    g ≤ `CLOSED_GAP` Σ_j |∂g/∂q_j| (|q_j| + 1), the one test of the impact solver, the resting contacts and the
    impulses read from a jump (`lagcomp.integrate.contacts.touching` is the same sum as a matrix product)."""
    scale = 0.0
    for j in range(q.shape[0]):
        scale += abs(gradients[row, j]) * (abs(q[j]) + 1.0)
    return gap <= CLOSED_GAP * scale


@njit(cache=True, error_model="numpy", fastmath=False)
def _contact_impacts(mass, gaps, gradients, normal_velocities, restitution, q, firing, qd):
    """`_constrained_contact_impacts` without constraints."""
    return _constrained_contact_impacts(mass, np.empty((0, q.shape[0])), gaps, gradients, normal_velocities,
                                        restitution, q, firing, qd)


@njit(cache=True, error_model="numpy", fastmath=False)
def _constrained_contact_impacts(mass, constraint, gaps, gradients, normal_velocities, restitution, q, firing, qd):
    """The impact of contact ``firing`` (its gap just closed) and of every other contact closed with it.

    mass (n, n) M, lower triangle; gaps, normal_velocities, restitution (C,) and gradients (C, n) of all C
    contacts (`lagcomp.codegen.contacts`); q (n) the coordinates; qd (n) the velocities before the impact,
    overwritten with those after; constraint (k, n) the constraint matrix Λ of a constrained system (k = 0
    without; the velocities before satisfy its constraints, and those after too).  Returns `IMPACT_SOLVED` or a
    negative status of `constrained_impact_velocities`.
    """
    n = q.shape[0]
    taking = np.zeros(gaps.shape[0], dtype=np.bool_)
    for d in range(gaps.shape[0]):
        taking[d] = d == firing or touching(gaps[d], gradients, d, q)
    c = 0
    for d in range(gaps.shape[0]):
        if taking[d]:
            c += 1
    G = np.empty((c, n))
    v_minus = np.empty(c)
    e = np.empty(c)
    row = 0
    for d in range(gaps.shape[0]):
        if taking[d]:
            for j in range(n):
                G[row, j] = gradients[d, j]
            v_minus[row] = normal_velocities[d]
            e[row] = restitution[d]
            row += 1
    impulses = np.empty(c)
    return constrained_impact_velocities(mass, constraint, G, v_minus, e, qd, impulses)


@njit(cache=True, error_model="numpy", fastmath=False)
def frictional_impact(mass, gradient, normal_velocity, restitution, slip_gradient, slip_velocity, static, kinetic,
                      qd):
    """`constrained_frictional_impact` without constraints (M⁻¹ in place of K)."""
    return constrained_frictional_impact(mass, np.empty((0, qd.shape[0])), gradient, normal_velocity, restitution,
                                         slip_gradient, slip_velocity, static, kinetic, qd)


@njit(cache=True, error_model="numpy", fastmath=False)
def constrained_frictional_impact(mass, constraint, gradient, normal_velocity, restitution, slip_gradient,
                                  slip_velocity, static, kinetic, qd):
    """The impact of one contact with Coulomb friction along one sliding velocity (a point on a floor).

    Impulses P_n along the gap's gradient G and P_t along the sliding velocity's a = ∂v/∂q̇:
    M (q̇⁺ − q̇⁻) = Gᵀ P_n + aᵀ P_t, so with W = [G; a] M⁻¹ [Gᵀ aᵀ] (2 × 2, symmetric)

        v_n⁺ = v_n⁻ + W_nn P_n + W_nt P_t = −e v_n⁻    (Newton's restitution on the normal),
        v_t⁺ = v_t⁻ + W_tn P_n + W_tt P_t,              |P_t| ≤ μ P_n (Coulomb).

    Stick first: v_t⁺ = 0 with the normal law, a 2 × 2 solve; kept when P_n ≥ 0 and |P_t| ≤ μs P_n.  Else slip:
    P_t = −μk s P_n, s = sign v_t⁻, so P_n = −(1 + e) v_n⁻ / (W_nn − μk s W_nt); if that would reverse v_t
    (s v_t⁺ < 0: the impulse that stops it is less than μk P_n, possible only when W_nt couples the two), the
    stick impulses are taken (v_t⁺ = 0).  For a point mass on a flat floor (W_nt = 0, W_nn = W_tt = 1/m):
    v_t⁺ = v_t⁻ − μk (1 + e) |v_n⁻| sign v_t⁻ when |v_t⁻| > μs (1 + e) |v_n⁻|, else 0.
    No impulse when the contact is not approaching (v_n⁻ ≥ 0).  mass (n, n) lower triangle (not written);
    gradient, slip_gradient (n); qd (n) before, overwritten with after.  Returns `IMPACT_SOLVED`, or
    `IMPACT_SINGULAR_MASS` / `IMPACT_DEPENDENT_CONTACTS` (G and a parallel) with qd unchanged.
    With constraints A q̇ + b = 0 (``constraint`` (k, n): A) M⁻¹ is K, the constrained response
    (`lagcomp.kernel_support.constrained_response`): the impulses keep the constraints' velocities, and W is
    [G; a] K [Gᵀ aᵀ]; without (k = 0) K is M⁻¹ bit for bit.
    """
    n = qd.shape[0]
    if not normal_velocity < 0.0:
        return IMPACT_SOLVED
    columns = np.empty((n, 2))                  # M⁻¹ Gᵀ, M⁻¹ aᵀ
    for j in range(n):
        columns[j, 0] = gradient[j]
        columns[j, 1] = slip_gradient[j]
    if response_columns(mass.copy(), constraint, columns) != 0:
        return IMPACT_SINGULAR_MASS
    w_nn = w_nt = w_tn = w_tt = 0.0
    for j in range(n):
        w_nn += gradient[j] * columns[j, 0]
        w_nt += gradient[j] * columns[j, 1]
        w_tn += slip_gradient[j] * columns[j, 0]
        w_tt += slip_gradient[j] * columns[j, 1]
    determinant = w_nn * w_tt - w_nt * w_tn
    if not determinant > 1e-12 * w_nn * w_tt:
        return IMPACT_DEPENDENT_CONTACTS
    normal_rhs = -(1.0 + restitution) * normal_velocity
    p_n = (normal_rhs * w_tt + slip_velocity * w_nt) / determinant            # stick: v_t⁺ = 0
    p_t = (-slip_velocity * w_nn - normal_rhs * w_tn) / determinant
    if p_n < 0.0 or abs(p_t) > static * p_n:
        s = 1.0 if slip_velocity > 0.0 else -1.0 if slip_velocity < 0.0 else (-1.0 if p_t > 0.0 else 1.0)
        slip_n = normal_rhs / (w_nn - kinetic * s * w_nt)
        slip_t = -kinetic * s * slip_n
        if slip_n >= 0.0 and s * (slip_velocity + w_tn * slip_n + w_tt * slip_t) >= 0.0:
            p_n, p_t = slip_n, slip_t
    for j in range(n):
        qd[j] += columns[j, 0] * p_n + columns[j, 1] * p_t
    return IMPACT_SOLVED


#: What the generated kernels call: `_contact_impacts` by symbol, optimised once
#: (`lagcomp.kernel_support.symbol_calls`).
contact_impacts = called_by_symbol(_contact_impacts)
constrained_contact_impacts = called_by_symbol(_constrained_contact_impacts)
