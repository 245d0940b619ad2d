"""Closed contacts: resting contact as an active constraint, lift-off, and impacts that close a contact (Zeno).

A contact (`lagcomp.model.contacts.Contact`) is open or closed, its mode kept in p (`lagcomp.ir.ContactModes`).
While closed its gap g(q, t) is held at its value by a holonomic constraint: with G the closed contacts' gap
gradients ∂g/∂q (c × n) and b = Σ_j ∂ġ/∂q_j q̇_j + ∂ġ/∂t (so that g̈ = G q̈ + b),

    M q̈ = F + Gᵀ λ,    G q̈ + b = 0    so    W λ = −(G q̈_free + b),    W = G M⁻¹ Gᵀ,    q̈ = q̈_free + M⁻¹ Gᵀ λ,

q̈_free = M⁻¹ F the motion without the contacts (the module's ``rhs_free``).  λ ≥ 0 pushes the gap open: it is
the normal force (in the units of the force conjugate to g: N for a gap in metres).  The contact lifts off when
λ would turn negative: the event of a closed contact is λ (direction −1), and its reset only opens the contact.

An impact under a pressing free normal acceleration a = G q̈_free + b < 0 (gravity on a bouncing ball) leaves the
contact with normal velocity v⁺ = −e v⁻; the bounces that follow, all under that acceleration, last
2 v⁺ / (|a| (1 − e)) in all (a geometric series) and end at rest.  When that is shorter than `ZENO_TIME` |t|,
or the next bounce 2 v⁺/|a| shorter than `BOUNCE_TIME` |t| (e near 1), or its height v⁺²/(2|a|) less than
`BOUNCE_HEIGHT` roundings of the gap, ε Σ_j |∂g/∂q_j| |q_j| (`bounces_unresolved`), the impact is made plastic
(e = 0: v⁺ = 0) and the contact closes: the error in the time the ball comes to rest is the remaining time.
A plastic impact (e = 0) that leaves the contact at rest closes it too, whatever a was before it.  Either closing
stands only if the closed contacts' forces all push at the state after the impact (the emitted branch computes
them there and does the impact again without closing otherwise): a before the impact depends on q̇, through b (a
curved gap's centripetal term) or a constrained q̈_free, so a fast plastic impact on a curved gap, a < 0 only once
it has stopped, closes on that check and not on a.

Why those scales: the drivers resolve a bounce down to about 2048 × 2 ε |t| ≈ 1e-12 |t| in time (an impact
located to 2 ε |t| leaves the gap a rounding below 0, and the bounce after it must reach above 0 by the first
sample of the step after the reset, 1/2048 of the step before it), and down to a height of a few roundings of
the gap (a ball on a floor at H, gap x − H: ε H; a bounce below that is not seen); below either a run ends with
EVENTS_ACCUMULATED.  With the time criteria every bounce a run resolves is ≥ 1e-11 |t| (a ball sliding into a
wall, e = 0.5, stalled at 1e-12); with the height one every bounce rises ≥ 64 ε H: without it a ball dropped
1 m on floors at H = 1, 10, 1000 stopped with EVENTS_ACCUMULATED after 28, 27, 23 impacts, 1e-7 s before t∞
(tests/test_units_invariance.py).  Each criterion compares quantities of one unit (times, gap lengths), so the
rule is the same in any units; the time of rest is then off by at most the bounces left out, 1/(1 − e) times
the largest of BOUNCE_TIME |t|, 2 √(2 BOUNCE_HEIGHT ε H/|a|) (1.1e-7 s for H = 1 m under g) and
ZENO_TIME |t| (1 − e).

Within a step the contact never pulls: the ``rhs`` stages hold λ ≥ 0 (`closed_contact_accelerations` with
``unilateral``), so a stage past a lift-off sees the body free, and a step that jumps over a lift-off and a
touch-down (a body at rest, whose steps grow tenfold each, pulled past its weight for a while) is rejected by
its own error estimate instead of holding the body down.

Drift: while a contact is closed, g̈ = 0 holds to rounding, and ġ starts at 0 (within the impact's rounding,
or checked at the start of a run), so g keeps its closing value up to the integration error of the step
controller: a particle held on the inside of a ring by its speed, 100 turns with dop853, drifts off it by
1.1e-11, 1.3e-9, 2.4e-7, 4.2e-5 at rtol = atol = 1e-12, 1e-10, 1e-8, 1e-6, half the relative error of its
speed² at each; a ball at rest keeps g = 0 exactly (q̈ = 0 to the last bit).  So no stabilisation terms are
added: they would trade that drift, of the size of the run's own error, for a stiffer rhs and the exact rest,
as lagcomp's bilateral constraints do by default (``baumgarte=(0, 0)``).

These are helpers of the emitted kernels (``closed_contacts``, ``event_reset``), which call the public entry points
(end of this module) by symbol (`lagcomp.kernel_support.symbol_calls`): numba optimises each once, not in every
kernel.  They allocate small work arrays, only while some contact is closed or at an event.
"""

