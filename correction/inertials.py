"""Link inertials for a model that has none: carried over from another description of the same arm.

Gravity torques (:mod:`.gravity`) need each link's mass and centre of mass in its DH frame. A URDF
without ``<inertial>`` elements (MUKCa's ``panda.urdf``, ``iiwa14.urdf``) gives none; a published
description of the same arm (the embedded Panda, FR3, iiwa14, Gen3 lite) does, but in its own DH frames.
:func:`transfer_inertials` checks that the two models describe the same joint axes and moves every
centre of mass into the other model's frames::

    com_user_i = inv(F_user_i(0)) F_donor_i(0) com_donor_i

with ``F_i(0)`` the world pose of link ``i``'s frame at zero angles (both frames are fixed on link ``i``,
so the transform between them does not depend on the angles once the joint axes coincide); an inertia tensor
about the centre of mass turns with the frame. :func:`link_inertias` gives every body's mass, centre of mass and
tensor, as the URDF and MJCF exports write them.
"""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np

from .chain import link_frames
from .gravity import inertials_of
from .inertia import rotated, six_of, sphere, tensor
from .model import RobotModel

#: Largest distance between corresponding joint axes [m] for two models to be the same arm (the URDFs
#: of one arm differ by fractions of a millimetre, e.g. the iiwa14's 0.44 mm joint-2 offset in one of them).
AXIS_DISTANCE_TOL = 2e-3
#: Largest angle between corresponding joint axes [rad] (0.57 deg).
AXIS_ANGLE_TOL = 1e-2
#: Joint angles [rad] at which the axes are compared (zero and two postures away from it).
_PROBES = (0.0, 0.4, -0.7)


def _placed(model: RobotModel, ignore_base: bool) -> RobotModel:
    return replace(model, base_xyz=np.zeros(3), base_rpy=np.zeros(3)) if ignore_base else model


