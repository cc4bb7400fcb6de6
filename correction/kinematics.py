"""Batched forward kinematics and analytic Jacobians of a :class:`RobotModel`.

All functions take joint angles ``q`` of shape (N, n) (or (n,) for one configuration, in
which case the batch axis is dropped from the result, except by :func:`frames`, which keeps
it as N = 1). Joint angle scales (``extras["scale"]``, :mod:`.scale`) and an elastic model
(``extras["compliance"]``, :mod:`.elastic`) are handled here, in that order: the tool point, tool pose
and both Jacobians take the *measured* angles ``q`` and work at the link angles

    q_joint = (1 + s) q                  (scale first: what the joint turns)
    q_link  = q_joint - c tau(q_joint)   (then gravity's deflection of that joint)

:func:`frames` and :func:`link_frames` take link angles as given. Internally a frame is kept as its
three axes and origin, each of shape (3, N), so that every step is a handful of contiguous
vector operations over the batch: no Python loop over samples.

The public functions refuse (:class:`JointAngleError`) an angle more than a full turn beyond its joint's limits
(:data:`ANGLE_MARGIN`): no revolute joint reports it, and a configuration in degrees does.
"""

from __future__ import annotations

import numpy as np

from .chain import (
    _as_batch,
    _cross,
    _homogeneous,
    _rigid_joint_jacobian,
    _tool_point,
    frames,
    rigid_tool_point,
)
from .elastic import compliance_of, link_angles
from .errors import SpherecalError
from .gravity import gravity_torques
from .model import RobotModel
from .scale import joint_angles, scale_of

#: How far beyond a joint's limits [rad] an angle given to the public entry points may lie: a full turn. Further, it
#: is no angle of that joint whatever its encoder's wrap or its file's limits (MUKCa's Gen3 lite passes gen3lite.urdf's
#: q6 limit by 0.65 rad; a joint that turns freely, URDF "continuous" (:attr:`RobotModel.full_turn`), is not checked:
#: a wrist that has turned five times reads 31 rad), and
#: most likely degrees: a Panda's joints accept up to 9.2 to 10 rad (down to -6.3 on its 6th), so a configuration in
#: degrees passes only with every joint within about 10 deg of zero. The samples reader is stricter (a quarter turn:
#: files.samples.HARD_MARGIN); these functions also see controller and IK states.
ANGLE_MARGIN = float(2 * np.pi)


class JointAngleError(SpherecalError):
    """Joint angles a revolute joint cannot report (beyond its limits by more than :data:`ANGLE_MARGIN`): degrees
    given where radians are expected, or another arm's configuration."""


def _checked(model: RobotModel, q: np.ndarray) -> tuple[np.ndarray, bool]:
    """``q`` as an (N, n) batch (and whether it was one configuration), refused with :class:`JointAngleError` when an
    angle lies more than :data:`ANGLE_MARGIN` beyond its joint's limits: the public entry points' check (two
    reductions over the whole batch, per joint only when those pass the narrowest joint's bound; a NaN is not refused
    here). Internal callers on angles already read and checked (identification's residuals) may use
    ``chain._as_batch`` and the ``_`` functions."""
    q2, single = _as_batch(model, q)
    if not q2.size:
        return q2, single
    if not (q2.max() <= model.upper.min() + ANGLE_MARGIN and q2.min() >= model.lower.max() - ANGLE_MARGIN):
        # past the narrowest joint's bound (the test above: 2 x 7 us per 10k x 7): per joint, 0.6 ms per 10k x 7
        upper, lower = np.asarray(model.upper) + ANGLE_MARGIN, np.asarray(model.lower) - ANGLE_MARGIN
        turning = model.full_turn  # a joint that turns freely (URDF "continuous") counts its turns: any angle is one
        upper, lower = np.where(turning, np.inf, upper), np.where(turning, -np.inf, lower)
        high, low = q2.max(axis=0), q2.min(axis=0)
        if np.any(high > upper) or np.any(low < lower):
            i = int(np.argmax(np.maximum(high - upper, lower - low)))
            k = int(np.argmax(np.maximum(q2[:, i] - upper[i], lower[i] - q2[:, i])))
            where = f"q[{i}]" if single else f"q[{k}, {i}]"
            raise JointAngleError(
                f"{where} (joint {i + 1}): {q2[k, i]:.6g} rad is more than a full turn ({ANGLE_MARGIN:.3g} rad) "
                f"beyond the joint limits [{model.lower[i]:.4g}, {model.upper[i]:.4g}] of {model.name}: no angle of "
                f"this joint (degrees? {q2[k, i]:.6g} deg is {np.radians(q2[k, i]):.4g} rad)")
    return q2, single


