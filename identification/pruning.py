"""Pruning after a solve: fix the parameters the data barely excites."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .identifiability import column_norms, normal_inverse, predicted_std, triangular
from .problem import CalibrationProblem, tolerance, zero_indices


def prune(
    problem: CalibrationProblem, x: np.ndarray, sigma: float, jac: np.ndarray | None = None
) -> tuple[CalibrationProblem, np.ndarray]:
    """Fix, one at a time, the parameters whose predicted std exceeds their tolerance (:func:`.problem.tolerance`: the
    prior spread, and for a joint's zero the wider :data:`.problem.ZERO_TOLERANCE`).

    Args:
        problem: a solved problem.
        x: (F,) its solution.
        sigma: residual noise [m] (estimated from the fit).
        jac: (M, F) Jacobian that judges the excitation (default: at ``x``;
            :meth:`CalibrationProblem.generic_jacobian` does not depend on how far a fit wandered).

    Returns:
        The problem without the barely excited parameters (they go back to the start model's value)
        and the matching unknown vector; the inputs when nothing is pruned.
    """
    prior = tolerance(problem.model)
    zeros = set(zero_indices(problem.model).tolist())
    names = problem.model.param_names
    params, centres = problem.unpack(x)
    jac = problem.jacobian(x) if jac is None else jac
    # the tall Jacobian factored once: each column subset below is an SVD of R's columns (F rows)
    norms, tri = column_norms(jac), triangular(jac)
    fp = problem.n_free_params
    keep = np.arange(fp)
    fixed = dict(problem.fixed)
    while keep.size > 1:
        cols = np.concatenate([keep, np.arange(fp, jac.shape[1])])
        std = predicted_std(tri[:, cols], sigma, normal_inverse(tri[:, cols], norms[cols]))[: keep.size]
        ratio = std / prior[problem.free[keep]]
        worst = int(np.argmax(ratio))
        if ratio[worst] <= 1.0:
            break
        name = names[problem.free[keep[worst]]]
        fmt = problem.model.layout.format
        limit = fmt(name, prior[problem.free[keep[worst]]])
        fixed[name] = (
            f"barely excited: predicted std {fmt(name, std[worst])} at {sigma * 1e3:.3g} mm residual noise "
            + (f"exceeds the {limit} a joint's zero may be off" if problem.free[keep[worst]] in zeros
               else f"exceeds the prior spread {limit}")
        )
        keep = np.delete(keep, worst)
    if keep.size == fp:
        return problem, x
    dropped = np.setdiff1d(problem.free, problem.free[keep])
    params[dropped] = problem.model.params[dropped]
    fixed = {name: fixed[name] for name in names if name in fixed}
    pruned = replace(problem, free=problem.free[keep], fixed=fixed)
    return pruned, pruned.pack(params, centres)
