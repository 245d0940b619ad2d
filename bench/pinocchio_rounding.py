"""Which side rounds on a long ball-jointed chain, and why: lagcomp's q̈ and Pinocchio's ABA against the exact q̈
(issue 39's q̈ check, docs/benchmarks.md "Multibody at scale").

For each ball chain (`bench.bench_scale`'s ``spherical_N``, its parameters) at the scale bench's 5 states
(`bench.bench_scale.states`), the normwise error max |Δq̈| / max |q̈| (`bench.bench_scale.relative`), in lagcomp's
coordinates (Pinocchio's converted by `lagcomp.multibody.pinocchio_peer`), of:

* lagcomp's ``rhs``; Pinocchio's ``aba``; Pinocchio's M⁻¹ (τ − h) (`bench.bench_scale.pinocchio_solved`: CRBA,
  RNEA and an LU solve, backward stable);
* `replica_aba`: Pinocchio's ABA (local convention, ``JointModelSpherical::calc_aba``) redone in numpy, as it is
  and with each articulated inertia made symmetric, (I + Iᵀ) / 2, as it is summed into the parent;

against the exact q̈: `lagcomp.accuracy.tree_reference`'s M and F in 25 digits, solved in 50 (``--exact``: a minute
or two a state for 90 DOF), else Pinocchio's M⁻¹ (τ − h) (within about cond(M) ε of it: too coarse to rank
lagcomp's ``rhs`` on an ill-conditioned chain, enough for errors far above cond(M) ε).  Also cond(M) (2-norm, of
the reference's M with ``--exact``, else Pinocchio's) and the asymmetry max |I − Iᵀ| of Pinocchio's own
articulated inertia of the root's child (``data.Yaba`` after ``aba``), which is exact-arithmetic zero.

    python -m bench.pinocchio_rounding [--systems spherical_10 spherical_30] [--exact]
"""

from __future__ import annotations

import argparse

import numpy as np

from bench import bench_scale
from bench.harness import Table

COLUMNS = ["system", "state", "cond(M)", "lagcomp rhs", "Pinocchio aba", "Pinocchio M⁻¹(τ − h)", "numpy ABA as Pinocchio's",
           "the same, inertias symmetrized", "Pinocchio's articulated inertia: max |I − Iᵀ|"]


def replica_aba(pin, model, data, q, v, tau, symmetric: bool) -> np.ndarray:
    """v̇ of a Pinocchio model whose joints are all ``JointModelSpherical``: Pinocchio's local-convention ABA
    (aba.hxx) in numpy, spatial vectors (linear, angular): a ball joint's U = I[:, 3:], D = U[3:], the articulated
    inertia I − U D⁻¹ Uᵀ moved into the parent as X* P X*ᵀ; `symmetric`: the parent's inertia then replaced by
    (I + Iᵀ) / 2, the only change."""
    pin.forwardKinematics(model, data, q, v)
    inertia, bias, product, U, Dinv, u = {}, {}, {}, {}, {}, np.array(tau, dtype=float)
    joints = range(1, model.njoints)
    rows = {i: slice(model.joints[i].idx_v, model.joints[i].idx_v + 3) for i in joints}
    for i in joints:
        inertia[i], velocity = model.inertias[i].matrix(), data.v[i]
        bias[i] = (velocity ^ pin.Force(inertia[i] @ velocity.vector)).vector
        product[i] = (velocity ^ pin.Motion(np.concatenate([np.zeros(3), v[rows[i]]]))).vector
    for i in reversed(joints):
        parent = model.parents[i]
        u[rows[i]] -= bias[i][3:]
        U[i] = inertia[i][:, 3:]
        Dinv[i] = np.linalg.inv(U[i][3:])
        if parent > 0:
            projected = inertia[i] - U[i] @ Dinv[i] @ U[i].T
            X = data.liMi[i].toDualActionMatrix()
            inertia[parent] = inertia[parent] + X @ projected @ X.T
            if symmetric:
                inertia[parent] = (inertia[parent] + inertia[parent].T) / 2
            bias[parent] = bias[parent] + X @ (bias[i] + projected @ product[i] + U[i] @ Dinv[i] @ u[rows[i]])
    acceleration, vdot = {0: -model.gravity.vector}, np.empty(model.nv)
    for i in joints:
        a = data.liMi[i].toDualActionMatrix().T @ acceleration[model.parents[i]] + product[i]
        vdot[rows[i]] = Dinv[i] @ (u[rows[i]] - U[i].T @ a)
        a[3:] += vdot[rows[i]]
        acceleration[i] = a
    return vdot


def exact(tree, y, p) -> tuple[np.ndarray, float]:
    """(q̈, cond(M)): `lagcomp.accuracy.tree_reference`'s M and F in 25 digits, solved in 50."""
    import mpmath

    from lagcomp.accuracy import tree_reference

    M, F = tree_reference(tree).mass_matrix_and_forcing(0.0, y, p, 25)
    with mpmath.workdps(50):
        solution = mpmath.lu_solve(mpmath.matrix(M), mpmath.matrix(F))
    return np.array([float(x) for x in solution]), float(np.linalg.cond(np.array([[float(x) for x in row]
                                                                                  for row in M])))


def rows(system: str, use_exact: bool) -> list:
    """The table's rows of one chain, one a state."""
    import pinocchio as pin

    import lagcomp as lc

    tree, values = bench_scale.build(system)
    model = lc.compile(tree, progress=False)
    p, n, out = model.parameter_vector(values), model.n, np.empty(2 * model.n)
    reference, state = bench_scale.pinocchio_peer(system, tree, values)
    data = reference.createData()
    found = []
    for k, y in enumerate(bench_scale.states(n)):
        q, v, tau, back = state(y)
        solved, condition = bench_scale.pinocchio_solved(pin, reference, data, q, v, tau)
        truth, condition = exact(tree, y, p) if use_exact else (back(solved), condition)
        model.kernels.rhs(0.0, y, p, out)
        aba = back(pin.aba(reference, data, q, v, tau))
        asymmetry = float(np.max(np.abs(data.Yaba[2] - data.Yaba[2].T))) if reference.njoints > 2 else 0.0
        errors = [out[n:], aba, back(solved), *(back(replica_aba(pin, reference, reference.createData(), q, v, tau, s))
                                              for s in (False, True))]
        found.append([system, k, f"{condition:.1e}", *(f"{bench_scale.relative(e, truth):.1e}" for e in errors),
                      f"{asymmetry:.1e}"])
    return found


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--systems", nargs="+", default=["spherical_10", "spherical_30"], help="ball chains")
    parser.add_argument("--exact", action="store_true", help="against the 25-digit reference (slow)")
    args = parser.parse_args(argv)
    against = ("the exact q̈ (`tree_reference`, 25 digits)" if args.exact
               else "Pinocchio's M⁻¹(τ − h) (within about cond(M) ε of the exact q̈)")
    table = Table("Which side rounds on a ball chain: max |Δq̈| / max |q̈| against " + against, COLUMNS,
                  note="Pinocchio's and the numpy ABAs' v̇ converted to lagcomp's coordinates (MRP rates).")
    for system in args.systems:
        for row in rows(system, args.exact):
            table.add(*row)
    print(table.markdown())


if __name__ == "__main__":
    main()
