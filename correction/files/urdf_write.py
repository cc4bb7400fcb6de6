"""URDF text of a :class:`RobotModel`: the calibrated arm as a description other stacks load.

The joint origins reproduce the DH chain exactly (to floating-point rounding) in both
conventions, the base placement included. Kinematics only: no visuals, collisions or
inertials (a stack that needs masses keeps its own and takes the joint origins from here).

Links and joints (``P`` is the prefix, ``panda_`` by default, ``n`` the joint count), Franka's
names for a Panda (``panda_link0..8``, ``panda_joint1..7``, the flange ``panda_link8``)::

    P{base}  --fixed Pbase_joint: base_xyz, base_rpy-->  Plink0      (DH frame 0)
    Plink{i-1}  --revolute Pjoint{i}, axis z-->  Plink{i}            i = 1..n
    Plink{n}  --fixed Pjoint{n+1}-->  Plink{n+1}                     (the tool point)

* ``modified``: ``Rx(alpha) Lx(a) Ry(beta) Rz(theta) Lz(d)`` is joint ``i``'s origin (the
  joint angle ``Rz(q)`` commutes with ``Lz(d)``), so ``Plink{i}`` is DH frame ``i`` exactly,
  as in Franka's own description, and ``Plink{n+1}`` is the tool point along it (Franka's
  flange ``panda_link8``, 0.107 m along ``z7``, for the nominal Panda).
* ``standard``: ``Rz(theta+q) Lz(d) Lx(a) Rx(alpha) Ry(beta)`` turns first, so joint ``i``'s
  origin is the previous joint's trailing ``Lz(d) Lx(a) Rx(alpha) Ry(beta)`` followed by
  ``Rz(theta)``; ``Plink{i}`` is DH frame ``i-1`` turned by ``theta_i + q_i``, and the last
  joint's trailing part goes into ``Pjoint{n+1}``.

In both, ``Plink{n+1}`` has the pose of :func:`correction.tool_pose` (orientation of the last
DH frame, origin at the tool point). Floats are written with ``repr``: nothing is rounded.
To change only the joint origins of the user's own URDF, see :mod:`correction.urdf_into`.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from xml.sax.saxutils import quoteattr

import numpy as np
import yaml

from ..errors import SpherecalError
from ..model import RobotModel, matrix_rpy

#: Franka's datasheet joint torque [N m] and velocity [rad/s] limits, used for 7-joint arms
#: when none are given (URDF requires both on a revolute joint).
PANDA_EFFORT: tuple[float, ...] = (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0)
PANDA_VELOCITY: tuple[float, ...] = (2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61)

#: Makes MuJoCo compile the kinematic URDF: keep fixed links as bodies, give massless
#: moving links a token mass (MuJoCo refuses zero-mass moving bodies). Other readers
#: ignore the ``<mujoco>`` element.
MUJOCO_EXTENSION = (
    '<mujoco><compiler discardvisual="true" fusestatic="false" boundmass="1e-3" boundinertia="1e-6"/></mujoco>'
)

_NAME = re.compile(r"^[A-Za-z0-9_./:-]*$")


class ExportError(SpherecalError):
    """A model or option that cannot be exported; the message names the field."""


def _f(value: float) -> str:
    """Shortest exact text of a float (``repr`` round-trips every bit)."""
    value = float(value)
    return repr(value + 0.0)  # + 0.0 turns -0.0 into 0.0


def _triple(values: np.ndarray) -> str:
    return " ".join(_f(v) for v in values)


def _rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0, 0.0], [0.0, c, -s, 0.0], [0.0, s, c, 0.0], [0.0, 0.0, 0.0, 1.0]])


def _rot_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0, 0.0], [s, c, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


def _rot_y(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s, 0.0], [0.0, 1.0, 0.0, 0.0], [-s, 0.0, c, 0.0], [0.0, 0.0, 0.0, 1.0]])


def _shift(x: float = 0.0, z: float = 0.0) -> np.ndarray:
    pose = np.eye(4)
    pose[0, 3], pose[2, 3] = x, z
    return pose


def joint_origins(model: RobotModel) -> tuple[np.ndarray, np.ndarray]:
    """Fixed parts of the chain as URDF joint origins.

    Args:
        model: the robot.

    Returns:
        ``origins`` (n, 4, 4): the origin of joint ``i`` in the frame of link ``i-1`` (link 0
        is DH frame 0, the base frame), followed in the chain by ``Rz(q_i)``; and ``flange``
        (4, 4): DH frame ``n`` in the frame of link ``n`` (identity for ``modified``).
    """
    n = model.n_joints
    origins = np.empty((n, 4, 4))
    if model.convention == "modified":
        for i in range(n):
            origins[i] = (_rot_x(model.alpha[i]) @ _shift(x=model.a[i]) @ _rot_y(model.beta[i])
                          @ _rot_z(model.theta[i]) @ _shift(z=model.d[i]))
        return origins, np.eye(4)
    trailing = [_shift(z=model.d[i]) @ _shift(x=model.a[i]) @ _rot_x(model.alpha[i]) @ _rot_y(model.beta[i])
                for i in range(n)]
    origins[0] = _rot_z(model.theta[0])
    for i in range(1, n):
        origins[i] = trailing[i - 1] @ _rot_z(model.theta[i])
    return origins, trailing[-1]


def _origin(pose: np.ndarray) -> str:
    return f'<origin xyz="{_triple(pose[:3, 3])}" rpy="{_triple(matrix_rpy(pose[:3, :3]))}"/>'


def _per_joint(values: Sequence[float] | None, default: Sequence[float], n: int, field: str) -> list[float]:
    if values is None:
        if len(default) != n:
            raise ExportError(f"{field}: no default for a {n}-joint robot, pass {n} values (or export --into the "
                              "robot's own URDF, which keeps its limits, meshes and inertials)")
        values = default
    values = [float(v) for v in values]
    if len(values) != n or not all(np.isfinite(values)) or min(values) < 0.0:
        raise ExportError(f"{field}: expected {n} finite non-negative numbers, got {values!r}")
    return values


def xml_comment(text: str) -> str:
    """An XML comment (``--`` may not appear inside one)."""
    while "--" in text:
        text = text.replace("--", "- -")
    return f"<!-- {text.rstrip()} -->"


def provenance_comment(model: RobotModel) -> str:
    """The robot file's ``calibration:`` block (if any) as an XML comment."""
    block = model.extras.get("calibration")
    if block is None:
        return xml_comment("calibration: none (nominal or hand-written robot file)")
    text = yaml.safe_dump({"calibration": block}, sort_keys=False, default_flow_style=False, width=1000)
    return xml_comment("provenance of the robot file\n" + text)


