"""The gauge and scale of a calibration: what spherical-joint data cannot see, and how it is held.

* :func:`scale_centre` and :func:`anchor_spread`: with no known distance, a uniform scale is held
  by one fixture's radius about the joint-1 axis point, off by the nominal model's spread;
* :func:`gauge_left`: the joint-1 parameters to fix so that no rigid motion keeping the known
  centres stays free.
"""

from __future__ import annotations

import numpy as np

from spherecal.correction import RobotModel, link_frames, param_jacobian
from spherecal.correction.files.samples import Dataset

from .problem import GAUGE


def scale_centre(model: RobotModel) -> np.ndarray:
    """(3,) the point on the joint-1 axis about which a uniform scale of the other lengths acts [m].

    With the joint-1 gauge parameters fixed, scaling every length from joint 2 on scales the tool
    points about this point: the frame-1 origin (modified DH) or the base origin moved ``d1``
    along the joint-1 axis (standard DH).
    """
    base = model.base_transform
    if model.convention == "modified":
        return link_frames(model, np.zeros(model.n_joints))[1, :3, 3]
    return base[:3, 3] + model.d[0] * base[:3, 2]


def anchor_spread(model: RobotModel, q: np.ndarray, point: np.ndarray) -> float:
    """Prior spread [m] of the distance between the mean tool point of ``q`` and ``point`` on ``model``.

    What a scale taken from the nominal model is off by: the radius's gradient with respect to the
    parameters times their prior spread (the layout's prior spread; gauge and base parameters left out).

    Args:
        model: the robot.
        q: (K, n) configurations at one fixture [rad].
        point: (3,) the scale centre [m] (:func:`scale_centre`).
    """
    jac, points = param_jacobian(model, q, return_point=True)
    radial = points.mean(axis=0) - point
    grad = (radial / np.linalg.norm(radial)) @ jac.mean(axis=0)  # (P,)
    prior = model.layout.spread()
    prior[[model.param_index(name) for name in GAUGE[model.convention]]] = 0.0
    prior[model.layout.base] = 0.0
    return max(float(np.linalg.norm(grad * prior)), 1e-9)


def gauge_left(model: RobotModel, dataset: Dataset, known: list[np.ndarray]) -> list[str]:
    """Joint-1 parameters to fix so that no rigid motion keeping the ``known`` centres stays free.

    Each joint-1 gauge parameter moves every tool point by a twist ``dp = w x p + v`` (constant:
    it acts before every joint variable). Combinations of them that keep every known centre in
    place (``w x c + v = 0``) are invisible; one parameter per such direction is fixed (pivoted QR,
    preferring ``theta1, d1, alpha1, a1``).
    """
    from scipy.linalg import qr  # scipy: loaded only when this path runs (start-up)

    gauge = list(GAUGE[model.convention])[::-1]  # theta1, d1, alpha1, a1 (preference to fix)
    q = dataset.q[np.linspace(0, dataset.n_samples - 1, min(dataset.n_samples, 12)).astype(int)]
    jac, points = param_jacobian(model, q, return_point=True)
    # fit (w, v) of every gauge column from dp_k = -p_k x w + v (exact for a rigid motion)
    skew = np.zeros((points.shape[0], 3, 3))
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = points[:, 2], -points[:, 1], points[:, 0]
    skew -= skew.transpose(0, 2, 1)
    design = np.concatenate([skew, np.broadcast_to(np.eye(3), skew.shape)], axis=2).reshape(-1, 6)
    cols = [model.param_index(name) for name in gauge]
    twists = np.linalg.lstsq(design, jac[:, :, cols].reshape(-1, len(cols)), rcond=None)[0]  # (6, g)
    moves = []
    for c in known:  # displacement of each known centre under each gauge twist: w x c + v
        moves.append(np.cross(twists[:3].T, c).T + twists[3:])
    a = np.concatenate(moves)  # (3 * known, g)
    s = np.linalg.svd(a, compute_uv=False)
    rank = int(np.sum(s > 1e-9 * max(1.0, s[0]))) if s.size else 0
    free_dims = len(cols) - rank
    if free_dims <= 0:
        return []
    _, _, vt = np.linalg.svd(a)
    null = vt[rank:]  # (free_dims, g)
    _, _, pivots = qr(null, pivoting=True)
    return sorted((gauge[i] for i in pivots[:free_dims]), key=GAUGE[model.convention].index)
