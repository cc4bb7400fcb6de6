"""The geometric chain of a :class:`RobotModel` at given link angles: frames, tool point, joint Jacobian.

The rigid core that :mod:`.gravity`, :mod:`.elastic` and :mod:`.kinematics` build on (no joint
compliance here: the angles are the links' own). Internally a frame is kept as its three axes and origin,
each of shape (3, N), so that every step is a handful of contiguous vector operations over the batch.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .errors import ShapeError
from .model import RobotModel


class Frames(NamedTuple):
    """World-frame axes and origins of frames 0 (base) .. n at N configurations (:func:`frames`).

    Index ``[i, :, k]`` is frame ``i`` at configuration ``k``: frame 0 the base, frame ``i`` link ``i``'s.
    """

    #: (n+1, 3, N) unit x axes, in the world.
    x: np.ndarray
    #: (n+1, 3, N) unit y axes, in the world.
    y: np.ndarray
    #: (n+1, 3, N) unit z axes, in the world.
    z: np.ndarray
    #: (n+1, 3, N) origins in the world [m].
    origin: np.ndarray


def as_batch(model: RobotModel, q: np.ndarray) -> tuple[np.ndarray, bool]:
    """``q`` as (N, n) [rad], and whether it was one configuration (n,).

    Args:
        model: the arm (its joint count ``n``).
        q: (N, n) or (n,) joint angles [rad].

    Raises:
        ShapeError: ``q`` not of shape (N, n) or (n,) for the model's ``n`` joints.
    """
    q = np.asarray(q, dtype=float)
    single = q.ndim == 1
    q2 = q[None, :] if single else q
    if q2.ndim != 2 or q2.shape[1] != model.n_joints:
        raise ShapeError(
            f"q must have shape (N, {model.n_joints}) or ({model.n_joints},), got {q.shape}"
        )
    return q2, single


def _cross(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Cross product of (3, N) arrays (or a (3, 1) axis against (3, N))."""
    return np.stack(
        [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ]
    )


def frames(model: RobotModel, q: np.ndarray) -> Frames:
    """Axes and origins of every link frame in the world, for the geometric chain at given link angles.

    The angles are taken as given: no joint scale or compliance is applied (see :func:`link_frames`), and no
    :class:`~.kinematics.JointAngleError` check is made.

    Args:
        model: the robot.
        q: (N, n) link angles [rad]; (n,) gives N = 1 (the batch axis is kept).

    Returns:
        :class:`Frames` with arrays of shape (n+1, 3, N): frame 0 is the base, frame ``i`` the frame of link
        ``i``; unit axes, origins [m].

    Raises:
        ValueError: ``q`` not of shape (N, n) or (n,).
    """
    q, _ = as_batch(model, q)
    n, count = model.n_joints, q.shape[0]
    xs, ys, zs, os_ = (np.empty((n + 1, 3, count)) for _ in range(4))
    base = model.base_transform
    xs[0], ys[0], zs[0] = (np.broadcast_to(base[:3, k, None], (3, count)) for k in range(3))
    os_[0] = base[:3, 3, None]
    angle = q + model.theta
    cos_q, sin_q = np.cos(angle).T, np.sin(angle).T
    cos_a, sin_a = np.cos(model.alpha), np.sin(model.alpha)
    cos_b, sin_b = np.cos(model.beta), np.sin(model.beta)
    modified = model.convention == "modified"
    for i in range(n):
        x, y, z, o = xs[i], ys[i], zs[i], os_[i]
        c, s = cos_q[i], sin_q[i]
        if modified:  # Rx(alpha) Lx(a) Ry(beta) Rz(theta+q) Lz(d)
            o = o + model.a[i] * x
            y, z = cos_a[i] * y + sin_a[i] * z, cos_a[i] * z - sin_a[i] * y
            if model.beta[i] != 0.0:
                x, z = cos_b[i] * x - sin_b[i] * z, sin_b[i] * x + cos_b[i] * z
            x, y = c * x + s * y, c * y - s * x
            o = o + model.d[i] * z
        else:  # Rz(theta+q) Lz(d) Lx(a) Rx(alpha) Ry(beta)
            x, y = c * x + s * y, c * y - s * x
            o = o + model.d[i] * z + model.a[i] * x
            y, z = cos_a[i] * y + sin_a[i] * z, cos_a[i] * z - sin_a[i] * y
            if model.beta[i] != 0.0:
                x, z = cos_b[i] * x - sin_b[i] * z, sin_b[i] * x + cos_b[i] * z
        xs[i + 1], ys[i + 1], zs[i + 1], os_[i + 1] = x, y, z, o
    return Frames(xs, ys, zs, os_)


