"""Which unknowns a data set can see: column scaling, greedy rank test, singular values, predicted spread."""

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
        s = np.sqrt(np.clip(_scaled_gram_eig(jac)[0][::-1], 0.0, None))
        cond = float(s[0] / s[-1]) if s.size and s[-1] > 0 else float("inf")
        return Identifiability(singular_values=s, condition_number=cond)


def _scaled_gram_eig(jac: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eigen-decomposition of the (F, F) normal matrix of the column-scaled Jacobian.

    The singular values of ``J D^-1`` are the square roots of its eigenvalues (ascending here). A
    tall (M, F) SVD is avoided on purpose: the Gram matrix is one BLAS product and an (F, F) eigh,
    ~10x faster, and accurate for condition numbers up to ~1e7 (beyond that, the problem is
    reported as ill-conditioned anyway).

    Returns:
        eigenvalues (F,) ascending, eigenvectors (F, F) as columns, column norms (F,).
    """
    norms = column_norms(jac)
    scaled = jac / norms
    # einsum, not BLAS: a threaded GEMM this small stalls for tens of ms on a busy machine
    values, vectors = np.linalg.eigh(np.einsum("ij,ik->jk", scaled, scaled))
    return values, vectors, norms


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
    jac = triangular(jac)  # the same inner products of the columns on F rows: what follows reads no others
    basis = np.empty((len(order), jac.shape[0]))  # rows 0..k-1: orthonormal basis of the accepted columns
    accepted: list[int] = []
    rejected: dict[int, np.ndarray] = {}
    for j in order:
        column = jac[:, j]
        if negligible[j]:
            rejected[int(j)] = np.zeros(jac.shape[1])
            continue
        v = column / norms[j]
        done = basis[: len(accepted)]
        for _ in range(2):  # classical Gram-Schmidt, re-orthogonalised once (as stable as modified, 2 products)
            v = v - (done @ v) @ done
        length = np.linalg.norm(v)
        if length > rel_tol:
            basis[len(accepted)] = v / length
            accepted.append(int(j))
        else:
            coef = np.zeros(jac.shape[1])
            if accepted:
                basis_cols = jac[:, accepted] / norms[accepted]
                gram = np.einsum("ij,ik->jk", basis_cols, basis_cols)
                coef[accepted] = np.linalg.solve(gram, np.einsum("ij,i->j", basis_cols, column)) / norms[accepted]
            rejected[int(j)] = coef
    return np.array(sorted(accepted), dtype=int), rejected


def triangular(jac: np.ndarray) -> np.ndarray:
    """(F, F) upper-triangular ``R`` of ``jac = Q R`` for a tall (M, F) ``jac`` (M > F); ``jac`` itself otherwise.

    ``R^T R = J^T J``: every column subset ``R[:, cols]`` (scaled or not) has the singular values and right
    singular vectors of ``J[:, cols]``, so the tall matrix is factored once (Householder, LAPACK ``geqrf``, no
    ``Q`` formed) and an SVD after it works on F rows. A thin SVD of the tall matrix does the same QR inside and
    then also forms its (M, F) ``U``, which none of ours reads: twice the time.
    """
    return np.linalg.qr(jac, mode="r") if jac.shape[0] > jac.shape[1] else jac


def normal_inverse(jac: np.ndarray, norms: np.ndarray | None = None) -> np.ndarray:
    """(F, F) ``(J^T J)^-1`` of a (M, F) Jacobian, through the SVD of the column-scaled Jacobian
    (never the squared normal matrix; a null direction gets a huge, not infinite, variance).

    ``jac`` may be the :func:`triangular` factor of the Jacobian (or columns of it) with ``norms``, the (F,)
    :func:`column_norms` of the Jacobian's matching columns (default: those of ``jac``)."""
    norms = column_norms(jac) if norms is None else norms
    _, s, vt = np.linalg.svd(triangular(jac / norms), full_matrices=False)
    inv = 1.0 / np.maximum(s, s[0] * 1e-14)
    return (vt.T * inv**2) @ vt / np.outer(norms, norms)


def predicted_std(jac: np.ndarray, sigma: float, inverse: np.ndarray | None = None) -> np.ndarray:
    """(F,) standard deviation of every unknown for residual noise ``sigma`` [m] (Gauss-Markov):
    the square root of the diagonal of ``cov = sigma^2 (J^T J)^-1`` (``inverse``: :func:`normal_inverse` of
    ``jac`` when already computed)."""
    return sigma * np.sqrt(np.diag(normal_inverse(jac) if inverse is None else inverse))


def symmetric_root(matrix: np.ndarray, floor: float | None = None) -> np.ndarray:
    """(N, r) root ``R`` of a symmetric positive semi-definite (N, N) ``matrix`` (``R R^T = matrix``) for drawing
    ``R z``, ``z`` standard normal: its eigenvectors scaled by the roots of their eigenvalues (negative ones, from
    rounding, taken as 0). ``floor``: leave out the eigenvalues at or below ``floor`` times the largest (None: keep
    every column, r = N).

    Each eigenvector's sign is fixed (its largest-magnitude entry positive): ``eigh`` may flip a sign for a change
    of the matrix in its last digit, and with it every Monte Carlo draw made through the root (a prediction then
    moved 2 % between two calibrations equal to 1e-15).
    """
    values, vectors = np.linalg.eigh(0.5 * (matrix + matrix.T))
    if floor is not None:
        keep = values > floor * values[-1]
        values, vectors = values[keep], vectors[:, keep]
    signs = np.sign(vectors[np.argmax(np.abs(vectors), axis=0), np.arange(vectors.shape[1])])
    return vectors * (np.where(signs == 0, 1.0, signs) * np.sqrt(np.clip(values, 0.0, None)))
