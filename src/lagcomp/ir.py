"""The intermediate representation between the symbolic model and emitted code.

A `ModuleIR` is the full content of one generated module as data: which
kernels it holds and, for each, straight-line assignments over local names.
It has no sympy mechanics objects in it, only expressions over plain symbols
named after the locals they print as, so the emitter is a pure printer.

Kernel calling convention (all arrays float64, C-contiguous):

- ``y`` is the state (q, q̇), shape (2n,); ``p`` the parameters in the
  module's documented order; ``t`` the time.
- kernels with ``out`` write their result into it and return nothing, except
  ``rhs``, which returns an int status (0, or k > 0 when the mass matrix is
  not positive definite at pivot k: the state is singular),
  ``rhs_jacobian``, ``rhs_with_jacobian`` (``rhs`` into ``ydot`` and ``rhs_jacobian`` into ``out`` at
  once), ``rhs_parameter_jacobian`` and a constrained system's ``reaction_jacobian``, which return the same, or
  `NO_JACOBIAN` where the module has no such Jacobian, and the DAE kernels of constrained systems, which return 0.
- scalar kernels (energies) return a float.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp


@dataclass(frozen=True)
class LinearSolve:
    """Solve M x = f for x after the stores, M symmetric positive definite.

    ``m[i][j]`` (i ≥ j, lower triangle) and ``f[i]`` are the scalar locals the
    stores bind; x is written to ``out[offset + i]``.  Unrolled, the
    factorization is straight-line code; otherwise the locals are gathered
    into arrays ``mm`` (n, n) and ``ff`` (n,) handed to a loop.
    ``zeros``: the (i, j), i > j, where M is zero whatever the state (its
    local is bound to 0.0), whose terms the unrolled factorization leaves out.
    """

    n: int
    m: tuple[tuple[str, ...], ...]
    f: tuple[str, ...]
    offset: int
    unrolled: bool = True
    zeros: frozenset = frozenset()


@dataclass(frozen=True)
class SymmetricProduct:
    """out[offset + i] = f[i] + Σ_j M_ij y[start + j] after the stores, M symmetric.

    ``m[i][j]`` (i ≥ j) and ``f[i]`` are the scalar locals the stores bind,
    gathered into arrays for a loop: for a large system the products written
    out one by one cost numba more to compile than the entries of M.
    """

    n: int
    m: tuple[tuple[str, ...], ...]
    f: tuple[str, ...]
    start: int
    offset: int


@dataclass(frozen=True)
class AugmentedSolve:
    """Solve the augmented system of a constrained system (`lagcomp.kernel_support.linear_solvers.kkt_solve`).

    The stores fill the work array ``_kkt`` of shape (N, N + 1), zeros
    included by allocation: [[M, −Λᵀ], [Λ, 0]] in its first N columns and the
    right-hand side (F, γ) in the last; M is the leading ``mass_block`` ×
    ``mass_block`` block.  Entries ``first .. first + count − 1`` of the
    solution go to ``out[offset:]``, and with `multipliers` the multipliers
    (the entries after M's block) to the argument ``lam`` too.  Unlike
    `LinearSolve` it does not need M to be regular (Schur complement where it
    is, LU with pivoting where not).
    """

    size: int
    mass_block: int
    first: int
    count: int
    offset: int
    multipliers: bool = False


#: What ``rhs_jacobian`` and ``rhs_parameter_jacobian`` return where their module has none (negative: never a
#: pivot); the module constant ``RHS_JACOBIAN_REFUSED`` (``RHS_PARAMETER_JACOBIAN_REFUSED``) then says why.
NO_JACOBIAN = -1


@dataclass(frozen=True)
class JacobianSolve:
    """The frame of ``rhs_jacobian``: y' = (x', a) with M a = F, and out = ∂y'/∂y of shape (size, size);
    with `columns` that of ``rhs_parameter_jacobian``, out = ∂y'/∂p of shape (size, columns).

    Before its loads the kernel calls ``rhs(t, y, p, _ydot)``, returning its status when it is not
    0, so that loads can bind the accelerations ā to ``_ydot[size − n + i]``: ``_ydot`` is the kernel's
    argument ``ydot`` with `given_ydot` (``rhs_with_jacobian``, which hands f back to its caller), else a
    local array.  ``_jac`` is `out` seen flat (size × width, width = `columns`, or size when None; `out`
    is C-contiguous), zeroed: no work array to allocate and copy.  The stores bind M's lower triangle to
    the scalar locals ``m[i][j]`` (i ≥ j, M symmetric) and write the nonzero entries of the Jacobian into
    ``_jac``, row-major (`lagcomp.codegen.jacobian_blocks.jacobian_entry`: a 1-D array compiles faster than `out`):
    the rows of x' and, in the last n rows, ∂(F − M ā)/∂y (or ∂/∂p) at ā = a.  Then the last n rows of
    `out` are overwritten with M⁻¹ times themselves: one LDLᵀ of M, a substitution per column
    (`lagcomp.kernel_support.linear_solvers.ldlt_solve_matrix`, or for n ≤
    `lagcomp.codegen.emit.JACOBIAN_UNROLL_MAX` its operations written out, bitwise the same), whose
    status is returned.
    """

    n: int
    size: int
    m: tuple[tuple[str, ...], ...]
    columns: int | None = None
    given_ydot: bool = False

    @property
    def width(self) -> int:
        """The columns of `out`: `columns`, or `size` for the square ∂y'/∂y."""
        return self.size if self.columns is None else self.columns


