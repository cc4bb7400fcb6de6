"""Batched forward kinematics and analytic Jacobians of a :class:`RobotModel`.

Every function takes measured joint angles ``q`` [rad] of shape (N, n), N configurations of an n-joint arm,
or (n,) for one configuration, in which case the batch axis is dropped from the result. Joint angle scales
(``extras["scale"]``, :mod:`.scale`) and an elastic model (``extras["compliance"]``, :mod:`.elastic`) are handled
here, in that order: the tool point, tool pose and the Jacobians take the *measured* angles ``q`` and work at the link
angles::

    q_joint = (1 + s) q                  (scale first: what the joint turns)
    q_link  = q_joint - c tau(q_joint)   (then gravity's deflection of that joint)

:func:`.chain.frames` and :func:`.chain.link_frames` take link angles as given (no scale, no compliance, no
check). Internally a frame is kept as its three axes and origin, each of shape (3, N), so that every step is
a handful of contiguous vector operations over the batch: no Python loop over samples.

The functions here refuse (:class:`JointAngleError`) an angle more than a full turn beyond its joint's limits
(:data:`ANGLE_MARGIN`): no revolute joint reports it, and a configuration in degrees does. Every one raises:

* :class:`JointAngleError`: an angle more than :data:`ANGLE_MARGIN` beyond its joint's limits;
* ``ValueError``: ``q`` of another shape than (N, n) or (n,);
* :class:`~.gravity.InertialsError`: an elastic model (non-zero ``compliance``) without an ``inertials``
  block, or a ``compliance`` list that is not n finite numbers;
* :class:`~.scale.ScaleError`: a ``scale`` list that is not n finite numbers.

(A model read from a robot file has had its lists checked: only the first two can arise there.)

Example::

    import numpy as np
    from spherecal.correction import load_robot, tool_point, joint_jacobian
    panda = load_robot("panda")
    q = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])   # (7,) [rad]
    tool_point(panda, q)                                    # (3,) [m]
    joint_jacobian(panda, q[None])                          # (1, 3, 7) [m/rad]
"""

from __future__ import annotations

import numpy as np

from .chain import (
    _cross,
    _homogeneous,
    _rigid_joint_jacobian,
    _tool_point,
    as_batch,
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
    ``chain.as_batch`` and the ``_`` functions."""
    q2, single = as_batch(model, q)
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


#: Step [rad] of the central differences of the gravity torque (:func:`_torque_slope`).
_STEP = 1e-6


def _dlink_djoint(model: RobotModel, q_joint: np.ndarray, jac: np.ndarray) -> np.ndarray:
    """``jac`` (N, 3, n) ``d p / d q_link`` times ``d q_link / d q_joint = I - diag(c) d tau / d q_joint``
    (unchanged for a rigid model); the torque's derivative by central differences (step 1e-6 rad: its
    error is ~1e-12 of the term, which is itself ~1e-3 of the Jacobian)."""
    if "compliance" not in model.extras:
        return jac
    c = compliance_of(model)
    if not np.any(c):
        return jac
    return _through_deflection(jac, c, _torque_slope(model, q_joint))


def _through_deflection(jac: np.ndarray, c: np.ndarray, slope: np.ndarray) -> np.ndarray:
    """``jac`` (N, m, n) ``d / d q_link`` carried to ``d / d q_joint``: ``jac (I - diag(c) slope)``, ``slope`` (N, n, n)
    the torque's (:func:`_torque_slope`)."""
    return jac - np.einsum("nxi,nik->nxk", jac * c, slope)


def _link_chain(s: np.ndarray, c: np.ndarray, slope: np.ndarray | None, count: int) -> np.ndarray:
    """(N, n, n) ``d q_link / d q = (I - diag(c) slope) diag(1 + s)`` for ``count`` configurations (``slope`` None:
    no compliance)."""
    n = len(s)
    jac = np.broadcast_to(np.eye(n), (count, n, n))
    if slope is not None:
        jac = jac - c[:, None] * slope
    return jac * (1.0 + s)  # column k times d q_joint_k / d q_k


