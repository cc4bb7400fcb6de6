"""The greedy rank test against the rank of the accepted columns, computed apart (SVD)."""

from __future__ import annotations

import numpy as np

from spherecal.identification.identifiability import greedy_rank


def test_greedy_rank_accepts_a_column_exactly_when_it_adds_rank() -> None:
    rng = np.random.default_rng(4)
    base = rng.normal(size=(300, 6)) * np.array([1.0, 1e3, 1e-3, 1.0, 5.0, 0.2])  # unequal column scales
    columns = [
        base[:, 0], base[:, 1],
        2.0 * base[:, 0] - 3e-3 * base[:, 1],  # a combination of the two before it
        base[:, 2],
        np.zeros(300),  # no effect at all
        base[:, 3] + 1e-3 * base[:, 4] / 5.0,  # near, not on, the next column: kept
        base[:, 3], base[:, 4],  # the first kept; the second rebuilt from it and the near one (x 5000)
        base[:, 5],
        base[:, 5] * 7.0,  # a multiple of the one before
    ]
    jac = np.stack(columns, axis=1)
    order = np.array([0, 1, 2, 3, 4, 5, 6, 7, 8, 9])
    accepted, rejected = greedy_rank(jac, order)
    expected = []
    for j in order:  # independent reference: does the column raise the rank of the unit columns accepted so far?
        unit = jac[:, expected + [j]] / np.maximum(np.linalg.norm(jac[:, expected + [j]], axis=0), 1e-300)
        if np.linalg.norm(jac[:, j]) > 0 and np.linalg.matrix_rank(unit, tol=1e-7) == len(expected) + 1:
            expected.append(int(j))
    np.testing.assert_array_equal(accepted, sorted(expected))
    assert sorted(rejected) == [2, 4, 7, 9]
    for j in (2, 7, 9):  # the coefficients rebuild the rejected column from the accepted ones before it
        np.testing.assert_allclose(jac @ rejected[j], jac[:, j], rtol=0, atol=1e-9 * np.linalg.norm(jac[:, j]))
    np.testing.assert_array_equal(rejected[4], np.zeros(jac.shape[1]))
