"""Every tableau and composition against its defining conditions, to round-off.

The coefficients are float64 numbers; each is converted exactly to a 40-digit
mpmath number and the conditions are evaluated in that precision, so what is
left of a condition is the rounding of the stored coefficients alone (a
fraction of an ulp of the condition's size), and a coefficient wrong in its
15th digit fails.  An order claimed one too high fails by a margin of
10¹⁰ and more.

* Runge–Kutta methods: Butcher's conditions Σ b_i Φ_i(τ) = 1/γ(τ) for every
  rooted tree τ with up to p nodes (HNW I, sec. II.2).  The trees are generated,
  not listed by hand, and counted against OEIS A000081.
* Embedded error estimators: the error weights E (a difference of two weight
  vectors over the stages plus the FSAL stage) annihilate every tree up to the
  estimator's order q, and not all trees of q + 1 nodes.
* Gauss–Legendre: the simplifying conditions B(2s), C(s), D(s) that define the
  method, the nodes as zeros of the shifted Legendre polynomial, symplecticity
  b_i a_ij + b_j a_ji = b_i b_j, and the tree conditions up to order 2s.
* Symmetric compositions: with a generic symmetric basic method
  Φ_h = exp(hX₁ + h³X₃ + h⁵X₅ + h⁷X₇) (random integer matrices X_k, which
  satisfy no accidental relation at these degrees), the composition's Taylor
  series in h agrees with exp(hX₁) up to h^p and not at h^(p+1): the BCH order
  conditions, all of them, without listing them.  Then the local error of the
  compositions of the Störmer–Verlet step (lagcomp's basic method) on the
  pendulum, in 40-digit arithmetic, scales as h^(p+1).
"""

from __future__ import annotations

import functools

import mpmath as mp
import numpy as np
import pytest

from lagcomp.integrate.collocation import GAUSS1, GAUSS2, GAUSS3
from lagcomp.integrate.compositions import VERLET, YOSHIDA4, YOSHIDA6
from lagcomp.integrate.tableaux import BS3, DOP853, DOPRI5, RK4, TSIT5

DPS = 40
ULP = 2.0**-52
#: Allowed residual of a condition, in ulps of its size (measured: at most 0.19 ulp, DOPRI5's order-5 trees;
#: compositions at most 0.25 of their ulp unit, Yoshida 4's h⁴ term).
ULPS = 2
#: Gauss–Legendre's entries are float expressions like 2/9 − √15/15, up to 5.8 ulps from the correctly rounded
#: value (GAUSS3 A[0, 1]); the worst condition, C(2) of gauss3, is then 3.8 ulps of its size.
GAUSS_ULPS = 8


@pytest.fixture(autouse=True)
def _precision():
    with mp.workdps(DPS):
        yield


# -- rooted trees ----------------------------------------------------------------------
# A tree is the sorted tuple of its root's subtrees; the single node is ().


@functools.lru_cache(maxsize=None)
def trees(n: int) -> tuple:
    """All rooted trees with n nodes, each once (grown by a leaf from those with n − 1 nodes)."""
    if n == 1:
        return ((),)

    def grown(tree) -> list:
        out = [tuple(sorted(tree + ((),)))]
        for i, child in enumerate(tree):
            out += [tuple(sorted(tree[:i] + (g,) + tree[i + 1:])) for g in grown(child)]
        return out

    return tuple(sorted({g for tree in trees(n - 1) for g in grown(tree)}))


def nodes(tree) -> int:
    return 1 + sum(nodes(c) for c in tree)


def density(tree) -> int:
    """γ(τ) = |τ| Π γ(τ_k)."""
    return nodes(tree) * int(np.prod([density(c) for c in tree], dtype=object))


def test_tree_counts_are_oeis_a000081():
    assert [len(trees(n)) for n in range(1, 10)] == [1, 1, 2, 4, 9, 20, 48, 115, 286]
    assert {t: density(t) for t in trees(3)} == {(((),),): 6, ((), ()): 3}  # the tall tree [[•]], bushy [•, •]


