"""Elastic joints: the link angle is the measured angle minus a compliance times the gravity torque.

    q_link = q - c * tau(q)          c (n,) [rad/Nm], tau (N, n) from :func:`gravity_torques`

``q`` is what the encoders record (the motor side of each joint's transmission), ``tau`` the torque
that holds the arm against gravity (MuJoCo's ``qfrc_bias`` sign), so gravity pulls each link by
``-c tau``. ``tau`` is evaluated at the *measured* angles: the first-order model (the deflection
changes ``tau`` by ``c |dtau/dq| tau``, about 1e-4 of it for a stiffness of 3e4 Nm/rad, micrometres at
the tool). The tool point of an elastic arm is the geometric tool point at ``q_link``.

The compliances live in ``model.extras["compliance"]`` (a robot file's ``compliance:`` list, one
number per joint [rad/Nm], zero for a rigid joint); the masses in ``inertials`` / ``payload``.
"""

from __future__ import annotations

import numpy as np

from .gravity import InertialsError, gravity_torques, inertials_of
from .model import RobotModel, joint_vector, with_joint_vector

#: Fixed-point iterations of :func:`motor_angles` (each gains a factor ``c |dtau/dq|`` ~ 1e-3).
MOTOR_ITERATIONS = 6


def compliance_of(model: RobotModel) -> np.ndarray:
    """(n,) joint compliances [rad/Nm] from ``model.extras["compliance"]``; zeros when absent.

    Raises:
        InertialsError: a malformed list, or compliances without an ``inertials`` block.
    """
    c = joint_vector(model, "compliance", "[rad/Nm]", InertialsError)
    if np.any(c != 0):
        inertials_of(model)  # a compliance without masses has no effect: refuse it loudly
    return c


def with_compliance(model: RobotModel, compliance: np.ndarray | None) -> RobotModel:
    """A copy of ``model`` with ``extras["compliance"]`` set to (n,) [rad/Nm] (removed when None)."""
    return with_joint_vector(model, "compliance", compliance)


def with_stiffness(model: RobotModel, stiffness) -> RobotModel:
    """A copy of ``model`` with (n,) joint stiffness [Nm/rad] as its compliance (0 = a rigid joint; every joint
    0: no compliance at all, removed)."""
    k = np.asarray(stiffness, dtype=float)
    compliance = np.divide(1.0, k, out=np.zeros_like(k), where=k > 0)
    return with_compliance(model, compliance if np.any(compliance) else None)


def link_angles(model: RobotModel, q: np.ndarray, compliance: np.ndarray | None = None,
                torques: np.ndarray | None = None) -> np.ndarray:
    """Link angles ``q - c tau(q)`` of measured angles ``q`` (N, n) or (n,) [rad].

    Args:
        compliance: (n,) [rad/Nm]; ``model``'s when None. All zero: ``q`` is returned unchanged.
        torques: ``tau(q)`` (N, n) [Nm] when the caller has it already (:func:`gravity_torques`).
    """
    c = compliance_of(model) if compliance is None else np.asarray(compliance, dtype=float)
    q = np.asarray(q, dtype=float)
    if not np.any(c):
        return q
    return q - c * (gravity_torques(model, q) if torques is None else torques)


def motor_angles(model: RobotModel, q_link: np.ndarray, compliance: np.ndarray | None = None) -> np.ndarray:
    """Measured angles that put the links at ``q_link`` (N, n) [rad]: solves ``q - c tau(q) = q_link``
    by fixed-point iteration (a contraction: ``c |dtau/dq|`` is about 1e-3)."""
    c = compliance_of(model) if compliance is None else np.asarray(compliance, dtype=float)
    q_link = np.asarray(q_link, dtype=float)
    if not np.any(c):
        return q_link
    q = q_link
    for _ in range(MOTOR_ITERATIONS):
        q = q_link + c * gravity_torques(model, q)
    return q
