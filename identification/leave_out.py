"""Leave one group of rows out of a solved least-squares fit, linearised (no refit).

At a solution ``x`` with residual ``r`` (M,) and Jacobian ``A`` (M, F) (columns scaled to unit norm
here, which changes nothing but the conditioning), the linearised fit of any subset of the rows is
one normal-equation solve in the (F, F) parameter space::

    N = A^T A,  b = A^T r,   SSR = |r|^2 - b^T N^+ b          all rows
    N_g = A_g^T A_g  (the rows R_g of group g),  N_-g = N - N_g,  b_-g = b - A_g^T r_g
    SSR_-g = |r|^2 - |r_g|^2 - b_-g^T N_-g^+ b_-g               the fit without group g
    e_g = r_g - A_g N_-g^+ b_-g                                  group g's residual at that fit

``dSSR_g = SSR - SSR_-g`` is the mean-shift outlier statistic: for Gaussian residuals of std ``sigma``,
``dSSR_g / sigma^2 ~ chi2(dof_g)`` with ``dof_g = |R_g| - (rank N - rank N_-g)`` (the rows the rest of
the data can check; a group that alone determines some unknowns is checked on fewer rows, and a group
with ``dof_g = 0`` cannot be checked at all). Exact for a linear problem; for the calibration it is the
first Gauss-Newton step of the refit from the solution, accurate while the refit moves the parameters
by much less than their nonlinearity scale (millimetres, tenths of a degree). Cost: one (F, F)
eigendecomposition per group, no pass over the rows beyond the group's own.

A refit that runs away (some unknown moves more than :data:`RUNAWAY` times its ``spread``: in a
calibration, the uniform scale, along which every sample residual shrinks in proportion, so that an
arm of zero size fits anything, once the left-out group was what fixed it) is redone with that step's
direction held fixed; the group is then checked only across it (one dof less per held direction).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Eigenvalues of the column-scaled normal matrix below this share of the largest count as zero.
RANK_TOL = 1e-10
#: Groups of at most this many rows get :attr:`LeftOut.fit_var`.
SMALL = 16
#: A refit step beyond this many ``spread`` in any unknown has run away along a gauge of the rest.
RUNAWAY = 20.0


@dataclass(frozen=True, eq=False)
class LeftOut:
    """The linearised fit without one group of rows.

    Attributes:
        rows: rows in the group.
        held: directions the refit held fixed (it ran away along them: the group alone fixed them).
        dof: rows the rest of the data can check (0: the group cannot be checked).
        delta_ssr: ``SSR - SSR_-g`` [residual units^2] (>= 0 up to rounding).
        ssr_rest: ``SSR_-g``, the other rows' sum of squares at the fit without the group.
        dof_rest: the other rows' degrees of freedom (rows minus rank).
        predicted: (rows,) the group's residual at the fit without it.
        fit_var: (rows,) variance of each entry of ``predicted`` from the fit without the group, per
            unit residual variance (the diagonal of ``A_g N_-g^+ A_g^T``); empty for groups of more
            than :data:`SMALL` rows.
    """

    rows: int
    held: int
    dof: int
    delta_ssr: float
    ssr_rest: float
    dof_rest: int
    predicted: np.ndarray
    fit_var: np.ndarray

    @property
    def sigma_rest(self) -> float:
        """Residual std of the other rows at the fit without the group (a sum of squares a little below zero by
        rounding, as a fixture of one sample leaves it, is zero: numpy's 'invalid value encountered in sqrt' then
        reached the user as a warning beside the refusal)."""
        return float(np.sqrt(max(self.ssr_rest, 0.0) / max(self.dof_rest, 1)))


def _pinv(normal: np.ndarray, tol: float) -> tuple[np.ndarray, int]:
    """Pseudo-inverse and rank of a symmetric positive semi-definite matrix (absolute tolerance)."""
    values, vectors = np.linalg.eigh(normal)
    keep = values > tol
    return (vectors[:, keep] / values[keep]) @ vectors[:, keep].T, int(keep.sum())


def leave_out(
    jac: np.ndarray, r: np.ndarray, groups: dict[str, np.ndarray], spread: np.ndarray | None = None
) -> tuple[float, int, dict[str, LeftOut]]:
    """Linearised leave-one-group-out of a least-squares fit.

    Args:
        jac: (M, F) Jacobian of the residuals at the solution.
        r: (M,) residuals at the solution.
        groups: name -> row indices of the group (groups may not overlap for the figures to add up).
        spread: (F,) typical size of each unknown's change (prior spread): a refit step beyond
            :data:`RUNAWAY` of them is held (see above); None: never.

    Returns:
        ``SSR`` of the linearised fit of all rows, its rank, and name -> :class:`LeftOut`.
    """
    norms = np.linalg.norm(jac, axis=0)
    norms = np.where(norms > 0, norms, 1.0)
    scaled = jac / norms
    limit = None if spread is None else RUNAWAY * spread * norms  # in the scaled unknowns
    normal = np.einsum("ij,ik->jk", scaled, scaled)  # einsum: a threaded GEMM this small stalls when busy
    b = scaled.T @ r
    tol = RANK_TOL * max(float(np.abs(np.diag(normal)).max(initial=0.0)), 1e-300)
    inverse, rank = _pinv(normal, tol)
    total = float(r @ r)
    ssr = total - float(b @ inverse @ b)
    out: dict[str, LeftOut] = {}
    for name, rows in groups.items():
        a_g, r_g = scaled[rows], r[rows]
        rest = normal - a_g.T @ a_g
        b_rest = b - a_g.T @ r_g
        basis = np.eye(len(b))
        held = 0
        while True:
            inner, rest_rank = _pinv(basis.T @ rest @ basis, tol)
            rest_inverse = basis @ inner @ basis.T
            step = rest_inverse @ b_rest
            if limit is None or held >= 3 or np.all(np.abs(step) <= limit):
                break
            unit = step / np.linalg.norm(step)  # hold this direction: the rest cannot fix it
            basis = np.linalg.eigh(basis @ basis.T - np.outer(unit, unit))[1][:, held + 1 :]
            held += 1
        ssr_rest = total - float(r_g @ r_g) - float(b_rest @ step)
        out[name] = LeftOut(
            rows=len(rows),
            held=held,
            dof=len(rows) - (rank - rest_rank),
            delta_ssr=ssr - ssr_rest,
            ssr_rest=ssr_rest,
            dof_rest=jac.shape[0] - len(rows) - rest_rank,
            predicted=r_g - a_g @ step,
            # per-row variances only for small groups (a constraint): O(rows F^2) on a fixture's samples
            fit_var=np.einsum("ij,jk,ik->i", a_g, rest_inverse, a_g) if len(rows) <= SMALL else np.empty(0),
        )
    return ssr, rank, out
