"""Which unknowns a data set can see: column scaling, greedy rank test, SVD, predicted spread."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Identifiability:
    """Singular values and condition number of a column-scaled Jacobian.

    Attributes:
        singular_values: (F,) of the Jacobian with unit-norm columns, descending.
        condition_number: largest / smallest singular value (inf when rank deficient).
    """

    singular_values: np.ndarray
    condition_number: float

    @staticmethod
    def of(jac: np.ndarray) -> Identifiability:
        """Identifiability of a (M, F) Jacobian after scaling its columns to unit norm."""
        scaled = jac / column_norms(jac)
        s = np.linalg.svd(scaled, compute_uv=False)
        cond = float(s[0] / s[-1]) if s.size and s[-1] > 0 else float("inf")
        return Identifiability(singular_values=s, condition_number=cond)


def column_norms(jac: np.ndarray) -> np.ndarray:
    """(F,) Euclidean norms of the columns, zeros replaced by 1 (scaling that leaves them zero)."""
    norms = np.linalg.norm(jac, axis=0)
    return np.where(norms > 0, norms, 1.0)


def greedy_rank(jac: np.ndarray, order: np.ndarray, rel_tol: float = 1e-7) -> tuple[np.ndarray, dict[int, np.ndarray]]:
    """Accept columns in preference order when they add rank (Gram-Schmidt on unit-norm columns).

    A column is rejected when the part of it orthogonal to the columns accepted before it is
    shorter than ``rel_tol`` times its norm (or it is zero).

    Args:
        jac: (M, F) Jacobian.
        order: (F,) column indices, most wanted first.
        rel_tol: relative tolerance of the rank test.

    Returns:
        Sorted indices of the accepted columns, and for each rejected column the least-squares
        coefficients (F,) that express it by the accepted ones before it (to say "redundant with").
    """
    norms = np.linalg.norm(jac, axis=0)
    negligible = norms <= 1e-10 * (np.median(norms) if norms.size else 0.0)
    basis: list[np.ndarray] = []
    accepted: list[int] = []
    rejected: dict[int, np.ndarray] = {}
    for j in order:
        column = jac[:, j]
        if negligible[j]:
            rejected[int(j)] = np.zeros(jac.shape[1])
            continue
        v = column / norms[j]
        for _ in range(2):  # re-orthogonalise once for stability
            for b in basis:
                v = v - (b @ v) * b
        length = np.linalg.norm(v)
        if length > rel_tol:
            basis.append(v / length)
            accepted.append(int(j))
        else:
            coef = np.zeros(jac.shape[1])
            if accepted:
                coef[accepted] = np.linalg.lstsq(jac[:, accepted], column, rcond=None)[0]
            rejected[int(j)] = coef
    return np.array(sorted(accepted), dtype=int), rejected


def predicted_std(jac: np.ndarray, sigma: float) -> np.ndarray:
    """(F,) standard deviation of every unknown for residual noise ``sigma`` [m] (Gauss-Markov).

    ``cov = sigma^2 (J^T J)^-1`` computed through the SVD of the column-scaled Jacobian.
    """
    norms = column_norms(jac)
    _, s, vt = np.linalg.svd(jac / norms, full_matrices=False)
    inv = 1.0 / np.maximum(s, s[0] * 1e-14)  # a null direction gives a huge (not infinite) std
    scaled_var = (vt.T**2) @ (inv**2)
    return sigma * np.sqrt(scaled_var) / norms
