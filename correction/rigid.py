"""Best rigid transform between two point sets (Kabsch / Horn, by SVD), and the angle of a rotation."""

from __future__ import annotations

import numpy as np


def fit_rigid_transform(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The rotation and translation that best map ``source`` onto ``target``.

    Minimises ``sum_k |R source_k + t - target_k|^2`` over proper rotations (det +1).

    Args:
        source: (N, 3) points [m].
        target: (N, 3) corresponding points [m], N >= 3 and not collinear (collinear points are not refused:
            the rotation about their line is then arbitrary).

    Returns:
        (4, 4) homogeneous transform ``T`` with ``target ~ T source`` (translation [m]).

    Raises:
        ValueError: point sets of different shapes, not (N, 3), or fewer than 3 points.
    """
    source, target = np.asarray(source, float), np.asarray(target, float)
    if source.shape != target.shape or source.ndim != 2 or source.shape[1] != 3 or len(source) < 3:
        raise ValueError(f"need two (N >= 3, 3) point sets, got {source.shape} and {target.shape}")
    mean_s, mean_t = source.mean(axis=0), target.mean(axis=0)
    covariance = (target - mean_t).T @ (source - mean_s)
    u, _, vt = np.linalg.svd(covariance)
    sign = np.sign(np.linalg.det(u @ vt)) or 1.0
    rotation = u @ np.diag([1.0, 1.0, sign]) @ vt
    transform = np.eye(4)
    transform[:3, :3] = rotation
    transform[:3, 3] = mean_t - rotation @ mean_s
    return transform


def apply_transform(transform: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Points mapped by a homogeneous transform: ``R p + t`` for each.

    Args:
        transform: (4, 4) homogeneous transform, translation [m].
        points: (N, 3) points [m], or (3,) for one.

    Returns:
        The mapped points [m], shaped as ``points``.
    """
    return np.asarray(points) @ transform[:3, :3].T + transform[:3, 3]


def registered_errors(predicted: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """(N,) distances [m] between ``reference`` and ``predicted`` after the best rigid fit of
    ``predicted`` onto ``reference`` (the base placement is not observable, so it is fitted).

    Args:
        predicted: (N, 3) points [m], e.g. :func:`.kinematics.tool_point` of a model.
        reference: (N, 3) the same points measured [m], N >= 3.

    Raises:
        ValueError: as :func:`fit_rigid_transform`.
    """
    fitted = apply_transform(fit_rigid_transform(predicted, reference), predicted)
    return np.linalg.norm(fitted - reference, axis=1)


def rotation_angle(rotation: np.ndarray) -> np.ndarray:
    """Rotation angle [rad], in [0, pi], of a rotation matrix: atan2 of the skew part's length and the trace's
    share, accurate near zero where arccos of the trace is not.

    Args:
        rotation: (3, 3) rotation or a (..., 3, 3) stack (dimensionless).

    Returns:
        A scalar, or (...,) angles [rad].
    """
    rotation = np.asarray(rotation, dtype=float)
    axis = np.stack([rotation[..., 2, 1] - rotation[..., 1, 2], rotation[..., 0, 2] - rotation[..., 2, 0],
                     rotation[..., 1, 0] - rotation[..., 0, 1]], axis=-1)
    trace = np.trace(rotation, axis1=-2, axis2=-1)
    return np.arctan2(0.5 * np.linalg.norm(axis, axis=-1), 0.5 * (trace - 1.0))