def _link_angles(model: RobotModel, q: np.ndarray, torques: np.ndarray | None = None) -> np.ndarray:
    """Link angles of measured angles ``q`` (N, n) [rad]: ``q_joint = (1 + s) q`` (scaled model, else ``q``),
    then ``q_joint - c tau(q_joint)`` (elastic model, else ``q_joint``; ``torques``: ``tau(q_joint)`` when known)."""
    q = joint_angles(model, q)
    if "compliance" not in model.extras:
        return q
    return link_angles(model, q, torques=torques)


def _dlink_djoint(model: RobotModel, q_joint: np.ndarray, jac: np.ndarray) -> np.ndarray:
    """``jac`` (N, 3, n) ``d p / d q_link`` times ``d q_link / d q_joint = I - diag(c) d tau / d q_joint``
    (unchanged for a rigid model); the torque's derivative by central differences (step 1e-6 rad: its
    error is ~1e-12 of the term, which is itself ~1e-3 of the Jacobian)."""
    if "compliance" not in model.extras:
        return jac
    c, h = compliance_of(model), 1e-6
    if not np.any(c):
        return jac
    n = model.n_joints
    shift = h * np.eye(n)
    dtau = np.stack([gravity_torques(model, q_joint + shift[k]) - gravity_torques(model, q_joint - shift[k])
                     for k in range(n)], axis=2) / (2 * h)  # (N, n, n): d tau_i / d q_k
    return jac - np.einsum("nxi,nik->nxk", jac * c, dtau)