@dataclass(frozen=True)
class AugmentedJacobianSolve:
    """The frame of the Jacobian kernels of a constrained system (`lagcomp.codegen.constrained_jacobian`):
    z = (q̈, λ) solves K z = (F, γ̃), K = [M −Λᵀ; Λ 0], and the kernel writes rows of ∂z/∂x, x the `width`
    variables (y, p or both).

    Before its loads the kernel calls ``rhs_and_reactions(t, y, p, _ydot, _lam)`` (``rhs`` and ``reactions`` at
    once, bitwise), returning its status when it is not 0, so that loads can bind q̈ to ``_ydot[n + i]``
    (``_ydot`` the argument ``ydot`` with `given_ydot`, else a local) and λ to ``_lam[c]``.  It allocates
    ``_kkt`` (n + k, n + k) and ``_jac`` ((n + k) × width, flat) zeroed; the stores fill K into ``_kkt`` and
    into ``_jac`` the nonzero entries of ∂/∂x [F − M ā + Λᵀ λ̄; γ̃ − Λ ā] at (ā, λ̄) = (q̈, λ), row-major.  Then
    ``kkt_solve_matrix`` overwrites them with K⁻¹ times themselves (its status returned when not 0): rows
    ``first .. first + count − 1`` of the solution go to ``out[offset:]``, the other rows of `out` are
    zero, and with `identity` out[i, n + i] = 1 for i < n (the rows q̇ of ∂f/∂y).
    """

    n: int
    k: int
    width: int
    first: int
    count: int
    offset: int
    identity: bool = False
    given_ydot: bool = False


@dataclass(frozen=True)
class DirectionalSolve:
    """The frame of ``rhs_directional`` (`lagcomp.codegen.directional`): f and its derivative along a direction
    from one CSE, in two phases around the solve for the accelerations.

    The first `phase_one` stores (f's rows q̇ into ``ydot[:n]``; M's lower triangle into the locals `m` and F
    into `f`, or K and its right-hand side (F, γ̃) into ``_kkt`` (n + k, n + k + 1) for a constrained system
    with `multipliers` k > 0) need no acceleration; then the solve writes q̈ into ``ydot[n:]`` (``_lam`` the
    multipliers' view), and the loads of `solved` (the accelerations ā, multipliers λ̄ the residual's partials
    are taken at), the temporaries that read them, and the other stores follow: the direction's right-hand side
    into the locals `g` (or the last column of ``_direction``, a copy of K made before the first solve), which a
    second substitution by the same LDLᵀ of M, written out (n is small: `lagcomp.codegen.directional`), or a
    second ``kkt_solve``, turns into ``out[offset + n:]``.  `ydot` names the array f goes to: ``ydot``, or
    ``out`` itself for the tangent kernels (``rhs_tangent``: f into ``out[:2n]``, the direction at `offset` =
    2n).

    `columns` non-empty makes the kernel one of many columns (``rhs_tangents``, `lagcomp.codegen.directional`):
    the stores after `phase_one` write the residual's partials into locals, and a loop over the columns of S
    in y = (x, S[:, 0], ..., S[:, m-1]) (m from y's size) contracts them with each column and substitutes by
    the factors (or solves all columns with one ``kkt_solve_matrix``).  ``columns[r]`` lists the nonzero
    partials of residual row r as (variable index, local): a state component below 2n, else parameter
    index − 2n, whose column is chosen per column of S by p's tail (see the kernel's docstring).
    """

    n: int
    phase_one: int
    solved: tuple[str, ...]
    multipliers: int = 0
    m: tuple[tuple[str, ...], ...] = ()
    f: tuple[str, ...] = ()
    g: tuple[str, ...] = ()
    ydot: str = "ydot"
    offset: int = 0
    columns: tuple[tuple[tuple[int, str], ...], ...] = ()


