"""Gravity torques of a serial arm from per-link masses and centres of mass.

Inertial data live in :attr:`RobotModel.extras`, exactly as a robot file's top-level blocks::

    inertials:                 # one entry per joint i: the link that moves with joint i
      - {mass: 4.970684, com: [0.003875, 0.002081, -0.04762]}   # [kg], [m] in DH frame i
      ...
    payload: {mass: 0.73, com: [0.0, 0.0, 0.14]}                # [kg], [m] in the last DH frame

Each entry may also give ``inertia: [ixx, ixy, ixz, iyy, iyz, izz]`` [kg m^2] about its centre of mass, in
the axes of the same frame (:mod:`.inertia`): gravity does not need it, a dynamics stack does (the URDF and
MJCF exports write it, :func:`correction.inertials.link_inertias`).

Frame ``i`` is the frame :func:`correction.link_frames` gives for link ``i`` (it moves with joint
``i`` in both DH conventions). The payload is what the flange carries (hand, ball), rigidly on the
last link.

Sign convention: :func:`gravity_torques` returns the torque the joints must apply to hold the
arm still against gravity (MuJoCo's ``qfrc_bias`` at zero velocity), ``tau = -sum_j J_cj^T m_j g``.
Gravity itself pushes each joint by ``-tau``, so a compliant joint deflects by ``-c tau``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .chain import as_batch, frames
from .errors import SpherecalError
from .inertia import checked_tensor
from .model import RobotModel

#: Standard gravity in the world (base) frame [m/s^2].
GRAVITY = (0.0, 0.0, -9.81)


#: Farthest a centre of mass may lie from its frame [m]: farther is a file in millimetres, not an arm.
MAX_COM_DISTANCE = 10.0
#: Most mass (links and payload) per cubic metre of the chain's length cubed [kg/m^3]: real arms carry 7-16
#: (Panda, FR3, Gen3 lite, iiwa14) and a 4.7 t KUKA titan about 75; a Panda's masses in grams give 7900.
MAX_MASS_DENSITY = 1000.0


class InertialsError(SpherecalError):
    """Missing or malformed ``inertials`` / ``payload`` data; the message names the field."""


def _entry(value: Any, where: str) -> tuple[float, np.ndarray]:
    if not isinstance(value, dict) or set(value) - {"mass", "com", "inertia"} or "mass" not in value:
        raise InertialsError(f"{where}': expected a mapping {{mass: kg, com: [x, y, z] m, inertia: [ixx, ixy, ixz, "
                             f"iyy, iyz, izz] kg m^2 (optional)}}, got {value!r}")
    mass = value["mass"]
    if isinstance(mass, bool) or not isinstance(mass, (int, float)) or not np.isfinite(mass) or mass < 0:
        raise InertialsError(f"{where}.mass': expected a finite mass >= 0 [kg], got {mass!r}")
    com = value.get("com", [0.0, 0.0, 0.0])
    try:
        com_array = np.asarray(com, dtype=float)
    except (TypeError, ValueError):
        com_array = np.empty(0)
    if com_array.shape != (3,) or not np.all(np.isfinite(com_array)):
        raise InertialsError(f"{where}.com': expected 3 finite numbers [m], got {com!r}")
    if np.linalg.norm(com_array) > MAX_COM_DISTANCE:
        raise InertialsError(f"{where}.com': {com!r} m is {np.linalg.norm(com_array):.4g} m from its frame, not "
                             f"physical (at most {MAX_COM_DISTANCE:g} m; the file is in metres)")
    if "inertia" in value:
        checked_tensor(value["inertia"], f"{where}.inertia'", InertialsError)
    return float(mass), com_array


def inertials_of(model: RobotModel, source: str | None = None,
                 rows: dict[str, int] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Link masses and centres of mass of ``model``, payload appended as an (n+1)-th body.

    Args:
        model: a robot whose ``extras`` carry ``inertials`` (and optionally ``payload``).
        source: file name for error messages (default: the robot's name).
        rows: file line of ``"inertials"``, ``"inertials[i]"`` and ``"payload"`` (for messages), when known.

    Returns:
        masses (n+1,) [kg] and coms (n+1, 3) [m], entry ``i < n`` in frame ``i+1``, the last in frame n.

    Raises:
        InertialsError: no ``inertials`` block, wrong length, or a malformed entry.
    """
    block, payload = model.extras.get("inertials"), model.extras.get("payload")
    parsed = _PARSED.get(id(block))
    if parsed is not None and parsed[0] is block and parsed[1] is payload and len(parsed[2]) == model.n_joints + 1:
        masses, coms = parsed[2].copy(), parsed[3].copy()  # read before: the same objects, for as many joints
    else:
        masses, coms = _parse(model, block, payload, source, rows)
        if len(_PARSED) >= PARSED_KEPT:
            _PARSED.clear()
        _PARSED[id(block)] = (block, payload, masses.copy(), coms.copy())  # held: their ids stay theirs
    size = model.chain_length  # 0: a check of the entries alone (a robot file's block before its geometry is read)
    if size > 0 and masses.sum() > MAX_MASS_DENSITY * size**3:  # grams for kilograms, or a payload of another scale
        k = int(np.argmax(masses))
        name = "payload" if k == model.n_joints else f"inertials[{k}]"
        raise InertialsError(f"{_field(model, source, rows, name)}.mass': {masses.sum():.6g} kg in all for an arm "
                             f"of {size:.3g} m of links, not physical (at most {MAX_MASS_DENSITY * size**3:.3g} kg; "
                             f"the file is in kilograms)")
    return masses, coms