def tool_pose(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """(N, 4, 4) pose of the tool: orientation of the last link, origin at the tool point.

    Raises:
        JointAngleError: an angle more than a full turn beyond its joint's limits (degrees given for radians?).
    """
    _, single = _checked(model, q)
    f = frames(model, _link_angles(model, np.asarray(q, dtype=float)))
    pose = _homogeneous(f.x[-1], f.y[-1], f.z[-1], _tool_point(model, f))
    return pose[0] if single else pose


def tool_point(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """(N, 3) tool point (centre of the spherical joint) in the world [m].

    Runs the chain backwards on the point alone (three numbers per sample and joint instead
    of a whole frame), the fast path that identification's residuals live on.

    Args:
        model: the arm.
        q: (N, n) or (n,) measured joint angles [rad], each within a full turn (:data:`ANGLE_MARGIN`) of its
            joint's limits (``model.lower``, ``model.upper``); the check costs two reductions over ``q``.

    Returns:
        (N, 3), or (3,) for one configuration, [m].

    Raises:
        JointAngleError: an angle more than a full turn beyond its joint's limits (degrees given for radians?).
    """
    q, single = _checked(model, q)
    p = rigid_tool_point(model, _link_angles(model, q))
    return p[0] if single else p


def joint_jacobian(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """Jacobian of the tool point with respect to the joint angles.

    Args:
        q: (N, n) joint angles [rad].

    Returns:
        (N, 3, n) ``d p / d q`` [m/rad]. Elastic model: ``J(q_link) (I - diag(c) d tau / d q_joint)``, the
        torque's derivative by central differences (step 1e-6 rad: its error is ~1e-12 of the term, which
        is itself ~1e-3 of the Jacobian); scaled model: times ``diag(1 + s)``.

    Raises:
        JointAngleError: an angle more than a full turn beyond its joint's limits (degrees given for radians?).
    """
    q2, single = _checked(model, q)
    q_joint = joint_angles(model, q2)
    jac = _dlink_djoint(model, q_joint, _rigid_joint_jacobian(model, _link_angles(model, q2)))
    if "scale" in model.extras:
        jac = jac * (1.0 + scale_of(model))
    return jac[0] if single else jac


def link_angle_jacobian(model: RobotModel, q: np.ndarray) -> np.ndarray | None:
    """(N, n, n) ``d q_link / d q`` of measured angles ``q`` (N, n) [rad/rad], None for a model whose link
    angles are the measured ones.

    Central differences (step 1e-6 rad) of the model's own map from measured to link angles, so every term
    that map carries (joint compliance, and any other joint-side term added to it) is differentiated without
    a formula of its own: the map is smooth and within 1e-2 of the identity, the difference error ~1e-12.

    Raises:
        JointAngleError: an angle more than a full turn beyond its joint's limits (degrees given for radians?).
    """
    q2, _ = _checked(model, q)
    if _link_angles(model, q2) is q2:
        return None
    n, h = model.n_joints, 1e-6
    shift = h * np.eye(n)
    columns = [(_link_angles(model, q2 + shift[k]) - _link_angles(model, q2 - shift[k])) / (2 * h) for k in range(n)]
    return np.stack(columns, axis=2)  # [:, i, k] = d q_link_i / d q_k


def pose_jacobian(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """Jacobian of the tool point and of the tool orientation with respect to the joint angles, for the full
    model (elastic terms included: taken at the link angles, through :func:`link_angle_jacobian`).

    Args:
        q: (N, n) measured joint angles [rad].

    Returns:
        (N, 6, n): rows 0-2 ``d p / d q`` [m/rad] (as :func:`joint_jacobian`), rows 3-5 the angular
        velocity of the tool frame in the world per unit joint rate [rad/rad].

    Raises:
        JointAngleError: an angle more than a full turn beyond its joint's limits (degrees given for radians?).
    """
    q2, single = _checked(model, q)
    q_link = _link_angles(model, q2)
    f = frames(model, q_link)
    axes = f.z[1:] if model.convention == "modified" else f.z[:-1]  # (n, 3, N): joint i turns about these
    angular = np.moveaxis(axes, 2, 0).transpose(0, 2, 1)  # (N, 3, n)
    chain = link_angle_jacobian(model, q2)
    if chain is not None:
        angular = angular @ chain
    jac = np.concatenate([joint_jacobian(model, q2), angular], axis=1)
    return jac[0] if single else jac


def param_jacobian(
    model: RobotModel, q: np.ndarray, return_point: bool = False
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Jacobian of the tool point with respect to every model parameter.

    Columns follow :attr:`RobotModel.param_names`: per joint ``a, alpha, d, theta``, then
    the tool point, then the base ``x, y, z, roll, pitch, yaw``. Each DH parameter moves the
    chain by a screw about a known world axis, so every column is an axis or an axis
    crossed with a lever arm:

    * modified: ``da = x_{i-1}``, ``dalpha = x_{i-1} x (p - o_{i-1})``, ``dd = z_i``,
      ``dtheta = z_i x (p - o_i)``;
    * standard: ``dtheta = z_{i-1} x (p - o_{i-1})``, ``dd = z_{i-1}``, ``da = x_i``,
      ``dalpha = x_i x (p - o_i)``.

    Hayati angles (columns after the joints' block, see :attr:`RobotModel.layout`): modified
    ``dbeta = y' x (p - o_i + d_i z_i)`` with ``y' = sin(theta_i+q_i) x_i + cos(theta_i+q_i) y_i``
    (the ``y`` axis before ``Rz``); standard ``dbeta = y_i x (p - o_i)``, and there ``a`` and
    ``alpha`` act along ``x' = cos(beta_i) x_i + sin(beta_i) z_i`` (the ``x`` axis before ``Ry``).
    Elastic model: the columns above at the link angles (the torque's own dependence on the
    geometry is neglected: a 1 mm change moves tau by ~1e-3 of itself), then ``d p / d c_i =
    -J_q(q_link)[:, i] tau_i(q_joint)`` (exact: tau is taken at the scaled angles, which do not depend
    on ``c``). Scaled model: ``d p / d s_i = J(q_link)[:, i] q_i``, exact for a rigid model; on an elastic
    one the torque's change with the angle (``c d tau / d q``, ~1e-3 of the column) is neglected as for the
    geometric columns (:func:`joint_jacobian` keeps it: 14 more gravity evaluations per call).

    Args:
        q: (N, n) joint angles [rad].
        return_point: also return the (N, 3) tool point.

    Returns:
        (N, 3, P) ``d p / d params`` [m/m and m/rad], and the tool point if asked.

    Raises:
        JointAngleError: an angle more than a full turn beyond its joint's limits (degrees given for radians?).
    """
    q2, single = _checked(model, q)
    lay = model.layout
    q_joint = joint_angles(model, q2)
    tau = gravity_torques(model, q_joint) if lay.elastic else None  # once: the link angles' and the c columns'
    q_link = _link_angles(model, q2, tau)
    f = frames(model, q_link)
    n = model.n_joints
    p = _tool_point(model, f)
    count = p.shape[1]
    jac = np.empty((model.n_params, 3, count))
    lever = p[None] - f.origin  # (n+1, 3, N)
    # Rotations about x and z of every frame, through its origin.
    rot_x = _cross(np.moveaxis(f.x, 1, 0), np.moveaxis(lever, 1, 0))  # (3, n+1, N)
    rot_z = _cross(np.moveaxis(f.z, 1, 0), np.moveaxis(lever, 1, 0))
    rot_x, rot_z = np.moveaxis(rot_x, 0, 1), np.moveaxis(rot_z, 0, 1)  # (n+1, 3, N)
    rot_y = np.moveaxis(_cross(np.moveaxis(f.y, 1, 0), np.moveaxis(lever, 1, 0)), 0, 1)
    joints = jac[lay.joints].reshape(n, len(lay.joint_fields), 3, count)
    a, alpha, d, theta = (lay.joint_fields.index(name) for name in ("a", "alpha", "d", "theta"))
    hayati = list(lay.hayati)
    if model.convention == "modified":
        joints[:, a] = f.x[:-1]
        joints[:, alpha] = rot_x[:-1]
        joints[:, d] = f.z[1:]
        joints[:, theta] = rot_z[1:]
        if hayati:  # Ry(beta) about y before Rz(theta+q), through o_i - d_i z_i
            k = np.array(hayati) + 1
            angle = (q_link[:, hayati] + model.theta[hayati]).T[:, None, :]  # (h, 1, N)
            axis = np.sin(angle) * f.x[k] + np.cos(angle) * f.y[k]
            arm = lever[k] + model.d[hayati][:, None, None] * f.z[k]
            jac[lay.beta] = np.moveaxis(_cross(np.moveaxis(axis, 1, 0), np.moveaxis(arm, 1, 0)), 0, 1)
    else:
        joints[:, a] = f.x[1:]
        joints[:, alpha] = rot_x[1:]
        joints[:, d] = f.z[:-1]
        joints[:, theta] = rot_z[:-1]
        if hayati:  # Ry(beta) last, about y_i through o_i; a and alpha act along x before it
            k = np.array(hayati) + 1
            cb, sb = np.cos(model.beta[hayati])[:, None, None], np.sin(model.beta[hayati])[:, None, None]
            x_before = cb * f.x[k] + sb * f.z[k]
            joints[hayati, a] = x_before
            joints[hayati, alpha] = np.moveaxis(_cross(np.moveaxis(x_before, 1, 0), np.moveaxis(lever[k], 1, 0)), 0, 1)
            jac[lay.beta] = rot_y[k]
    jac[lay.tool] = np.stack([f.x[-1], f.y[-1], f.z[-1]])
    jac[lay.base_xyz] = np.eye(3)[:, :, None]
    roll, pitch, yaw = model.base_rpy
    cy, sy, cp, sp = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
    base_axes = np.array([[cy * cp, sy * cp, -sp], [-sy, cy, 0.0], [0.0, 0.0, 1.0]])
    base_lever = p - model.base_xyz[:, None]
    for k, row in enumerate(range(lay.base_rpy.start, lay.base_rpy.stop)):
        jac[row] = _cross(base_axes[k][:, None], base_lever)
    if lay.elastic or lay.scaled:
        rigid = _rigid_joint_jacobian(model, q_link, f)  # (N, 3, n)
    if lay.elastic:  # d p / d c_i = -J_q(q_link)[:, i] tau_i(q_joint); exact, q_joint does not depend on c
        jac[lay.compliance] = -rigid.transpose(2, 1, 0) * tau.T[:, None]
    if lay.scaled:  # d p / d s_i = (d p / d q_link)[:, i] q_i, the torque's dependence on q neglected
        jac[lay.scale] = (rigid * q2[:, None, :]).transpose(2, 1, 0)
    out = np.ascontiguousarray(jac.transpose(2, 1, 0))
    if single:
        out, p = out[0], p[:, 0]
    return (out, p.T if not single else p) if return_point else out