class Weights:
    """Elementary weights Φ(τ) of a stage matrix A, exactly from its float64 entries (and with |A|)."""

    def __init__(self, A):
        self.A = [[mp.mpf(float(x)) for x in row] for row in np.asarray(A)]
        self.absA = [[abs(x) for x in row] for row in self.A]
        self._cache = {}

    def phi(self, tree, absolute=False):
        key = (tree, absolute)
        if key not in self._cache:
            A = self.absA if absolute else self.A
            v = [mp.mpf(1)] * len(A)
            for child in tree:
                w = self.phi(child, absolute)
                v = [vi * mp.fsum(a * wj for a, wj in zip(row, w)) for vi, row in zip(v, A)]
            self._cache[key] = v
        return self._cache[key]

    def condition(self, b, tree, target):
        """(|Σ b_i Φ_i(τ) − target|, its size Σ |b_i| Φ_i(τ; |A|) + |target|)."""
        b = [mp.mpf(float(x)) for x in b]
        value = mp.fsum(bi * p for bi, p in zip(b, self.phi(tree)))
        size = mp.fsum(abs(bi) * p for bi, p in zip(b, self.phi(tree, absolute=True))) + abs(target)
        return abs(value - target), size


def worst(weights: Weights, b, order: int, target) -> tuple[float, float]:
    """(largest residual in ulps of its size, largest residual · γ) over the trees with `order` nodes."""
    in_ulps, relative = 0.0, 0.0
    for tree in trees(order):
        goal = target(tree)
        residual, size = weights.condition(b, tree, goal)
        in_ulps = max(in_ulps, float(residual / size) / ULP)
        relative = max(relative, float(residual * density(tree)))
    return in_ulps, relative


def _butcher(tree):
    return mp.mpf(1) / density(tree)


def _zero(tree):
    return mp.mpf(0)


@pytest.mark.parametrize("tab", [RK4, DOPRI5, DOP853, TSIT5, BS3], ids=lambda t: t.name)
def test_runge_kutta_order_conditions(tab):
    weights = Weights(tab.A)
    for order in range(1, tab.order + 1):
        in_ulps, _ = worst(weights, tab.B, order, _butcher)
        assert in_ulps <= ULPS, (tab.name, order, in_ulps)
    # the order is not higher than claimed: some tree of p + 1 nodes fails (measured: γ·residual ≥ 0.02)
    _, relative = worst(weights, tab.B, tab.order + 1, _butcher)
    assert relative > 1e-3


def _with_fsal_stage(tab) -> np.ndarray:
    """The (s + 1)-stage matrix whose last row is B: the stage f(t + h, y_new) the error weights use."""
    s = tab.n_stages
    A = np.zeros((s + 1, s + 1))
    A[:s, :s], A[s, :s] = tab.A, tab.B
    return A


@pytest.mark.parametrize("tab, name, order", [(DOPRI5, "E", 4), (DOP853, "E5", 5), (DOP853, "E3", 3),
                                              (TSIT5, "E", 4), (BS3, "E", 2)],
                         ids=["DOPRI5-E", "DOP853-E5", "DOP853-E3", "TSIT5-E", "BS3-E"])
def test_error_estimators_have_their_order(tab, name, order):
    """E = b − b̂ with both of order ≥ q: Σ E_i Φ_i(τ) = 0 for every tree up to q nodes, not for all of q + 1.

    DOPRI5's estimate is 5(4); DOP853 combines a 5th- and a 3rd-order estimate into one of order 7
    (err5²/√(err5² + 0.01 err3²) ~ h⁸, scipy's `error_estimator_order` = 7 = `DOP853.error_order`).
    """
    E = getattr(tab, name)
    weights = Weights(_with_fsal_stage(tab))
    for n in range(1, order + 1):
        in_ulps, _ = worst(weights, E, n, _zero)
        assert in_ulps <= ULPS, (name, n, in_ulps)
    _, relative = worst(weights, E, order + 1, _zero)
    assert relative > 1e-3  # measured: 0.097 (DOPRI5 E), 0.017 (E5), 0.10 (E3)


