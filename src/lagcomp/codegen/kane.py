r"""Emit the module of a Kane model: kernels over the state y = (q, u), then the drivers.

The input is a `FirstOrderForm` from `lagcomp.mechanics.kane` (q̇ = N,
M u̇ = F, Φ = 0, Ψ = 0, no multipliers), with T + V and the auxiliary
reactions when the model has them.  Kernels (``n_q`` coordinates, ``n_u``
speeds, state length ``n_q + n_u``; same calling conventions as
`lagcomp.ir`):

- ``rhs(t, y, p, out)``: out[:n_q] = N, out[n_q:] = u̇ from M u̇ = F by LU
  with partial pivoting (``lu_solve``: M is square but not symmetric when
  the velocity constraints are among its rows).  Returns 0, or j > 0 when
  pivot j is zero (M singular there).
- ``rhs_with_jacobian(t, y, p, ydot, out)``: ydot = f as ``rhs`` computes it, out = ∂(q̇, u̇)/∂(q, u),
  shape (n_q + n_u, n_q + n_u), exact (`_rhs_jacobian` derives it); the status of ``rhs``, or of the LU
  of M.  ``rhs_jacobian(t, y, p, out)``: the same without f.
- ``rhs_parameter_jacobian(t, y, p, out)``: ∂(q̇, u̇)/∂p, shape (n_q + n_u, P), P parameters,
  exact (`_rhs_parameter_jacobian`); the same statuses.
- ``kinematics(t, y, p, out)``: q̇ = N, shape (n_q,).
- ``energy(t, y, p)``: T + V, NaN when it could not be formed; ``energy_function`` is the same kernel.
- ``constraint_residuals(t, y, p, out)``: Φ (n_h), then Ψ (n_v); with constraints,
  ``constraint_residual_scales`` the rounding scale of each (`lagcomp.codegen.rounding_scale`);
  ``configuration_jacobian`` ∂Φ/∂q (n_h, n_q) and ``velocity_constraint_matrix``
  [∂Ψ/∂u | Ψ at u = 0] (n_v, n_u + 1), which ``project`` uses.
- ``reactions(t, y, p, out)``: the noncontributing forces of the auxiliary
  speeds at the u̇ of ``rhs`` (only when the model has them).

- ``event_values(t, y, p, out)``: g of each declared event (`lagcomp.Event`
  over q, u and t); without events a stub, and the drivers' event code is left out.
  ``event_gradients(t, y, p, out) -> 0``: their partials ∂g/∂y, ∂g/∂t, ∂g/∂p, (E, N + 1 + P), for
  the sensitivities of the events' times; a stub without events.
- ``geometry(t, y, p, out)``: writes nothing, ``GEOMETRY = ()``, ``GEOMETRY_SIZE = 0``
  (`lagcomp.codegen.geometry`): a Kane model's bodies are not drawn yet.

Then the hooks the drivers call (``project``, ``constraint_residual``, with
the constraint sizes as module constants), ``observables`` and
``kinematics_along`` / ``reactions_along`` over saved rows, and the equations
as LaTeX and text (``EQUATIONS``).  The kernels have
the names and signatures of a Lagrange module's
(`lagcomp.integrate.drivers.kernel_types`), so the library drivers take
either; sin, cos and the solvers come from `lagcomp.kernel_support`.  Locals are ``_q<i>``, ``_u<i>``, ``_p<k>``: no user name
reaches the emitted code, so none can collide with it (DESIGN.md, "Names");
the header lists which is which.
"""

from __future__ import annotations

import sympy as sp

from lagcomp import __version__
from lagcomp.codegen.cse import cse_kernel
from lagcomp.codegen.emit import (
    INDENT,
    PROJECTION_ITERATIONS,
    delegated_call,
    kernel_source,
    kernel_support_names,
    module_constants,
    support_imports,
)
from lagcomp.codegen.geometry import no_geometry_kernel
from lagcomp.codegen.jacobian_blocks import (
    RHS_PARAMETER_JACOBIAN_DOC,
    RHS_WITH_JACOBIAN_DOC,
    WITH_JACOBIAN_ARGS,
    acceleration_partials,
    jacobian_entry,
    jacobian_only,
)
from lagcomp.codegen.latex import equations_source, kane_equations
from lagcomp.codegen.lower import event_reset_kernel
from lagcomp.codegen.printer import to_code
from lagcomp.codegen.rounding_scale import rounding_scale
from lagcomp.mechanics.first_order import FirstOrderForm
from lagcomp.mechanics.kane import acceleration_symbols
from lagcomp.model.system import t

