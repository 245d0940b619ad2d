"""Invariants of the Runge-Kutta tableaux in lagcomp.integrate.tableaux."""

import dataclasses

import numpy as np
import pytest
import scipy.integrate

from lagcomp.integrate.tableaux import BS3, DOP853, DOPRI5, RK4, TSIT5, Tableau, driver_arguments

TABLEAUX = [RK4, DOPRI5, DOP853, TSIT5, BS3]
IDS = [t.name for t in TABLEAUX]
ARRAY_NAMES = ("A", "B", "C", "E", "E3", "E5", "P", "D", "A_EXTRA", "C_EXTRA")


def _arrays(tab):
    return {k: getattr(tab, k) for k in ARRAY_NAMES if getattr(tab, k) is not None}


@pytest.mark.parametrize("tab", TABLEAUX, ids=IDS)
def test_consistency(tab):
    s = tab.n_stages
    assert tab.A.shape == (s, s) and tab.C.shape == (s,)
    np.testing.assert_allclose(tab.A.sum(axis=1), tab.C, rtol=0, atol=1e-14)
    assert abs(tab.B.sum() - 1.0) <= 1e-14
    assert tab.C[0] == 0.0
    assert np.all(np.triu(tab.A) == 0.0)


@pytest.mark.parametrize("tab", TABLEAUX, ids=IDS)
def test_error_weights_sum_to_zero(tab):
    weights = [getattr(tab, k) for k in ("E", "E3", "E5") if getattr(tab, k) is not None]
    assert (len(weights) == 0) == (tab.error_order is None)
    for w in weights:
        assert w.shape == (tab.n_stages + 1,)
        assert abs(w.sum()) <= 1e-14


@pytest.mark.parametrize("tab", TABLEAUX, ids=IDS)
def test_order_conditions_up_to_four(tab):
    """Butcher's order conditions for orders 1-4 (HNW I, table II.2.2), those up to the method's order."""
    A, b, c = tab.A, tab.B, tab.C
    conditions = [
        (b.sum(), 1.0),
        (b @ c, 1 / 2),
        (b @ c**2, 1 / 3),
        (b @ A @ c, 1 / 6),
        (b @ c**3, 1 / 4),
        (b @ (c * (A @ c)), 1 / 8),
        (b @ A @ c**2, 1 / 12),
        (b @ A @ A @ c, 1 / 24),
    ]
    count = {1: 1, 2: 2, 3: 4}.get(tab.order, len(conditions))  # the conditions of orders up to tab.order
    for value, expected in conditions[:count]:
        assert value == pytest.approx(expected, abs=1e-14)