@dataclass(frozen=True)
class Delegate:
    """The whole body: ``return kernel(t, y, p, np.empty(scratch), out)``, a kernel that computes what
    `kernel` does and keeps only `out` (``rhs_jacobian`` from ``rhs_with_jacobian``, f dropped): one
    compiled body for both, the same values bitwise."""

    kernel: str
    scratch: int


@dataclass(frozen=True)
class ReturnZero:
    """After the stores, ``return 0``: an `out` kernel that cannot fail, with the int status of the drivers'
    kernel types (``dae_residual``)."""


@dataclass(frozen=True)
class LaneBuffer:
    """The frame of a `Kernel.lanes` kernel whose stores go into a stack buffer of `width` lanes, ``_buf[i * width +
    _j]`` for ``out[i, _c + _j]``, copied into `out` ((`rows`, B)) after each chunk of lanes ``_c .. _c + width``.

    Why: LLVM vectorizes the loop over lanes only when it can rule out that its stores into `out` overwrite what
    later lanes read from the inputs; with `out`'s rows at a stride known at run time only, that takes a runtime
    check per pair of rows, and past a few rows it gives up ("loop not vectorized: too many memory checks needed")
    and the loop runs one lane at a time.  A buffer in the kernel's stack frame cannot alias an argument: the loop
    over a chunk vectorizes whatever the number of rows, and the copy into `out` is a loop per row.  Each lane's
    arithmetic is unchanged (no fastmath): the same bits."""

    rows: int
    width: int


@dataclass(frozen=True)
class FlatMatrix:
    """The frame of a kernel whose stores fill a (size, size) matrix (``dae_jacobian``): before its temporaries
    it allocates the work array ``_jac`` of size² zeros, the stores write the nonzero entries into it, row-major
    (`lagcomp.codegen.jacobian_blocks.jacobian_entry`: a 1-D array compiles faster than `out`), and after them ``_jac``
    is copied into `out`, every entry, and the kernel returns 0.

    With `symmetric`, the stores write the lower triangle only (i ≥ j) and a loop mirrors it into the upper one
    before the copy (``mass_matrix`` of a tree: half the stores, each a fraction of a 2-D store's compile time);
    without `status`, the kernel returns nothing (the signature of ``mass_matrix``).

    With `width`, the matrix is (size, width), rows of `width` entries in ``_jac`` (a tree's ``rhs_with_jacobian``,
    ``rhs_parameter_jacobian``); with `in_place`, ``_jac`` is `out` itself seen flat, no array allocated, nothing
    zeroed or copied: the stores write every entry, zeros too (`out` C-contiguous: the drivers' ``MATRIX``,
    `lagcomp.integrate.drivers.kernel_types`)."""

    size: int
    symmetric: bool = False
    status: bool = True
    #: Entries per row (None: `size`, square).
    width: int | None = None
    in_place: bool = False

    @property
    def columns(self) -> int:
        """The matrix's number of columns: `width`, or `size` when square."""
        return self.size if self.width is None else self.width