ARGS = ("t", "y", "p", "out")

def _bindings(form: FirstOrderForm, reactions: bool):
    """Model symbol -> local symbol, and the loads binding the locals (u̇ too when `reactions`)."""
    n_q = form.n_q
    sources = [(s, f"_q{i}", f"y[{i}]") for i, s in enumerate(form.q)]
    sources += [(s, f"_u{i}", f"y[{n_q + i}]") for i, s in enumerate(form.u)]
    sources += [(s, f"_p{k}", f"p[{k}]") for k, s in enumerate(form.parameters)]
    if reactions:
        sources += [(s, f"_ud{i}", f"_ydot[{n_q + i}]") for i, s in enumerate(acceleration_symbols(form))]
    mapping = {s: sp.Symbol(local, real=True) for s, local, _ in sources}
    mapping[t] = sp.Symbol("t", real=True)
    return mapping, tuple((local, source) for _, local, source in sources)


def _function(kernel, before=(), after=()) -> str:
    """The source of `kernel`, with lines `before` its loads and `after` its stores."""
    body = f'"""{kernel.doc}"""'.splitlines() + list(before)
    body += [f"{local} = {source}" for local, source in kernel.loads]
    body += [f"{name} = {to_code(expr)}" for name, expr in kernel.temps]
    for target, expr in kernel.stores:
        body.append(f"return {to_code(expr)}" if target == "return" else f"{target} = {to_code(expr)}")
    body += list(after)
    lines = ["", "", '@njit(cache=True, error_model="numpy")', f"def {kernel.name}({', '.join(kernel.args)}):"]
    return "\n".join(lines + [INDENT + line if line else "" for line in body]) + "\n"


def _rhs(form: FirstOrderForm, mapping, loads) -> tuple:
    n_q, n_u = form.n_q, form.n_u
    stores = [(f"out[{i}]", form.N[i]) for i in range(n_q)]
    stores += [(f"_kkt[{i}, {j}]", form.M[i, j]) for i in range(n_u) for j in range(n_u) if form.M[i, j] != 0]
    stores += [(f"_kkt[{i}, {n_u}]", form.F[i]) for i in range(n_u)]
    kernel = cse_kernel(
        "rhs", f"dy/dt = (q̇, u̇), shape ({n_q + n_u},): q̇ = N(q, u, t) and M u̇ = F by LU with pivoting.\n\n"
        "Returns 0, or j > 0 when pivot j of M is zero (M singular here); `out` is then invalid.",
        ARGS, stores, mapping, loads,
    )
    after = ["_status = lu_solve(_kkt)", "if _status:", f"{INDENT}return _status"]
    after += [f"out[{n_q + i}] = _kkt[{i}, {n_u}]" for i in range(n_u)] + ["return 0"]
    return kernel, _function(kernel, before=[f"_kkt = np.zeros(({n_u}, {n_u + 1}))"], after=after)


def _partial_stores(form: FirstOrderForm, variables) -> list:
    """The stores of ∂(N, u̇)/∂x, x = `variables` (the state (q, u), or the parameters), before the LU solve:
    rows ∂N/∂x into ``_jac`` (row-major, len(x) wide), M into ``_lu``, and the block
    ∂(F − M ū)/∂x |_{ū = u̇} (`acceleration_partials`) into the rows below, which ``lu_solve_matrix`` then
    overwrites with M⁻¹ times themselves."""
    n_q, n_u, width = form.n_q, form.n_u, len(variables)
    kinematic = form.N.jacobian(sp.Matrix(variables)) if width else sp.zeros(n_q, 0)
    block = acceleration_partials(form.M, form.F, acceleration_symbols(form), variables)
    stores = [(jacobian_entry(i, j, width), kinematic[i, j])
              for i in range(n_q) for j in range(width) if kinematic[i, j] != 0]
    stores += [(f"_lu[{i}, {j}]", form.M[i, j]) for i in range(n_u) for j in range(n_u) if form.M[i, j] != 0]
    stores += [(jacobian_entry(n_q + i, j, width), block[i][j])
               for i in range(n_u) for j in range(width) if block[i][j] != 0]
    return stores