import numpy as np
from numba import njit

from lagcomp.kernel_support.constrained_response import response_columns
from lagcomp.kernel_support.impacts import (
    CLOSED_GAP,
    IMPACT_FRICTION_UNSOLVED,
    IMPACT_SOLVED,
    _constrained_contact_impacts,
    constrained_frictional_impact,
    solve_on_set,
    touching,
)
from lagcomp.kernel_support.linear_solvers import ldlt_solve_matrix, lu_solve
from lagcomp.kernel_support.symbol_calls import called_by_symbol

#: The closed contacts' constraints are dependent (W singular): ``rhs`` returns this positive status, as for a
#: singular mass matrix (the drivers stop with RHS_FAILED).
DEPENDENT_CLOSED_CONTACTS = 1_000_000

#: An impact under pressing closes its contact when the bounces it would start last less than this times |t| in
#: all: the time of rest is off by less than that (5.7e-10 for a ball at rest from t∞ = 5.7 s).
ZENO_TIME = 1e-10
#: ... or when the next bounce would last less than this times |t|: ten times the drivers' resolution of a bounce in
#: time (module docstring), for e near 1, whose bounces shrink slowly (the time of rest then off by up to
#: BOUNCE_TIME |t|/(1 − e)).
BOUNCE_TIME = 1e-11
#: ... or when the next bounce would rise less than this many roundings of the gap, ε Σ_j |∂g/∂q_j| |q_j| (a floor at
#: height H: ε H), above it: the gap cannot see it (module docstring).
BOUNCE_HEIGHT = 64.0
EPS = 2.220446049250313e-16


@njit(cache=True, error_model="numpy", fastmath=False)
def _closed_contact_accelerations(mass, gradients, bias, modes, qdd, forces, unilateral):
    """Correct the free accelerations ``qdd`` (n) in place for the contacts closed in ``modes`` (C,); their normal
    forces λ into ``forces`` (C,), 0 for the open ones.

    mass (n, n): M, lower triangle (overwritten); gradients (C, n): ∂g/∂q of every contact; bias (C): b, so that
    g̈ = G q̈ + b.  With ``unilateral`` 1 a closed contact whose λ would pull (λ < 0) pushes with 0 instead, as an
    open one (the most negative first, then the others' forces again, until none pulls): the complementarity
    λ ≥ 0, g̈ ≥ 0, λ g̈ = 0 of a unilateral contact.  That is what ``rhs`` uses, so that a step's stages see the
    lift-off its ends may not show (a body at rest, whose pull passes its weight and falls back within one step,
    leaves the step's error estimate large: the step is rejected, shorter ones find λ's zero); with 0 the
    multipliers of the constraints as they are, of either sign (``contact_forces``: the lift-off events).
    Returns 0; 1 (the status of a singular first pivot) when M is not positive definite, or
    `DEPENDENT_CLOSED_CONTACTS` when the closed contacts' W is singular: ``rhs`` returns it, the drivers stop.
    """
    count = modes.shape[0]
    active = np.empty(count, dtype=np.bool_)
    for d in range(count):
        active[d] = modes[d] != 0.0
    return held_row_accelerations(mass, gradients, bias, active, count, qdd, forces, unilateral)


@njit(cache=True, error_model="numpy", fastmath=False)
def _constrained_closed_contact_accelerations(mass, constraint, gradients, bias, modes, qdd, forces, unilateral):
    """`closed_contact_accelerations` for a system with constraints Λ q̇ + b = 0 (``constraint`` (k, n): Λ).

    ``qdd`` (n) on entry is the constrained motion without contacts (the module's ``rhs_free``: it satisfies
    Λ q̈ = γ, Baumgarte terms included).  The constraints are k more rows held two-sided after the contacts',
    with bias −Λ q̈_free, so that the correction keeps Λ q̈ as it is:

        M q̈ = M q̈_free + Gᵀ λ + Λᵀ Δμ,    [G; Λ] q̈ + [b; −Λ q̈_free] = 0 on the held rows,

    the block system of `lagcomp.kernel_support.constrained_response` at the level of accelerations (its Schur
    complement on the contacts' rows is W = G K Gᵀ).  ``forces`` (C + k): the contacts' normal forces, then
    Δμ, the change of the constraints' multipliers (the generalized forces along the rows of Λ, `reactions`'
    convention M q̈ = F + Λᵀ μ) that the closed contacts cause.  Returns as `closed_contact_accelerations`.
    """
    count = modes.shape[0]
    held = np.empty(count, dtype=np.bool_)
    for d in range(count):
        held[d] = modes[d] != 0.0
    return held_with_constraints(mass, constraint, gradients, bias, held, count, qdd, forces, unilateral)