def _axis_lines(model: RobotModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3) unit directions and (n, 3) points of the joint axes in the world frame of ``model`` [m]."""
    poses = link_frames(model, q)
    frames = poses[1:] if model.convention == "modified" else poses[:-1]
    return frames[:, :3, 2], frames[:, :3, 3]


def axis_mismatch(model: RobotModel, donor: RobotModel, ignore_base: bool = True) -> tuple[float, float]:
    """Largest distance [m] and angle [rad] between corresponding joint axes of two models.

    Compared at zero angles and two other postures; with ``ignore_base`` in each model's own base frame (the
    base placement is where the arm stands, not the arm), else in the world. Joint counts must be equal
    (else ``ValueError``). An axis and its reverse are pi apart.

    Args:
        model, donor: two models of the same joint count, either convention.
        ignore_base: compare in the base frames (True) or in the world (False).

    Returns:
        ``(distance [m], angle [rad])``, the largest over joints and postures.
    """
    distance, angle = 0.0, 0.0
    model, donor = _placed(model, ignore_base), _placed(donor, ignore_base)
    for value in _PROBES:
        q = np.full(model.n_joints, value)
        z_user, p_user = _axis_lines(model, q)
        z_donor, p_donor = _axis_lines(donor, q)
        cos = np.clip(np.sum(z_user * z_donor, axis=1), -1.0, 1.0)
        angle = max(angle, float(np.max(np.arccos(cos))))
        gap = p_donor - p_user  # distance of each donor point from the user's line, and back
        off_user = np.linalg.norm(gap - np.sum(gap * z_user, axis=1)[:, None] * z_user, axis=1)
        off_donor = np.linalg.norm(gap - np.sum(gap * z_donor, axis=1)[:, None] * z_donor, axis=1)
        distance = max(distance, float(np.max(np.maximum(off_user, off_donor))))
    return distance, angle


def transfer_inertials(model: RobotModel, donor: RobotModel, distance_tol: float = AXIS_DISTANCE_TOL,
                       angle_tol: float = AXIS_ANGLE_TOL, ignore_base: bool = True) -> RobotModel | None:
    """``model`` with ``donor``'s link inertials and payload, moved into ``model``'s DH frames.

    Args:
        model: the arm without (or with other) inertials.
        donor: a description of the same arm with an ``inertials`` block (any DH convention and frames).
        distance_tol, angle_tol: largest joint-axis distance [m] and angle [rad] (:func:`axis_mismatch`).
        ignore_base: compare the arms in their own base frames (another description of the arm), else in the
            world (the same arm described another way, e.g. in the other DH convention).

    Returns:
        The model with ``extras["inertials"]`` and ``extras["payload"]`` (masses [kg], centres of mass [m]
        in the model's DH frame ``i``, the payload in frame ``n``), or None when the joint counts differ or
        the joint axes do not coincide (another arm, or joint directions reversed).

    Raises:
        InertialsError: ``donor`` has no valid ``inertials`` block.
    """
    if model.n_joints != donor.n_joints:
        return None
    distance, angle = axis_mismatch(model, donor, ignore_base)
    if distance > distance_tol or angle > angle_tol:
        return None
    masses, coms = inertials_of(donor)
    zero = np.zeros(model.n_joints)
    mine = link_frames(_placed(model, ignore_base), zero)[1:]  # (n, 4, 4): frame i of link i
    theirs = link_frames(_placed(donor, ignore_base), zero)[1:]
    frame = np.append(np.arange(model.n_joints), model.n_joints - 1)  # the payload rides on link n
    entries = [*donor.extras["inertials"], donor.extras.get("payload") or {}]
    moved = []
    for f, m, c, entry in zip(frame, masses, coms, entries, strict=True):
        turn = np.linalg.solve(mine[f], theirs[f])  # the donor's frame in this model's
        out = {"mass": float(m), "com": [float(v) for v in turn[:3, :3] @ c + turn[:3, 3]]}
        if "inertia" in entry:  # the tensor turns with the frame (about the centre: no shift)
            out["inertia"] = six_of(rotated(tensor(np.asarray(entry["inertia"], dtype=float)), turn[:3, :3]))
        moved.append(out)
    extras = {**model.extras, "inertials": moved[:-1], "payload": moved[-1]}
    return replace(model, extras=extras)


class LinkInertias(NamedTuple):
    """Every body of the arm as a dynamics stack needs it (:func:`link_inertias`): links 1..n, then the payload."""

    #: (n+1,) masses [kg].
    masses: np.ndarray
    #: (n+1, 3) centres of mass [m], link ``i`` in DH frame ``i``, the payload in frame ``n``.
    coms: np.ndarray
    #: (n+1, 3, 3) inertia about each centre of mass, in the axes of the same frame [kg m^2].
    tensors: np.ndarray
    #: (n+1,) bool: no tensor given, a uniform sphere stands in (:func:`correction.inertia.sphere`).
    estimated: np.ndarray


def link_inertias(model: RobotModel) -> LinkInertias:
    """Masses, centres of mass and inertia tensors of ``model``'s links and payload.

    A body with a mass but no ``inertia`` in its entry gets a uniform solid sphere of radius
    :data:`correction.inertia.ESTIMATE_RADIUS` (gravity is exact without it; accelerations are not), flagged in
    ``estimated``.

    Returns:
        :class:`LinkInertias` of n+1 bodies (links 1..n, then the payload; 0 kg when there is none).

    Raises:
        InertialsError: no ``inertials`` block, or a malformed entry (:func:`correction.gravity.inertials_of`).
    """
    masses, coms = inertials_of(model)
    entries = [*model.extras["inertials"], model.extras.get("payload") or {}]
    tensors = np.zeros((len(masses), 3, 3))
    estimated = np.zeros(len(masses), dtype=bool)
    for k, (mass, entry) in enumerate(zip(masses, entries, strict=True)):
        if "inertia" in entry:
            tensors[k] = tensor(np.asarray(entry["inertia"], dtype=float))
        elif mass > 0:
            tensors[k], estimated[k] = sphere(mass), True
    return LinkInertias(masses, coms, tensors, estimated)