@dataclass(frozen=True)
class Unavailable:
    """A kernel the module defines (every module defines every kernel) but cannot compute: it writes
    nothing and returns `status`; the module constant `constant` holds `reason` (None: another kernel's
    constant says it already)."""

    status: int
    constant: str | None
    reason: str


@dataclass(frozen=True)
class ContactImpact:
    """The solve of the contacts' branch of ``event_reset`` (`lagcomp.codegen.contacts`): the stores fill
    ``_mass`` (n, n), ``_gap``, ``_gradient`` (C, n), ``_normal_velocity`` and ``_restitution`` (C) for the
    C = len(`events`) contacts, whose events are `events` (in contact order); the branch then calls
    ``contact_impacts`` on the contact of the event ``e`` that fired, writing the velocities ``out[n:2n]``,
    and returns its status."""

    n: int
    events: tuple[int, ...]
    #: The first mode slot of p (`ContactModes`), or None for a module without modes (a Kane model's): then
    #: the branch is the impact alone; with them, `lagcomp.kernel_support.resting.contact_event` (lift-off of a
    #: closed contact, an impact that may close it); ``_bias`` is stored too.
    modes: int | None = None
    #: The friction elements of a module with modes (their mode slots follow the closing flag): the branch also
    #: stores ``_slip_gradient`` (F, n) = ∂v/∂q̇ and ``_slip_offset`` (F) = v at q̇ = 0, and decides their modes
    #: again from the velocities after the contact's event (`lagcomp.kernel_support.resting`).
    elements: int = 0
    #: Per friction element, the contact (in contact order) that presses it or −1; () when none is pressed by a
    #: contact.  Then the branch also stores ``_static``, ``_kinetic`` (F) and an impact is frictional
    #: (`lagcomp.kernel_support.resting.pressed_contact_event`).
    pressing: tuple[int, ...] = ()
    #: The constraints of a constrained module (k rows of Λ): the branch also stores ``_constraint`` (k, n) = Λ and
    #: calls the constrained solvers (`lagcomp.kernel_support.constrained_response`: the impact keeps Λ q̇ + b = 0).
    constraints: int = 0


@dataclass(frozen=True)
class ContactModes:
    """Where a module's contacts keep their modes (`lagcomp.codegen.contacts`): ``p[first + d]`` is 0 while
    contact d is open, 1 while it is closed (a holonomic constraint g_d = 0 whose multiplier is its normal
    force), and ``p[first + count]`` is 1 when an impact may close a contact (the runs of methods whose rhs
    reads the modes), 0 otherwise.  The solve of the kernels that read them:

    * ``rhs``: ``rhs_free`` (today's q̈ of M q̈ = F), then, when some mode is 1, ``closed_contacts``;
    * ``closed_contacts(t, y, p, out, forces, unilateral)``: the stores fill ``_mass`` (n, n, lower triangle),
      ``_gradient`` (C, n) and ``_bias`` (C) = ġ's partials times (q̇, 1): g̈ = G q̈ + b; then
      `lagcomp.kernel_support.resting.closed_contact_accelerations` corrects ``out[n:2n]`` (``rhs``: no pulling
      force, ``unilateral`` 1);
    * ``contact_forces(t, y, p, out)``: the normal forces (C,), 0 for an open contact;
    * ``event_values``: after its stores, a closed contact's value is its normal force (`events`: the contacts'
      event indices, in contact order).

    Friction elements (`lagcomp.model.friction.Friction`, event indices `frictions`) have their modes after the
    closing flag, ``p[first + count + 1 + f]``: 0 stick (a row of ``closed_contacts``, held two-sided, after the
    contacts' rows; its multiplier the friction force, after the normal forces in ``contact_forces``), ±1 slip;
    their ``event_values`` are s·v while slipping and μs |N| − |λ_f| (``friction_limits``) while sticking.
    """

    kind: str
    n: int
    count: int
    first: int
    events: tuple[int, ...] = ()
    frictions: tuple[int, ...] = ()
    #: Per friction element, the index (in contact order) of the contact whose normal force presses it, −1 for an
    #: N given as an expression; () when no element is pressed by a contact (`lagcomp.codegen.contacts`).
    pressing: tuple[int, ...] = ()
    #: The constraints of a constrained module (k rows of Λ): ``closed_contacts`` also stores ``_constraint``
    #: (k, n) = Λ, holds them beside the closed contacts and sticking friction elements
    #: (`lagcomp.kernel_support.resting.held_with_constraints`: its ``forces`` are rows + k, the constraints' Δμ
    #: last), and ``reactions`` (kind "reactions") adds that Δμ to ``reactions_free``.
    constraints: int = 0

    @property
    def rows(self) -> int:
        """The rows ``closed_contacts`` may hold: the contacts', then the friction elements'."""
        return self.count + len(self.frictions)

    def friction_slot(self, f: int) -> int:
        """The slot of p of friction element f's mode."""
        return self.first + self.count + 1 + f