def _rhs_jacobian(form: FirstOrderForm) -> tuple:
    """The exact Jacobian of y' = (N(q, u, t), u̇), M u̇ = F: ``rhs_with_jacobian`` (f into ``ydot`` too),
    ``rhs_jacobian`` (the same, f dropped: `lagcomp.ir.Delegate`), and their source.

    Differentiating M u̇ = F along y = (q, u) gives M ∂u̇/∂y = ∂F/∂y − ∂(M ū)/∂y |_{ū = u̇}, with
    symbols ū for the accelerations held fixed while differentiating (`acceleration_partials`), bound
    to the u̇ that `rhs` solved.  The kernel calls `rhs` (returning its status when not 0), writes
    ∂N/∂y and that block (into `out` seen flat as ``_jac``, as `lagcomp.ir.JacobianSolve` explains), then
    overwrites the block with M⁻¹ times itself (``lu_solve_matrix``: the pivoting of `rhs`'s ``lu_solve``).
    One CSE for ∂N/∂y, M and the block.
    """
    n_q, n_u = form.n_q, form.n_u
    size = n_q + n_u
    mapping, loads = _bindings(form, reactions=True)  # binds ū (acceleration_symbols) to _ydot[n_q:]
    stores = _partial_stores(form, (*form.q, *form.u))
    kernel = cse_kernel(
        "rhs_with_jacobian",
        RHS_WITH_JACOBIAN_DOC +
        "Rows ∂N/∂y of q̇ = N(q, u, t), then ∂u̇/∂y = M⁻¹ (∂F/∂y − ∂(M ū)/∂y |ū=u̇) (u̇ from `rhs`).\n"
        "Returns 0, or j > 0 as `rhs` does, or when this LU of M finds pivot j zero (then `rhs` was\n"
        "within rounding of its threshold); `out` is then invalid.",
        WITH_JACOBIAN_ARGS, stores, mapping, loads,
    )
    before = ["_ydot = ydot", "_status = rhs(t, y, p, _ydot)", "if _status:", f"{INDENT}return _status",
              f"_jac = out.reshape({size * size})", "_jac[:] = 0.0", f"_lu = np.zeros(({n_u}, {n_u}))"]
    after = [f"return lu_solve_matrix(_lu, out[{n_q}:])"]
    only = jacobian_only(size)
    source = _function(kernel, before=before, after=after) + _function(only, after=[delegated_call(only.solve)])
    return kernel, only, source


def _rhs_parameter_jacobian(form: FirstOrderForm) -> tuple:
    """The exact parameter Jacobian ∂(N, u̇)/∂p of y' = (N(q, u, t, p), u̇), M u̇ = F, as a kernel and its source.

    As `_rhs_jacobian` along the parameters: M ∂u̇/∂p = ∂F/∂p − ∂(M ū)/∂p |_{ū = u̇}, the rows ∂N/∂p
    above (q̇ = N may depend on parameters: a wheel's radius), one CSE, one LU of M (``lu_solve_matrix``).
    """
    n_q, n_u = form.n_q, form.n_u
    size, width = n_q + n_u, len(form.parameters)
    mapping, loads = _bindings(form, reactions=True)  # binds ū (acceleration_symbols) to _ydot[n_q:]
    stores = _partial_stores(form, form.parameters)
    kernel = cse_kernel(
        "rhs_parameter_jacobian",
        RHS_PARAMETER_JACOBIAN_DOC +
        "Rows ∂N/∂p of q̇ = N(q, u, t), then ∂u̇/∂p = M⁻¹ (∂F/∂p − ∂(M ū)/∂p |ū=u̇) (u̇ from `rhs`).\n"
        "Returns 0, or j > 0 as `rhs` does, or when this LU of M finds pivot j zero (then `rhs` was\n"
        "within rounding of its threshold); `out` is then invalid.",
        ARGS, stores, mapping, loads,
    )
    before = [f"_ydot = np.empty({size})", "_status = rhs(t, y, p, _ydot)", "if _status:", f"{INDENT}return _status",
              f"_jac = out.reshape({size * width})", "_jac[:] = 0.0", f"_lu = np.zeros(({n_u}, {n_u}))"]
    after = [f"return lu_solve_matrix(_lu, out[{n_q}:])"]
    return kernel, _function(kernel, before=before, after=after)