#: Inertials blocks read (:func:`inertials_of`): id -> (block, payload, masses, coms). A fit reads a model's masses
#: at every step (gravity torques, a compliance's check), and every model of one fit holds the same block: checking
#: it once saves a seventh of a default calibration. The objects are held, so an id is not taken by another block;
#: extras are not changed in place (every ``with_*`` makes a copy).
_PARSED: dict[int, tuple] = {}
#: Blocks kept before the memory of them is cleared.
PARSED_KEPT = 64


def _field(model: RobotModel, source: str | None, rows: dict[str, int] | None, key: str) -> str:
    where = source or model.extras.get("source") or model.name
    rows = rows or {}
    return f"{where}: {f'row {rows[key]}, ' if key in rows else ''}field '{key}"


def _parse(model: RobotModel, block: Any, payload: Any, source: str | None,
           rows: dict[str, int] | None) -> tuple[np.ndarray, np.ndarray]:
    """Masses (n+1,) and centres of mass (n+1, 3) of the checked entries (:func:`inertials_of`)."""

    def at(key: str) -> str:
        return _field(model, source, rows, key)

    n = model.n_joints
    if not isinstance(block, list) or len(block) != n:
        got = "none" if block is None else (f"{len(block)} entries" if isinstance(block, list) else repr(block))
        hint = " (link masses: --inertials FILE or an inertials block in the robot file)" if block is None else ""
        raise InertialsError(f"{at('inertials')}': expected a list of {n} {{mass, com}} entries, got "
                             f"{got}{hint}")
    entries = [_entry(v, at(f"inertials[{i}]")) for i, v in enumerate(block)]
    entries.append((0.0, np.zeros(3)) if payload is None else _entry(payload, at("payload")))
    return np.array([m for m, _ in entries]), np.stack([c for _, c in entries])


def has_inertials(model: RobotModel) -> bool:
    """True when ``model.extras`` carries an ``inertials`` block (present, not checked: :func:`inertials_of`)."""
    return "inertials" in model.extras


def weighs_nothing(model: RobotModel) -> bool:
    """True when ``model``'s inertials give every link and the payload 0 kg: gravity loads no joint, and a
    compliance has nothing to be fitted against (an inertials file of zeros from another tool). False without
    an ``inertials`` block.

    Raises:
        InertialsError: a malformed ``inertials`` block (:func:`inertials_of`).
    """
    return has_inertials(model) and not inertials_of(model)[0].any()


def gravity_torques(
    model: RobotModel,
    q: np.ndarray,
    masses: np.ndarray | None = None,
    coms: np.ndarray | None = None,
    g: np.ndarray = GRAVITY,
) -> np.ndarray:
    """Joint torques that hold the arm still against gravity (MuJoCo's ``qfrc_bias`` at rest).

    ``tau_i = -(z_i x (S_i - M_i o_i)) . g`` with ``M_i``, ``S_i`` the mass and first moment of
    everything joint ``i`` carries, ``z_i``, ``o_i`` its axis and a point on it (world frame).

    Args:
        model: the robot (either DH convention; base placement included).
        q: (N, n) or (n,) angles of the geometric chain [rad], taken as given: no joint scale or compliance is
            applied, and no :class:`~.kinematics.JointAngleError` check is made.
        masses, coms: (n+1,) [kg] and (n+1, 3) [m] as :func:`inertials_of` returns them (read from
            ``model.extras`` when either is None).
        g: (3,) gravity in the world frame [m/s^2].

    Returns:
        (N, n), or (n,) for one configuration: torques [Nm], ``tau = dV/dq`` of the potential energy ``V``.

    Raises:
        InertialsError: ``masses`` or ``coms`` not given and ``model`` has no valid ``inertials`` block.
        ShapeError: ``q`` not of shape (N, n) or (n,) (a ``ValueError`` too).
    """
    if masses is None or coms is None:
        masses, coms = inertials_of(model)
    q, single = as_batch(model, q)
    f = frames(model, q)  # axes and origins (n+1, 3, N): the rotations, not whole 4 x 4 poses
    rotations = np.stack([f.x, f.y, f.z], axis=-1).transpose(2, 0, 1, 3)  # (N, n+1, 3, 3), columns x y z
    origins = f.origin.transpose(2, 0, 1)  # (N, n+1, 3)
    n = model.n_joints
    rot, origin = rotations[:, 1:], origins[:, 1:]  # frames 1..n
    body_frame = np.minimum(np.arange(n + 1), n - 1)  # link i in frame i+1, the payload in frame n
    centres = np.einsum("nbij,bj->nbi", rot[:, body_frame], coms) + origin[:, body_frame]  # (N, n+1, 3)
    weighted = masses[None, :, None] * centres
    first_moment = np.cumsum(weighted[:, ::-1], axis=1)[:, ::-1][:, :n]  # S_i: bodies i..n
    carried = np.cumsum(masses[::-1])[::-1][:n]  # M_i
    if model.convention == "modified":  # joint i turns about z of frame i
        axis, point = rot[:, :, :, 2], origin
    else:  # about z of frame i-1
        axis, point = rotations[:, :-1, :, 2], origins[:, :-1]
    lever = first_moment - carried[None, :, None] * point
    tau = -np.einsum("nij,j->ni", np.cross(axis, lever), np.asarray(g, dtype=float))
    return tau[0] if single else tau