def _tool_point(model: RobotModel, f: Frames) -> np.ndarray:
    """(3, N) tool point in the world from the last frame."""
    t = model.tool
    return f.origin[-1] + t[0] * f.x[-1] + t[1] * f.y[-1] + t[2] * f.z[-1]


def _homogeneous(x: np.ndarray, y: np.ndarray, z: np.ndarray, o: np.ndarray) -> np.ndarray:
    """(..., N, 4, 4) transforms from axes and origins of shape (..., 3, N)."""
    pose = np.zeros(x.shape[:-2] + (x.shape[-1], 4, 4))
    for k, column in enumerate((x, y, z, o)):
        pose[..., :3, k] = np.moveaxis(column, -1, -2)
    pose[..., 3, 3] = 1.0
    return pose


def link_frames(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """Homogeneous transforms of every link frame in the world, for the geometric chain at given link angles.

    The angles are taken as given (no :class:`~.kinematics.JointAngleError` check): on a model with a joint
    scale or compliance these are not the frames at measured angles. Pass the link angles,
    ``elastic.link_angles(model, scale.joint_angles(model, q))``, as :func:`.kinematics.tool_pose` does;
    given measured angles instead, the last frame of a Panda with 3e4 Nm/rad joints and
    0.1 % scales is off by up to 8e-3 in its rotation's entries.

    Args:
        model: the robot.
        q: (N, n) or (n,) link angles [rad] (the measured angles on a rigid, unscaled model).

    Returns:
        (N, n+1, 4, 4), or (n+1, 4, 4) for one configuration: frame 0 is the base, frame ``i`` link ``i``;
        translations [m].

    Raises:
        ValueError: ``q`` not of shape (N, n) or (n,).
    """
    _, single = as_batch(model, q)
    f = frames(model, q)
    poses = np.moveaxis(_homogeneous(f.x, f.y, f.z, f.origin), 0, 1)
    return poses[0] if single else poses


def rigid_tool_point(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """Tool point of the geometric chain at given link angles (no scale, compliance or angle check).

    Runs the chain backwards on the point alone (three numbers per sample and joint instead
    of a whole frame), the fast path that identification's residuals live on. On measured angles use
    :func:`.kinematics.tool_point`, which applies the model's scale and compliance and refuses degrees.

    Args:
        model: the robot.
        q: (N, n) or (n,) link angles [rad].

    Returns:
        (N, 3), or (3,) for one configuration, [m] in the world.

    Raises:
        ValueError: ``q`` not of shape (N, n) or (n,).
    """
    q, single = as_batch(model, q)
    angle = (q + model.theta).T
    cos_q, sin_q = np.cos(angle), np.sin(angle)
    count = q.shape[0]
    x, y, z = (np.full(count, v) for v in model.tool)
    modified = model.convention == "modified"
    for i in reversed(range(model.n_joints)):
        c, s = cos_q[i], sin_q[i]
        ca, sa = np.cos(model.alpha[i]), np.sin(model.alpha[i])
        beta = model.beta[i]
        if modified:  # Rx(alpha) Lx(a) Ry(beta) Rz(theta+q) Lz(d)
            z = z + model.d[i]
            x, y = c * x - s * y, s * x + c * y
            if beta != 0.0:
                x, z = np.cos(beta) * x + np.sin(beta) * z, np.cos(beta) * z - np.sin(beta) * x
            x = x + model.a[i]
            y, z = ca * y - sa * z, sa * y + ca * z
        else:  # Rz(theta+q) Lz(d) Lx(a) Rx(alpha) Ry(beta)
            if beta != 0.0:
                x, z = np.cos(beta) * x + np.sin(beta) * z, np.cos(beta) * z - np.sin(beta) * x
            y, z = ca * y - sa * z, sa * y + ca * z
            x = x + model.a[i]
            z = z + model.d[i]
            x, y = c * x - s * y, s * x + c * y
    base = model.base_transform
    p = np.stack([x, y, z], axis=1) @ base[:3, :3].T + base[:3, 3]
    return p[0] if single else p


def _rigid_joint_jacobian(model: RobotModel, q: np.ndarray, f: Frames | None = None) -> np.ndarray:
    """(N, 3, n) ``d p / d q`` of the geometric chain at link angles ``q`` (N, n) [m/rad] (``f``: their
    :func:`frames` when already known)."""
    f = frames(model, q) if f is None else f
    p = _tool_point(model, f)
    axes = slice(1, None) if model.convention == "modified" else slice(0, -1)
    z = np.moveaxis(f.z[axes], 1, 0)  # (3, n, N): joint i turns about z of this frame
    lever = p[:, None, :] - np.moveaxis(f.origin[axes], 1, 0)
    return np.ascontiguousarray(np.moveaxis(_cross(z, lever), 2, 0))  # (N, 3, n)