def _torque_slope(model: RobotModel, q_joint: np.ndarray) -> np.ndarray:
    """(N, n, n) ``[:, i, k] = d tau_i / d q_joint_k`` [Nm/rad] at ``q_joint`` (N, n) [rad]: central differences
    (step :data:`_STEP`) of :func:`gravity_torques`, one batch of the 2 n shifted copies. Its rounding floor is
    ~1e-16 |tau| / step, ~1e-8 Nm/rad, and its truncation ~1e-12 |d3 tau|: times a compliance (~1e-4 rad/Nm at
    most), ~1e-12 of an angle's derivative."""
    tau = gravity_torques(model, _shifted(q_joint, _STEP))
    return _central(tau, _STEP, q_joint.shape)


def _shifted(q: np.ndarray, h: float) -> np.ndarray:
    """(2 n N, n): ``q`` (N, n) shifted by ``+h`` on each joint in turn, then by ``-h`` (:func:`_central`)."""
    shift = h * np.eye(q.shape[1])[:, None, :]  # (n, 1, n)
    return np.concatenate([q[None] + shift, q[None] - shift]).reshape(-1, q.shape[1])


def _central(values: np.ndarray, h: float, shape: tuple[int, int]) -> np.ndarray:
    """(N, m, n) central differences ``[:, i, k] = d value_i / d q_k`` of ``values`` (2 n N, m) at :func:`_shifted`'s
    angles for ``q`` of ``shape`` (N, n)."""
    count, n = shape
    plus, minus = values.reshape(2, n, count, -1)
    return (plus - minus).transpose(1, 2, 0) / (2 * h)


