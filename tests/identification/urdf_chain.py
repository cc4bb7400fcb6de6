"""A URDF serial chain evaluated directly (product of joint origins and axis rotations): the
independent reference the hand-written MUKCa robot files are checked against."""

from __future__ import annotations

import numpy as np


def _rot(axis: np.ndarray, angle: float) -> np.ndarray:
    axis = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)


def origin(xyz, rpy) -> np.ndarray:
    """4x4 of a URDF ``<origin>``: translation, then R = Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = rpy
    out = np.eye(4)
    out[:3, :3] = _rot([0, 0, 1], y) @ _rot([0, 1, 0], p) @ _rot([1, 0, 0], r)
    out[:3, 3] = xyz
    return out


def chain_point(joints: list[tuple], tip: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(N, 3) tip point [m] of a chain of ``(xyz, rpy, axis)`` revolute joints (fixed joints folded into ``tip``)."""
    out = []
    for qk in np.atleast_2d(q):
        T = np.eye(4)
        for (xyz, rpy, axis), angle in zip(joints, qk, strict=True):
            T = T @ origin(xyz, rpy)
            R = np.eye(4)
            R[:3, :3] = _rot(axis, angle)
            T = T @ R
        out.append(T[:3, :3] @ tip + T[:3, 3])
    return np.array(out)


#: MUKCa's urdf/gen3lite.urdf, kinova_base_link -> end_effector_link (joint_1 .. joint_6).
GEN3LITE = [
    ((0, 0, 0.12825), (0, 0, 0), (0, 0, 1)),
    ((0, -0.03, 0.115), (1.5708, 0, 0), (0, 0, 1)),
    ((0, 0.28, 0), (-3.1416, 0, 0), (0, 0, 1)),
    ((0, -0.14, 0.02), (1.5708, 0, 0), (0, 0, 1)),
    ((0.0285, 0, 0.105), (0, 1.5708, 0), (0, 0, 1)),
    ((-0.105, 0, 0.0285), (0, -1.5708, 0), (0, 0, 1)),
]
#: ball_link in end_effector_link (end_effector, arm_gripper_base_joint fixed at identity, then ball_joint).
GEN3LITE_BALL = np.array([0.00038860649894460975, -0.0005822849938650045, 0.180196205872143])
