"""Per-joint angle scale: the joint's angle is its recorded angle times ``1 + s``::

    q_joint = (1 + s) * q          s (n,) dimensionless, q (N, n) recorded angles [rad]

An encoder or transmission whose ratio is off by ``s`` (a gear ratio, an encoder's counts per turn, a
joint-torque sensor's elastic offset proportional to the angle) turns the recorded angle ``q`` into
``(1 + s) q``. On an elastic model (:mod:`.elastic`) the scale comes first: the compliance deflects the
scaled angle, ``q_link = q_joint - c tau(q_joint)`` (see ``correction.kinematics``).

The scales live in ``model.extras["scale"]`` (a robot file's ``scale:`` list, one number per joint,
zero for an exact joint); the layout carries them as ``s1 .. sn`` (:data:`.layout.SCALE`).
"""

from __future__ import annotations

import numpy as np

from .errors import SpherecalError
from .model import RobotModel, joint_vector, with_joint_vector


class ScaleError(SpherecalError):
    """A malformed ``scale`` list; the message names the field."""


def scale_of(model: RobotModel) -> np.ndarray:
    """(n,) joint angle scales ``s`` (dimensionless) from ``model.extras["scale"]``; zeros when absent.

    Raises:
        ScaleError: not ``n`` finite numbers.
    """
    return joint_vector(model, "scale", "(dimensionless)", ScaleError)


def with_scale(model: RobotModel, scale: np.ndarray | None) -> RobotModel:
    """A copy of ``model`` with ``extras["scale"]`` set (removed when None; zeros keep the list, and the
    ``s1..sn`` parameters, with no effect on the angles).

    Args:
        model: the arm.
        scale: (n,) angle scales ``s`` (dimensionless), or None.
    """
    return with_joint_vector(model, "scale", scale)


def joint_angles(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """Joint angles ``(1 + s) q`` of recorded angles ``q``; ``q`` itself without scale.

    Args:
        model: the arm.
        q: (N, n) or (n,) recorded angles [rad].

    Returns:
        Joint angles [rad], shaped as ``q``.

    Raises:
        ScaleError: as :func:`scale_of`.
    """
    q = np.asarray(q, dtype=float)
    if "scale" not in model.extras:
        return q
    s = scale_of(model)
    return q if not np.any(s) else q * (1.0 + s)


def recorded_angles(model: RobotModel, q_joint: np.ndarray) -> np.ndarray:
    """The inverse of :func:`joint_angles`: recorded angles ``q_joint / (1 + s)``.

    Args:
        model: the arm.
        q_joint: (N, n) or (n,) joint angles [rad].

    Returns:
        Recorded angles [rad], shaped as ``q_joint``.

    Raises:
        ScaleError: as :func:`scale_of`.
    """
    q_joint = np.asarray(q_joint, dtype=float)
    if "scale" not in model.extras:
        return q_joint
    return q_joint / (1.0 + scale_of(model))
