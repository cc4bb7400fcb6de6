"""Elastic joints: the link angle is the measured angle minus a compliance times the gravity torque::

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
        InertialsError: not n finite numbers, or a non-zero compliance without an ``inertials`` block (or with a
            malformed one).
    """
    c = joint_vector(model, "compliance", "[rad/Nm]", InertialsError)
    if np.any(c != 0):
        inertials_of(model)  # a compliance without masses has no effect: refuse it loudly
    return c


def with_compliance(model: RobotModel, compliance: np.ndarray | None) -> RobotModel:
    """A copy of ``model`` with ``extras["compliance"]`` set to ``compliance`` (n,) [rad/Nm] (removed when None).

    Not checked here: :func:`compliance_of` (every kinematic function) refuses a non-zero compliance on a model
    without ``inertials``. The parameter vector gains ``c1..cn`` (:attr:`RobotModel.layout`) even when all are
    zero.

    Args:
        model: the arm.
        compliance: (n,) compliances [rad/Nm], or None.
    """
    return with_joint_vector(model, "compliance", compliance)


def with_stiffness(model: RobotModel, stiffness: np.ndarray) -> RobotModel:
    """A copy of ``model`` with joint stiffnesses as its compliance ``1 / stiffness`` [rad/Nm].

    Args:
        model: the arm.
        stiffness: (n,) joint stiffness [Nm/rad]; 0 or less is a rigid joint (every joint rigid: no compliance
            at all, the list removed).
    """
    k = np.asarray(stiffness, dtype=float)
    compliance = np.divide(1.0, k, out=np.zeros_like(k), where=k > 0)
    return with_compliance(model, compliance if np.any(compliance) else None)


def link_angles(model: RobotModel, q: np.ndarray, compliance: np.ndarray | None = None,
                torques: np.ndarray | None = None) -> np.ndarray:
    """Link angles ``q - c tau(q)`` of joint angles ``q`` (compliance only: a scaled model's angles are scaled
    first, :func:`.scale.joint_angles`; :mod:`.kinematics` does both).

    Args:
        model: the arm (its ``inertials`` give ``tau``).
        q: (N, n) or (n,) joint angles [rad] (not checked for degrees).
        compliance: (n,) [rad/Nm]; ``model``'s when None. All zero: ``q`` is returned unchanged.
        torques: ``tau(q)``, shaped as ``q`` [Nm], when the caller has it already (:func:`gravity_torques`).

    Returns:
        Link angles shaped as ``q`` [rad].

    Raises:
        InertialsError: as :func:`compliance_of`, or no ``inertials`` to compute ``tau``.
    """
    c = compliance_of(model) if compliance is None else np.asarray(compliance, dtype=float)
    q = np.asarray(q, dtype=float)
    if not np.any(c):
        return q
    return q - c * (gravity_torques(model, q) if torques is None else torques)


def motor_angles(model: RobotModel, q_link: np.ndarray, compliance: np.ndarray | None = None) -> np.ndarray:
    """Joint angles that put the links at ``q_link``: the inverse of :func:`link_angles`.

    Solves ``q - c tau(q) = q_link`` by :data:`MOTOR_ITERATIONS` fixed-point iterations (a contraction:
    ``c |dtau/dq|`` is about 1e-3: a Panda at 3e4 Nm/rad is back to rounding).

    Args:
        model: the arm.
        q_link: (N, n) or (n,) link angles [rad].
        compliance: (n,) [rad/Nm]; ``model``'s when None. All zero: ``q_link`` is returned unchanged.

    Returns:
        Joint angles shaped as ``q_link`` [rad].

    Raises:
        InertialsError: as :func:`link_angles`.
    """
    c = compliance_of(model) if compliance is None else np.asarray(compliance, dtype=float)
    q_link = np.asarray(q_link, dtype=float)
    if not np.any(c):
        return q_link
    q = q_link
    for _ in range(MOTOR_ITERATIONS):
        q = q_link + c * gravity_torques(model, q)
    return q
