"""The start posture of the reach IK: the Panda's ready pose on a Panda, a well-conditioned pose found in the limits
on any other arm. Kinematics alone (no MuJoCo)."""

from __future__ import annotations

import numpy as np

from spherecal.correction import RobotModel, joint_jacobian, tool_point
from spherecal.correction.files.robots import reference_robot
from spherecal.correction.inertials import axis_mismatch

#: The Panda's "ready" pose [rad] (franka_ros; the FR3, whose chain is the Panda's, shares it).
HOME = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])
#: Largest distance [m] and angle [rad] between corresponding joint axes (:func:`correction.inertials.axis_mismatch`)
#: of an arm taken for the embedded Panda. Looser than the inertials' 2 mm and 0.01 rad: a simulation's true Panda
#: (1 mm and 0.2 deg per parameter) is up to 17 mm and 0.03 rad off over 200 seeds; another 7-joint arm is decimetres
#: off (an iiwa14: 0.18 m, and an axis reversed).
PANDA_AXIS_DISTANCE = 0.05
PANDA_AXIS_ANGLE = 0.1
#: Candidate postures of the search on another arm (:func:`derived_home`), drawn once with this seed.
CANDIDATES, CANDIDATE_SEED = 256, 0
#: Share of each joint's range, about its middle, the candidates are drawn from (away from the limits).
CANDIDATE_SPAN = 0.5


def is_panda(model: RobotModel) -> bool:
    """Whether ``model``'s chain is the embedded Panda's: 7 joints whose axes lie within :data:`PANDA_AXIS_DISTANCE`
    and :data:`PANDA_AXIS_ANGLE` of the Panda's (in their base frames, either DH convention), as the embedded arm
    whose inertials a chain takes is matched (:func:`correction.files.robots.embedded_inertials`)."""
    panda = reference_robot("panda")
    if model.n_joints != panda.n_joints:
        return False
    distance, angle = axis_mismatch(model, panda)
    return distance <= PANDA_AXIS_DISTANCE and angle <= PANDA_AXIS_ANGLE


def derived_home(model: RobotModel) -> np.ndarray:
    """(n,) [rad] a start posture of ``model`` from its own limits: of the middle of every joint's range and
    :data:`CANDIDATES` - 1 postures drawn (seed :data:`CANDIDATE_SEED`) in the middle :data:`CANDIDATE_SPAN` of each
    range, the one farthest from a singularity (the largest smallest singular value of the tool point's (3, n)
    Jacobian [m/rad]: the least the tool moves per radian in any direction), among those with the tool above the
    base's xy-plane (the table) when any is. Deterministic: the same model gives the same posture.

    The middle of the ranges alone is a singular posture on many arms (an iiwa14's zeros: stretched straight up; a
    UR's: stretched out), where a Gauss-Newton reach stalls and the null-space task loses a direction.
    """
    lower, upper = np.asarray(model.lower, dtype=float), np.asarray(model.upper, dtype=float)
    middle, half = 0.5 * (lower + upper), 0.5 * CANDIDATE_SPAN * (upper - lower)
    draws = np.random.default_rng(CANDIDATE_SEED).uniform(-1.0, 1.0, (CANDIDATES - 1, model.n_joints))
    candidates = np.vstack([middle, middle + draws * half])
    smallest = np.linalg.svd(joint_jacobian(model, candidates), compute_uv=False)[:, -1]
    above = (tool_point(model, candidates) - model.base_transform[:3, 3]) @ model.base_transform[:3, 2] > 0.0
    score = np.where(above, smallest, -np.inf) if above.any() else smallest
    return candidates[int(np.argmax(score))]


def home(model: RobotModel) -> np.ndarray:
    """(n,) start posture of the reach IK [rad], inside ``model``'s limits: the Panda's ready pose :data:`HOME` for
    an arm whose chain is the Panda's (:func:`is_panda`), else :func:`derived_home`."""
    start = HOME if is_panda(model) else derived_home(model)
    return np.clip(start, model.lower, model.upper)