@pytest.mark.parametrize("tab, order", [(DOPRI5, 4), (TSIT5, 4), (BS3, 3)], ids=lambda t: getattr(t, "name", ""))
def test_dense_output_order_conditions(tab, order):
    """The interpolant y + h Σ b_i(x) K_i, b_i(x) = Σ_m P[i, m] x^(m+1), has order `order` at every x:
    Σ b_i(x) Φ_i(τ) = x^|τ| / γ(τ) for the trees up to `order` nodes (HNW II.6), i.e. power by power,
    Σ_i P[i, m] Φ_i(τ) = [m + 1 = |τ|] / γ(τ); and not for all trees of order + 1 nodes at x = 1/2.
    Tsit5's polynomials are the paper's, given to about 19 digits: allowed 4 ulps of each condition's size."""
    weights = Weights(_with_fsal_stage(tab))
    for m in range(tab.P.shape[1]):
        for n in range(1, order + 1):
            for tree in trees(n):
                goal = mp.mpf(1) / density(tree) if n == m + 1 else mp.mpf(0)
                residual, size = weights.condition(tab.P[:, m], tree, goal)
                assert residual <= 2 * ULPS * ULP * size, (tab.name, m, tree, float(residual))
    half = tab.P @ (0.5 ** np.arange(1, tab.P.shape[1] + 1))
    _, relative = worst(weights, half, order + 1, lambda tree: mp.mpf(0.5) ** (order + 1) / density(tree))
    assert relative > 1e-4


# -- Gauss–Legendre collocation --------------------------------------------------------


def _mp(values):
    return [mp.mpf(float(v)) for v in np.ravel(values)]


def _within(residual, size, what):
    assert residual <= GAUSS_ULPS * ULP * size, (what, float(residual / size) / ULP)


@pytest.mark.parametrize("method", [GAUSS1, GAUSS2, GAUSS3], ids=lambda m: m.name)
def test_gauss_legendre_simplifying_conditions(method):
    """B(2s): Σ b_i c_i^(k−1) = 1/k, k ≤ 2s; C(s): Σ_j a_ij c_j^(k−1) = c_i^k/k, k ≤ s;
    D(s): Σ_i b_i c_i^(k−1) a_ij = b_j (1 − c_j^k)/k, k ≤ s (HLW II.1.3, HNW II.7)."""
    s = method.C.size
    assert method.order == 2 * s
    A = [_mp(row) for row in method.A]
    b, c = _mp(method.B), _mp(method.C)
    for k in range(1, 2 * s + 1):
        terms = [bi * ci ** (k - 1) for bi, ci in zip(b, c)]
        _within(abs(mp.fsum(terms) - mp.mpf(1) / k), mp.fsum(abs(x) for x in terms) + mp.mpf(1) / k, f"B({k})")
    _, relative = worst(Weights(method.A), method.B, 2 * s + 1, _butcher)  # not B(2s + 1): order exactly 2s
    assert relative > 1e-3
    for k in range(1, s + 1):
        for i in range(s):
            terms = [a * cj ** (k - 1) for a, cj in zip(A[i], c)]
            _within(abs(mp.fsum(terms) - c[i] ** k / k), mp.fsum(abs(x) for x in terms) + c[i] ** k / k, f"C({k})")
        for j in range(s):
            terms = [b[i] * c[i] ** (k - 1) * A[i][j] for i in range(s)]
            goal = b[j] * (1 - c[j] ** k) / k
            _within(abs(mp.fsum(terms) - goal), mp.fsum(abs(x) for x in terms) + abs(goal), f"D({k})")