@njit(cache=True, error_model="numpy", fastmath=False)
def _constrained_frictional_accelerations(mass, constraint, gradients, bias, modes, frictions, qdd, forces,
                                          unilateral):
    """`frictional_accelerations` for a system with constraints (``constraint`` (k, n): Λ): the sticking elements'
    rows after the closed contacts', the constraints' after theirs (`constrained_closed_contact_accelerations`);
    ``forces`` (C + F + k)."""
    held = _held_rows(modes, frictions)
    return held_with_constraints(mass, constraint, gradients, bias, held, modes.shape[0], qdd, forces, unilateral)


@njit(cache=True, error_model="numpy", fastmath=False)
def held_with_constraints(mass, constraint, gradients, bias, held, one_sided, qdd, forces, unilateral):
    """`held_row_accelerations` on the rows R of ``gradients`` (R, n) that are ``held``, then the k rows of
    ``constraint`` (k, n), always held, with bias −Λ q̈_free (``qdd`` on entry): the correction keeps Λ q̈.
    ``forces`` (R + k): the rows' multipliers, then the constraints' Δμ."""
    return coupled_with_constraints(mass, constraint, gradients, gradients, bias, held, one_sided, qdd, forces,
                                    unilateral, True)


@njit(cache=True, error_model="numpy", fastmath=False)
def coupled_with_constraints(mass, constraint, gradients, columns, bias, held, one_sided, qdd, forces, unilateral,
                             symmetric):
    """`held_with_constraints` with the forces' directions ``columns`` (R, n) apart from the rows ``gradients``
    (`coupled_row_accelerations`); the constraints' rows are their own columns."""
    count, k, n = held.shape[0], constraint.shape[0], qdd.shape[0]
    rows = np.empty((count + k, n))
    stacked_columns = np.empty((count + k, n))
    stacked_bias = np.empty(count + k)
    active = np.empty(count + k, dtype=np.bool_)
    for d in range(count):
        active[d] = held[d]
        stacked_bias[d] = bias[d]
        for j in range(n):
            rows[d, j] = gradients[d, j]
            stacked_columns[d, j] = columns[d, j]
    for r in range(k):
        active[count + r] = True
        s = 0.0
        for j in range(n):
            rows[count + r, j] = constraint[r, j]
            stacked_columns[count + r, j] = constraint[r, j]
            s -= constraint[r, j] * qdd[j]
        stacked_bias[count + r] = s
    return coupled_row_accelerations(mass, rows, stacked_columns, stacked_bias, active, one_sided, qdd, forces,
                                     unilateral, symmetric)


@njit(cache=True, error_model="numpy", fastmath=False)
def _frictional_accelerations(mass, gradients, bias, modes, frictions, qdd, forces, unilateral):
    """`closed_contact_accelerations` with friction elements (`lagcomp.model.friction.Friction`): rows C.. of
    ``gradients`` (C + F, n) and ``bias`` (C + F) are the elements' a = ∂v/∂q̇ and b (v̇ = a q̈ + b), held
    (two-sided) while the element sticks (its mode in ``frictions`` (F,) is 0); their multipliers, the friction
    forces along v, go into ``forces`` (C + F) after the contacts' normal forces (0 while slipping)."""
    active = _held_rows(modes, frictions)
    return held_row_accelerations(mass, gradients, bias, active, modes.shape[0], qdd, forces, unilateral)


@njit(cache=True, error_model="numpy", fastmath=False)
def _held_rows(modes, frictions):
    """Which rows are held: each contact's while closed (its mode in ``modes`` (C,) not 0), then each friction
    element's while it sticks (its mode in ``frictions`` (F,) 0); shape (C + F,)."""
    count, elements = modes.shape[0], frictions.shape[0]
    held = np.empty(count + elements, dtype=np.bool_)
    for d in range(count):
        held[d] = modes[d] != 0.0
    for f in range(elements):
        held[count + f] = frictions[f] == 0.0
    return held


@njit(cache=True, error_model="numpy", fastmath=False)
def _pressed_frictional_accelerations(mass, gradients, bias, modes, frictions, pressing, kinetic, qdd, forces,
                                     unilateral):
    """`frictional_accelerations` where some friction elements are pressed by a contact's normal force
    (``pressing`` (F,): the contact's index, −1 for an element whose N is an expression; ``kinetic`` (F,): μk).

    Such an element acts only while its contact is closed (an open contact presses with 0: the element is held
    neither way).  Slipping (mode s = ±1), its force −μk s λ_c along v is the generalized force
    −μk s λ_c aᵀ (a = ∂v/∂q̇): linear in the contact's multiplier, it joins that contact's column,

        M q̈ = F + Σ_c (G_cᵀ − Σ_f μk_f s_f a_fᵀ) λ_c + Σ_stick a_fᵀ λ_f,

    so W = G_A M⁻¹ C_Aᵀ with columns C ≠ rows G: not symmetric (`held_row_accelerations` then solves by LU).
    Sticking, its row a q̈ + b = 0 is held beside the contact's, its multiplier λ_f the friction force (the
    limit μs λ_c is the event's business, ``friction_limits``).  Without a slipping pressed element on a closed
    contact the columns are the rows and the solve that of `frictional_accelerations`."""
    count, elements = modes.shape[0], frictions.shape[0]
    active = np.empty(count + elements, dtype=np.bool_)
    columns = gradients.copy()
    coupled = _pressed_columns(gradients, modes, frictions, pressing, kinetic, active, columns)
    return coupled_row_accelerations(mass, gradients, columns, bias, active, count, qdd, forces, unilateral,
                                     not coupled)