def _plain_kernels(form: FirstOrderForm, energy, mapping, loads) -> list:
    n_q, n_u = form.n_q, form.n_u
    n_h, n_v = form.Phi.rows, form.Psi.rows
    at_rest = {u: 0 for u in form.u}
    A = form.Psi.jacobian(sp.Matrix(form.u)) if n_v else sp.zeros(0, n_u)
    J = form.Phi.jacobian(sp.Matrix(form.q)) if n_h else sp.zeros(0, n_q)
    specs = [
        ("kinematics", f"q̇ = N(q, u, t), shape ({n_q},), into `out`.", ARGS,
         [(f"out[{i}]", form.N[i]) for i in range(n_q)]),
        ("energy", "T + V" + ("" if energy is not None else ": not available for this model (NaN)") + ".",
         ARGS[:3], [("return", sp.nan if energy is None else energy)]),
        ("constraint_residuals", f"Φ ({n_h} configuration constraints), then Ψ ({n_v} velocity constraints).",
         ARGS, [(f"out[{i}]", form.Phi[i]) for i in range(n_h)] + [(f"out[{n_h + i}]", form.Psi[i])
                                                                   for i in range(n_v)]),
        ("configuration_jacobian", f"∂Φ/∂q, shape ({n_h}, {n_q}), into `out`.", ARGS,
         [(f"out[{i}, {j}]", J[i, j]) for i in range(n_h) for j in range(n_q)]),
        ("velocity_constraint_matrix", f"[∂Ψ/∂u | Ψ(u = 0)], shape ({n_v}, {n_u + 1}), into `out`.", ARGS,
         [(f"out[{i}, {j}]", A[i, j]) for i in range(n_v) for j in range(n_u)]
         + [(f"out[{i}, {n_u}]", form.Psi[i].xreplace(at_rest)) for i in range(n_v)]),
    ]
    if n_h + n_v:   # (what the check of a start divides by: `lagcomp.integrate.constraints`)
        specs.append(("constraint_residual_scales", (f"Rounding scales, shape ({n_h + n_v},), of the entries of "
                                                     "`constraint_residuals` (lagcomp.codegen.rounding_scale)."), ARGS,
                      [(f"out[{i}]", rounding_scale(row)) for i, row in enumerate([*form.Phi, *form.Psi])]))
    return [cse_kernel(name, doc, args, stores, mapping, loads) for name, doc, args, stores in specs]


def _reactions(form: FirstOrderForm, names, expressions, mapping, loads) -> tuple:
    n = form.n_q + form.n_u
    kernel = cse_kernel(
        "reactions", f"Noncontributing forces {tuple(names)} at the u̇ of `rhs`, into `out`.\n"
        "Returns 0, or the status of `rhs` when M is singular.",
        ARGS, [(f"out[{i}]", e) for i, e in enumerate(expressions)], mapping, loads,
    )
    before = [f"_ydot = np.empty({n})", "_status = rhs(t, y, p, _ydot)", "if _status:", f"{INDENT}return _status"]
    return kernel, _function(kernel, before=before, after=["return 0"]) + _REACTIONS_ALONG


_REACTIONS_ALONG = '''

@njit(cache=True, error_model="numpy")
def reactions_along(ts, ys, p, out):
    """The auxiliary reactions at each saved row, shape (m, n_r); returns i + 1 if rhs fails at row i."""
    for k in range(ts.shape[0]):
        if reactions(ts[k], ys[k], p, out[k]):
            return k + 1
    return 0
'''

_NO_EVENTS = '''

@njit(cache=True, error_model="numpy")
def event_values(t, y, p, out):
    """No events: this model declares none."""
    pass


@njit(cache=True, error_model="numpy")
def event_gradients(t, y, p, out):
    """No events: this model declares none."""
    return 0
'''

