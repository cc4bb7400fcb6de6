"""The kinematic parameter set of a serial arm of revolute joints."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np

from . import layout
from .layout import ParameterLayout, layout_for

Convention = Literal["standard", "modified"]
CONVENTIONS: tuple[str, ...] = ("standard", "modified")

#: Per-joint DH fields, in the order they appear in the flat parameter vector (see :mod:`.layout`).
JOINT_FIELDS: tuple[str, ...] = tuple(name for name, _ in layout.JOINT_FIELDS)


def _frozen_array(values: Any, shape: tuple[int, ...], name: str) -> np.ndarray:
    array = np.array(values, dtype=float).reshape(shape) if np.size(values) else np.zeros(shape)
    if array.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got {array.shape}")
    array.setflags(write=False)
    return array


#: Tolerance [rad] on a span of exactly one turn (:attr:`RobotModel.full_turn`).
FULL_TURN_TOL = 1e-9
#: Two descriptions of one arm agree on its joint limits within this [rad] (:meth:`RobotModel.mismatch`): files
#: round them (170 deg is -2.96706 rad in the embedded iiwa14, -2.9668 in MUKCa's iiwa14.urdf); another arm's differ
#: by tenths of a radian.
LIMIT_MATCH = 1e-3


@dataclass(frozen=True, eq=False)
class RobotModel:
    """DH parameters, joint limits, tool point and base placement of a serial arm.

    Conventions (one joint ``i``, joint angle ``q``):
      * ``standard`` (paper eq. 1): ``Rz(theta+q) Lz(d) Lx(a) Rx(alpha)``; joint ``i``
        turns about ``z`` of frame ``i-1``.
      * ``modified`` (Craig, as Franka publishes): ``Rx(alpha) Lx(a) Rz(theta+q) Lz(d)``;
        joint ``i`` turns about ``z`` of frame ``i``.

    The world frame is the base frame, placed by ``base_xyz`` [m] and ``base_rpy`` [rad]
    (URDF convention, ``R = Rz(yaw) Ry(pitch) Rx(roll)``). The tool point [m] (the centre of
    the spherical joint) is expressed in the frame of the last joint.

    Attributes:
        name: robot name.
        convention: ``"standard"`` or ``"modified"``.
        a, alpha, d, theta: (n,) DH parameters [m, rad, m, rad].
        lower, upper: (n,) joint limits [rad].
        tool: (3,) tool point in the last frame [m].
        base_xyz, base_rpy: (3,) base placement [m], [rad].
        extras: other top-level keys of the robot file, written back unchanged.
        beta: (n,) Hayati rotations about ``y`` [rad] (zeros when not given): ``modified``
            ``Rx(alpha) Lx(a) Ry(beta) Rz(theta+q) Lz(d)``, ``standard``
            ``Rz(theta+q) Lz(d) Lx(a) Rx(alpha) Ry(beta)`` (nearly parallel axes). Non-zero
            only on the ``hayati`` joints.
        hayati: 0-based joints whose ``beta`` is a parameter (in :attr:`params`); beside each, a
            ``d`` is held at zero (:meth:`ParameterLayout.held`).

    Arrays are copied to read-only float arrays on construction.

    Raises:
        ValueError: an unknown convention, no joint, an array of another shape than above, ``lower > upper``
            on a joint, a ``hayati`` index outside ``0..n-1`` or repeated, or a non-zero ``beta`` on a joint
            not in ``hayati``.

    Example::

        model = RobotModel("two_link", "standard", a=[0.3, 0.2], alpha=[0.0, 0.0], d=[0.1, 0.0],
                           theta=[0.0, 0.0], lower=[-2.9, -2.9], upper=[2.9, 2.9], tool=[0.05, 0.0, 0.0])
        model.param_names[:4]        # ('a1', 'alpha1', 'd1', 'theta1')
    """

    name: str
    convention: Convention
    a: np.ndarray
    alpha: np.ndarray
    d: np.ndarray
    theta: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    tool: np.ndarray = field(default_factory=lambda: np.zeros(3))
    base_xyz: np.ndarray = field(default_factory=lambda: np.zeros(3))
    base_rpy: np.ndarray = field(default_factory=lambda: np.zeros(3))
    extras: dict = field(default_factory=dict)
    beta: np.ndarray = field(default_factory=lambda: np.zeros(0))
    hayati: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        if self.convention not in CONVENTIONS:
            raise ValueError(
                f"unknown convention {self.convention!r}, expected one of {CONVENTIONS}"
            )
        n = np.size(self.a)
        if n < 1:
            raise ValueError("a robot needs at least one joint")
        if not self.hayati and np.size(self.beta) != n and not np.any(self.beta):
            # no Hayati joint: a zero beta of another length (a copy with fewer joints) means none
            object.__setattr__(self, "beta", np.zeros(n))
        for name in ("a", "alpha", "d", "theta", "lower", "upper", "beta"):
            object.__setattr__(self, name, _frozen_array(getattr(self, name), (n,), name))
        for name in ("tool", "base_xyz", "base_rpy"):
            object.__setattr__(self, name, _frozen_array(getattr(self, name), (3,), name))
        if np.any(self.lower > self.upper):
            raise ValueError("joint limits: lower > upper")
        object.__setattr__(self, "hayati", layout_for(n, tuple(self.hayati)).hayati)
        # not np.setdiff1d: 12x slower here, and it imports numpy.ma
        others = np.array([j for j in range(n) if j not in self.hayati], dtype=int)
        if np.any(self.beta[others] != 0.0):
            raise ValueError(f"beta is non-zero on joint(s) {others[self.beta[others] != 0.0] + 1} not in hayati")

    # ----------------------------------------------------------------- sizes
    @property
    def n_joints(self) -> int:
        """Number of joints ``n``."""
        return int(self.a.size)

    @property
    def full_turn(self) -> np.ndarray:
        """(n,) bool: the joints that turn freely, a URDF's ``continuous`` joints (read as ``[-pi, pi]``): an export
        writes them without limits (MJCF) or as ``continuous`` (URDF). A model read from a URDF names them
        (``extras["urdf"]["continuous_joints"]``, by the names in ``extras["joint_names"]``), so a revolute joint
        limited to ``[-pi, pi]`` (a UR arm's elbow) keeps its limits; any other model (a DH file, one written before
        the names were kept) counts every joint whose limits span exactly one turn. A joint limited to more than a
        turn (a UR arm's +-2 pi) keeps its limits."""
        block, names = self.extras.get("urdf"), self.extras.get("joint_names")
        named = block.get("continuous_joints") if isinstance(block, dict) else None
        if isinstance(named, list) and isinstance(names, list) and len(names) == self.n_joints:
            return np.array([name in named for name in names])
        return np.abs(np.asarray(self.upper) - np.asarray(self.lower) - 2 * np.pi) <= FULL_TURN_TOL

    @property
    def reach(self) -> float:
        """:attr:`chain_length` plus ``|tool|`` [m]: no tool point lies farther than this from the base origin (the
        bound known positions, distances and controller targets are checked against: millimetres typed for
        metres)."""
        return self.chain_length + float(np.linalg.norm(self.tool))

    @property
    def chain_length(self) -> float:
        """Sum of ``|a|`` and ``|d|`` [m]: no point of the chain is farther than this from the base frame's
        origin along the links (a bound on reach, tool excluded)."""
        return float(np.abs(self.a).sum() + np.abs(self.d).sum())

    @property
    def n_params(self) -> int:
        """Length ``P`` of the flat parameter vector (see :attr:`layout`)."""
        return self.layout.size

    @property
    def layout(self) -> ParameterLayout:
        """Names, kinds, prior spread and slices of the flat parameter vector (with the joint compliances
        ``c1..cn`` when ``extras`` has a ``compliance`` list: an elastic model, :mod:`.elastic`; with the
        joint angle scales ``s1..sn`` when it has a ``scale`` list, :mod:`.scale`)."""
        return layout_for(self.n_joints, self.hayati, "compliance" in self.extras, "scale" in self.extras)

    # ----------------------------------------------------- flat parameter view
    @property
    def param_names(self) -> tuple[str, ...]:
        """(P,) names of the flat parameter vector: ``a1, alpha1, d1, theta1, a2, ..., beta{j} (Hayati joints),
        tool_x, tool_y, tool_z, base_x, base_y, base_z, base_roll, base_pitch, base_yaw`` then ``c1..cn`` (an
        elastic model) and ``s1..sn`` (a scaled one): :mod:`.layout`."""
        return self.layout.names

    @property
    def params(self) -> np.ndarray:
        """(P,) flat parameter vector, ordered as :attr:`param_names`: lengths [m], angles [rad], compliances
        [rad/Nm], scales (dimensionless); the unit of each is ``layout.kinds[i].unit``."""
        lay = self.layout
        out = np.empty(lay.size)
        for name in lay.joint_fields:
            out[lay.field(name)] = getattr(self, name)
        out[lay.beta] = self.beta[list(lay.hayati)]
        out[lay.tool], out[lay.base_xyz], out[lay.base_rpy] = self.tool, self.base_xyz, self.base_rpy
        if lay.elastic:
            out[lay.compliance] = np.asarray(self.extras["compliance"], dtype=float).reshape(self.n_joints)
        if lay.scaled:
            out[lay.scale] = np.asarray(self.extras["scale"], dtype=float).reshape(self.n_joints)
        return out

    def with_params(self, params: np.ndarray) -> RobotModel:
        """A copy of this model with the flat parameter vector replaced.

        Args:
            params: (P,) parameters ordered as :attr:`param_names`, in the units of :attr:`params` ([m], [rad],
                [rad/Nm], dimensionless scales).

        Returns:
            The new model (same convention, joint limits, Hayati joints and other ``extras``).

        Raises:
            ValueError: ``params`` not of shape (P,).
        """
        params = np.asarray(params, dtype=float)
        if params.shape != (self.n_params,):
            raise ValueError(f"params must have shape ({self.n_params},), got {params.shape}")
        lay = self.layout
        fields = {name: params[lay.field(name)] for name in lay.joint_fields}
        beta = np.zeros(self.n_joints)
        beta[list(lay.hayati)] = params[lay.beta]
        extras = dict(self.extras)
        if lay.elastic:
            extras["compliance"] = [float(v) for v in params[lay.compliance]]
        if lay.scaled:
            extras["scale"] = [float(v) for v in params[lay.scale]]
        if lay.elastic or lay.scaled:
            fields["extras"] = extras
        return replace(
            self, **fields, beta=beta, tool=params[lay.tool], base_xyz=params[lay.base_xyz],
            base_rpy=params[lay.base_rpy]
        )

    def param_index(self, name: str) -> int:
        """Index of a named parameter (``"a3"``, ``"tool_z"``, ...) in :attr:`params`.

        Raises:
            KeyError: no parameter of that name in this model.
        """
        return self.layout.index(name)

    # -------------------------------------------------------------- helpers
    @property
    def base_transform(self) -> np.ndarray:
        """(4, 4) homogeneous transform of the base frame in the world."""
        return pose_matrix(self.base_xyz, self.base_rpy)

    def within_limits(self, q: np.ndarray, tol: float = 0.0) -> np.ndarray:
        """Which configurations lie inside the joint limits.

        Args:
            q: (N, n) or (n,) joint angles [rad].
            tol: margin added to each limit [rad].

        Returns:
            (N,) bool, True where every joint lies inside ``[lower - tol, upper + tol]``; (1,) for one
            configuration (the batch axis is kept).
        """
        q = np.atleast_2d(q)
        return np.all((q >= self.lower - tol) & (q <= self.upper + tol), axis=1)

    def random_configurations(self, count: int, rng: np.random.Generator) -> np.ndarray:
        """(count, n) joint angles [rad] drawn uniformly inside the joint limits from ``rng``."""
        return rng.uniform(self.lower, self.upper, size=(count, self.n_joints))

    def mismatch(self, other: RobotModel, limits: bool = False) -> tuple[str, str] | None:
        """The first way ``other`` is not a description of the same arm as this model.

        Args:
            other: the model to compare (a calibration, a truth file, ...).
            limits: also require the same joint limits (a calibration changes geometry, not limits), within
                :data:`LIMIT_MATCH` (a robot file rounds them: the embedded iiwa14's -2.96706 rad, 170 deg, is
                -2.9668 in MUKCa's iiwa14.urdf, and its calibration was refused as another arm's).

        Returns:
            ``(field, what)``, e.g. ``("joints", "6 joints, expected 7")``, or None when they match.
        """
        if other.n_joints != self.n_joints:
            return "joints", f"{other.n_joints} joints, expected {self.n_joints}"
        if other.convention != self.convention:
            return "convention", (
                f"{other.convention!r}, expected {self.convention!r} (convert it with correction.convert first)"
            )
        if other.hayati != self.hayati:
            joints = ", ".join(str(j + 1) for j in self.hayati) or "none"
            return "beta", f"Hayati beta on joints {[j + 1 for j in other.hayati]}, expected {joints}"
        if limits:
            for name in ("lower", "upper"):
                diff = np.abs(getattr(other, name) - getattr(self, name))
                if np.any(diff > LIMIT_MATCH):
                    joint = int(np.argmax(diff))
                    return f"joints[{joint}].{name}", (
                        f"{float(getattr(other, name)[joint]):.6g} rad, expected "
                        f"{float(getattr(self, name)[joint]):.6g} rad"
                    )
        return None

    def same_as(self, other: RobotModel, atol: float = 0.0) -> bool:
        """True when both models have the same convention, joint count, Hayati joints, parameters (:attr:`params`)
        and joint limits, within ``atol`` (absolute, in each parameter's unit: [m], [rad], ...)."""
        return (
            self.convention == other.convention
            and self.n_joints == other.n_joints
            and self.n_params == other.n_params
            and self.hayati == other.hayati
            and np.allclose(self.params, other.params, rtol=0.0, atol=atol)
            and np.allclose(self.lower, other.lower, rtol=0.0, atol=atol)
            and np.allclose(self.upper, other.upper, rtol=0.0, atol=atol)
        )


def param_names(n_joints: int) -> tuple[str, ...]:
    """Flat parameter names of an ``n_joints`` model without Hayati angles, compliances or scales (4 n + 9 names,
    see :attr:`RobotModel.param_names`; a model's own: ``model.param_names``)."""
    return layout_for(n_joints).names


def rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    """(3, 3) rotation ``Rz(yaw) Ry(pitch) Rx(roll)`` (URDF's ``rpy``).

    Args:
        rpy: (3,) ``(roll, pitch, yaw)`` [rad].
    """
    r, p, y = np.asarray(rpy, dtype=float)
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def matrix_rpy(rotation: np.ndarray) -> np.ndarray:
    """(3,) roll-pitch-yaw angles [rad] of a (3, 3) rotation (inverse of :func:`rpy_matrix`).

    Args:
        rotation: (3, 3) rotation matrix (dimensionless, orthonormal; not checked).

    Pitch in ``[-pi/2, pi/2]``, roll and yaw in ``(-pi, pi]``; at gimbal lock (pitch of +-pi/2) the yaw is
    returned as 0 and roll carries the combined rotation (only ``roll - yaw`` or ``roll + yaw``
    is defined there).
    """
    r = np.asarray(rotation, dtype=float)
    pitch = np.arctan2(-r[2, 0], np.hypot(r[0, 0], r[1, 0]))
    if np.hypot(r[0, 0], r[1, 0]) < 1e-12:  # gimbal lock: put all of it in roll
        return np.array([np.arctan2(-r[1, 2], r[1, 1]), pitch, 0.0])
    return np.array([np.arctan2(r[2, 1], r[2, 2]), pitch, np.arctan2(r[1, 0], r[0, 0])])


def pose_matrix(xyz: np.ndarray, rpy: np.ndarray) -> np.ndarray:
    """(4, 4) homogeneous transform of a translation and a roll-pitch-yaw rotation (:func:`rpy_matrix`).

    Args:
        xyz: (3,) translation [m].
        rpy: (3,) ``(roll, pitch, yaw)`` [rad].
    """
    pose = np.eye(4)
    pose[:3, :3] = rpy_matrix(rpy)
    pose[:3, 3] = xyz
    return pose


def joint_vector(model: RobotModel, key: str, unit: str, error: type[Exception]) -> np.ndarray:
    """(n,) per-joint numbers of ``model.extras[key]`` (``compliance``, ``scale``); zeros when absent.

    Args:
        key: the extras key (a robot file's top-level list).
        unit: the unit named in the error (``[rad/Nm]``, ``(dimensionless)``).
        error: the exception raised for a malformed list (one line naming the field).
    """
    block = model.extras.get(key)
    if block is None:
        return np.zeros(model.n_joints)
    try:
        values = np.asarray(block, dtype=float)
    except (TypeError, ValueError):
        values = np.empty(0)
    if values.shape != (model.n_joints,) or not np.all(np.isfinite(values)):
        raise error(f"{model.name}: field '{key}': expected {model.n_joints} finite numbers {unit}, got {block!r}")
    return values


def with_joint_vector(model: RobotModel, key: str, values: np.ndarray | None) -> RobotModel:
    """A copy of ``model`` with ``extras[key]`` set to (n,) plain floats (removed when None).

    Args:
        model: the arm.
        key: the extras key (``compliance``, ``scale``).
        values: (n,) numbers in the key's unit ([rad/Nm], dimensionless), or None.
    """
    extras = {k: v for k, v in model.extras.items() if k != key}
    if values is not None:
        extras[key] = [float(v) for v in np.asarray(values, dtype=float).reshape(model.n_joints)]
    return replace(model, extras=extras)


def geometric_part(model: RobotModel) -> RobotModel:
    """``model`` without its joint-side parameter blocks: every ``extras`` key whose removal shortens the
    parameter vector (compliance and scale today, any block added to the layout the same way tomorrow).

    The rigid, unscaled geometry of an elastic or scaled calibration: DH, Hayati, tool and base unchanged,
    every other ``extras`` key (inertials, calibration record, ...) kept.
    """
    extras = dict(model.extras)
    size = model.layout.size
    for key in list(extras):
        trial = replace(model, extras={k: v for k, v in extras.items() if k != key})
        if trial.layout.size < size:
            extras.pop(key)
            size = trial.layout.size
    return replace(model, extras=extras)
