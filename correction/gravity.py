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

import math
from typing import Any, NamedTuple

import numpy as np

from .chain import as_batch
from .errors import ShapeError, SpherecalError
from .inertia import checked_tensor
from .model import RobotModel, rpy_matrix

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
    if (parsed is not None and parsed.block is block and parsed.payload is payload
            and len(parsed.masses) == model.n_joints + 1):
        masses, coms = parsed.masses.copy(), parsed.coms.copy()  # read before: the same objects, for as many joints
    else:
        masses, coms = _parse(model, block, payload, source, rows)
        if len(_PARSED) >= PARSED_KEPT:
            _PARSED.clear()
        _PARSED[id(block)] = _Parsed(block, payload, masses.copy(), coms.copy())  # held: their ids stay theirs
    size = model.chain_length  # 0: a check of the entries alone (a robot file's block before its geometry is read)
    if size > 0 and masses.sum() > MAX_MASS_DENSITY * size**3:  # grams for kilograms, or a payload of another scale
        k = int(np.argmax(masses))
        name = "payload" if k == model.n_joints else f"inertials[{k}]"
        raise InertialsError(f"{_field(model, source, rows, name)}.mass': {masses.sum():.6g} kg in all for an arm "
                             f"of {size:.3g} m of links, not physical (at most {MAX_MASS_DENSITY * size**3:.3g} kg; "
                             f"the file is in kilograms)")
    return masses, coms


class _Parsed(NamedTuple):
    """One inertials block as :func:`inertials_of` read it (:data:`_PARSED`)."""

    #: The ``extras["inertials"]`` and ``extras["payload"]`` objects it was read from, held so that their ids stay
    #: theirs (a later model is matched by identity).
    block: Any
    payload: Any
    #: (n+1,) masses [kg] and (n+1, 3) centres of mass [m], payload last.
    masses: np.ndarray
    coms: np.ndarray


