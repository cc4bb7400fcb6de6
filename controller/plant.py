"""The MuJoCo plant of a DH robot model, with spherical-joint fixtures as ``connect`` equalities.

One body per joint, placed by its DH transform, so that body ``i``'s frame *is* frame ``i`` of
:mod:`correction`'s kinematics (both conventions). A site ``tool`` sits at the tool point,
optional sites ``marker0 ..`` sit rigidly on the last link, and every fixture is a world site
``fixture<k>`` tied to the tool site by a ``<connect>`` equality that starts released: MuJoCo,
not our code, closes the chain when a fixture is engaged.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from xml.sax.saxutils import quoteattr

import mujoco
import numpy as np

from spherecal.correction import RobotModel, link_frames
from spherecal.correction.elastic import link_angles
from spherecal.correction.files.urdf_write import xml_comment
from spherecal.correction.gravity import has_inertials, inertials_of
from spherecal.correction.inertials import link_inertias

from .reach import check_fixture_distance, fixture_centre
from .stiffness import stiffness_of

#: Physical defaults of the plant (settings that keep the closed chain stable at 1 kHz).
TIMESTEP = 1e-3  # [s] the Panda's 1 kHz control rate
CONNECT_SOLREF = (0.002, 1.0)  # stiff: MuJoCo's default 0.02 leaves 1-2 mm of violation
VELOCITY_GAIN = 100.0  # kv of the joint velocity actuators [N m s/rad]
LINK_MASS = 2.0  # [kg]
LINK_INERTIA = 0.02  # [kg m^2] diagonal
ARMATURE = 0.1  # [kg m^2]
JOINT_DAMPING = 1.0  # [N m s/rad]
ROTOR_MASS = 0.05  # [kg] motor-side body of an elastic joint (its inertia is mostly the armature)
ROTOR_INERTIA = 1e-4  # [kg m^2] diagonal
FLEX_ARMATURE = 0.01  # [kg m^2] of the link-side hinge of an elastic joint
FLEX_DAMPING_RATIO = 1.0  # of the link-side hinge against a 1 kg m^2 link (no ringing at 1 kHz)
#: [N m] bound of a ``flex`` hinge's actuator force, which its gravity compensation is sent to (``actuatorgravcomp``):
#: the springs carry gravity in MuJoCo alone. MuJoCo refuses an empty range ("0 0"); what this one lets through bends
#: a 1e3 Nm/rad spring by 1e-15 rad.
FLEX_GRAVCOMP_LIMIT = 1e-12


def _num(value: float) -> str:
    return format(float(value), ".17g")


def _vec(values: np.ndarray) -> str:
    return " ".join(_num(v) for v in np.ravel(values))


def _quat(rotation: np.ndarray) -> np.ndarray:
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(rotation, dtype=float).ravel())
    return quat


def _inertial(mass: float, com: np.ndarray, tensor: np.ndarray) -> str:
    """An MJCF ``<inertial>``: a diagonal tensor as ``diaginertia`` (the plant's defaults, written as before), any
    other as ``fullinertia`` (MJCF's order ``ixx iyy izz ixy ixz iyz``) [kg m^2] about ``com`` [m]."""
    if not np.any(tensor - np.diag(np.diag(tensor))):
        inertia = f'diaginertia="{_vec(np.diag(tensor))}"'
    else:
        inertia = f'fullinertia="{_vec(tensor[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]])}"'
    return f'<inertial pos="{_vec(com)}" mass="{_num(mass)}" {inertia}/>'


def joint_offsets(model: RobotModel) -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """Per joint, the body placement in its parent and the hinge in the body, at ``q = 0``.

    The placements are the relative transforms of :func:`correction.link_frames` at ``q = 0``, so
    the DH chain is defined in one place. Modified DH: the hinge turns about ``z`` through the body's
    origin (``Rz(q)`` commutes with ``Lz(d)``). Standard DH: about ``z`` of the parent frame, through
    the parent's origin.

    Returns:
        For each joint ``i``: ``(pos (3,), rotation (3, 3), joint_pos (3,), joint_axis (3,))``,
        body ``i`` in body ``i-1`` [m] and the hinge anchor and axis in body ``i``.
    """
    frames = link_frames(model, np.zeros(model.n_joints))  # (n+1, 4, 4), frame 0 is the base
    z = np.array([0.0, 0.0, 1.0])
    out = []
    for parent, child in zip(frames[:-1], frames[1:], strict=True):
        rotation = parent[:3, :3].T @ child[:3, :3]
        pos = parent[:3, :3].T @ (child[:3, 3] - parent[:3, 3])
        if model.convention == "modified":
            out.append((pos, rotation, np.zeros(3), z))
        else:
            out.append((pos, rotation, -rotation.T @ pos, rotation.T @ z))
    return out


#: The attributes of a ``flex`` hinge that keep the bodies' ``gravcomp`` off it (MuJoCo >= 3.1.4).
_FLEX_GRAVITY = (f'actuatorgravcomp="true" actuatorfrclimited="true" '
                 f'actuatorfrcrange="{_num(-FLEX_GRAVCOMP_LIMIT)} {_num(FLEX_GRAVCOMP_LIMIT)}"')


def _rotor_masses(masses: np.ndarray, stiffness: np.ndarray) -> np.ndarray:
    """(n,) mass of each elastic joint's motor-side body [kg]: :data:`ROTOR_MASS`, at most half its link's; 0 for a
    rigid joint."""
    n = stiffness.size
    return np.where(stiffness > 0, np.minimum(ROTOR_MASS, 0.5 * masses[:n]), 0.0)


def _without_rotors(masses: np.ndarray, coms: np.ndarray, rotors: np.ndarray, offsets: list) -> tuple:
    """Link masses and centres of mass with each rotor's mass taken out, its first moment kept: the rotor sits on its
    hinge axis (``joint_pos`` of :func:`joint_offsets`, in the link's frame), where it loads every joint before it as
    the link's share did and its own flex hinge not at all, so the plant's gravity torques are the model's
    (:func:`correction.gravity_torques`). The rotors added to the links' masses bent a Panda 31-33 um further than its
    elastic model at the tool (a review: 17 um)."""
    masses, coms = np.array(masses, dtype=float), np.array(coms, dtype=float)
    for i in np.flatnonzero(rotors):
        rest = masses[i] - rotors[i]
        coms[i] = (masses[i] * coms[i] - rotors[i] * offsets[i][2]) / rest
        masses[i] = rest
    return masses, coms


def build_mjcf(
    model: RobotModel,
    fixtures: dict[str, np.ndarray] | None = None,
    markers: np.ndarray | None = None,
    timestep: float = TIMESTEP,
    connect_solref: tuple[float, float] = CONNECT_SOLREF,
    velocity_gain: float = VELOCITY_GAIN,
    inertials: bool = False,
) -> str:
    """MJCF text of the arm.

    Elastic joints (``model.extras["compliance"]`` > 0, see :mod:`correction.elastic`): joint ``i``
    becomes a motor-side hinge ``joint<i>`` (actuated, its angle is the recorded one) in a light body
    ``rotor<i>``, then the link body ``link<i>`` on a second hinge ``flex<i>`` about the same axis with
    stiffness ``1/c_i`` [Nm/rad]. Every body is gravity compensated (as a Panda's controller does at
    the motors), but on a ``flex`` hinge the compensation goes to its actuator force (``actuatorgravcomp``),
    bounded to :data:`FLEX_GRAVCOMP_LIMIT`: gravity acts on the springs only, and the links sag by ``-c tau``
    while the motors hold, in plain ``mj_step`` (the plant and the exported file alike). The link masses are then
    the robot's ``inertials`` (and ``payload``), the masses the deflection comes from.

    Args:
        model: the robot (nominal or a perturbed "true" robot), either convention.
        fixtures: fixture name -> (3,) centre in the world [m]; one world site ``fixture<k>``
            and one released ``connect`` equality ``connect<k>`` each, in dict order.
        markers: (M, 3) offsets in the last link frame [m]; sites ``marker0 ..``.
        timestep: [s].
        connect_solref: ``solref`` of the connect equalities (time constant [s], damping ratio).
        velocity_gain: ``kv`` of the joint velocity actuators.
        inertials: every link body (and the payload) gets the model's own mass, centre of mass and inertia tensor
            (:func:`correction.inertials.link_inertias`), rigid or elastic: the export for a dynamics stack, the
            same bodies as the URDF export. False (the simulated plant): a rigid model's links weigh
            :data:`LINK_MASS` at their origins, an elastic one's carry its masses with a :data:`LINK_INERTIA`
            diagonal. A model without inertials keeps the plant's defaults either way.

    Returns:
        The MJCF document (floats written with 17 significant digits).
    """
    fixtures = fixtures or {}
    n = model.n_joints
    offsets = joint_offsets(model)
    stiffness = stiffness_of(model)
    elastic = bool(np.any(stiffness > 0))
    masses, coms = inertials_of(model) if elastic else (np.append(np.full(n, LINK_MASS), 0.0), np.zeros((n + 1, 3)))
    tensors = np.broadcast_to(LINK_INERTIA * np.eye(3), (n + 1, 3, 3)).copy()
    tensors[n] = 1e-3 * np.eye(3)
    if inertials and has_inertials(model):
        masses, coms, tensors, _ = link_inertias(model)
    rotors = _rotor_masses(masses, stiffness)
    masses, coms = _without_rotors(masses, coms, rotors, offsets)
    base = model.base_transform
    lines = [
        f"<mujoco model={quoteattr(model.name)}>",
        '  <compiler angle="radian" autolimits="true"/>',
        f'  <option timestep="{_num(timestep)}" integrator="implicitfast" gravity="0 0 -9.81"/>',
        "  <default>",
        '    <geom contype="0" conaffinity="0" group="1" rgba="0.85 0.85 0.9 1"/>',
        f'    <joint type="hinge" armature="{_num(ARMATURE)}" damping="{_num(JOINT_DAMPING)}"/>',
        '    <site size="0.005"/>',
        "  </default>",
        "  <worldbody>",
    ]
    for k, (name, centre) in enumerate(fixtures.items()):
        lines.append(f'    <site name="fixture{k}" pos="{_vec(centre)}" size="0.01" rgba="1 0.3 0.1 1"/>'
                     + xml_comment(name))
    lines.append(f'    <body name="link0" pos="{_vec(base[:3, 3])}" quat="{_vec(_quat(base[:3, :3]))}">')
    lines.append('      <geom type="cylinder" size="0.06 0.02" pos="0 0 0.02"/>')
    indent = "      "
    for i in range(n):
        pos, rotation, joint_pos, axis = offsets[i]
        if np.linalg.norm(pos) > 1e-6:
            lines.append(f'{indent}<geom type="capsule" size="0.025" fromto="0 0 0 {_vec(pos)}"/>')
        placement = f'pos="{_vec(pos)}" quat="{_vec(_quat(rotation))}"'
        hinge = f'pos="{_vec(joint_pos)}" axis="{_vec(axis)}"'
        # a joint of a whole turn (URDF "continuous") has no range: autolimits leaves it unlimited, as on the arm
        limits = "" if model.full_turn[i] else f' range="{_num(model.lower[i])} {_num(model.upper[i])}"'
        motor = f'<joint name="joint{i + 1}" {hinge}{limits}/>'
        if stiffness[i] > 0:  # its mass on the hinge axis, taken from the link's (:func:`_without_rotors`)
            lines.append(f'{indent}<body name="rotor{i + 1}" {placement} gravcomp="1">')
            lines.append(f'{indent}  <inertial pos="{_vec(joint_pos)}" mass="{_num(rotors[i])}" '
                         f'diaginertia="{_vec([ROTOR_INERTIA] * 3)}"/>')
            lines.append(f"{indent}  {motor}")
            indent += "  "
            placement = ""
        lines.append(f'{indent}<body name="link{i + 1}" {placement} gravcomp="1">')
        indent += "  "
        lines.append(f'{indent}{_inertial(masses[i], coms[i], tensors[i])}')
        if stiffness[i] > 0:
            damping = 2.0 * FLEX_DAMPING_RATIO * np.sqrt(stiffness[i])
            lines.append(f'{indent}<joint name="flex{i + 1}" {hinge} stiffness="{_num(stiffness[i])}" '
                         f'damping="{_num(damping)}" armature="{_num(FLEX_ARMATURE)}" {_FLEX_GRAVITY}/>')
        else:
            lines.append(f"{indent}{motor}")
        lines.append(f'{indent}<geom type="sphere" size="0.03" pos="{_vec(joint_pos)}"/>')
    if np.linalg.norm(model.tool) > 1e-6:
        lines.append(f'{indent}<geom type="capsule" size="0.015" fromto="0 0 0 {_vec(model.tool)}"/>')
    lines.append(f'{indent}<site name="tool" pos="{_vec(model.tool)}" rgba="0.1 0.8 0.2 1"/>')
    for m, offset in enumerate(np.zeros((0, 3)) if markers is None else np.asarray(markers, float).reshape(-1, 3)):
        lines.append(f'{indent}<site name="marker{m}" pos="{_vec(offset)}" rgba="0.2 0.4 1 1"/>')
    if masses[n] > 0:
        lines.append(f'{indent}<body name="payload" gravcomp="1">{_inertial(masses[n], coms[n], tensors[n])}</body>')
    for _ in range(n + 1 + int(np.sum(stiffness > 0))):
        indent = indent[:-2]
        lines.append(f"{indent}</body>")
    lines.append("  </worldbody>")
    if fixtures:
        lines.append("  <equality>")
        for k in range(len(fixtures)):
            lines.append(f'    <connect name="connect{k}" site1="tool" site2="fixture{k}" active="false" '
                         f'solref="{_vec(connect_solref)}"/>')
        lines.append("  </equality>")
    lines.append("  <actuator>")
    for i in range(n):
        lines.append(f'    <velocity name="velocity{i + 1}" joint="joint{i + 1}" kv="{_num(velocity_gain)}"/>')
    lines.append("  </actuator>")
    lines.append("</mujoco>")
    return "\n".join(lines) + "\n"


@dataclass(eq=False)
class Plant:
    """A MuJoCo arm built from a :class:`RobotModel`, with its fixtures.

    Attributes:
        model: the robot it was built from.
        mjcf: the MJCF text.
        mj_model, mj_data: MuJoCo's model and data.
        fixture_names: fixture names in site order (``fixture<k>`` is ``fixture_names[k]``).
        fixture_centres: (F, 3) nominal centres of the fixture sites [m].
        tool_site: site id of the tool point.
        marker_sites: (M,) site ids of ``marker0 ..``.
        fixture_sites: (F,) site ids of the fixture sites.
        motor_qpos, motor_dofs: (n,) qpos and dof addresses of the actuated (recorded) hinges ``joint<i>``.
        flex_qpos, flex_dofs: qpos and dof addresses of the ``flex<i>`` hinges of elastic joints.
        flex_joints: (E,) indices ``i`` (0-based) of the elastic joints.
    """

    model: RobotModel
    mjcf: str
    mj_model: mujoco.MjModel
    mj_data: mujoco.MjData
    fixture_names: tuple[str, ...] = ()
    fixture_centres: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    tool_site: int = 0
    marker_sites: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    fixture_sites: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    motor_qpos: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    motor_dofs: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    flex_qpos: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    flex_dofs: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    flex_joints: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))

    # ----------------------------------------------------------------------- state
    @property
    def n_joints(self) -> int:
        return self.model.n_joints

    @property
    def elastic(self) -> bool:
        """True when some joint has a compliant link-side hinge."""
        return self.flex_dofs.size > 0

    @property
    def q(self) -> np.ndarray:
        """(n,) joint readings [rad]: the motor-side angles (a view for a rigid plant, a copy otherwise)."""
        if not self.elastic:
            return self.mj_data.qpos[: self.n_joints]
        return self.mj_data.qpos[self.motor_qpos]

    def _set_qpos(self, data: mujoco.MjData, q: np.ndarray) -> None:
        """Motor angles ``q`` (n,) and, for elastic joints, the link side at its static sag ``-c tau(q)``."""
        data.qpos[self.motor_qpos] = q
        if self.elastic:
            sag = link_angles(self.model, q) - q
            data.qpos[self.flex_qpos] = sag[self.flex_joints]

    def set_state(self, q: np.ndarray, qdot: np.ndarray | None = None) -> None:
        """Teleport to joint angles ``q`` (n,) [rad] with velocity ``qdot`` (zero if None); elastic joints
        start at their static deflection."""
        n = self.n_joints
        self.mj_data.qvel[:] = 0.0
        self._set_qpos(self.mj_data, np.asarray(q, dtype=float))
        self.mj_data.qvel[self.motor_dofs] = 0.0 if qdot is None else qdot
        self.mj_data.ctrl[:n] = self.mj_data.qvel[self.motor_dofs]
        mujoco.mj_forward(self.mj_model, self.mj_data)

    def advance(self, start: int, q_log: np.ndarray, tool_log: np.ndarray, ctrl: np.ndarray,
                anchor: np.ndarray | None = None, fixture: int = 0) -> None:
        """Physics steps ``start .. start + len(ctrl) - 1``, one actuator command each, logged at every step.

        ``q_log[s]`` gets the joint readings at the start of step ``s`` and ``tool_log[s]`` the tool
        site at the same state (MuJoCo computes positions before integrating): ``mj_step`` with no numpy
        between steps but the copies (an elastic plant's gravity is in its MJCF, :func:`build_mjcf`).

        Args:
            start: index of the first step (into the logs).
            q_log: (S, n) joint readings [rad], written in place.
            tool_log: (S, 3) tool site in the world [m], written in place.
            ctrl: (P, n) actuator commands of the P steps (joint velocities [rad/s]).
            anchor: (S, 3) world position of fixture site ``fixture`` at each step [m] (a moving
                fixture, e.g. compliance), or None to leave it where it is.
            fixture: index of the fixture site that ``anchor`` moves.
        """
        m, d = self.mj_model, self.mj_data
        n = self.n_joints
        command = d.ctrl[:n]  # views into MuJoCo's buffers: written before and read after each step
        tool = d.site_xpos[self.tool_site]
        site = None if anchor is None else m.site_pos[self.fixture_sites[fixture]]
        rigid = not self.elastic  # its qpos is the n motor angles, in order
        qpos = d.qpos[:n]
        for s, u in enumerate(ctrl, start):
            command[:] = u
            if site is not None:
                site[:] = anchor[s]
            q_log[s] = qpos if rigid else d.qpos[self.motor_qpos]
            mujoco.mj_step(m, d)
            tool_log[s] = tool

    # -------------------------------------------------------------------- fixtures
    def fixture_index(self, name: str) -> int:
        try:
            return self.fixture_names.index(name)
        except ValueError:
            raise KeyError(f"no fixture named {name!r}; have {self.fixture_names}") from None

    def engage(self, name: str) -> None:
        """Activate the spherical joint of fixture ``name`` (and release every other one)."""
        index = self.fixture_index(name)
        self.mj_data.eq_active[:] = 0
        self.mj_data.eq_active[index] = 1

    def release(self) -> None:
        """Release every fixture."""
        self.mj_data.eq_active[:] = 0

    def move_fixture(self, name: str, centre: np.ndarray) -> None:
        """Move the world site of fixture ``name`` to ``centre`` (3,) [m] (compliance, backlash).

        Raises:
            KeyError: no fixture ``name``.
            ShapeError, UnreachableFixtureError: ``centre`` is not three numbers, or lies out of reach
                (:func:`controller.reach.check_fixture_distance`, as :func:`build_plant` checks); the site is left
                where it was.
        """
        site = self.fixture_sites[self.fixture_index(name)]
        self.mj_model.site_pos[site] = check_fixture_distance(self.model, name, centre)

    # ----------------------------------------------------------------- kinematics
    def tool_position(self) -> np.ndarray:
        """(3,) copy of the tool site in the world [m] at the last computed state."""
        return self.mj_data.site_xpos[self.tool_site].copy()

    def site_positions(self, q: np.ndarray, sites: np.ndarray | None = None) -> np.ndarray:
        """World positions of sites over a batch of configurations (kinematics only).

        Args:
            q: (N, n) or (n,) joint angles [rad].
            sites: (S,) site ids; the marker sites when None.

        Returns:
            (N, S, 3) positions [m] ((S, 3) for a single configuration). The plant's state is
            restored afterwards.
        """
        sites = self.marker_sites if sites is None else np.asarray(sites, dtype=int)
        q = np.asarray(q, dtype=float)
        batch = np.atleast_2d(q)
        data = mujoco.MjData(self.mj_model)
        out = np.empty((batch.shape[0], sites.size, 3))
        for k, qk in enumerate(batch):
            self._set_qpos(data, qk)
            mujoco.mj_kinematics(self.mj_model, data)
            out[k] = data.site_xpos[sites]
        return out[0] if q.ndim == 1 else out

    def tool_points(self, q: np.ndarray) -> np.ndarray:
        """(N, 3) tool site over a batch of configurations ``q`` (N, n) [m]."""
        return self.site_positions(np.atleast_2d(q), np.array([self.tool_site]))[:, 0]


