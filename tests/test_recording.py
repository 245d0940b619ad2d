"""`record="summary"`'s running reductions (`lagcomp.integrate.recording.fold_rows`) against numpy's.

The fold runs in one compiled pass over each chunk of rows; these tests hold it to the numpy reductions it
replaced (min and max of each column, the largest deviation of the energies and cyclic momenta from their
first values, NaN sticking as in ``np.minimum``/``np.maximum``), chunk by chunk and for any chunking.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from lagcomp.integrate.recording import fold_rows

_VALUES = st.floats(allow_nan=True, allow_infinity=True, width=64)


def _numpy_fold(ys, energy, energy_function, momenta, cyclic, start, extremes, deviation):
    """The reductions as numpy computes them (what `Recorder._fold` did before `fold_rows`)."""
    extremes[0] = np.minimum(extremes[0], ys.min(axis=0))
    extremes[1] = np.maximum(extremes[1], ys.max(axis=0))
    tracked = np.column_stack([energy, energy_function, momenta[:, cyclic]])
    deviation[:] = np.maximum(deviation, np.max(np.abs(tracked - start), axis=0))


@settings(max_examples=200, deadline=None)
@given(data=st.data(), rows=st.integers(1, 12), n=st.integers(1, 3), cuts=st.lists(st.integers(1, 11), max_size=3))
def test_fold_rows_is_numpys_reduction(data, rows, n, cuts):
    ys = data.draw(arrays(np.float64, (rows, 2 * n), elements=_VALUES))
    energy, energy_function = (data.draw(arrays(np.float64, rows, elements=_VALUES)) for _ in range(2))
    momenta = data.draw(arrays(np.float64, (rows, n), elements=_VALUES))
    cyclic = np.array(data.draw(st.lists(st.integers(0, n - 1), unique=True)), dtype=np.int64)
    start = data.draw(arrays(np.float64, 2 + cyclic.size, elements=st.floats(-1e3, 1e3)))
    ours = (np.array([np.full(2 * n, np.inf), np.full(2 * n, -np.inf)]), np.zeros(2 + cyclic.size))
    theirs = (ours[0].copy(), ours[1].copy())
    for chunk in np.split(np.arange(rows), sorted({c for c in cuts if c < rows})):
        part = (ys[chunk], energy[chunk], energy_function[chunk], momenta[chunk])
        fold_rows(*part, cyclic, start, *ours)
        _numpy_fold(*part, cyclic, start, *theirs)
    for a, b in zip(ours, theirs, strict=True):
        # equal values and NaNs; a signed zero may differ (min(0.0, -0.0) is either), so compare with ==
        assert np.array_equal(a, b, equal_nan=True)
