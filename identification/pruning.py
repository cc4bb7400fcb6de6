"""Pruning after a solve: fix the parameters the data barely excites."""

from __future__ import annotations

from dataclasses import fields, replace

import numpy as np

from spherecal.correction.files.fixtures import FixtureSpec

from .identifiability import column_norms, normal_inverse, predicted_std, triangular
from .problem import CalibrationProblem, tolerance, zero_indices

#: Fields of a problem that every problem sharing its cache has alike (the model, the samples) or that its Jacobian
#: does not read: left out of :func:`generic_excitation`'s key.
_ALIKE = ("model", "dataset", "fixed", "warnings", "_cache")


def generic_excitation(problem: CalibrationProblem) -> tuple[np.ndarray, np.ndarray]:
    """(F,) column norms and (F, F) triangular factor (:func:`.identifiability.triangular`) of
    :meth:`CalibrationProblem.generic_jacobian`: what :func:`prune` judges the excitation by.

    Kept in ``problem``'s cache, keyed by every field its Jacobian reads beside the model and the samples (which the
    problems sharing a cache have alike): a calibration prunes its built problem at the generic point, and its
    self-check's prediction prunes the same problem there again (:func:`.prediction.deviation_root`). Each was a tall
    QR of the whole Jacobian (a quarter of a second at 20 000 samples). The arrays are shared, not to be written.
    """
    key = ("generic_excitation", *(_exact(getattr(problem, f.name)) for f in fields(problem) if f.name not in _ALIKE))
    found = problem._cache.get(key)
    if found is None:
        jac = problem.generic_jacobian()
        found = (column_norms(jac), triangular(jac))
        for array in found:
            array.setflags(write=False)
        problem._cache[key] = found
    return found


def _exact(value):
    """``value`` as a hashable key compared exactly: arrays by dtype, shape and bytes, a fixture spec by its known
    distances (what a Jacobian reads of it), tuples and lists item by item."""
    if isinstance(value, np.ndarray):
        return value.dtype.str, value.shape, value.tobytes()
    if isinstance(value, (tuple, list)):
        return tuple(_exact(v) for v in value)
    if isinstance(value, FixtureSpec):
        return "distances", _exact(value.distances)
    return value


def prune(
    problem: CalibrationProblem, x: np.ndarray, sigma: float, jac: np.ndarray | None = None,
    excitation: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[CalibrationProblem, np.ndarray]:
    """Fix, one at a time, the parameters whose predicted std exceeds their tolerance (:func:`.problem.tolerance`: the
    prior spread, and for a joint's zero the wider :data:`.problem.ZERO_TOLERANCE`).

    Args:
        problem: a solved problem.
        x: (F,) its solution.
        sigma: residual noise [m] (estimated from the fit).
        jac: (M, F) Jacobian that judges the excitation (default: at ``x``;
            :meth:`CalibrationProblem.generic_jacobian` does not depend on how far a fit wandered).
        excitation: ``(norms, R)`` of that Jacobian when already factorised (:func:`generic_excitation`); ``jac``
            is then not read.

    Returns:
        The problem without the barely excited parameters (they go back to the start model's value)
        and the matching unknown vector; the inputs when nothing is pruned.
    """
    prior = tolerance(problem.model)
    zeros = set(zero_indices(problem.model).tolist())
    names = problem.model.param_names
    params, centres = problem.unpack(x)
    if excitation is None:
        jac = problem.jacobian(x) if jac is None else jac
        # the tall Jacobian factored once: each column subset below is an SVD of R's columns (F rows)
        excitation = column_norms(jac), triangular(jac)
    norms, tri = excitation
    fp = problem.n_free_params
    keep = np.arange(fp)
    fixed = dict(problem.fixed)
    while keep.size > 1:
        cols = np.concatenate([keep, np.arange(fp, tri.shape[1])])
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
