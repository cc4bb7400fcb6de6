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

from dataclasses import replace

import numpy as np

from .chain import _rigid_joint_jacobian, rigid_tool_point
from .gravity import InertialsError, gravity_torques, inertials_of
from .model import RobotModel
from .scale import joint_angles

#: Fixed-point iterations of :func:`motor_angles` (each gains a factor c |dtau/dq| ~ 1e-3).
MOTOR_ITERATIONS = 6


def compliance_of(model: RobotModel) -> np.ndarray:
    """(n,) joint compliances [rad/Nm] from ``model.extras["compliance"]``; zeros when absent.

    Raises:
        InertialsError: a malformed list, or compliances without an ``inertials`` block.
    """
    block = model.extras.get("compliance")
    if block is None:
        return np.zeros(model.n_joints)
    try:
        c = np.asarray(block, dtype=float)
    except (TypeError, ValueError):
        c = np.empty(0)
    if c.shape != (model.n_joints,) or not np.all(np.isfinite(c)):
        raise InertialsError(
            f"{model.name}: field 'compliance': expected {model.n_joints} finite numbers [rad/Nm], got {block!r}"
        )
    if np.any(c != 0):
        inertials_of(model)  # a compliance without masses has no effect: refuse it loudly
    return c


def is_elastic(model: RobotModel) -> bool:
    """True when some joint has a non-zero compliance."""
    return bool(np.any(compliance_of(model) != 0))


def with_compliance(model: RobotModel, compliance: np.ndarray | None) -> RobotModel:
    """A copy of ``model`` with ``extras["compliance"]`` set to (n,) [rad/Nm] (removed when None)."""
    extras = {k: v for k, v in model.extras.items() if k != "compliance"}
    if compliance is not None:
        extras["compliance"] = [float(v) for v in np.asarray(compliance, dtype=float).reshape(model.n_joints)]
    return replace(model, extras=extras)


def link_angles(model: RobotModel, q: np.ndarray, compliance: np.ndarray | None = None) -> np.ndarray:
    """Link angles ``q - c tau(q)`` of measured angles ``q`` (N, n) or (n,) [rad].

    Args:
        compliance: (n,) [rad/Nm]; ``model``'s when None. All zero: ``q`` is returned unchanged.
    """
    c = compliance_of(model) if compliance is None else np.asarray(compliance, dtype=float)
    q = np.asarray(q, dtype=float)
    if not np.any(c):
        return q
    return q - c * gravity_torques(model, q)


def elastic_tool_point(model: RobotModel, q: np.ndarray, compliance: np.ndarray | None = None) -> np.ndarray:
    """(N, 3) tool point [m] of measured angles ``q`` (N, n): the geometric tool point at the link angles
    (what :func:`correction.tool_point` gives for a model carrying ``compliance``; a ``scale`` applies first)."""
    model = model if compliance is None else with_compliance(model, compliance)
    q = joint_angles(model, q)
    return rigid_tool_point(model, link_angles(model, q))


def compliance_jacobian(model: RobotModel, q: np.ndarray, compliance: np.ndarray | None = None) -> np.ndarray:
    """(N, 3, n) ``d p / d c`` [m per rad/Nm]: ``-J_q(q_link)[:, :, i] tau_i(q_joint)`` (exact: tau is
    evaluated at the scaled measured angles ``q_joint``, :mod:`.scale`, which do not depend on ``c``)."""
    q = joint_angles(model, np.atleast_2d(np.asarray(q, dtype=float)))
    tau = gravity_torques(model, q)
    return -_rigid_joint_jacobian(model, link_angles(model, q, compliance)) * tau[:, None, :]


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