#: Inertials blocks read (:func:`inertials_of`): id -> :class:`_Parsed`. A fit reads a model's masses at every step
#: (gravity torques, a compliance's check), and every model of one fit holds the same block: checking it once saves
#: a seventh of a default calibration. The objects are held, so an id is not taken by another block; extras are not
#: changed in place (every ``with_*`` makes a copy).
_PARSED: dict[int, _Parsed] = {}
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

    Computed in each joint's own frame (its axis along z, its origin on the axis), without the world frames:
    the first moment about the joint and the mass carried, ``[S - M o; M]``, go back along the chain as a
    homogeneous point (one fixed 4 x 4 product and one turn about z per joint), gravity goes forward as a
    direction, and ``tau_i`` is minus the z component of their cross product. One configuration runs on
    Python floats (a controller's period: no array operation to pay for per joint).

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
    q, single = as_batch(model, q)
    chain, bodies, body_rows = _prepared(model, masses, coms)
    gravity = np.asarray(g, dtype=float) @ chain.base  # (3,) in the base frame
    angle = q + model.theta
    count = q.shape[0]
    if count == 1:
        tau = _torques_one(chain, angle[0].tolist(), body_rows, gravity.tolist())[None]
    elif count <= BLOCK:
        tau = _torques_batch(chain, angle, bodies, gravity)
    else:
        tau = np.concatenate([_torques_batch(chain, angle[start:start + BLOCK], bodies, gravity)
                              for start in range(0, count, BLOCK)])
    return tau[0] if single else tau


#: Configurations per block of a batch's torques: the block's arrays stay in the processor's cache, and its (N, 4) x
#: (4, 4) products stay on one BLAS thread (100 000 Panda configurations in one block took 1.5 to 16 us each, one
#: thread or two, on a loaded machine; in blocks of 2048, 0.9).
BLOCK = 2048


class _Chain(NamedTuple):
    """The fixed part of each joint's transform: frame ``i+1`` in frame ``i`` is ``F_i Rz(theta_i + q_i)`` (modified:
    ``F = Rx(alpha) Lx(a) Ry(beta) Lz(d)``, ``Lz`` commuting with ``Rz``) or ``Rz(theta_i + q_i) F_i`` (standard:
    ``F = Lz(d) Lx(a) Rx(alpha) Ry(beta)``)."""

    #: (n, 4, 4): a row ``[S, M]`` (first moment [kg m] about frame ``i+1``'s origin, in its axes, and mass [kg])
    #: times ``carry[i]`` is ``F_i [S; M]``: the same about frame ``i``'s origin (less the turn), ``M`` unchanged.
    carry: np.ndarray
    #: (n, 4, 4): a row ``[g, 0]`` times ``back[i]`` is gravity in ``F_i``'s axes (``F_i`` rotation transposed).
    back: np.ndarray
    #: (3, 3) rotation of the base in the world.
    base: np.ndarray
    #: (n, 3, 3) rotations ``Rx(alpha) Ry(beta)`` and (n, 3) translations [m] of ``F``, as nested lists of floats.
    rot_rows: list
    shift_rows: list
    #: The modified DH convention (joint ``i`` turns about z of frame ``i+1``, else of frame ``i``).
    modified: bool


class _Prepared(NamedTuple):
    """What :func:`gravity_torques` keeps of one model (:data:`_PREPARED`)."""

    #: The model, held so that its id stays its own (its geometry is read-only arrays).
    model: RobotModel
    #: Its :class:`_Chain`.
    chain: _Chain
    #: The ``extras["inertials"]`` and ``extras["payload"]`` objects ``bodies`` were read from (the loads are checked
    #: against the model's extras by identity); None with ``bodies`` before they are read.
    block: Any
    payload: Any
    #: (n+1, 4) read-only rows ``[m com, m]`` [kg m, kg] of the links and payload, and the same as nested lists of
    #: floats (:func:`_torques_one`); None until the inertials are read.
    bodies: np.ndarray | None
    rows: list | None


#: Models read by :func:`gravity_torques`: id -> :class:`_Prepared`. A controller asks for one model's torques every
#: period: kept, one configuration's torques take 10 us instead of 40 (a Panda).
_PREPARED: dict[int, _Prepared] = {}


def _prepared(model: RobotModel, masses: np.ndarray | None, coms: np.ndarray | None) -> tuple[_Chain, np.ndarray, list]:
    """``model``'s :class:`_Chain`, and the (n+1, 4) rows ``[m com, m]`` (kg m, kg) of its links and payload (of
    ``masses`` and ``coms`` when both are given), as an array and as nested lists; kept for the model's next call."""
    kept = _PREPARED.get(id(model))
    if kept is None or kept.model is not model:
        kept = _Prepared(model, _chain_of(model), None, None, None, None)
        if len(_PREPARED) >= PARSED_KEPT:
            _PREPARED.clear()
        _PREPARED[id(model)] = kept
    chain = kept.chain
    block, payload = model.extras.get("inertials"), model.extras.get("payload")
    if masses is None or coms is None:
        if kept.block is block and kept.payload is payload and kept.bodies is not None:
            return chain, kept.bodies, kept.rows
        bodies = _bodies(model, *inertials_of(model))
        rows = bodies.tolist()
        _PREPARED[id(model)] = _Prepared(model, chain, block, payload, bodies, rows)
        return chain, bodies, rows
    bodies = _bodies(model, masses, coms)
    return chain, bodies, bodies.tolist()


def _bodies(model: RobotModel, masses: np.ndarray, coms: np.ndarray) -> np.ndarray:
    """(n+1, 4) read-only rows ``[m com, m]`` [kg m, kg] of ``masses`` (n+1,) [kg] and ``coms`` (n+1, 3) [m].

    Raises:
        ShapeError: ``masses`` or ``coms`` of another shape.
    """
    masses, coms = np.asarray(masses, dtype=float), np.asarray(coms, dtype=float)
    n = model.n_joints
    if masses.shape != (n + 1,) or coms.shape != (n + 1, 3):
        raise ShapeError(f"masses and coms must have shapes ({n + 1},) and ({n + 1}, 3) for {model.name}'s {n} "
                         f"links and payload, got {masses.shape} and {coms.shape}")
    bodies = np.concatenate([masses[:, None] * coms, masses[:, None]], axis=1)
    bodies.setflags(write=False)
    return bodies


def _chain_of(model: RobotModel) -> _Chain:
    """The :class:`_Chain` of ``model``."""
    n = model.n_joints
    ca, sa, cb, sb = np.cos(model.alpha), np.sin(model.alpha), np.cos(model.beta), np.sin(model.beta)
    rot = np.stack([cb, np.zeros(n), sb, sa * sb, ca, -sa * cb, -ca * sb, sa, ca * cb], axis=1).reshape(n, 3, 3)
    modified = model.convention == "modified"
    if modified:  # Rx Lx(a) Ry Lz(d): a along x, d along the turned z
        shift = model.d[:, None] * rot[:, :, 2]
        shift[:, 0] += model.a
    else:  # Lz(d) Lx(a) Rx Ry
        shift = np.stack([model.a, np.zeros(n), model.d], axis=1)
    carry = np.zeros((n, 4, 4))
    carry[:, :3, :3] = rot.transpose(0, 2, 1)
    carry[:, 3, :3] = shift
    carry[:, 3, 3] = 1.0
    back = np.zeros((n, 4, 4))
    back[:, :3, :3] = rot
    base = rpy_matrix(model.base_rpy)
    for kept in (carry, back, base):
        kept.setflags(write=False)
    return _Chain(carry, back, base, rot.tolist(), shift.tolist(), modified)


def _torques_batch(chain: _Chain, angle: np.ndarray, bodies: np.ndarray, gravity: np.ndarray) -> np.ndarray:
    """(N, n) torques [Nm] of :func:`gravity_torques` at ``angle`` (N, n) [rad] (link angles plus ``theta``), N at
    once, ``bodies`` (n+1, 4) and ``gravity`` (3,) in the base frame as :func:`gravity_torques` makes them.

    Vectors are rows ``[x, y, z, w]``, viewed as two complex numbers ``x + iy``, ``z + iw``: a turn about z is one
    product by ``exp(i angle)``.
    """
    count, n = angle.shape
    angle = np.ascontiguousarray(angle.T)  # (n, N): a joint's angles side by side
    turn = np.empty((n, count), dtype=complex)  # exp(i angle): cheaper than np.exp of complex numbers
    turn.real, turn.imag = np.cos(angle), np.sin(angle)
    unturn = turn.conj()
    down = np.empty((n, count), dtype=complex)  # gravity's x + iy in joint i's frame (z its axis)
    held = np.empty((n, count), dtype=complex)  # the first moment's x + iy about joint i, in the same frame
    along = np.zeros((count, 4))
    along[:, :3] = gravity
    for i in range(n):
        if chain.modified:  # joint i turns about z of frame i+1
            along = along @ chain.back[i]
            along.view(complex)[:, 0] *= unturn[i]
            down[i] = along.view(complex)[:, 0]
        else:  # about z of frame i, turned by its angle
            along.view(complex)[:, 0] *= unturn[i]
            down[i] = along.view(complex)[:, 0]
            along = along @ chain.back[i]
    moment = np.empty((count, 4))
    moment[:] = bodies[n - 1] + bodies[n]  # the last link and the payload, about frame n's origin
    for i in range(n - 1, -1, -1):
        if chain.modified:
            held[i] = moment.view(complex)[:, 0]
            moment.view(complex)[:, 0] *= turn[i]
            moment = moment @ chain.carry[i]
        else:
            moment = moment @ chain.carry[i]
            held[i] = moment.view(complex)[:, 0]
            moment.view(complex)[:, 0] *= turn[i]
        if i > 0:
            moment += bodies[i - 1]
    return np.ascontiguousarray(-(held.conj() * down).imag.T)  # -(S x g)_z = -(S_x g_y - S_y g_x)


def _torques_one(chain: _Chain, angle: list, bodies: list, gravity: list) -> np.ndarray:
    """(n,) torques [Nm] of :func:`gravity_torques` at one configuration, on Python floats (arguments as
    :func:`_torques_batch`'s, ``angle`` (n,), as lists)."""
    n, modified = len(angle), chain.modified
    cos_q, sin_q = [math.cos(v) for v in angle], [math.sin(v) for v in angle]
    down = []
    gx, gy, gz = gravity
    for i in range(n):
        (r0, r1, r2), (r3, r4, r5), (r6, r7, r8) = chain.rot_rows[i]
        c, s = cos_q[i], sin_q[i]
        if modified:
            gx, gy, gz = r0 * gx + r3 * gy + r6 * gz, r1 * gx + r4 * gy + r7 * gz, r2 * gx + r5 * gy + r8 * gz
            gx, gy = c * gx + s * gy, c * gy - s * gx
            down.append((gx, gy))
        else:
            gx, gy = c * gx + s * gy, c * gy - s * gx
            down.append((gx, gy))
            gx, gy, gz = r0 * gx + r3 * gy + r6 * gz, r1 * gx + r4 * gy + r7 * gz, r2 * gx + r5 * gy + r8 * gz
    tau = [0.0] * n
    sx, sy, sz, w = (u + v for u, v in zip(bodies[n - 1], bodies[n], strict=True))
    for i in range(n - 1, -1, -1):
        (r0, r1, r2), (r3, r4, r5), (r6, r7, r8) = chain.rot_rows[i]
        tx, ty, tz = chain.shift_rows[i]
        c, s = cos_q[i], sin_q[i]
        if modified:
            tau[i] = sy * down[i][0] - sx * down[i][1]
            sx, sy = c * sx - s * sy, s * sx + c * sy
        sx, sy, sz = (r0 * sx + r1 * sy + r2 * sz + w * tx, r3 * sx + r4 * sy + r5 * sz + w * ty,
                      r6 * sx + r7 * sy + r8 * sz + w * tz)
        if not modified:
            tau[i] = sy * down[i][0] - sx * down[i][1]
            sx, sy = c * sx - s * sy, s * sx + c * sy
        if i > 0:
            bx, by, bz, bw = bodies[i - 1]
            sx, sy, sz, w = sx + bx, sy + by, sz + bz, w + bw
    return np.array(tau)
