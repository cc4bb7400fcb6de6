"""Inverse kinematics of a tool point (and optionally an orientation) with a given model.

With a calibrated model this is the correction a controller applies: ask the calibrated model,
not the nominal one, which joint angles put the real tool point on the target.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from spherecal.correction import RobotModel, joint_jacobian, pose_jacobian, tool_point, tool_pose
from spherecal.correction.errors import ShapeError, SpherecalError

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
        position_error: ``|p(q) - target|`` [m].
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
    if orientation is None:
        return target - tool_point(model, q), joint_jacobian(model, q)
    pose = tool_pose(model, q)  # the full model: an elastic one at its link angles
    err_o = _rotvec(orientation @ pose[:3, :3].T)
    return np.concatenate([target - pose[:3, 3], err_o]), pose_jacobian(model, q)


#: The tool point (3,) [m] and its Jacobian (3, n) [m/rad] at joint angles (n,) [rad].
Kinematics = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


#: Evaluates a batch of configurations (k, n) [rad]: task errors (k, m) and their Jacobians (k, m, n).
Evaluate = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def _evaluator(model: RobotModel, target: np.ndarray, orientation: np.ndarray | None,
               kinematics: Kinematics | None) -> Evaluate:
    """The task error and Jacobian of a batch, row by row, from ``kinematics`` (its buffers are
    copied) or from :mod:`correction`'s kinematics of ``model``."""
    m, n = 3 if orientation is None else 6, model.n_joints

    def evaluate(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        err, jac = np.empty((q.shape[0], m)), np.empty((q.shape[0], m, n))
        for k, qk in enumerate(q):
            if kinematics is None:
                err[k], jac[k] = _error_and_jacobian(model, qk, target, orientation)
            else:
                point, jac[k] = kinematics(qk)
                err[k] = target - point
        return err, jac

    return evaluate


def _reached(err: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """(k,) rows of ``err`` (k, 3 or 6) within ``scale`` x the tolerances."""
    ok = np.linalg.norm(err[:, :3], axis=1) < POSITION_TOL * scale
    if err.shape[1] > 3:
        ok &= np.linalg.norm(err[:, 3:], axis=1) < ORIENTATION_TOL * scale
    return ok


def _answer(running: np.ndarray, ok: np.ndarray) -> int | None:
    """Index of the first start that converged with every earlier one finished without converging
    (what trying the starts one after another returns), -1 when all failed, None while undecided."""
    for k, (busy, good) in enumerate(zip(running, ok, strict=True)):
        if busy:
            return None
        if good:
            return k
    return -1


def _solve_batch(lower: np.ndarray, upper: np.ndarray, starts: np.ndarray, evaluate: Evaluate,
                 max_iter: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Damped Gauss-Newton with clamping to the limits (joints pinned at a limit are frozen), run
    from every start in lockstep (one numpy call per iteration for the whole batch).

    Each start goes on until it converges (errors below a tenth of the tolerances), its damping
    exceeds 1e3 or ``max_iter``; the batch stops as soon as the answer is known (:func:`_answer`).

    Args:
        lower, upper: (n,) limits [rad].
        starts: (S, n) starts [rad].
        evaluate: task errors and Jacobians of a batch.
        max_iter: iterations per start.

    Returns:
        ``(q (S, n), err (S, m), iterations (S,), answer)`` with ``answer`` from :func:`_answer`.
    """
    q = np.array(starts, dtype=float)
    err, jac = evaluate(q)
    cost = np.einsum("sm,sm->s", err, err)
    lam2 = np.full(q.shape[0], 1e-6)
    iterations = np.zeros(q.shape[0], dtype=int)
    running = np.ones(q.shape[0], dtype=bool)
    eye = np.eye(err.shape[1])
    for _ in range(max_iter):
        running &= ~_reached(err, 0.1)
        if not running[0] and _answer(running, _reached(err)) is not None:
            break
        idx = np.flatnonzero(running)
        iterations[idx] += 1
        qi, ei, ji = q[idx], err[idx], jac[idx]
        free = np.ones(qi.shape, dtype=bool)
        for _ in range(2):
            jf = ji * free[:, None, :]
            jft = jf.transpose(0, 2, 1)
            dq = (jft @ np.linalg.solve(jf @ jft + lam2[idx, None, None] * eye, ei[..., None]))[..., 0]
            pinned = ((qi <= lower) & (dq < 0)) | ((qi >= upper) & (dq > 0))
            if not np.any(pinned & free):
                break
            free &= ~pinned
        trial = np.clip(qi + dq, lower, upper)
        trial_err, trial_jac = evaluate(trial)
        trial_cost = np.einsum("sm,sm->s", trial_err, trial_err)
        better = trial_cost < cost[idx]
        won, lost = idx[better], idx[~better]
        q[won], err[won], jac[won], cost[won] = trial[better], trial_err[better], trial_jac[better], trial_cost[better]
        lam2[won] = np.maximum(lam2[won] * 0.1, 1e-12)
        lam2[lost] *= 10.0
        running[lost[lam2[lost] > 1e3]] = False
    running[:] = False
    return q, err, iterations, _answer(running, _reached(err))


def _finite(value, shape: tuple[int, ...], field: str, expected: str) -> np.ndarray:
    """``value`` as a float array of ``shape``; anything else (numpy's broadcast and reshape errors, a NaN that came
    back as a NaN miss) raises naming ``field``: :class:`ShapeError` for another shape (or no array at all),
    :class:`SpherecalError` for a value that is not finite."""
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        array = np.full(0, np.nan)
    if array.shape != shape:
        raise ShapeError(f"{field}: expected {expected}, got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise SpherecalError(f"{field}: expected {expected}, got shape {array.shape} with a value that is not finite")
    return array


def check_shape(value, shape: tuple[int, ...], field: str, expected: str) -> None:
    """Raise :class:`ShapeError` naming ``field`` unless ``value`` (an array, or a list numpy reads as one) has
    ``shape``: the check a control loop can afford every period (an array's shape compared, about 0.1 us), where
    :func:`_finite` also converts and reads every value."""
    if getattr(value, "shape", None) != shape:
        given = np.shape(value)  # a list or a tuple: the shape numpy would give it
        if given != shape:
            raise ShapeError(f"{field}: expected {expected}, got shape {given}")


def check_joint_angles(model: RobotModel, q, field: str) -> np.ndarray:
    """``q`` as (n,) float joint angles [rad] of ``model``.

    Raises:
        ShapeError: not (n,) (another arm's joint count, a batch), naming ``field`` and both shapes.
        SpherecalError: an angle that is not finite.
    """
    return _finite(q, (model.n_joints,), field, f"{model.n_joints} finite joint angles [rad]")


def check_target(model: RobotModel, target: np.ndarray) -> np.ndarray:
    """``target`` (3,) [m] as an array, refused when it is not 3 finite coordinates or lies farther from the base than
    twice the arm's links and tool reach at all (:attr:`correction.RobotModel.reach`): a target in millimetres (a
    user trial: 'misses by 634888 mm'; a controls trial: the QP controller drove toward one at the velocity limit).

    Raises:
        ShapeError: not 3 coordinates.
        SpherecalError: a coordinate that is not finite.
        UnreachableError: beyond twice the reach, naming the distance.
    """
    target = _finite(target, (3,), "target", "3 finite coordinates [m]")
    away = float(np.linalg.norm(target - model.base_transform[:3, 3]))
    if away > 2.0 * model.reach:  # beyond any posture by twice: not a target of this arm
        raise UnreachableError(f"target {np.round(target, 4).tolist()} m is {away:.4g} m from the base of "
                               f"{model.name!r}, whose links and tool reach {model.reach:.3g} m at most (millimetres? "
                               "targets are in metres)")
    return target


def ik(
    model: RobotModel,
    target: np.ndarray,
    q0: np.ndarray,
    orientation: np.ndarray | None = None,
    max_iter: int = 200,
    restarts: int = 0,
    rng: np.random.Generator | None = None,
    kinematics: Kinematics | None = None,
    lockstep: bool = False,
) -> IKResult:
    """Joint angles that put the tool point of ``model`` on ``target``.

    Damped Gauss-Newton on :mod:`correction`'s kinematics, started from ``q0`` (the minimum-norm
    step keeps the answer near it), clamped to the joint limits; if it does not converge, up to
    ``restarts`` more starts drawn uniformly inside the limits with ``rng`` (drawn together and
    run in lockstep; the first of them, in order, that converges is the answer, as if they had
    been tried one after another).

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
        lockstep: draw the restarts at once and run them with ``q0`` from the first iteration
            (same answer; worth it when a start often fails and evaluations are cheap, as in the
            coverage goal search; the restarts are drawn even when ``q0`` converges).

    Returns:
        :class:`IKResult` (check ``converged``; the best attempt is returned either way).

    Raises:
        ShapeError: a ``target``, ``q0`` or ``orientation`` of another shape.
        SpherecalError: one that is not finite, ``restarts`` without ``rng``, an ``orientation`` with ``kinematics``.
    """
    target = _finite(target, (3,), "target", "3 finite coordinates [m]")
    orientation = None if orientation is None else _finite(orientation, (3, 3), "orientation",
                                                           "a (3, 3) rotation matrix")
    q0 = check_joint_angles(model, q0, "q0")
    if restarts and rng is None:
        raise SpherecalError("rng: ik's restarts need a seeded generator (rng=np.random.default_rng(seed))")
    if kinematics is not None and orientation is not None:
        raise SpherecalError("orientation: ik with a kinematics callable solves for the position only")
    evaluate = _evaluator(model, target, orientation, kinematics)
    first = np.clip(np.asarray(q0, dtype=float), model.lower, model.upper)[None]
    if lockstep and restarts:
        starts = np.vstack([first, model.random_configurations(restarts, rng)])
        q, err, iterations, answer = _solve_batch(model.lower, model.upper, starts, evaluate, max_iter)
    else:
        q, err, iterations, answer = _solve_batch(model.lower, model.upper, first, evaluate, max_iter)
    if answer < 0 and restarts and not lockstep:  # the restarts run together, the first that converges wins
        more = _solve_batch(model.lower, model.upper, model.random_configurations(restarts, rng), evaluate, max_iter)
        q, err, iterations = (np.concatenate([a, b]) for a, b in zip((q, err, iterations), more[:3], strict=True))
        answer = -1 if more[3] < 0 else 1 + more[3]
    pos = np.linalg.norm(err[:, :3], axis=1)
    ang = np.linalg.norm(err[:, 3:], axis=1) if orientation is not None else np.zeros(pos.size)
    pick = answer if answer >= 0 else int(np.argmin(pos + ang))
    return IKResult(q[pick], float(pos[pick]), float(ang[pick]), int(iterations.sum()), answer >= 0)