@pytest.mark.parametrize("tab", TABLEAUX, ids=IDS)
def test_arrays_are_read_only_float64(tab):
    for name, arr in _arrays(tab).items():
        assert arr.dtype == np.float64, name
        assert not arr.flags.writeable, name
        with pytest.raises(ValueError):
            arr.flat[0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        tab.order = 3


def test_dense_output_shapes_and_continuity():
    s = DOPRI5.n_stages
    assert DOPRI5.P.shape == (s + 1, 4)
    # The interpolant passes through y_new at x = 1 and has slope f_old at x = 0.
    np.testing.assert_allclose(DOPRI5.P.sum(axis=1), np.append(DOPRI5.B, 0.0), atol=1e-14)
    np.testing.assert_array_equal(DOPRI5.P[:, 0], np.eye(s + 1)[0])

    s = DOP853.n_stages
    assert (s, DOP853.A_EXTRA.shape, DOP853.D.shape) == (12, (3, 16), (4, 16))
    np.testing.assert_allclose(DOP853.A_EXTRA.sum(axis=1), DOP853.C_EXTRA, atol=1e-14)


def test_coefficients_are_scipys_bit_for_bit():
    """The copied Dormand-Prince data equal scipy's class attributes exactly (and scipy's orders)."""
    rk45, dop853 = scipy.integrate.RK45, scipy.integrate.DOP853
    np.testing.assert_array_equal(DOPRI5.A[:, :5], rk45.A)
    assert np.all(DOPRI5.A[:, 5] == 0.0)
    for field in ("B", "C", "E", "P"):
        np.testing.assert_array_equal(getattr(DOPRI5, field), getattr(rk45, field), err_msg=field)
    for field in ("A", "B", "C", "E3", "E5", "D", "A_EXTRA", "C_EXTRA"):
        np.testing.assert_array_equal(getattr(DOP853, field), getattr(dop853, field), err_msg=field)
    assert (rk45.order, rk45.error_estimator_order) == (DOPRI5.order, DOPRI5.error_order)
    assert (dop853.order, dop853.error_estimator_order) == (DOP853.order, DOP853.error_order)
    assert (DOPRI5.order, DOPRI5.error_order) == (5, 4)
    assert (DOP853.order, DOP853.error_order) == (8, 7)


def test_driver_arguments():
    """The embedded driver's tableau data: stages, error weights and norm, exponent, dense output, stiffness bound."""
    from lagcomp.integrate.drivers.events import DENSE_CONTD8, DENSE_POWERS
    from lagcomp.integrate.tableaux import ERROR_DOP853, ERROR_RMS

    A, C, _, _ = driver_arguments(RK4)
    np.testing.assert_array_equal(A, RK4.A)
    np.testing.assert_array_equal(C, RK4.C)
    for tab in (DOPRI5, TSIT5, BS3, DOP853):
        args = driver_arguments(tab)
        A, B, C, errors, norm, exponent, kind, dense, extra_A, extra_C, stiffness_bound = args
        assert type(stiffness_bound) is float and stiffness_bound == tab.stiffness_bound
        for arr, name in zip((A, B, C), "ABC"):
            np.testing.assert_array_equal(arr, getattr(tab, name))
        assert exponent == -1.0 / (tab.error_order + 1)
        if tab is DOP853:
            assert norm == ERROR_DOP853 and kind == DENSE_CONTD8
            np.testing.assert_array_equal(errors, [tab.E5, tab.E3])
            for arr, name in zip((dense, extra_A, extra_C), ("D", "A_EXTRA", "C_EXTRA")):
                np.testing.assert_array_equal(arr, getattr(tab, name))
        else:
            assert norm == ERROR_RMS and kind == DENSE_POWERS
            np.testing.assert_array_equal(errors, [tab.E])
            np.testing.assert_array_equal(dense, tab.P.T)
            assert extra_A.shape == (0, tab.n_stages + 1) and extra_C.shape == (0,)
        for arr in (A, B, C, errors, dense, extra_A, extra_C):
            assert arr.dtype == np.float64 and arr.flags.c_contiguous and arr.flags.writeable
        assert not any(np.shares_memory(arr, getattr(tab, name)) for arr, name in zip((A, B, C), "ABC"))


def test_bs3_is_scipys_rk23_bit_for_bit():
    rk23 = scipy.integrate.RK23
    for field in ("A", "B", "C", "E", "P"):
        np.testing.assert_array_equal(getattr(BS3, field), getattr(rk23, field), err_msg=field)
    assert (rk23.order, rk23.error_estimator_order) == (BS3.order, BS3.error_order) == (3, 2)


def test_tsit5_dense_output_starts_with_f_and_ends_at_y_new():
    """x = 0: slope f_old (P[:, 0] = e_0); x = 1: y_new (rows of P sum to [B, 0]); also the slope there is
    f_new, the FSAL stage: the interpolant is C¹ across steps."""
    s = TSIT5.n_stages
    np.testing.assert_array_equal(TSIT5.P[:, 0], np.eye(s + 1)[0])
    np.testing.assert_allclose(TSIT5.P.sum(axis=1), np.append(TSIT5.B, 0.0), rtol=0, atol=1e-14)
    slope_at_1 = TSIT5.P @ np.arange(1, TSIT5.P.shape[1] + 1)
    np.testing.assert_allclose(slope_at_1, np.eye(s + 1)[s], rtol=0, atol=1e-12)


def test_fixed_step_weights_are_integers_over_their_common_denominator():
    """RK4's B = (1/6, 1/3, 1/3, 1/6) reaches the driver as 1 2 2 1 over 6, which it multiplies exactly."""
    *_, weights, denominator = driver_arguments(RK4)
    np.testing.assert_array_equal(weights, [1.0, 2.0, 2.0, 1.0])
    assert denominator == 6.0
    np.testing.assert_array_equal(weights / denominator, RK4.B)
    assert weights.flags.c_contiguous and weights.flags.writeable


def _rk4_kwargs(**changes):
    kw = _arrays(RK4)
    kw.update(name="broken", order=4, error_order=None)
    kw.update(changes)
    return kw


def _dopri5_kwargs(**changes):
    kw = _arrays(DOPRI5)
    kw.update(name="broken", order=5, error_order=4)
    kw.update(changes)
    return kw


def _dop853_kwargs(**changes):
    kw = _arrays(DOP853)
    kw.update(name="broken", order=8, error_order=7)
    kw.update(changes)
    return kw


def _perturbed(arr, index, delta):
    out = np.array(arr, copy=True)
    out[index] += delta
    return out


# name: (constructor arguments, fragment of the expected error message)
BROKEN = {
    "row_sum_not_C": (_rk4_kwargs(C=[0.0, 0.5, 0.5, 0.9]), "row sums of A"),
    "B_sum_not_1": (_rk4_kwargs(B=[1 / 6, 1 / 3, 1 / 3, 1 / 5]), r"sum\(B\)"),
    # Implicit entries, placed so that the row sums still equal C.
    "A_upper_entry": (
        _rk4_kwargs(A=_perturbed(_perturbed(RK4.A, (1, 2), 0.25), (1, 0), -0.25)),
        "strictly lower triangular",
    ),
    "A_diagonal": (
        _rk4_kwargs(A=_perturbed(_perturbed(RK4.A, (1, 1), 0.25), (1, 0), -0.25)),
        "strictly lower triangular",
    ),
    "A_not_square": (_rk4_kwargs(A=RK4.A[:, :3]), "inconsistent shapes"),
    "C_wrong_length": (_rk4_kwargs(C=[0.0, 0.5, 0.5]), "inconsistent shapes"),
    "error_order_without_weights": (_rk4_kwargs(error_order=3), "without error weights"),
    "E_sum_not_0": (_dopri5_kwargs(E=_perturbed(DOPRI5.E, 0, 1e-10)), r"sum\(E\)"),
    "E_without_fsal_entry": (_dopri5_kwargs(E=DOPRI5.E[:-1]), "n_stages \\+ 1"),
    "E_without_error_order": (_dopri5_kwargs(error_order=None), "error_order"),
    "P_not_continuous": (_dopri5_kwargs(P=_perturbed(DOPRI5.P, (2, 1), 1e-6)), "rows of P"),
    "P_wrong_rows": (_dopri5_kwargs(P=DOPRI5.P[:-1]), "P must have shape"),
    "E3_without_E5": (_dop853_kwargs(E5=None), "together"),
    "E3_sum_not_0": (_dop853_kwargs(E3=_perturbed(DOP853.E3, 4, 1e-12)), r"sum\(E3\)"),
    "A_EXTRA_row_sum": (_dop853_kwargs(C_EXTRA=_perturbed(DOP853.C_EXTRA, 1, 1e-3)), "A_EXTRA"),
    "A_EXTRA_future_stage": (
        _dop853_kwargs(A_EXTRA=_perturbed(_perturbed(DOP853.A_EXTRA, (0, 14), 1.0), (0, 0), -1.0)),
        "not yet computed",
    ),
    "D_row_sum": (_dop853_kwargs(D=_perturbed(DOP853.D, (0, 3), 1e-6)), "rows of D"),
    "D_without_A_EXTRA": (_dop853_kwargs(A_EXTRA=None), "together"),
    "non_finite": (_rk4_kwargs(B=[np.nan, 1 / 3, 1 / 3, 1 / 6]), "non-finite"),
    "A_one_dimensional": (_rk4_kwargs(A=RK4.B), "2-dimensional"),
}


@pytest.mark.parametrize("kwargs, message", list(BROKEN.values()), ids=list(BROKEN))
def test_broken_invariant_raises(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Tableau(**kwargs)


@pytest.mark.parametrize("tab", TABLEAUX, ids=IDS)
def test_valid_copy_constructs(tab):
    """Sanity check of the broken-tableau tests: the unmodified data passes."""
    kw = _arrays(tab)
    copy = Tableau(name=tab.name, order=tab.order, error_order=tab.error_order, **kw)
    for name, arr in _arrays(copy).items():
        np.testing.assert_array_equal(arr, getattr(tab, name))