def tool_pose(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """Pose of the tool in the world: the orientation of the last DH frame, the origin at the tool point.

    Args:
        model: the arm (scale and compliance applied as in :func:`tool_point`).
        q: (N, n) or (n,) measured joint angles [rad].

    Returns:
        (N, 4, 4), or (4, 4) for one configuration: homogeneous transforms, translation [m].

    Raises:
        JointAngleError: an angle more than a full turn beyond its joint's limits (degrees given for radians?).
        ValueError: ``q`` not of shape (N, n) or (n,).
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
        model: the arm (its scale and compliance, when it has them, applied: see the module's notes).
        q: (N, n) or (n,) measured joint angles [rad], each within a full turn (:data:`ANGLE_MARGIN`) of its
            joint's limits (``model.lower``, ``model.upper``); the check costs two reductions over ``q``.

    Returns:
        (N, 3), or (3,) for one configuration, [m].

    Raises:
        JointAngleError: an angle more than a full turn beyond its joint's limits (degrees given for radians?).
        ValueError: ``q`` not of shape (N, n) or (n,).
    """
    q, single = _checked(model, q)
    p = rigid_tool_point(model, _link_angles(model, q))
    return p[0] if single else p


def joint_jacobian(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """Jacobian of the tool point with respect to the measured joint angles.

    Args:
        model: the arm.
        q: (N, n) or (n,) measured joint angles [rad].

    Returns:
        (N, 3, n), or (3, n) for one configuration: ``d p / d q`` [m/rad]. Elastic model:
        ``J(q_link) (I - diag(c) d tau / d q_joint)``, the torque's derivative by central differences (step
        1e-6 rad: its error is ~1e-12 of the term, which is itself ~1e-3 of the Jacobian); scaled model: times
        ``diag(1 + s)``.

    Raises:
        JointAngleError: an angle more than a full turn beyond its joint's limits (degrees given for radians?).
        ValueError: ``q`` not of shape (N, n) or (n,).
    """
    q2, single = _checked(model, q)
    q_joint = joint_angles(model, q2)
    jac = _dlink_djoint(model, q_joint, _rigid_joint_jacobian(model, _link_angles(model, q2)))
    if "scale" in model.extras:
        jac = jac * (1.0 + scale_of(model))
    return jac[0] if single else jac


def link_angle_jacobian(model: RobotModel, q: np.ndarray) -> np.ndarray | None:
    """Jacobian ``d q_link / d q`` of the link angles with respect to the measured angles.

    ``q_link = q_joint - c tau(q_joint)`` with ``q_joint = (1 + s) q``, so::

        d q_link / d q = (I - diag(c) d tau / d q_joint) diag(1 + s)

    The linear part exactly; ``d tau / d q_joint`` by central differences (step 1e-6 rad) of the gravity torque
    alone, so the difference's rounding error is that of the deflection ``c tau`` (~1e-3 rad), not of the angles
    (~3 rad, whose rounding over a 2e-6 step was a 2e-10 floor until stop 20): within ~1e-12 of the exact
    derivative, the torque being smooth.

    Args:
        model: the arm.
        q: (N, n) or (n,) measured joint angles [rad].

    Returns:
        (N, n, n) [rad/rad], entry ``[k, i, j] = d q_link_i / d q_j`` at configuration ``k``, or (n, n) for one
        configuration (n,) (until stop 17 it kept the batch axis, (1, n, n), unlike every other function here);
        None for a model whose link angles are the measured ones (no scale and no compliance, or all of them zero).

    Raises:
        JointAngleError: an angle more than a full turn beyond its joint's limits (degrees given for radians?).
        ValueError: ``q`` not of shape (N, n) or (n,).
    """
    q2, single = _checked(model, q)
    s, c = scale_of(model), compliance_of(model)  # zeros when absent
    if not (np.any(s) or np.any(c)):
        return None
    slope = _torque_slope(model, joint_angles(model, q2)) if np.any(c) else None
    jac = _link_chain(s, c, slope, len(q2))
    return jac[0] if single else jac


def pose_jacobian(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """Jacobian of the tool point and of the tool orientation with respect to the joint angles, for the full
    model (elastic terms included: taken at the link angles, through :func:`link_angle_jacobian`).

    Args:
        model: the arm.
        q: (N, n) or (n,) measured joint angles [rad].

    Returns:
        (N, 6, n), or (6, n) for one configuration: rows 0-2 ``d p / d q`` [m/rad] (as :func:`joint_jacobian`),
        rows 3-5 the angular velocity of the tool frame (:func:`tool_pose`) in the world per unit joint rate
        [rad/rad].

    Raises:
        JointAngleError: an angle more than a full turn beyond its joint's limits (degrees given for radians?).
        ValueError: ``q`` not of shape (N, n) or (n,).
    """
    q2, single = _checked(model, q)
    q_link = _link_angles(model, q2)
    f = frames(model, q_link)
    axes = f.z[1:] if model.convention == "modified" else f.z[:-1]  # (n, 3, N): joint i turns about these
    angular = np.moveaxis(axes, 2, 0).transpose(0, 2, 1)  # (N, 3, n)
    # the rows of joint_jacobian and the chain of link_angle_jacobian from one set of frames and one torque slope
    s, c = scale_of(model), compliance_of(model)  # zeros when absent
    slope = _torque_slope(model, joint_angles(model, q2)) if np.any(c) else None
    linear = _rigid_joint_jacobian(model, q_link, f)
    if slope is not None:
        linear = _through_deflection(linear, c, slope)
    if "scale" in model.extras:
        linear = linear * (1.0 + s)
    if np.any(s) or np.any(c):
        angular = angular @ _link_chain(s, c, slope, len(q2))
    jac = np.concatenate([linear, angular], axis=1)
    return jac[0] if single else jac


def param_jacobian(
    model: RobotModel, q: np.ndarray, return_point: bool = False
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Jacobian of the tool point with respect to every model parameter.

    Columns follow :attr:`RobotModel.param_names` (:mod:`.layout`): per joint ``a, alpha, d, theta``, then the
    Hayati ``beta`` angles (if any), the tool point, the base ``x, y, z, roll, pitch, yaw``, then the
    compliances ``c1..cn`` of an elastic model and the scales ``s1..sn`` of a scaled one. Each DH parameter moves the
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
        model: the arm.
        q: (N, n) or (n,) measured joint angles [rad].
        return_point: also return the tool point (:func:`tool_point`, computed on the way).

    Returns:
        (N, 3, P), or (3, P) for one configuration, ``P = model.n_params``: ``d p / d params``, per column
        [m/m] for a length, [m/rad] for an angle, [m/(rad/Nm)] for a compliance, [m] per unit of a
        (dimensionless) scale. With ``return_point``, the pair ``(jacobian, point)``, point (N, 3) or (3,) [m].

    Raises:
        JointAngleError: an angle more than a full turn beyond its joint's limits (degrees given for radians?).
        ValueError: ``q`` not of shape (N, n) or (n,).
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