def robot_to_urdf(
    model: RobotModel,
    prefix: str = "panda_",
    effort: Sequence[float] | None = None,
    velocity: Sequence[float] | None = None,
    mujoco: bool = False,
    header: str = "",
) -> str:
    """URDF text of a model (kinematics, joint limits, tool frame, provenance comment).

    Args:
        model: the (calibrated) robot.
        prefix: prepended to every link and joint name (``panda_link3``, ``panda_joint3``).
        effort: (n,) joint torque limits [N m]; Franka's for a 7-joint arm by default.
        velocity: (n,) joint velocity limits [rad/s]; Franka's for a 7-joint arm by default.
        mujoco: add :data:`MUJOCO_EXTENSION` so that MuJoCo compiles the file as is.
        header: more lines for the top comment (inputs, versions).

    Returns:
        The URDF document as text.

    Raises:
        ExportError: a prefix that is not a valid name, or limits of the wrong length.
    """
    if not _NAME.match(prefix):
        raise ExportError(f"prefix: {prefix!r} may contain only letters, digits and _ . / : -")
    n = model.n_joints
    effort = _per_joint(effort, PANDA_EFFORT, n, "effort")
    velocity = _per_joint(velocity, PANDA_VELOCITY, n, "velocity")
    origins, flange = joint_origins(model)
    p = prefix
    lines = [
        '<?xml version="1.0"?>',
        xml_comment(
            f"generated by spherecal from robot {model.name!r} ({model.convention} DH, {n} joints): "
            "kinematics only, metres and radians"
        ),
        *([xml_comment(header)] if header.strip() else []),
        provenance_comment(model),
        f"<robot name={quoteattr(model.name)}>",
    ]
    if mujoco:
        lines.append("  " + MUJOCO_EXTENSION)
    links = [f"{p}base"] + [f"{p}link{i}" for i in range(n + 2)]
    lines += [f"  <link name={quoteattr(name)}/>" for name in links]

    def fixed(name: str, parent: str, child: str, origin: str) -> None:
        lines.append(f"  <joint name={quoteattr(name)} type=\"fixed\">")
        lines.append(f"    <parent link={quoteattr(parent)}/>\n    <child link={quoteattr(child)}/>")
        lines.append(f"    {origin}\n  </joint>")

    # The base placement is already URDF xyz/rpy: written as stored, bit for bit.
    base = f'<origin xyz="{_triple(model.base_xyz)}" rpy="{_triple(model.base_rpy)}"/>'
    fixed(f"{p}base_joint", f"{p}base", f"{p}link0", base)
    for i in range(n):
        kind = "continuous" if model.full_turn[i] else "revolute"  # read back as [-pi, pi], written as it came
        lines.append(f"  <joint name={quoteattr(f'{p}joint{i + 1}')} type=\"{kind}\">")
        lines.append(f"    <parent link={quoteattr(f'{p}link{i}')}/>\n    <child link={quoteattr(f'{p}link{i + 1}')}/>")
        lines.append(f"    {_origin(origins[i])}")
        lines.append('    <axis xyz="0 0 1"/>')
        bounds = "" if model.full_turn[i] else f'lower="{_f(model.lower[i])}" upper="{_f(model.upper[i])}" '
        lines.append(f'    <limit {bounds}effort="{_f(effort[i])}" velocity="{_f(velocity[i])}"/>')
        lines.append("  </joint>")
    tool = flange.copy()
    tool[:3, 3] = flange[:3, :3] @ model.tool + flange[:3, 3]
    fixed(f"{p}joint{n + 1}", f"{p}link{n}", f"{p}link{n + 1}", _origin(tool))
    lines.append("</robot>")
    return "\n".join(lines) + "\n"