@pytest.mark.parametrize("method", [GAUSS1, GAUSS2, GAUSS3], ids=lambda m: m.name)
def test_gauss_legendre_nodes_symplecticity_and_trees(method):
    s = method.C.size
    A = [_mp(row) for row in method.A]
    b, c = _mp(method.B), _mp(method.C)
    for ci in c:  # zeros of the shifted Legendre polynomial P_s(2c − 1); |P_s'| ≤ s(s+1)/2 · 2 on [0, 1]
        assert abs(mp.legendre(s, 2 * ci - 1)) <= GAUSS_ULPS * ULP * s * (s + 1)  # measured ≤ 0.37 ulp
    for i in range(s):
        for j in range(s):
            terms = (b[i] * A[i][j], b[j] * A[j][i], b[i] * b[j])
            _within(abs(terms[0] + terms[1] - terms[2]), sum(abs(x) for x in terms), "symplecticity")
    weights = Weights(method.A)
    for order in range(1, 2 * s + 1):
        in_ulps, _ = worst(weights, method.B, order, _butcher)
        assert in_ulps <= GAUSS_ULPS, (method.name, order, in_ulps)  # measured ≤ 0.67 ulp


# -- symmetric compositions -------------------------------------------------------------

DEGREE = 8  # Taylor coefficients h^0 .. h^8 (order 6 needs 7 to show it is not 7)


def _product(a, b):
    """Product of two truncated power series in h (lists of N × N mpmath matrices, h^0 .. h^DEGREE)."""
    n = a[0].rows
    out = [mp.zeros(n, n) for _ in range(DEGREE + 1)]
    for i in range(DEGREE + 1):
        for j in range(DEGREE + 1 - i):
            out[i + j] += a[i] * b[j]
    return out


def _exp(y):
    """exp of a truncated power series with y[0] = 0."""
    n = y[0].rows
    out = [mp.eye(n)] + [mp.zeros(n, n) for _ in range(DEGREE)]
    term = list(out)
    for m in range(1, DEGREE + 1):
        term = _product(term, y)
        out = [o + t / mp.factorial(m) for o, t in zip(out, term)]
    return out


@functools.lru_cache(maxsize=1)
def _generators():
    rng = np.random.default_rng(7)
    return {k: mp.matrix(rng.integers(-3, 4, (4, 4)).tolist()) for k in (1, 3, 5, 7)}


def _basic_method(X, weight):
    """Taylor series of Φ_{wh} = exp(wh X₁ + (wh)³X₃ + (wh)⁵X₅ + (wh)⁷X₇): any symmetric 2nd-order method."""
    y = [mp.zeros(4, 4) for _ in range(DEGREE + 1)]
    for k in (1, 3, 5, 7):
        y[k] = weight**k * X[k]
    return _exp(y)


def _composition_minus_flow(weights, degree: int) -> list:
    """Taylor coefficients h^0 .. h^degree of Ψ_h − exp(hX₁) for the composition with these substep weights."""
    X = _generators()
    psi = [mp.eye(4)] + [mp.zeros(4, 4) for _ in range(DEGREE)]
    for w in weights:
        psi = _product(_basic_method(X, w), psi)
    exact = _exp([mp.zeros(4, 4), X[1]] + [mp.zeros(4, 4)] * (DEGREE - 1))
    return [p - e for p, e in zip(psi, exact)][: degree + 1]