@dataclass(frozen=True)
class FrictionSwitch:
    """The solve of a friction element's branch of ``event_reset`` (`lagcomp.codegen.contacts`): the element's new
    mode into p (`lagcomp.kernel_support.resting.friction_mode_after`) from the force that holds it
    (``contact_forces`` with the element sticking, its entry `row` of `rows`) and its static limit
    (``friction_limits``, entry `element` of `elements`); its mode is ``p[slot]``.  No stores; the state does not
    jump."""

    slot: int
    row: int
    rows: int
    element: int
    elements: int
    #: Some element is pressed by a contact: the limit too is taken with the element sticking (λ_c depends on
    #: the modes), not after its mode is restored.
    pressed: bool = False


@dataclass(frozen=True)
class EventResets:
    """The body of ``event_reset(t, y, p, e, out)``: ``out`` = ``y`` (`size` entries), then for the event e that
    has a reset, the loads, temporaries and stores of its `Kernel` in `branches` ((event index, kernel), ...,
    each CSE'd on its own: only one runs; the contacts' events share one branch, keyed by the tuple of their
    indices, whose kernel's solve is a `ContactImpact`), and ``return 0``."""

    size: int
    branches: tuple


@dataclass(frozen=True)
class Helper:
    """A function of scalars shared by several steps of one kernel (`lagcomp.codegen.outline`): the body of a
    recursion's step that repeats node after node, compiled by numba once and inlined by LLVM at each call.

    `args` are its parameters' names, `temps` its assignments in order (over the args and earlier temps), and
    `returns` the temps it hands back, as a tuple, in that order.  `inline`: LLVM inlines it at every call
    (numba's ``forceinline``), else it is called."""

    name: str
    args: tuple[str, ...]
    temps: tuple[tuple[str, sp.Expr], ...]
    returns: tuple[str, ...]
    inline: bool = True

    @property
    def operation_count(self) -> int:
        """Arithmetic operations of its body."""
        return int(sum(sp.count_ops(e) for _, e in self.temps))


class HelperCall(sp.Function):
    """``helper(arg, ...)`` in a kernel's temporaries: the call of the `Helper` named by the first argument (a
    Symbol) on the other arguments.  The temporary's local is the comma-separated list of the names its results
    unpack into."""

    nargs = None

    def _pythoncode(self, printer) -> str:
        return f"{self.args[0].name}({', '.join(printer._print(a) for a in self.args[1:])})"


