"""Emit the repeated steps of a straight-line program once, as shared helpers: numba's compile time grows with the
code it types, not with the code it runs.

numba types and lowers each arithmetic operation of a kernel on its own (about 1 ms each on the 2-core machine),
so a 100-link chain's articulated-body ``rhs`` (11,000 operations) took 17 s to compile, though its links are all
alike.  A recursion over a tree forms the same quantities node after node: each node's share of a pass (a *step*,
`lagcomp.multibody.program.Program.step`) is the same little program over its own inputs.  `outline` finds the
steps that are the same up to the names of their inputs, emits each such program once as a `lagcomp.ir.Helper`
(``@njit(forceinline=True)``: numba compiles it once, LLVM inlines it at every call, so the machine code is the
straight-line code it replaces) and calls it at each step with that step's inputs.  A step that occurs once stays
inline.  LLVM's optimization of the inlined copies then grows with the operations the kernel evaluates: past
`INLINE_LIMIT` of them the helpers are called instead (a 100-link chain's rhs: 2.2 s less to compile, 12% slower).

Two steps are the same when renaming their inputs (in the order the step first reads them) and their own locals
(in the order it forms them) gives the same assignments and the same locals read after the step.  The renaming
keeps each sum's terms and each product's factors in the order the step holds them (`_renamed`), and two steps are
the same only when those orders agree too: the result is the same arithmetic in the same order, and the kernel
computes the same bits.  (The program's locals are numbered with a fixed width, so the steps of identical nodes
list their terms alike; so do forward mode's derivatives, grouped by step and direction,
`lagcomp.multibody.forward_mode`.)
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import replace

import sympy as sp

from lagcomp.ir import Helper, HelperCall

#: The least number of identical steps worth a helper.
MIN_CALLS = 2
#: The most operations a kernel evaluates with its helpers inlined (`lagcomp.ir.Helper.inline`).
INLINE_LIMIT = 8000


def outline(kernel_name: str, temps, step_of: dict, outputs) -> tuple[tuple, tuple[Helper, ...]]:
    """The temporaries of a kernel with its repeated steps replaced by calls, and the helpers they call.

    Parameters
    ----------
    kernel_name : str
        Names the helpers (``_<kernel_name>_step<k>``).
    temps : sequence of (Symbol, Expr)
        The kernel's assignments in order (`lagcomp.multibody.program.Program.live`).
    step_of : dict
        The step of each local (`lagcomp.multibody.program.Program.step_of`); None: no step.
    outputs : sequence of Expr
        What the kernel stores: the locals they read are read after every step.

    Returns
    -------
    temps : tuple of (str, Expr)
        For `lagcomp.ir.Kernel`: assignments by local name, and `lagcomp.ir.HelperCall` s whose local is the
        comma-separated names of their results.
    helpers : tuple of Helper
    """
    runs = _runs(temps, step_of)
    readers = _readers(temps, runs, outputs)
    forms = [_canonical(temps, run, readers) if key is not None else None for key, run in runs]
    helper_of = _called(kernel_name, forms)
    helpers = list({h.name: h for h in helper_of.values()}.values())
    evaluated = sum(sp.count_ops(temps[i][1]) for r, (_, run) in enumerate(runs) if r not in helper_of for i in run)
    evaluated += sum(h.operation_count for h in helper_of.values())
    if evaluated > INLINE_LIMIT:
        called = {h.name: replace(h, inline=False) for h in helpers}
        helpers = list(called.values())
        helper_of = {r: called[h.name] for r, h in helper_of.items()}
    out = []
    for r, (_, run) in enumerate(runs):
        helper = helper_of.get(r)
        if helper is None:
            out += [(temps[i][0].name, temps[i][1]) for i in run]
            continue
        returns = forms[r][2]
        results = ", ".join(temps[run[j]][0].name for j in returns) + ("," if len(returns) == 1 else "")
        out.append((results, HelperCall(sp.Symbol(helper.name), *_inputs(temps, run))))
    return tuple(out), tuple(helpers)


def _called(kernel_name: str, forms) -> dict:
    """{run index: the Helper it calls} for the runs whose canonical form (`_canonical`; None: no step) occurs at
    least `MIN_CALLS` times and hands something back."""
    groups = defaultdict(list)
    for r, form in enumerate(forms):
        if form is not None and form[2]:
            groups[form].append(r)
    helper_of, count = {}, 0
    for (body, inputs, returns), members in groups.items():
        if len(members) < MIN_CALLS:
            continue
        helper = Helper(name=f"_{kernel_name}_step{count}", args=tuple(f"_a{k}" for k in range(inputs)),
                        temps=tuple((f"_t{j}", e) for j, e in enumerate(body)),
                        returns=tuple(f"_t{j}" for j in returns))
        count += 1
        helper_of.update(dict.fromkeys(members, helper))
    return helper_of


def _runs(temps, step_of: dict) -> list[tuple[object, list[int]]]:
    """The temps as consecutive runs of one step each: (step key or None, indices); a temp of no step is a run of
    its own."""
    runs = []
    for i, (local, _) in enumerate(temps):
        key = step_of.get(local)
        if key is not None and runs and runs[-1][0] == key:
            runs[-1][1].append(i)
        else:
            runs.append((key, [i]))
    return runs


def _readers(temps, runs, outputs) -> set:
    """The locals read outside the run that forms them (by a later run or by the stores)."""
    run_of = {temps[i][0]: r for r, (_, run) in enumerate(runs) for i in run}
    read = set().union(*(sp.sympify(e).free_symbols for e in outputs)) if outputs else set()
    for r, (_, run) in enumerate(runs):
        for i in run:
            read |= {s for s in temps[i][1].free_symbols if run_of.get(s, r) != r}
    return read


def _ordered_symbols(expr) -> list:
    """The symbols of `expr` in the order a preorder walk over its (canonically ordered) arguments meets them."""
    seen, order = set(), []
    for node in sp.preorder_traversal(expr):
        if node.is_Symbol and node not in seen:
            seen.add(node)
            order.append(node)
    return order


def _canonical(temps, run, readers) -> tuple:
    """The run's program with its inputs renamed ``_a<k>`` and its locals ``_t<j>``: (assignments, number of
    inputs, positions of the locals read after it)."""
    names, inputs = {}, 0
    own = {temps[i][0] for i in run}
    body = []
    for j, i in enumerate(run):
        local, expr = temps[i]
        for s in _ordered_symbols(expr):
            if s not in names and s not in own:
                names[s] = sp.Symbol(f"_a{inputs}", real=True)
                inputs += 1
        body.append(_renamed(expr, names))
        names[local] = sp.Symbol(f"_t{j}", real=True)
    returns = tuple(j for j, i in enumerate(run) if temps[i][0] in readers)
    return tuple(body), inputs, returns


def _renamed(expr, names: dict):
    """`expr` with its symbols renamed by `names`, each sum's terms and each product's factors kept in the order
    `expr` holds them (not sorted again by the new names, as ``xreplace`` would): the helper then adds and
    multiplies in the order of the inline code it replaces, so it computes the same bits, and two runs are the same
    only when they compute in the same order."""
    if expr.is_Symbol:
        return names.get(expr, expr)
    if not expr.args:
        return expr
    args = [_renamed(a, names) for a in expr.args]
    try:
        return expr.func(*args, evaluate=False)
    except TypeError:   # (a node without the keyword: a Piecewise's pair)
        return expr.func(*args)


def _inputs(temps, run) -> list:
    """The run's inputs, in the order `_canonical` numbers them."""
    own, seen, order = {temps[i][0] for i in run}, set(), []
    for i in run:
        for s in _ordered_symbols(temps[i][1]):
            if s not in own and s not in seen:
                seen.add(s)
                order.append(s)
    return order


def evaluated_operations(kernel) -> int:
    """The arithmetic operations one call of `kernel` (`lagcomp.ir.Kernel`) performs: its own and, for each call
    of a helper, the helper's (`Kernel.operation_count` counts each helper once: what numba compiles)."""
    helpers = {h.name: h.operation_count for h in kernel.helpers}
    total = sum(sp.count_ops(e) for _, e in kernel.stores)
    for _, expr in kernel.temps:
        total += helpers[expr.args[0].name] if isinstance(expr, HelperCall) else sp.count_ops(expr)
    return int(total)