def no_log_file() -> None:
    """Keep MuJoCo's warnings off the disk: by default its first warning of a kind writes
    ``MUJOCO_LOG.TXT`` into the current working directory (the user's folder); they still go to
    the console. Idempotent; called by :func:`build_plant`."""
    config = mujoco.MjLogConfig.get()
    if config.logto_file:
        config.logto_file = False
        config.set()


def build_plant(
    model: RobotModel,
    fixtures: dict[str, np.ndarray] | None = None,
    markers: np.ndarray | None = None,
    **options,
) -> Plant:
    """Build the MuJoCo plant of ``model`` (see :func:`build_mjcf` for the arguments); MuJoCo writes
    no log file from then on (:func:`no_log_file`).

    Raises:
        ShapeError: a fixture centre that is not three numbers (:func:`controller.reach.fixture_centre`), naming the
            fixture and the shape given.
        UnreachableFixtureError: a fixture centre farther from the base than any posture of ``model`` reaches
            (:func:`controller.reach.check_fixture_distance`: one in millimetres), naming it, before MuJoCo is called.
    """
    no_log_file()
    fixtures = {str(k): fixture_centre(str(k), v) for k, v in (fixtures or {}).items()}  # every shape, then reach
    for name, centre in fixtures.items():
        check_fixture_distance(model, name, centre)
    mjcf = build_mjcf(model, fixtures, markers, **options)
    mj_model = mujoco.MjModel.from_xml_string(mjcf)
    mj_data = mujoco.MjData(mj_model)
    n_markers = 0 if markers is None else np.asarray(markers).reshape(-1, 3).shape[0]
    site = lambda name: mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_SITE, name)  # noqa: E731
    plant = Plant(
        model=model,
        mjcf=mjcf,
        mj_model=mj_model,
        mj_data=mj_data,
        fixture_names=tuple(fixtures),
        fixture_centres=np.array(list(fixtures.values())).reshape(-1, 3),
        tool_site=site("tool"),
        marker_sites=np.array([site(f"marker{m}") for m in range(n_markers)], dtype=int),
        fixture_sites=np.array([site(f"fixture{k}") for k in range(len(fixtures))], dtype=int),
        **_joint_addresses(mj_model, model.n_joints),
    )
    mujoco.mj_forward(mj_model, mj_data)
    return plant


def _joint_addresses(mj_model: mujoco.MjModel, n: int) -> dict[str, np.ndarray]:
    """qpos / dof addresses of the motor hinges ``joint<i>`` and the elastic ``flex<i>`` hinges."""
    joint = lambda name: mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_JOINT, name)  # noqa: E731
    motors = [joint(f"joint{i + 1}") for i in range(n)]
    flex = [i for i in range(n) if joint(f"flex{i + 1}") >= 0]
    ids = [joint(f"flex{i + 1}") for i in flex]
    return {
        "motor_qpos": np.array([mj_model.jnt_qposadr[j] for j in motors], dtype=int),
        "motor_dofs": np.array([mj_model.jnt_dofadr[j] for j in motors], dtype=int),
        "flex_qpos": np.array([mj_model.jnt_qposadr[j] for j in ids], dtype=int),
        "flex_dofs": np.array([mj_model.jnt_dofadr[j] for j in ids], dtype=int),
        "flex_joints": np.array(flex, dtype=int),
    }