@njit(cache=True, error_model="numpy", fastmath=False)
def _constrained_pressed_frictional_accelerations(mass, constraint, gradients, bias, modes, frictions, pressing,
                                                  kinetic, qdd, forces, unilateral):
    """`pressed_frictional_accelerations` for a system with constraints (``constraint`` (k, n): Λ): the
    constraints' rows held after the contacts' and the elements' (`coupled_with_constraints`, as
    `constrained_closed_contact_accelerations`); ``forces`` (C + F + k), the constraints' Δμ last."""
    count, elements = modes.shape[0], frictions.shape[0]
    active = np.empty(count + elements, dtype=np.bool_)
    columns = gradients.copy()
    coupled = _pressed_columns(gradients, modes, frictions, pressing, kinetic, active, columns)
    return coupled_with_constraints(mass, constraint, gradients, columns, bias, active, count, qdd, forces,
                                    unilateral, not coupled)


@njit(cache=True, error_model="numpy", fastmath=False)
def _pressed_columns(gradients, modes, frictions, pressing, kinetic, active, columns):
    """Into ``active`` (C + F,) the held rows of `pressed_frictional_accelerations` (a closed contact's; a sticking
    element's whose contact is closed or whose N is an expression), and into ``columns`` (a copy of ``gradients``
    on entry) each closed contact's column with its slipping elements' −μk s a_f; True when some column moved."""
    count = modes.shape[0]
    for d in range(count):
        active[d] = modes[d] != 0.0
    coupled = False
    for f in range(frictions.shape[0]):
        d = pressing[f]
        active[count + f] = frictions[f] == 0.0 and (d < 0 or modes[d] != 0.0)
        if d >= 0 and modes[d] != 0.0 and frictions[f] != 0.0:
            coupled = True
            for j in range(columns.shape[1]):
                columns[d, j] -= kinetic[f] * frictions[f] * gradients[count + f, j]
    return coupled


@njit(cache=True, error_model="numpy", fastmath=False)
def held_row_accelerations(mass, gradients, bias, held, one_sided, qdd, forces, unilateral):
    """Correct ``qdd`` (n) in place for the rows r of G q̈ + b = 0 that are ``held`` (R,): M q̈ = M q̈_free + Gᵀ λ,
    W λ = −(G q̈_free + b) on the held rows, λ into ``forces`` (R,), 0 for the others.  The first `one_sided`
    rows are contacts: with ``unilateral`` 1 one whose λ would pull is dropped (`closed_contact_accelerations`);
    the rows after them (sticking friction) hold with a λ of either sign.  Returns 0, 1 (M not positive definite)
    or `DEPENDENT_CLOSED_CONTACTS`."""
    return coupled_row_accelerations(mass, gradients, gradients, bias, held, one_sided, qdd, forces, unilateral,
                                     True)


@njit(cache=True, error_model="numpy", fastmath=False)
def coupled_row_accelerations(mass, gradients, columns, bias, held, one_sided, qdd, forces, unilateral, symmetric):
    """`held_row_accelerations` with the forces' directions ``columns`` (R, n) apart from the rows ``gradients``:
    M q̈ = M q̈_free + Cᵀ λ, W = G_A M⁻¹ C_Aᵀ (slip coupled to a normal force,
    `pressed_frictional_accelerations`); ``symmetric`` (C is G) solves W by LDLᵀ, else by LU."""
    n = qdd.shape[0]
    rows = held.shape[0]
    c = 0
    for d in range(rows):
        forces[d] = 0.0
        if held[d]:
            c += 1
    if c == 0:
        return 0
    index = np.empty(c, dtype=np.int64)
    minv_gt = np.empty((n, c))                  # M⁻¹ G_Aᵀ, column per held row
    a = 0
    for d in range(rows):
        if held[d]:
            index[a] = d
            for i in range(n):
                minv_gt[i, a] = columns[d, i]
            a += 1
    if ldlt_solve_matrix(mass, minv_gt) != 0:
        return 1
    delassus = np.empty((c, c))
    free = np.empty(c)                          # the rows' G q̈_free + b, without their forces
    for a in range(c):
        s = bias[index[a]]
        for i in range(n):
            s += gradients[index[a], i] * qdd[i]
        free[a] = s
        for b in range(c):
            s = 0.0
            for i in range(n):
                s += gradients[index[a], i] * minv_gt[i, b]
            delassus[a, b] = s
    active = np.ones(c, dtype=np.bool_)
    lam = np.empty(c)
    for _ in range(c + 1):                      # (each pass but the last drops a contact)
        solved = solve_on_set(delassus, free, active, lam) if symmetric else lu_solve_on_set(delassus, free, active,
                                                                                             lam)
        if not solved:                          # λ_A = −W_AA⁻¹ (G_A q̈_free + b_A)
            return DEPENDENT_CLOSED_CONTACTS
        pulling = -1
        for a in range(c):
            if (unilateral != 0.0 and index[a] < one_sided and active[a] and lam[a] < 0.0
                    and (pulling < 0 or lam[a] < lam[pulling])):
                pulling = a
        if pulling < 0:
            break
        active[pulling] = False
    for i in range(n):
        s = 0.0
        for a in range(c):
            s += minv_gt[i, a] * lam[a]
        qdd[i] += s
    for a in range(c):
        forces[index[a]] = lam[a]
    return 0