_HOOKS = '''

@njit(cache=True, error_model="numpy")
def constraint_residual(t, y, p):
    """Largest |Φ| and |Ψ| (0.0 without constraints)."""
    if HOLONOMIC_COUNT + VELOCITY_CONSTRAINT_COUNT == 0:
        return 0.0
    r = np.empty(HOLONOMIC_COUNT + VELOCITY_CONSTRAINT_COUNT)
    constraint_residuals(t, y, p, r)
    return np.max(np.abs(r))


@njit(cache=True, error_model="numpy")
def project(t, y, p):
    """Move y onto Φ = 0 (Gauss-Newton on q) and Ψ = 0 (least change of u), in place.

    Returns 0, or j > 0 when a Gram matrix is singular (dependent constraints).
    """
    n_q, n_u = COORDINATE_COUNT, SPEED_COUNT
    n_h, n_v = HOLONOMIC_COUNT, VELOCITY_CONSTRAINT_COUNT
    if n_h:
        J = np.empty((n_h, n_q))
        r = np.empty(n_h + n_v)
        mu = np.empty(n_h)
        rows = np.arange(n_h)
        for _ in range(PROJECTION_ITERATIONS):
            constraint_residuals(t, y, p, r)
            configuration_jacobian(t, y, p, J)
            rhs_ = r[:n_h].copy()
            status = gram_solve(J, rows, n_q, rhs_, mu)
            if status:
                return status
            step, size = 0.0, 0.0
            for c in range(n_q):
                d = 0.0
                for i in range(n_h):
                    d += J[i, c] * mu[i]
                y[c] -= d
                step = max(step, abs(d))
                size = max(size, abs(y[c]))
            if step <= 4e-16 * size:
                break
    if n_v:
        a = np.empty((n_v, n_u + 1))
        velocity_constraint_matrix(t, y, p, a)
        rhs_ = np.empty(n_v)
        mu = np.empty(n_v)
        for i in range(n_v):
            s = a[i, n_u]
            for c in range(n_u):
                s += a[i, c] * y[n_q + c]
            rhs_[i] = s
        status = gram_solve(a, np.arange(n_v), n_u, rhs_, mu)
        if status:
            return status
        for c in range(n_u):
            d = 0.0
            for i in range(n_v):
                d += a[i, c] * mu[i]
            y[n_q + c] -= d
    return 0


@njit(cache=True, error_model="numpy")
def observables(ts, ys, p, energy_out, energy_function_out, momenta_out):
    """Along saved rows: T + V (twice: Kane models have no separate energy function); no momenta (NaN)."""
    for k in range(ts.shape[0]):
        energy_out[k] = energy(ts[k], ys[k], p)
        energy_function_out[k] = energy_out[k]
        momenta_out[k, :] = np.nan


@njit(cache=True, error_model="numpy")
def kinematics_along(ts, ys, p, out):
    """q̇ at each saved row, shape (m, n_q)."""
    for k in range(ts.shape[0]):
        kinematics(ts[k], ys[k], p, out[k])
'''


def _sizes(form: FirstOrderForm) -> str:
    """The module constants the hooks read: the sizes of q, u, Φ and Ψ, and the projection's iteration limit."""
    return (
        "\n\n#: Coordinates q, speeds u, configuration constraints Φ, velocity constraints Ψ.\n"
        f"COORDINATE_COUNT, SPEED_COUNT = {form.n_q}, {form.n_u}\n"
        f"HOLONOMIC_COUNT, VELOCITY_CONSTRAINT_COUNT = {form.Phi.rows}, {form.Psi.rows}\n"
        "#: Gauss-Newton corrections `project` makes at most on Φ (two or three reach rounding level).\n"
        f"PROJECTION_ITERATIONS = {PROJECTION_ITERATIONS}\n"
    )


