"""The flat parameter vector of a model: names, kinds, units, prior spread and slices, in one place.

Every other module asks a :class:`ParameterLayout` where a parameter lives and what it is, instead of
computing ``4 * n + 3`` or guessing from a name prefix. Adding a parameter (a per-joint field or a
block such as a compliance) means adding it here::

    layout = model.layout                     # or layout_for(7)
    layout.names[layout.tool]                 # ('tool_x', 'tool_y', 'tool_z')
    layout.field("theta")                     # (n,) indices of theta1..thetan
    layout.kinds[layout.index("alpha3")]      # ANGLE
    layout.spread()                           # (P,) prior std [m, rad]

Order of the vector: per joint ``a, alpha, d, theta`` (joint 1 first), then one Hayati angle
``beta{j}`` per joint that has one (nearly parallel axes, see :class:`RobotModel`; none for most arms),
then the tool point ``tool_x, tool_y, tool_z``, then the base ``base_x, base_y, base_z, base_roll,
base_pitch, base_yaw``, then, for an elastic model only (``layout_for(n, elastic=True)``: its robot file
has a ``compliance:`` list), the joint compliances ``c1 .. cn`` [rad/Nm], then, for a scaled model only
(``layout_for(n, scaled=True)``: its robot file has a ``scale:`` list), the joint angle scales ``s1 .. sn``
(dimensionless: the joint turns ``(1 + s_i) q_i``, :mod:`correction.scale`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import lru_cache

import numpy as np


@dataclass(frozen=True)
class ParamKind:
    """What a parameter is: its quantity, SI unit, display unit and prior spread.

    Attributes:
        name: ``"length"`` or ``"angle"``.
        unit: unit in files and APIs (``"m"``, ``"rad"``).
        display_unit: unit of printed tables (``"mm"``, ``"deg"``).
        display_scale: factor from ``unit`` to ``display_unit``.
        prior_std: how far a real arm's value typically sits from its design value, in ``unit``
            (lengths 1 mm, angles 0.2 deg: the issues' true-robot spread).
    """

    name: str
    unit: str
    display_unit: str
    display_scale: float
    prior_std: float

    def format(self, value: float) -> str:
        """``value`` (in :attr:`unit`) for humans, e.g. ``"0.1234 mm"``."""
        return f"{value * self.display_scale:.4g} {self.display_unit}"


LENGTH = ParamKind("length", "m", "mm", 1e3, 1e-3)
ANGLE = ParamKind("angle", "rad", "deg", float(np.rad2deg(1.0)), float(np.deg2rad(0.2)))
#: A joint's compliance under load (:mod:`correction.elastic`): arm joints are 1e4-1e5 Nm/rad stiff, so
#: the prior spread about rigid is 3e-5 rad/Nm (3.3e4 Nm/rad, the middle of that range on a log scale). A
#: compliance the data cannot pin down better than that (a wrist joint carrying a few Nm) is not identified.
COMPLIANCE = ParamKind("compliance", "rad/Nm", "urad/Nm", 1e6, 3e-5)
#: A joint's angle scale (:mod:`correction.scale`): ``q_joint = (1 + s) q``. Prior spread 1e-3: a gear
#: ratio or encoder resolution off by 0.1 % (3 mrad over a 3 rad stroke, the size of the 0.2 deg angle prior).
SCALE = ParamKind("scale", "1", "ppm", 1e6, 1e-3)

#: Per-joint fields in vector order, with their kinds.
JOINT_FIELDS: tuple[tuple[str, ParamKind], ...] = (("a", LENGTH), ("alpha", ANGLE), ("d", LENGTH), ("theta", ANGLE))
#: The tool point in the last joint frame.
TOOL_FIELDS: tuple[tuple[str, ParamKind], ...] = (("tool_x", LENGTH), ("tool_y", LENGTH), ("tool_z", LENGTH))
#: The base placement in the world (URDF roll-pitch-yaw).
BASE_FIELDS: tuple[tuple[str, ParamKind], ...] = (
    ("base_x", LENGTH),
    ("base_y", LENGTH),
    ("base_z", LENGTH),
    ("base_roll", ANGLE),
    ("base_pitch", ANGLE),
    ("base_yaw", ANGLE),
)


@dataclass(frozen=True, eq=False)
class ParameterLayout:
    """Where every parameter of an ``n_joints`` model sits in the flat vector, and what it is.

    Attributes:
        n_joints: number of joints ``n``.
        names: (P,) parameter names (``a1, alpha1, ..., tool_x, ..., base_yaw``).
        kinds: (P,) :class:`ParamKind` of every parameter.
        joints: slice of the per-joint block (``len(JOINT_FIELDS) * n`` entries, joint-major).
        hayati: 0-based joints that carry a Hayati ``beta`` (sorted).
        beta: slice of their ``beta`` angles (``len(hayati)`` entries, in joint order).
        tool: slice of the tool point (3).
        base_xyz: slice of the base translation (3).
        base_rpy: slice of the base roll-pitch-yaw (3).
        compliance: slice of the joint compliances ``c1 .. cn`` (empty for a rigid model).
        scale: slice of the joint angle scales ``s1 .. sn`` (empty for an unscaled model).
    """

    n_joints: int
    names: tuple[str, ...]
    kinds: tuple[ParamKind, ...]
    joints: slice
    hayati: tuple[int, ...]
    beta: slice
    tool: slice
    base_xyz: slice
    base_rpy: slice
    compliance: slice = dataclasses.field(default_factory=lambda: slice(0, 0))
    scale: slice = dataclasses.field(default_factory=lambda: slice(0, 0))

    @property
    def elastic(self) -> bool:
        """True when the vector carries joint compliances."""
        return self.compliance.stop > self.compliance.start

    @property
    def scaled(self) -> bool:
        """True when the vector carries joint angle scales."""
        return self.scale.stop > self.scale.start

    @property
    def size(self) -> int:
        """Length ``P`` of the vector."""
        return len(self.names)

    @property
    def joint_fields(self) -> tuple[str, ...]:
        """Per-joint field names in vector order (``a, alpha, d, theta``)."""
        return _JOINT_FIELD_NAMES

    @property
    def base(self) -> slice:
        """Slice of the whole base placement (6)."""
        return slice(self.base_xyz.start, self.base_rpy.stop)

    def index(self, name: str) -> int:
        """Index of a named parameter (``"a3"``, ``"tool_z"``, ...).

        Raises:
            KeyError: no parameter of that name in this layout.
        """
        try:
            return self._lookup()[name]
        except KeyError:
            raise KeyError(f"no parameter named {name!r} in a {self.n_joints}-joint model") from None

    def field(self, name: str) -> np.ndarray:
        """(n,) indices of one per-joint field (``"a"``, ``"theta"``, ...) for joints 1..n (read-only).

        Raises:
            ValueError: ``name`` is not one of :attr:`joint_fields`.
        """
        return _field_index(self.joints.start, self.n_joints, name)

    def held(self, convention: str) -> tuple[str, ...]:
        """Names of the ``d`` held at zero beside each ``beta``: Hayati's rule that the joint whose
        frame is tilted by ``beta`` has no offset along the (nearly) parallel axis. ``standard``:
        ``Rz(theta+q) Lz(d) Lx(a) Rx(alpha) Ry(beta)``, the same joint's ``d``; ``modified``:
        ``Rx(alpha) Lx(a) Ry(beta) Rz(theta+q) Lz(d)`` is the standard one shifted by a joint, so
        the previous joint's ``d``."""
        shift = 1 if convention == "modified" else 0
        return tuple(f"d{j + 1 - shift}" for j in self.hayati if j - shift >= 0)

    def is_angle(self, name: str) -> bool:
        """True for angular parameters (radians), False for lengths (metres)."""
        return self.kinds[self.index(name)] is ANGLE

    def mask(self, kind: ParamKind) -> np.ndarray:
        """(P,) True where the parameter is of ``kind``."""
        return np.array([k is kind for k in self.kinds])

    def display_scale(self) -> np.ndarray:
        """(P,) factors from file units to table units (1e3 for m -> mm, 57.3 for rad -> deg)."""
        return np.array([k.display_scale for k in self.kinds])

    def format(self, name: str, value: float) -> str:
        """A value or deviation of parameter ``name`` for humans: mm for lengths, deg for angles."""
        return self.kinds[self.index(name)].format(value)

    def spread(
        self,
        length: float = LENGTH.prior_std,
        angle: float = ANGLE.prior_std,
        tool: float = LENGTH.prior_std,
        base: bool = True,
    ) -> np.ndarray:
        """(P,) std of every parameter [m, rad]: the prior of a calibration, or a simulated arm's errors.

        Args:
            length: std of the joints' lengths and the base translation [m].
            angle: std of the joints' angles and the base rotation [rad].
            tool: std of each tool-point coordinate [m].
            base: False to give the base placement zero spread.
        """
        std = np.array([length if k is LENGTH else angle if k is ANGLE else k.prior_std for k in self.kinds])
        std[self.tool] = tool
        if not base:
            std[self.base] = 0.0
        return std

    def _lookup(self) -> dict[str, int]:
        return _name_index(self.names)


_JOINT_FIELD_NAMES: tuple[str, ...] = tuple(name for name, _ in JOINT_FIELDS)


@lru_cache(maxsize=256)
def _field_index(start: int, n_joints: int, name: str) -> np.ndarray:
    """:meth:`ParameterLayout.field`, computed once (every parameter vector a fit packs or unpacks reads it)."""
    index = start + _JOINT_FIELD_NAMES.index(name) + len(JOINT_FIELDS) * np.arange(n_joints)
    index.setflags(write=False)
    return index


@lru_cache(maxsize=64)
def _name_index(names: tuple[str, ...]) -> dict[str, int]:
    return {name: i for i, name in enumerate(names)}


@lru_cache(maxsize=64)
def layout_for(
    n_joints: int, hayati: tuple[int, ...] = (), elastic: bool = False, scaled: bool = False
) -> ParameterLayout:
    """The (shared, immutable) layout of an ``n_joints`` model with Hayati ``beta`` on the 0-based
    joints ``hayati`` (and the compliances ``c1..cn`` if ``elastic``, the scales ``s1..sn`` if ``scaled``).

    Raises:
        ValueError: a ``hayati`` index outside ``0..n_joints-1``, or repeated.
    """
    hayati = tuple(sorted(int(j) for j in hayati))
    if any(not 0 <= j < n_joints for j in hayati) or len(set(hayati)) != len(hayati):
        raise ValueError(f"hayati joints must be distinct indices in 0..{n_joints - 1}, got {hayati}")
    joints = [(f"{name}{i + 1}", kind) for i in range(n_joints) for name, kind in JOINT_FIELDS]
    joints += [(f"beta{i + 1}", ANGLE) for i in hayati]
    compliance = [(f"c{i + 1}", COMPLIANCE) for i in range(n_joints)] if elastic else []
    scale = [(f"s{i + 1}", SCALE) for i in range(n_joints)] if scaled else []
    entries = joints + list(TOOL_FIELDS) + list(BASE_FIELDS) + compliance + scale
    j = len(joints)
    k = len(JOINT_FIELDS) * n_joints
    return ParameterLayout(
        n_joints=n_joints,
        names=tuple(name for name, _ in entries),
        kinds=tuple(kind for _, kind in entries),
        joints=slice(0, k),
        hayati=hayati,
        beta=slice(k, j),
        tool=slice(j, j + 3),
        base_xyz=slice(j + 3, j + 6),
        base_rpy=slice(j + 6, j + 9),
        compliance=slice(j + 9, j + 9 + len(compliance)),
        scale=slice(j + 9 + len(compliance), j + 9 + len(compliance) + len(scale)),
    )