@njit(cache=True, error_model="numpy", fastmath=False)
def lu_solve_on_set(W, q, active, z):
    """`lagcomp.kernel_support.impacts.solve_on_set` for a W that is not symmetric: z_A = −W_AA⁻¹ q_A by LU with
    partial pivoting, 0 elsewhere; False if W_AA is singular."""
    c = q.shape[0]
    index = np.empty(c, dtype=np.int64)
    m = 0
    for i in range(c):
        if active[i]:
            index[m] = i
            m += 1
    augmented = np.empty((m, m + 1))
    for a in range(m):
        augmented[a, m] = -q[index[a]]
        for b in range(m):
            augmented[a, b] = W[index[a], index[b]]
    if m > 0 and lu_solve(augmented) != 0:
        return False
    for i in range(c):
        z[i] = 0.0
    for a in range(m):
        z[index[a]] = augmented[a, m]
    return True


@njit(cache=True, error_model="numpy", fastmath=False)
def friction_mode_after(mode, force, limit):
    """A friction element's mode after its event (`lagcomp.model.friction.Friction`): from stick (``mode`` 0,
    its force reached ``limit`` = μs |N|) slip against the force that held it, −sign ``force``; from slip (v reached
    0) stick when the ``force`` needed to hold v = 0 is within ``limit``, else slip against it (the other way).
    A limit of 0 (no normal force: an open contact presses with none) never sticks: the element is idle, its slip
    force 0, and a held row would hold v = 0 with no force to spare."""
    if mode != 0.0 and abs(force) <= limit and limit > 0.0:
        return 0.0
    return -1.0 if force > 0.0 else 1.0


@njit(cache=True, error_model="numpy", fastmath=False)
def bounces_unresolved(v_after, pressing, restitution, t, gradient, q):
    """Whether an impact that leaves a contact at normal velocity ``v_after`` under the free normal acceleration
    ``pressing`` (< 0: pressed shut) should close it instead: the bounces it starts, 2 v⁺/(|a| (1 − e)) in all,
    end within `ZENO_TIME` |t|, or the next, 2 v⁺/|a|, lasts less than `BOUNCE_TIME` |t| (time's rounding) or rises
    v⁺²/(2|a|) < `BOUNCE_HEIGHT` ε Σ_j |∂g/∂q_j| |q_j| (the gap's rounding at q; ``gradient`` (n,): ∂g/∂q).

    Each side is in one unit (time, or the gap's): the rule is the same in any units."""
    if not pressing < 0.0:
        return False
    a = -pressing
    if 2.0 * v_after < ZENO_TIME * abs(t) * a * (1.0 - restitution) or 2.0 * v_after < BOUNCE_TIME * abs(t) * a:
        return True
    rounding = 0.0
    for j in range(q.shape[0]):
        rounding += abs(gradient[j]) * abs(q[j])
    return v_after * v_after < 2.0 * a * BOUNCE_HEIGHT * EPS * rounding


@njit(cache=True, error_model="numpy", fastmath=False)
def _contact_event(mass, gaps, gradients, normal_velocities, restitution, bias, qdd_free, q, t, firing, modes, closing,
                  qd):
    """`impact_and_closing` without constraints."""
    return impact_and_closing(mass, np.empty((0, q.shape[0])), gaps, gradients, normal_velocities, restitution, bias,
                              qdd_free, q, t, firing, modes, closing, qd)


@njit(cache=True, error_model="numpy", fastmath=False)
def _constrained_contact_event(mass, constraint, gaps, gradients, normal_velocities, restitution, bias, qdd_free, q,
                               t, firing, modes, closing, qd):
    """`impact_and_closing` with the constraints Λ (``constraint`` (k, n))."""
    return impact_and_closing(mass, constraint, gaps, gradients, normal_velocities, restitution, bias, qdd_free, q, t,
                              firing, modes, closing, qd)