def composition_defects(weights, degree: int) -> list[float]:
    """‖h^k coefficient of Ψ_h − exp(hX₁)‖ in units of the change one ulp in the weights makes to it.

    The unit is the largest change over four random-sign perturbations w_i (1 ± 2⁻⁵²) of every weight:
    what rounding the weights to float64 can do (0 for k = 0, where nothing can change).
    """
    stored = [mp.mpf(float(w)) for w in weights]
    defects = _composition_minus_flow(stored, degree)
    unit = [mp.mpf(0)] * (degree + 1)
    for signs in np.random.default_rng(3).choice([-1, 1], (4, len(stored))):
        moved = _composition_minus_flow([w * (1 + int(si) * mp.mpf(ULP)) for w, si in zip(stored, signs)], degree)
        unit = [max(u, mp.mnorm(m - d, 1)) for u, m, d in zip(unit, moved, defects)]
    return [float(mp.mnorm(d, 1) / u) if u else float(mp.mnorm(d, 1)) for d, u in zip(defects, unit)]


@pytest.mark.parametrize("composition", [VERLET, YOSHIDA4, YOSHIDA6], ids=lambda c: c.name)
def test_symmetric_composition_order_conditions(composition):
    """All order conditions up to p hold to round-off; at p + 1 the composition differs (order exactly p).

    Measured, in ulps as `composition_defects` counts them: Verlet 0; Yoshida 4 ≤ 0.25; Yoshida 6 ≤ 0.11
    with its weights refined to double precision (Yoshida's published 15 digits left up to 9.5).
    """
    p = composition.order
    defects = composition_defects(composition.weights, p + 1)
    assert max(defects[: p + 1]) <= ULPS, defects
    assert defects[p + 1] > 1e10, defects


def test_yoshida4_is_the_triple_jump():
    """Σ w = 1, Σ w³ = 0 (Yoshida 1990): the only order-4 conditions for three symmetric substeps."""
    w = _mp(YOSHIDA4.weights)
    assert abs(mp.fsum(w) - 1) <= ULP
    assert abs(mp.fsum(x**3 for x in w)) <= ULPS * ULP * mp.fsum(abs(x) ** 3 for x in w)


def _pendulum_flow():
    """The exact flow of q̈ = −sin q from (1, 0.5), by mpmath's Taylor-series ODE solver at 40 digits."""
    return mp.odefun(lambda t, y: [y[1], -mp.sin(y[0])], 0, [mp.mpf(1), mp.mpf("0.5")])


def _composed_verlet_step(weights, h):
    """lagcomp's composition: kick–drift–kick Verlet substeps of sizes w_i h, on H = p²/2 − cos q."""
    q, p = mp.mpf(1), mp.mpf("0.5")
    for w in weights:
        sub = mp.mpf(float(w)) * h
        p -= sub / 2 * mp.sin(q)
        q += sub * p
        p -= sub / 2 * mp.sin(q)
    return q, p


@pytest.mark.parametrize("composition", [VERLET, YOSHIDA4, YOSHIDA6], ids=lambda c: c.name)
def test_local_error_of_composed_verlet_scales_as_h_to_the_p_plus_1(composition):
    """Fitted log-log slope of the one-step error on the (nonlinear) pendulum, h = 2⁻⁶ .. 2⁻⁹.

    The exact flow is taken over the time the rounded weights advance, (Σw) h: the ~1e-16 by which Σw misses 1
    would otherwise put an error floor of ~1e-19 under Yoshida 6's 1e-22.
    Measured slopes: 2.995 (Verlet), 4.994 (Yoshida 4), 6.990 (Yoshida 6); window ±0.02.
    """
    flow = _pendulum_flow()
    advanced = mp.fsum(mp.mpf(float(w)) for w in composition.weights)  # Σw = 1 up to rounding (checked above)
    steps = [mp.mpf(2) ** -k for k in range(6, 10)]
    errors = []
    for h in steps:
        q, p = _composed_verlet_step(composition.weights, h)
        exact = flow(advanced * h)
        errors.append(mp.sqrt((q - exact[0]) ** 2 + (p - exact[1]) ** 2))
    slope = np.polyfit([float(mp.log(h)) for h in steps], [float(mp.log(e)) for e in errors], 1)[0]
    assert abs(slope - (composition.order + 1)) <= 0.02, slope