@dataclass(frozen=True)
class Kernel:
    """One numba function: load inputs, compute temporaries, store outputs.

    Attributes
    ----------
    name : str
        Function name in the module.
    doc : str
        Its docstring (what it computes, shapes, units).
    args : tuple of str
        Argument names, e.g. ``("t", "y", "p", "out")``.
    loads : tuple of (local, source)
        Inputs bound to locals, e.g. ``("q_theta1", "y[0]")`` (user symbols are ``q_``, ``qd_``,
        ``p_`` ... locals: `lagcomp.codegen.lower`, Names).
    temps : tuple of (local, Expr)
        Common subexpressions, in evaluation order; or a recursion's intermediate quantities, each a small
        expression of earlier ones (`lagcomp.multibody.program`).
    stores : tuple of (target, Expr)
        Output assignments; the target is an lvalue (``out[0]``, a local) or
        ``return`` for scalar kernels.
    solve : LinearSolve, AugmentedSolve, SymmetricProduct, JacobianSolve, AugmentedJacobianSolve,
        DirectionalSolve, Delegate, ReturnZero, FlatMatrix, Unavailable or None
        Linear solve appended after the stores (the q̈ of ``rhs``, the λ of ``reactions``,
        M⁻¹ applied to the rows of ``rhs_with_jacobian``), the call of another kernel
        (``rhs_jacobian``), the matrix-vector product of
        ``momenta`` for large systems, the status 0 of a kernel that cannot fail (the DAE
        kernels; ``dae_jacobian`` through its flat work array), the status of a kernel
        that computes nothing, or the branches of ``event_reset``.
    lanes : bool
        The body runs once per lane ``_l`` of a batch (structure of arrays:
        ``Y[i, _l]``, ``P[k, _l]``, ``out[i, _l]``), in a loop LLVM can
        vectorize: no early return, a singular pivot sets ``bad[_l]``.
    alias : str or None
        The name of another kernel of the module that computes the same
        thing: this one is emitted as that function (``name = alias``), so
        numba compiles it once.
    constants : tuple of (name, comment, value)
        Module constants emitted after the kernel, ``name = repr(value)`` under the
        comment ``#: comment``: data that describes the kernel's output to Python
        callers (``geometry``'s layout, `lagcomp.codegen.geometry`).  Values are
        Python literals (numbers, strings, tuples of them).
    helpers : tuple of Helper
        Functions its temporaries call (`HelperCall`), emitted before it.
    """

    name: str
    doc: str
    args: tuple[str, ...]
    loads: tuple[tuple[str, str], ...]
    temps: tuple[tuple[str, sp.Expr], ...]
    stores: tuple[tuple[str, sp.Expr], ...]
    solve: (LinearSolve | AugmentedSolve | SymmetricProduct | JacobianSolve | AugmentedJacobianSolve
            | DirectionalSolve | Delegate | ReturnZero | FlatMatrix | Unavailable | EventResets | ContactModes
            | FrictionSwitch | LaneBuffer | None) = None
    lanes: bool = False
    alias: str | None = None
    constants: tuple[tuple[str, str, object], ...] = ()
    helpers: tuple[Helper, ...] = ()

    @property
    def operation_count(self) -> int:
        """Arithmetic operations left after CSE (what numba's compile time grows with): those of its body and of
        its helpers, each once (a call counts one)."""
        return int(sum(sp.count_ops(e) for _, e in self.temps + self.stores)
                   + sum(h.operation_count for h in self.helpers))


@dataclass(frozen=True)
class ModuleIR:
    """Everything one generated module contains."""

    system_name: str
    description: str
    coordinate_names: tuple[str, ...]
    parameter_names: tuple[str, ...]
    kernels: tuple[Kernel, ...]
    constraint_names: tuple[str, ...] = ()
    holonomic: tuple[bool, ...] = ()
    event_names: tuple[str, ...] = ()
    #: Inputs supplied at run time, in the order of their headers in p, and the highest derivative of each
    #: that the kernels read (`lagcomp.kernel_support.inputs`).
    input_names: tuple[str, ...] = ()
    input_orders: tuple[int, ...] = ()
    #: How the kernels get the motion, for the module's docstring: Lagrange's equations, or the recursions over a
    #: kinematic tree (`lagcomp.codegen.tree_lower`).
    formulation: str = "Equations of motion: M(q, t) q̈ = F(q, q̇, t) (see lagcomp.mechanics.lagrange)."

    @property
    def k(self) -> int:
        return len(self.constraint_names)

    @property
    def n(self) -> int:
        return len(self.coordinate_names)

    def kernel(self, name: str) -> Kernel:
        return next(k for k in self.kernels if k.name == name)


def target_local(target: str) -> str:
    """A kernel store target as the local the emitted solve reads: ``mm[1, 0]`` -> ``_m1_0``,
    ``ff[2]`` -> ``_f2``; other targets (``out[3]``, ``_m1_0``) stay as they are."""
    if target.startswith("mm["):
        i, j = target[3:-1].split(", ")
        return f"_m{i}_{j}"
    if target.startswith("ff["):
        return f"_f{target[3:-1]}"
    return target