@njit(cache=True, error_model="numpy", fastmath=False)
def impact_and_closing(mass, constraint, gaps, gradients, normal_velocities, restitution, bias, qdd_free, q, t,
                       firing, modes, closing, qd):
    """The reset of contact ``firing``'s event: the lift-off of a closed contact, or the impact of an open one.

    A closed contact (``modes[firing]`` 1) whose force reached 0 opens: its mode becomes 0, the velocities do not
    jump.  An open one's impact is `lagcomp.kernel_support.impacts.contact_impacts`, the velocities ``qd`` (n)
    overwritten; then, when ``closing`` is 1, each contact taking part that is a candidate to close
    (`_closes`: its bounces the run would not resolve, or a plastic impact left it at rest) closes: the impact is
    done again with e = 0 for those, and their modes become 1.  Whether the closed contacts' forces all push is
    not decided here but at the state after the impact, by the emitted branch (``contact_forces`` under the new
    modes), which does the impact again without closing when a contact it closed would pull
    (`lagcomp.codegen.contacts.contact_event_call`): q̈_free and b depend on q̇ (a curved gap's centripetal
    ġ' q̇, a rod's pull Λ q̈ = −Λ̇ q̇), so the forces before an impact say nothing of those after it (a fast
    plastic impact on a curved gap does not press before it and rests pressed after it).
    mass (n, n) lower triangle, gaps, normal_velocities, restitution, bias (C,), gradients (C, n) as in
    `contact_impacts`; qdd_free (n): q̈ without contacts at the state before.  ``constraint`` (k, n): the
    constraint matrix Λ of a constrained system (k = 0 without): the impacts keep its constraints' velocities
    (`lagcomp.kernel_support.impacts.constrained_contact_impacts`).  Returns the impact's status.
    """
    if modes[firing] != 0.0:
        modes[firing] = 0.0
        return IMPACT_SOLVED
    count = gaps.shape[0]
    before = qd.copy()
    status = _constrained_contact_impacts(mass, constraint, gaps, gradients, normal_velocities, restitution, q,
                                          firing, qd)
    if status != IMPACT_SOLVED or closing == 0.0:
        return status
    plastic = restitution.copy()
    closed = modes.copy()
    any_closing = False
    for d in range(count):
        if modes[d] != 0.0 or (d != firing and not touching(gaps[d], gradients, d, q)):
            continue
        if _closes(d, gradients, bias, normal_velocities[d], restitution[d], qdd_free, q, t, before, qd):
            plastic[d] = 0.0
            closed[d] = 1.0
            any_closing = True
    if not any_closing:
        return status
    return _close_plastic(mass, constraint, gaps, gradients, normal_velocities, plastic, q, firing, modes, closed,
                          before, qd)


@njit(cache=True, error_model="numpy", fastmath=False)
def _closes(d, gradients, bias, v_before, restitution, qdd_free, q, t, before, after):
    """Whether contact ``d``, at normal velocity ``v_before`` before an impact that took the velocities from
    ``before`` to ``after`` (n), is a candidate to close: its bounces under the free normal acceleration before,
    a = G_d q̈_free + b_d, would not be resolved (`bounces_unresolved`), or its restitution is 0 and the impact
    left it at rest (`_at_rest`) whatever a was (the forces after the impact decide)."""
    pressing = bias[d]
    v_after = v_before
    for j in range(q.shape[0]):
        pressing += gradients[d, j] * qdd_free[j]
        v_after += gradients[d, j] * (after[j] - before[j])
    return bounces_unresolved(v_after, pressing, restitution, t, gradients[d], q) or (
        restitution == 0.0 and _at_rest(v_after, gradients, d, after))


@njit(cache=True, error_model="numpy", fastmath=False)
def _at_rest(v, gradients, row, qd):
    """Whether the normal velocity v of contact ``row`` is 0 on the scale of rest (`CLOSED_GAP` Σ_j |∂g/∂q_j|
    (|q̇_j| + 1), a run's start's): a plastic impact's, which closes the contact when its force pushes at the state
    after (the emitted branch checks it there, `impact_and_closing`; the free normal acceleration before a fast
    impact may point either way)."""
    scale = 0.0
    for j in range(qd.shape[0]):
        scale += abs(gradients[row, j]) * (abs(qd[j]) + 1.0)
    return abs(v) <= CLOSED_GAP * scale


@njit(cache=True, error_model="numpy", fastmath=False)
def _close_plastic(mass, constraint, gaps, gradients, normal_velocities, plastic, q, firing, modes, closed, before,
                   qd):
    """The impact from the velocities ``before`` again with the restitutions ``plastic`` (0 for the contacts that
    close), into ``qd``; the modes ``closed`` into ``modes`` when it is solved.  Returns its status."""
    for j in range(q.shape[0]):
        qd[j] = before[j]
    status = _constrained_contact_impacts(mass, constraint, gaps, gradients, normal_velocities, plastic, q, firing,
                                          qd)
    if status == IMPACT_SOLVED:
        for d in range(gaps.shape[0]):
            modes[d] = closed[d]
    return status



