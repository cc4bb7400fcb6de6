"""URDF text of a :class:`RobotModel`: the calibrated arm as a description other stacks load.

The joint origins reproduce the DH chain exactly (to floating-point rounding) in both
conventions, the base placement included. No visuals or collisions. When the model has link
inertials (``extras["inertials"]`` and ``payload``, :mod:`correction.gravity`), each moving link
gets its ``<inertial>``: mass, centre of mass and inertia tensor moved from DH frame ``i`` into
that link's frame (:func:`dh_in_links`), the payload on the tool link; a tensor nobody gave is
a uniform sphere (:func:`correction.inertials.link_inertias`, said by :func:`dynamics_note`).
Without inertials the file is kinematics only and :func:`dynamics_note` says what a dynamics
stack (MuJoCo, Gazebo, pinocchio) still needs.

Links and joints (``P`` is the prefix, ``n`` the joint count), Franka's names for a Franka arm (``panda_link0..8``,
``panda_joint1..7``, the flange ``panda_link8``). Another arm (:func:`default_prefix`) gets its own name as the prefix
and its joints the names its description gave them (``extras["joint_names"]``, ``joint_a1`` for MUKCa's iiwa14), so a
controller matching ``joint_states`` by name finds them::

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

``Plink{i}`` is DH frame ``i`` (modified) or DH frame ``i`` is ``Plink{i}`` moved by joint
``i``'s trailing ``Lz(d) Lx(a) Rx(alpha) Ry(beta)`` (standard): link ``i``'s inertial, given in
DH frame ``i``, is written in ``Plink{i}`` through that transform. In both, ``Plink{n+1}`` has
the pose of :func:`correction.tool_pose` (orientation of the last DH frame, origin at the tool
point). Floats are written with ``repr``: nothing is rounded.
To change only the joint origins of the user's own URDF, see :mod:`correction.urdf_into`.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from xml.sax.saxutils import quoteattr

import numpy as np
import yaml

from ..errors import SpherecalError
from ..gravity import has_inertials
from ..inertia import FIELDS, rotated, six_of
from ..inertials import link_inertias
from ..model import RobotModel, matrix_rpy

#: Franka's datasheet joint torque [N m] and velocity [rad/s] limits, used for a Franka arm (:func:`is_franka`)
#: when none are given (URDF requires both on a revolute joint); another arm's must be given.
PANDA_EFFORT: tuple[float, ...] = (87.0, 87.0, 87.0, 87.0, 12.0, 12.0, 12.0)
PANDA_VELOCITY: tuple[float, ...] = (2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61)
#: Largest joint torque limit [N m] taken: ten times what gravity alone asks of the strongest industrial arm's
#: shoulder (FANUC M-2000iA/2300: 2.3 t at 3.7 m, about 85 kN m); beyond it a slip (a review wrote 1e9 N m).
MAX_EFFORT = 1e6
#: Largest joint velocity limit [rad/s] taken: the fastest robot joints (a delta picker's or a SCARA's wrist, about
#: 3600 deg/s = 63 rad/s) stay under it, while limits typed in deg/s mostly do not (Franka's 2.175 rad/s is 125 deg/s).
MAX_VELOCITY = 100.0
#: Per URDF limit: the option giving it, its unit on the command line, its largest value and the hint beyond it.
LIMITS = {"effort": ("--effort", "Nm", MAX_EFFORT, "the limit is in Nm"),
          "velocity": ("--velocity", "rad/s", MAX_VELOCITY, "deg/s? the limit is in rad/s")}
#: Joint position limits [rad] (lower, upper) of the Franka arms (Panda, FR3) as their descriptions give them.
FRANKA_LIMITS: tuple[tuple[tuple[float, ...], tuple[float, ...]], ...] = (
    ((-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973),
     (2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973)),
    ((-2.7437, -1.7837, -2.9007, -3.0421, -2.8065, 0.5445, -3.0159),
     (2.7437, 1.7837, 2.9007, -0.1518, 2.8065, 4.5169, 3.0159)),
)


def is_franka(model: RobotModel) -> bool:
    """A Franka arm (Panda, FR3): 7 joints, named so (``panda``, ``fr3`` or ``franka`` in the robot's name) or with
    Franka's position limits (within 1e-3 rad). Another 7-joint arm (a KUKA iiwa14) got Franka's names and torque
    limits without a word before (a review, stop 9)."""
    if model.n_joints != 7:
        return False
    if re.search(r"panda|fr3|franka", model.name, re.I):
        return True
    return any(np.allclose(model.lower, lower, atol=1e-3) and np.allclose(model.upper, upper, atol=1e-3)
               for lower, upper in FRANKA_LIMITS)


def default_prefix(model: RobotModel) -> str:
    """``panda_`` for a Franka arm, else the model's name made a valid URDF name, then ``_`` (``kuka_iiwa14_``)."""
    if is_franka(model):
        return "panda_"
    name = re.sub(r"[^A-Za-z0-9_.:-]", "_", model.name).strip("_") or "robot"
    return f"{name}_"

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


def _trailing(model: RobotModel, i: int) -> np.ndarray:
    """(4, 4) joint ``i``'s (0-based) part after its turn, standard convention: ``Lz(d) Lx(a) Rx(alpha) Ry(beta)``."""
    return _shift(z=model.d[i]) @ _shift(x=model.a[i]) @ _rot_x(model.alpha[i]) @ _rot_y(model.beta[i])


def dh_in_links(model: RobotModel) -> np.ndarray:
    """(n, 4, 4) DH frame ``i`` (where link ``i``'s inertial is given) in the frame of the URDF link ``Plink{i}``:
    the identity for ``modified``, joint ``i``'s trailing ``Lz(d) Lx(a) Rx(alpha) Ry(beta)`` for ``standard``."""
    if model.convention == "modified":
        return np.broadcast_to(np.eye(4), (model.n_joints, 4, 4)).copy()
    return np.array([_trailing(model, i) for i in range(model.n_joints)])


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
    trailing = [_trailing(model, i) for i in range(n)]
    origins[0] = _rot_z(model.theta[0])
    for i in range(1, n):
        origins[i] = trailing[i - 1] @ _rot_z(model.theta[i])
    return origins, trailing[-1]


def _origin(pose: np.ndarray) -> str:
    return f'<origin xyz="{_triple(pose[:3, 3])}" rpy="{_triple(matrix_rpy(pose[:3, :3]))}"/>'


def _per_joint(values: Sequence[float] | None, default: Sequence[float], n: int, field: str) -> list[float]:
    """The ``n`` joint limits of ``field`` (``effort`` or ``velocity``, :data:`LIMITS`), ``default`` when None.

    Raises:
        ExportError: no default for ``n`` joints, or not ``n`` values each > 0 and at most the real arms' bound
            (one line naming the option and its unit).
    """
    option, unit, most, hint = LIMITS[field]
    if values is None:
        if len(default) != n:
            raise ExportError(f"field '{option}': no default for a {n}-joint robot, pass {n} values [{unit}] (or "
                              "export --into the robot's own URDF, which keeps its limits, meshes and inertials)")
        values = default
    values = [float(v) for v in values]
    if len(values) != n:
        raise ExportError(f"field '{option}': expected {n} limits [{unit}], one per joint, got {len(values)}")
    for joint, value in enumerate(values, 1):
        if not value > 0:  # nan too; a URDF limit of 0 is a joint that may not move
            raise ExportError(f"field '{option}': joint {joint}: {value:g} {unit}, expected a finite limit > 0 "
                              f"[{unit}]")
        if value > most:
            raise ExportError(f"field '{option}': joint {joint}: {value:g} {unit} is beyond any real arm (at most "
                              f"{most:g} {unit}) ({hint})")
    return values


def xml_comment(text: str) -> str:
    """An XML comment (``--`` may not appear inside one)."""
    while "--" in text:
        text = text.replace("--", "- -")
    return f"<!-- {text.rstrip()} -->"


#: What the exported file's comment leaves out of the ``calibration:`` block: machine records for ``validate`` (the
#: parameters' covariance at held-out sockets, the training samples' fingerprint), not for a reader. A ROS user's
#: trial found a URDF of 8 kB written with 56 kB of comment (about 1,970 lines), most of it a covariance matrix.
MACHINE_RECORDS = (("self_check", "prediction"), ("trained_on",))


def provenance_comment(model: RobotModel) -> str:
    """The robot file's ``calibration:`` block (if any) as an XML comment, less its :data:`MACHINE_RECORDS` (the
    calibrated robot file, named with its SHA-256 in the export's own provenance, holds them)."""
    block = model.extras.get("calibration")
    if block is None:
        return xml_comment("calibration: none (nominal or hand-written robot file)")
    shown, left = block, []
    for path in MACHINE_RECORDS:
        if _holds(shown, path):
            shown = _without(shown, path)
            left.append(".".join(path))
    text = yaml.safe_dump({"calibration": shown}, sort_keys=False, default_flow_style=False, width=1000)
    note = f"(left out here, in the robot file: {', '.join(left)})\n" if left else ""
    return xml_comment("provenance of the robot file\n" + note + text)


def _holds(block: dict, path: tuple[str, ...]) -> bool:
    """Whether the nested ``block`` has the key ``path``."""
    for key in path:
        if not isinstance(block, dict) or key not in block:
            return False
        block = block[key]
    return True


def _without(block: dict, path: tuple[str, ...]) -> dict:
    """A copy of the nested ``block`` without the key ``path`` (the dicts along it copied, the rest shared)."""
    head, *rest = path
    return ({k: v for k, v in block.items() if k != head} if not rest
            else {**block, head: _without(block[head], tuple(rest))})


def _inertial(mass: float, com: np.ndarray, inertia: np.ndarray) -> str:
    """An ``<inertial>`` in its link's axes (``rpy`` zero: the tensor is already turned into them)."""
    six = " ".join(f"{name}={quoteattr(_f(v))}" for name, v in zip(FIELDS, six_of(inertia), strict=True))
    return (f'    <inertial>\n      <origin xyz="{_triple(com)}" rpy="0.0 0.0 0.0"/>\n'
            f'      <mass value="{_f(mass)}"/>\n      <inertia {six}/>\n    </inertial>')


def link_inertials(model: RobotModel, tool: np.ndarray) -> dict[int, str]:
    """``<inertial>`` text of links ``1..n`` and of the tool link ``n+1`` (the payload), by link number.

    Args:
        model: a robot with ``inertials`` (:func:`correction.inertials.link_inertias`).
        tool: (4, 4) pose of ``Plink{n+1}`` in ``Plink{n}``.

    Returns:
        Link number -> its ``<inertial>``; massless bodies are left out (a URDF link may have none).
    """
    bodies = link_inertias(model)
    places = list(dh_in_links(model))
    places.append(np.linalg.solve(tool, places[-1]))  # the payload, in DH frame n, on the tool link
    out = {}
    for k, place in enumerate(places):
        if bodies.masses[k] > 0:
            com = place[:3, :3] @ bodies.coms[k] + place[:3, 3]
            out[k + 1] = _inertial(bodies.masses[k], com, rotated(bodies.tensors[k], place[:3, :3]))
    return out


def dynamics_note(model: RobotModel, without: str = "the file is kinematics only") -> str | None:
    """One line on what the exported links carry for a dynamics stack, or None when every body is complete.

    Args:
        model: the exported model.
        without: what the file holds when the model has no inertials (an MJCF plant's placeholder masses).

    Returns:
        Without inertials: ``without`` and how to give them. With bodies whose tensor nobody gave: which, and that
        a sphere stands in (gravity exact, accelerations approximate). Else None.
    """
    if not has_inertials(model):
        return (f"no link inertials: {without}; a dynamics stack (MuJoCo, Gazebo, pinocchio) needs them: give "
                "--inertials FILE (masses, centres of mass, tensors per DH link), or export --into your arm's own "
                "URDF, which keeps its inertials")
    bodies = link_inertias(model)
    if not bodies.estimated.any():
        return None
    n = model.n_joints
    names = ", ".join("payload" if k == n else f"link {k + 1}" for k in np.flatnonzero(bodies.estimated))
    return (f"no inertia tensor for {names}: a uniform sphere of its mass stands in (gravity torques exact, "
            "accelerations approximate); give 'inertia: [ixx, ixy, ixz, iyy, iyz, izz]' [kg m^2] in the inertials")


def _described(model: RobotModel, key: str) -> list[float] | None:
    """The ``n`` joint limits ``key`` (``effort`` [N m] or ``velocity`` [rad/s]) of the URDF the model was read from
    (``extras["urdf"]``, every joint's ``<limit>`` gave one), or None. A UR5e-like arm read from its own URDF, which
    names them, was refused a standalone export for want of Franka's defaults."""
    block = model.extras.get("urdf")
    values = block.get(key) if isinstance(block, dict) else None
    if not isinstance(values, list) or len(values) != model.n_joints:
        return None
    try:
        values = [float(v) for v in values]
    except (TypeError, ValueError):
        return None
    return values if all(np.isfinite(v) and v > 0 for v in values) else None


def names_and_limits(model: RobotModel, prefix: str | None = None, effort: Sequence[float] | None = None,
                     velocity: Sequence[float] | None = None) -> tuple[str, list[str] | None, list[float], list[float]]:
    """The names and joint limits :func:`robot_to_urdf` writes (its arguments of the same names; see there), checked.

    Returns:
        ``(prefix, joint names or None for <prefix>joint<i>, effort [N m], velocity [rad/s])``; a limit not given
        is the one the model's URDF gave (:func:`_described`), else Franka's for a Franka arm.

    Raises:
        ExportError: a prefix that is not a valid name, limits of the wrong length, or none for an arm that is not a
            Franka arm and whose URDF gave none.
    """
    n = model.n_joints
    named = model.extras.get("joint_names") if prefix is None else None
    joint_names = ([str(k) for k in named] if isinstance(named, list) and len(named) == n and len(set(named)) == n
                   and all(_NAME.match(str(k)) for k in named) else None)
    prefix = default_prefix(model) if prefix is None else prefix
    if not _NAME.match(prefix):
        raise ExportError(f"field '--prefix': {prefix!r} may contain only letters, digits and _ . / : -")
    effort, velocity = (_described(model, key) if given is None else given
                        for key, given in (("effort", effort), ("velocity", velocity)))
    missing = [field for field, given in (("--effort", effort), ("--velocity", velocity)) if given is None]
    if missing and not is_franka(model):
        raise ExportError(f"field '{missing[0]}': no default for {model.name!r} (Franka's are for a Franka arm, whose "
                          f"joint limits these are not): give {n} comma-separated values to {' and '.join(missing)}, "
                          "or export --into the robot's own URDF, which keeps its limits, meshes and inertials")
    return (prefix, joint_names, _per_joint(effort, PANDA_EFFORT, n, "effort"),
            _per_joint(velocity, PANDA_VELOCITY, n, "velocity"))


def robot_to_urdf(
    model: RobotModel,
    prefix: str | None = None,
    effort: Sequence[float] | None = None,
    velocity: Sequence[float] | None = None,
    mujoco: bool = False,
    header: str = "",
) -> str:
    """URDF text of a model (kinematics, link inertials when it has them, joint limits, tool frame, provenance).

    Args:
        model: the (calibrated) robot.
        prefix: prepended to every link and joint name (``panda_link3``, ``panda_joint3``); None:
            :func:`default_prefix`, and the joints keep the names the model's description gave them.
        effort: (n,) joint torque limits [N m]; by default those of the URDF the model was read from (every
            joint's ``<limit effort>``), else Franka's for a Franka arm; required otherwise.
        velocity: (n,) joint velocity limits [rad/s]; likewise.
        mujoco: add :data:`MUJOCO_EXTENSION` so that MuJoCo compiles the file as is.
        header: more lines for the top comment (inputs, versions).

    Returns:
        The URDF document as text.

    Raises:
        ExportError: a prefix that is not a valid name, limits of the wrong length, or none for an arm that is not a
            Franka arm (:func:`names_and_limits`).
    """
    n = model.n_joints
    prefix, joint_names, effort, velocity = names_and_limits(model, prefix, effort, velocity)
    origins, flange = joint_origins(model)
    p = prefix
    lines = [
        '<?xml version="1.0"?>',
        xml_comment(
            f"generated by spherecal from robot {model.name!r} ({model.convention} DH, {n} joints): "
            + ("kinematics and link inertials, metres, radians, kilograms" if has_inertials(model)
               else "kinematics only, metres and radians")
        ),
        *([xml_comment(header)] if header.strip() else []),
        provenance_comment(model),
        f"<robot name={quoteattr(model.name)}>",
    ]
    if mujoco:
        lines.append("  " + MUJOCO_EXTENSION)
    tool = flange.copy()
    tool[:3, 3] = flange[:3, :3] @ model.tool + flange[:3, 3]
    inertials = link_inertials(model, tool) if has_inertials(model) else {}
    lines.append(f"  <link name={quoteattr(f'{p}base')}/>")
    for i in range(n + 2):
        name = quoteattr(f"{p}link{i}")
        lines.append(f"  <link name={name}>\n{inertials[i]}\n  </link>" if i in inertials else f"  <link name={name}/>")

    def fixed(name: str, parent: str, child: str, origin: str) -> None:
        lines.append(f"  <joint name={quoteattr(name)} type=\"fixed\">")
        lines.append(f"    <parent link={quoteattr(parent)}/>\n    <child link={quoteattr(child)}/>")
        lines.append(f"    {origin}\n  </joint>")

    # The base placement is already URDF xyz/rpy: written as stored, bit for bit.
    base = f'<origin xyz="{_triple(model.base_xyz)}" rpy="{_triple(model.base_rpy)}"/>'
    fixed(f"{p}base_joint", f"{p}base", f"{p}link0", base)
    for i in range(n):
        kind = "continuous" if model.full_turn[i] else "revolute"  # read back as [-pi, pi], written as it came
        joint = joint_names[i] if joint_names else f"{p}joint{i + 1}"
        lines.append(f"  <joint name={quoteattr(joint)} type=\"{kind}\">")
        lines.append(f"    <parent link={quoteattr(f'{p}link{i}')}/>\n    <child link={quoteattr(f'{p}link{i + 1}')}/>")
        lines.append(f"    {_origin(origins[i])}")
        lines.append('    <axis xyz="0 0 1"/>')
        bounds = "" if model.full_turn[i] else f'lower="{_f(model.lower[i])}" upper="{_f(model.upper[i])}" '
        lines.append(f'    <limit {bounds}effort="{_f(effort[i])}" velocity="{_f(velocity[i])}"/>')
        lines.append("  </joint>")
    fixed(f"{p}joint{n + 1}", f"{p}link{n}", f"{p}link{n + 1}", _origin(tool))
    lines.append("</robot>")
    return "\n".join(lines) + "\n"
