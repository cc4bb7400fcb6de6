"""Inverse kinematics of a tool point (and optionally an orientation) with a given model.

With a calibrated model this is the correction a controller applies: ask the calibrated model,
not the nominal one, which joint angles put the real tool point on the target.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from spherecal.correction import RobotModel, frames, joint_jacobian, tool_point, tool_pose
from spherecal.correction.errors import SpherecalError

#: Position tolerance [m] and orientation tolerance [rad] of a converged solution.
POSITION_TOL = 1e-10
ORIENTATION_TOL = 1e-9


class UnreachableError(SpherecalError):
    """No joint angles inside the limits put the tool point on the target."""


@dataclass(frozen=True)
class IKResult:
    """Outcome of :func:`ik`.

    Attributes:
        q: (n,) joint angles inside the limits [rad] (the best found, even if not converged).
        position_error: |p(q) - target| [m].
        orientation_error: rotation angle between the tool and the target orientation [rad]
            (0 when no orientation was asked).
        iterations: Gauss-Newton iterations used (over all starts).
        converged: both errors below the tolerances.
    """

    q: np.ndarray
    position_error: float
    orientation_error: float
    iterations: int
    converged: bool


def _rotvec(rotation: np.ndarray) -> np.ndarray:
    """(3,) rotation vector of a (3, 3) rotation [rad], angle in [0, pi].

    Near a half turn the skew part vanishes, so the axis is taken from the symmetric part
    ``(R + R^T)/2 = cos I + (1 - cos) n n^T`` instead (a half turn is not a zero error).
    """
    axis = np.array([rotation[2, 1] - rotation[1, 2], rotation[0, 2] - rotation[2, 0],
                     rotation[1, 0] - rotation[0, 1]])
    sin, cos = 0.5 * np.linalg.norm(axis), 0.5 * (np.trace(rotation) - 1.0)
    angle = np.arctan2(sin, cos)
    if sin < 1e-9:
        if cos > 0:
            return 0.5 * axis
        outer = (0.5 * (rotation + rotation.T) - cos * np.eye(3)) / (1.0 - cos)  # n n^T
        k = int(np.argmax(np.diag(outer)))
        unit = outer[k] / np.sqrt(outer[k, k])
        return angle * (unit if unit @ axis >= 0 else -unit)
    return axis * (angle / (2.0 * sin))


def _error_and_jacobian(model: RobotModel, q: np.ndarray, target: np.ndarray, orientation: np.ndarray | None
                        ) -> tuple[np.ndarray, np.ndarray]:
    """Task error (3,) or (6,) [m, rad] and its Jacobian d(p, omega)/dq (3 or 6, n)."""
    jac_p = joint_jacobian(model, q)
    if orientation is None:
        return target - tool_point(model, q), jac_p
    pose = tool_pose(model, q)
    z = frames(model, q[None]).z[:, :, 0]  # (n+1, 3): joint i turns about z of frame i (modified) or i-1
    axes = z[1:] if model.convention == "modified" else z[:-1]
    err_o = _rotvec(orientation @ pose[:3, :3].T)
    return np.concatenate([target - pose[:3, 3], err_o]), np.vstack([jac_p, axes.T])


#: The tool point (3,) [m] and its Jacobian (3, n) [m/rad] at joint angles (n,) [rad].
Kinematics = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def _solve_from(model: RobotModel, q: np.ndarray, target: np.ndarray, orientation: np.ndarray | None,
                max_iter: int, kinematics: Kinematics | None = None) -> tuple[np.ndarray, np.ndarray, int]:
    """Damped Gauss-Newton with clamping to the limits (joints pinned at a limit are frozen).

    ``kinematics`` (position only) replaces :mod:`correction`'s kinematics of ``model``; its
    arrays may be buffers overwritten by the next call (they are copied)."""
    lower, upper = model.lower, model.upper
    if kinematics is None:
        error_and_jacobian = lambda q: _error_and_jacobian(model, q, target, orientation)  # noqa: E731
    else:
        def error_and_jacobian(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            point, jac = kinematics(q)
            return target - point, jac.copy()
    err, jac = error_and_jacobian(q)
    cost = err @ err
    lam2 = 1e-6
    it = 0
    for it in range(1, max_iter + 1):  # noqa: B007
        if np.linalg.norm(err[:3]) < POSITION_TOL * 0.1 and (orientation is None or
                                                             np.linalg.norm(err[3:]) < ORIENTATION_TOL * 0.1):
            break
        free = np.ones(q.size, dtype=bool)
        for _ in range(2):
            jf = jac[:, free]
            dq = np.zeros(q.size)
            dq[free] = jf.T @ np.linalg.solve(jf @ jf.T + lam2 * np.eye(err.size), err)
            pinned = ((q <= lower) & (dq < 0)) | ((q >= upper) & (dq > 0))
            if not np.any(pinned & free):
                break
            free &= ~pinned
        trial = np.clip(q + dq, lower, upper)
        trial_err, trial_jac = error_and_jacobian(trial)
        trial_cost = trial_err @ trial_err
        if trial_cost < cost:
            q, err, jac, cost = trial, trial_err, trial_jac, trial_cost
            lam2 = max(lam2 * 0.1, 1e-12)
        else:
            lam2 *= 10.0
            if lam2 > 1e3:
                break
    return q, err, it


def ik(
    model: RobotModel,
    target: np.ndarray,
    q0: np.ndarray,
    orientation: np.ndarray | None = None,
    max_iter: int = 200,
    restarts: int = 0,
    rng: np.random.Generator | None = None,
    kinematics: Kinematics | None = None,
) -> IKResult:
    """Joint angles that put the tool point of ``model`` on ``target``.

    Damped Gauss-Newton on :mod:`correction`'s kinematics, started from ``q0`` (the minimum-norm
    step keeps the answer near it), clamped to the joint limits; if it does not converge, up to
    ``restarts`` more starts drawn uniformly inside the limits with ``rng``.

    Args:
        model: the kinematics to invert (nominal, true or calibrated).
        target: (3,) tool-point position in the world [m].
        q0: (n,) start [rad].
        orientation: optional (3, 3) orientation of the last frame in the world.
        max_iter: iterations per start.
        restarts: extra random starts when a start fails.
        rng: seeded generator for the restarts (required when ``restarts > 0``).
        kinematics: ``q (n,) -> (tool point (3,) [m], Jacobian (3, n) [m/rad])`` of ``model``
            computed elsewhere (e.g. :meth:`NullSpaceController.kinematics`, MuJoCo, ~100x
            faster than numpy on one configuration); position only. ``model`` still gives the
            limits.

    Returns:
        :class:`IKResult` (check ``converged``; the best attempt is returned either way).
    """
    target = np.asarray(target, dtype=float).reshape(3)
    orientation = None if orientation is None else np.asarray(orientation, dtype=float).reshape(3, 3)
    if restarts and rng is None:
        raise ValueError("ik: restarts need a seeded rng")
    if kinematics is not None and orientation is not None:
        raise ValueError("ik: a kinematics callable gives the position only, not an orientation")
    starts = [np.clip(np.asarray(q0, dtype=float), model.lower, model.upper)]
    best, total = None, 0
    for k in range(restarts + 1):
        start = starts[0] if k == 0 else model.random_configurations(1, rng)[0]
        q, err, it = _solve_from(model, start, target, orientation, max_iter, kinematics)
        total += it
        pos, ang = float(np.linalg.norm(err[:3])), float(np.linalg.norm(err[3:])) if orientation is not None else 0.0
        result = IKResult(q, pos, ang, total, pos < POSITION_TOL and ang < ORIENTATION_TOL)
        if best is None or (result.position_error + result.orientation_error
                            < best.position_error + best.orientation_error):
            best = result
        if result.converged:
            return IKResult(q, pos, ang, total, True)
    return IKResult(best.q, best.position_error, best.orientation_error, total, False)