@njit(cache=True, error_model="numpy", fastmath=False)
def friction_modes_after_jump(slip_gradients, slip_offsets, qd, frictions):
    """The friction elements' modes (F,) after a contact's event (an impact, a closing, a lift-off), decided again
    from the velocities ``qd`` (n) after it, into ``frictions``: slip with s = sign v where v = a·q̇ + c (rows of
    ``slip_gradients`` (F, n) = ∂v/∂q̇, ``slip_offsets`` (F) = c) is beyond rounding (`CLOSED_GAP` Σ_j |a_j|
    (|q̇_j| + 1), the scale a run starts with), else stick.  An impact reverses or stops a sliding body: a mode
    kept from before would push it along its old direction.  Returns True when some element sticks, whose holding
    force the caller checks against its limit (`slip_most_overloaded`)."""
    n = qd.shape[0]
    any_stuck = False
    for f in range(frictions.shape[0]):
        v = slip_offsets[f]
        scale = 0.0
        for j in range(n):
            v += slip_gradients[f, j] * qd[j]
            scale += abs(slip_gradients[f, j]) * (abs(qd[j]) + 1.0)
        if abs(v) > CLOSED_GAP * scale:
            frictions[f] = 1.0 if v > 0.0 else -1.0
        else:
            frictions[f] = 0.0
            any_stuck = True
    return any_stuck


@njit(cache=True, error_model="numpy", fastmath=False)
def slip_most_overloaded(forces, limits, frictions):
    """Of the sticking elements (mode 0 in ``frictions`` (F,)) whose holding force (``forces`` (F,), the friction
    rows of ``contact_forces``) exceeds its static limit (``limits`` (F,) = μs |N|), the one most beyond it slips
    against its force (−sign λ_f, the free motion's way; one with a limit of 0 first).  Returns True when one
    did: the others' forces change, the caller computes them again (one pass per element at most, as a run's
    start does)."""
    worst = -1
    excess = 0.0
    for f in range(frictions.shape[0]):
        beyond = np.inf if not limits[f] > 0.0 else abs(forces[f]) - limits[f]    # (no normal force: never sticks)
        if frictions[f] == 0.0 and beyond > excess:
            worst = f
            excess = beyond
    if worst < 0:
        return False
    frictions[worst] = -1.0 if forces[worst] > 0.0 else 1.0
    return True


@njit(cache=True, error_model="numpy", fastmath=False)
def _friction_left_out(mass, constraint, gaps, gradients, q, before, after, firing, modes, pressing, slip_gradients,
                       slip_offsets):
    """Whether the frictionless impact that took the velocities from ``before`` to ``after`` (n) gave a normal
    impulse to a contact that presses a friction element sliding before or after it (v beyond the scale of rest
    `CLOSED_GAP` Σ_j |a_j| (|q̇_j| + 1)), where Coulomb's law would have added a tangential impulse.  The impulses
    of the contacts that took part (the firing one, the closed and the touching ones, set A) from the jump:
    M Δq̇ = G_Aᵀ P (+ Λᵀ Λc with constraints, ``constraint`` (k, n): Λ), so Δq̇ = K G_Aᵀ P, W_AA P = G_A Δq̇,
    W = G K Gᵀ (K = M⁻¹ without constraints, `lagcomp.kernel_support.constrained_response`); a P_d above 1e-10 of
    the largest counts.  True too when W_AA is singular (the impulses cannot be told apart)."""
    n, count = q.shape[0], gaps.shape[0]
    involved = np.zeros(count, dtype=np.bool_)
    for d in range(count):
        involved[d] = d == firing or modes[d] != 0.0 or touching(gaps[d], gradients, d, q)
    minv_gt = np.zeros((n, count))
    for d in range(count):
        if involved[d]:
            for j in range(n):
                minv_gt[j, d] = gradients[d, j]
    if response_columns(mass.copy(), constraint, minv_gt) != 0:
        return True
    delassus = np.zeros((count, count))
    jump = np.zeros(count)                  # −G Δq̇: solve_on_set gives P = −W⁻¹ (−G Δq̇)
    for a in range(count):
        for j in range(n):
            jump[a] -= gradients[a, j] * (after[j] - before[j])
        for b in range(count):
            for j in range(n):
                delassus[a, b] += gradients[a, j] * minv_gt[j, b]
    impulses = np.zeros(count)
    if not solve_on_set(delassus, jump, involved, impulses):
        return True
    largest = 0.0
    for d in range(count):
        largest = max(largest, abs(impulses[d]))
    for f in range(pressing.shape[0]):
        d = pressing[f]
        if d < 0 or not involved[d] or not impulses[d] > 1e-10 * largest:
            continue
        rest, v_before, v_after = 0.0, slip_offsets[f], slip_offsets[f]
        for j in range(n):
            rest += abs(slip_gradients[f, j]) * (abs(after[j]) + 1.0)
            v_before += slip_gradients[f, j] * before[j]
            v_after += slip_gradients[f, j] * after[j]
        if abs(v_before) > CLOSED_GAP * rest or abs(v_after) > CLOSED_GAP * rest:
            return True
    return False