def _events(form: FirstOrderForm, events, resets, mapping, loads) -> tuple:
    """The ``event_values``, ``event_gradients`` and ``event_reset`` kernels (g of each event, its partials, the
    state after it, into `out`) and their source; stubs without events."""
    reset = event_reset_kernel(tuple(name for name, _ in events), resets, form.n_q + form.n_u, mapping, loads)
    if not events:
        return (reset,), _NO_EVENTS + kernel_source(reset)
    names = tuple(name for name, _ in events)
    values = cse_kernel("event_values", f"Event functions g = {names} at one state, into `out`.", ARGS,
                     [(f"out[{i}]", g) for i, (_, g) in enumerate(events)], mapping, loads)
    size = form.n_q + form.n_u
    stores = []
    for i, (_, g) in enumerate(events):
        stores += [(f"out[{i}, {j}]", g.diff(v)) for j, v in enumerate((*form.q, *form.u))]
        stores.append((f"out[{i}, {size}]", sum((g.diff(s) for s in g.free_symbols if s.name == t.name), sp.S.Zero)))
        stores += [(f"out[{i}, {size + 1 + j}]", g.diff(s)) for j, s in enumerate(form.parameters)]
    gradients = cse_kernel(
        "event_gradients",
        f"Partials of the event functions {names}, shape ({len(names)}, {size + 1 + len(form.parameters)}), into\n"
        f"`out`: row i is event i, columns ∂g_i/∂y_j (y = (q, u), {size} of them), then ∂g_i/∂t, then ∂g_i/∂p_j.\n"
        "Returns 0.",
        ARGS, stores, mapping, loads)
    return ((values, gradients, reset),
            _function(values) + _function(gradients, after=["return 0"]) + kernel_source(reset))


def _header(name: str, form: FirstOrderForm, reaction_names, kernels) -> str:
    locals_ = ", ".join(f"_q{i}={c}" for i, c in enumerate(form.coordinate_names))
    locals_ += "; " + ", ".join(f"_u{i}={c}" for i, c in enumerate(form.speed_names))
    params = ", ".join(f"_p{k}={s.name}" for k, s in enumerate(form.parameters)) or "(none)"
    return (
        f'"""Kernels of the Kane model {name!r}, generated by lagcomp {__version__}. Do not edit.\n\n'
        f"State       y = (q, u), n_q = {form.n_q}, n_u = {form.n_u}: {locals_}\n"
        f"Parameters  p: {params}\n"
        f"Constraints Φ: {form.Phi.rows}, Ψ: {form.Psi.rows}; reactions {tuple(reaction_names)}\n\n"
        "Equations: q̇ = N(q, u, t), M u̇ = F as sympy's KanesMethod forms them (lagcomp.mechanics.kane).\n"
        '"""\n\nimport math\n\nimport numpy as np\nfrom numba import njit\n\n'
        # rhs and rhs_jacobian solve by LU, project by Gram matrices
        + support_imports(kernel_support_names(kernels) | {"lu_solve", "lu_solve_matrix", "gram_solve"})
    )


def emit_kane(name: str, form: FirstOrderForm, energy=None, reaction_names=(), reactions=None,
              events=(), resets=()) -> tuple[str, dict]:
    """The module source for a Kane model, and the operation count of each kernel after CSE.

    `events` are (name, g) pairs, g over the plain symbols of `form` (`lagcomp.mechanics.kane.kane_events`);
    `resets` their resets, ((state index, value), ...) per event (`lagcomp.mechanics.kane.kane_resets`).
    The module ends with the equations as LaTeX and text (``EQUATIONS``, `lagcomp.codegen.latex`).
    """
    mapping, loads = _bindings(form, bool(reaction_names))
    rhs, rhs_source = _rhs(form, mapping, loads)
    combined, jacobian, jacobian_source = _rhs_jacobian(form)
    parameter_jacobian, parameter_jacobian_source = _rhs_parameter_jacobian(form)
    kernels = [rhs, combined, jacobian, parameter_jacobian] + _plain_kernels(form, energy, mapping, loads)
    parts = [rhs_source, jacobian_source, parameter_jacobian_source] + [_function(k) for k in kernels[4:]]
    parts.append("\n\nenergy_function = energy\n")
    if reaction_names:
        kernel, source = _reactions(form, reaction_names, reactions, mapping, loads)
        kernels.append(kernel)
        parts.append(source)
    event_kernels, event_source = _events(form, events, resets or ((),) * len(events), mapping, loads)
    kernels += event_kernels
    parts.append(event_source)
    geometry = no_geometry_kernel()  # a Kane model's bodies are not drawn yet: size 0
    kernels.append(geometry)
    parts.append(_function(geometry) + module_constants(geometry))
    parts.append(_sizes(form) + _HOOKS)
    parts.append(equations_source(kane_equations(form, energy)))
    return _header(name, form, reaction_names, kernels) + "".join(parts), {k.name: k.operation_count for k in kernels}