@njit(cache=True, error_model="numpy", fastmath=False)
def _pressed_contact_event(mass, gaps, gradients, normal_velocities, restitution, bias, qdd_free, q, t, firing, modes,
                          closing, qd, slip_gradients, slip_offsets, pressing, static, kinetic):
    """`constrained_pressed_contact_event` without constraints."""
    return _constrained_pressed_contact_event(mass, np.empty((0, q.shape[0])), gaps, gradients, normal_velocities,
                                              restitution, bias, qdd_free, q, t, firing, modes, closing, qd,
                                              slip_gradients, slip_offsets, pressing, static, kinetic)


@njit(cache=True, error_model="numpy", fastmath=False)
def _constrained_pressed_contact_event(mass, constraint, gaps, gradients, normal_velocities, restitution, bias,
                                       qdd_free, q, t, firing, modes, closing, qd, slip_gradients, slip_offsets,
                                       pressing, static, kinetic):
    """`contact_event` where friction elements are pressed by contacts (``pressing`` (F,): the contact's index or
    −1; ``static``, ``kinetic`` (F,): μs, μk; ``slip_gradients`` (F, n), ``slip_offsets`` (F): v = a·q̇ + c).

    The impact of an open contact that presses an element, alone at that instant (no other contact closed or
    touching), is frictional: `lagcomp.kernel_support.impacts.frictional_impact` (Newton on the normal, the
    tangential impulse within μ P_n), with the closing of `contact_event` (done again with e = 0, the contact
    closed, when it is a candidate, `_closes`; the emitted branch checks its force after).  Every other event
    is `contact_event`'s, frictionless, which is right as long as no contact that presses a sliding element takes
    a normal impulse (a block sliding on a floor into a smooth wall: the floor takes none); otherwise
    (`_friction_left_out`) the tangential impulses would need a complementarity problem of their own, not solved
    yet: `IMPACT_FRICTION_UNSOLVED`, and the run stops at the impact (RESET_FAILED).
    With constraints (``constraint`` (k, n): Λ; k = 0 without) every impulse goes through the constrained
    response K (`lagcomp.kernel_support.impacts.constrained_frictional_impact`, `impact_and_closing`)."""
    if modes[firing] != 0.0:
        modes[firing] = 0.0
        return IMPACT_SOLVED
    n = q.shape[0]
    element = -1
    for f in range(pressing.shape[0]):
        if pressing[f] == firing and element < 0:
            element = f
    alone = element >= 0
    for d in range(gaps.shape[0]):
        if d != firing and (modes[d] != 0.0 or touching(gaps[d], gradients, d, q)):
            alone = False
    before = qd.copy()
    if not alone:
        status = impact_and_closing(mass, constraint, gaps, gradients, normal_velocities, restitution, bias, qdd_free,
                                    q, t, firing, modes, closing, qd)
        if status == IMPACT_SOLVED and _friction_left_out(mass, constraint, gaps, gradients, q, before, qd, firing,
                                                          modes, pressing, slip_gradients, slip_offsets):
            return IMPACT_FRICTION_UNSOLVED
        return status
    slip_velocity = slip_offsets[element]
    for j in range(n):
        slip_velocity += slip_gradients[element, j] * qd[j]
    e = restitution[firing]
    status = constrained_frictional_impact(mass, constraint, gradients[firing], normal_velocities[firing], e,
                                           slip_gradients[element], slip_velocity, static[element], kinetic[element],
                                           qd)
    if status != IMPACT_SOLVED or closing == 0.0:
        return status
    if _closes(firing, gradients, bias, normal_velocities[firing], e, qdd_free, q, t, before, qd):
        for j in range(n):
            qd[j] = before[j]
        status = constrained_frictional_impact(mass, constraint, gradients[firing], normal_velocities[firing], 0.0,
                                               slip_gradients[element], slip_velocity, static[element],
                                               kinetic[element], qd)
        if status == IMPACT_SOLVED:
            modes[firing] = 1.0
    return status


#: What the generated kernels call: the routines above, by symbol, optimised once
#: (`lagcomp.kernel_support.symbol_calls`).
closed_contact_accelerations = called_by_symbol(_closed_contact_accelerations)
frictional_accelerations = called_by_symbol(_frictional_accelerations)
pressed_frictional_accelerations = called_by_symbol(_pressed_frictional_accelerations)
contact_event = called_by_symbol(_contact_event)
constrained_closed_contact_accelerations = called_by_symbol(_constrained_closed_contact_accelerations)
constrained_frictional_accelerations = called_by_symbol(_constrained_frictional_accelerations)
constrained_contact_event = called_by_symbol(_constrained_contact_event)
pressed_contact_event = called_by_symbol(_pressed_contact_event)
constrained_pressed_frictional_accelerations = called_by_symbol(_constrained_pressed_frictional_accelerations)
constrained_pressed_contact_event = called_by_symbol(_constrained_pressed_contact_event)
