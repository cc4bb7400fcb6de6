"""Where a fixture cannot be: inside the robot's base column, or out of reach. Kinematics alone (no MuJoCo):
planning checks its candidates with it without loading the plant."""

from __future__ import annotations

import numpy as np

from spherecal.correction import RobotModel, frames
from spherecal.correction.errors import ShapeError, SpherecalError

#: A fixture closer than this to the Panda's base column (base to the first joint's frame) is inside the robot [m];
#: another arm's radius is this scaled by its size (:func:`base_radius`).
BASE_RADIUS = 0.12
#: :attr:`~spherecal.correction.RobotModel.chain_length` of the embedded Panda [m] (``|a|`` and ``|d|`` summed:
#: 0.333 + 0.316 + 0.0825 + 0.0825 + 0.384 + 0.088), the length :data:`BASE_RADIUS` goes with.
PANDA_CHAIN_LENGTH = 1.286
#: Share of an arm's :attr:`~spherecal.correction.RobotModel.reach` a fixture centre may lie beyond it (a fixture
#: placed for the nominal arm on a perturbed one; the reach, every link laid end to end, is already more than any
#: posture reaches).
REACH_MARGIN = 0.1


class UnreachableFixtureError(SpherecalError):
    """The tool point of the true robot cannot reach a fixture inside the joint limits.

    Attributes:
        fixture: the fixture's name (for the caller to name the file and field that placed it).
    """

    def __init__(self, message: str, fixture: str | None = None):
        super().__init__(message)
        self.fixture = fixture


class FixtureInsideRobotError(UnreachableFixtureError):
    """A fixture lies inside the robot's base column."""


def size_vs_panda(model: RobotModel) -> float:
    """How thick ``model``'s links are against the Panda's: its :attr:`~spherecal.correction.RobotModel.chain_length`
    over the Panda's (:data:`PANDA_CHAIN_LENGTH`), tool excluded (a longer tool does not thicken the arm).

    A DH model carries no link thickness, only lengths; an arm's links are about as thick for its length as the
    Panda's are for its own (they carry its payload over its reach). The Panda 1; an iiwa14 (1.18 m of chain) 0.92, a
    Kinova Gen3 lite (0.835 m) 0.65, a UR5 (1.19 m) 0.93. What scales a Panda's thickness to another arm:
    :func:`base_radius`, and the link capsules of the recordings (``validation.viewer.recording.link_radius``).
    """
    return model.chain_length / PANDA_CHAIN_LENGTH


def base_radius(model: RobotModel) -> float:
    """The radius [m] of ``model``'s base column that a fixture must keep out of: :data:`BASE_RADIUS` (the Panda's,
    0.12 m) scaled by the arm's size (:func:`size_vs_panda`). The Panda keeps 0.12 m; an iiwa14 gets 0.110 m, a
    Kinova Gen3 lite 0.078 m (its base is about 0.05 m in radius), a UR5 0.111 m.
    """
    return BASE_RADIUS * size_vs_panda(model)


def fixture_centre(name: str, centre) -> np.ndarray:
    """``centre`` as a (3,) float array [m]; :class:`~spherecal.correction.errors.ShapeError` naming fixture ``name``
    and the shape given for anything else (two numbers, a (1, 3) row, text), where numpy's reshape error named
    neither."""
    try:
        array = np.asarray(centre, dtype=float)
    except (TypeError, ValueError):
        raise ShapeError(f"fixture {name}: expected a position (3,) [m], got {centre!r}") from None
    if array.shape != (3,):
        raise ShapeError(f"fixture {name}: expected a position (3,) [m], got shape {array.shape}")
    return array


def check_fixture_distance(model: RobotModel, name: str, centre: np.ndarray) -> np.ndarray:
    """``centre`` as a (3,) float array [m] (:func:`fixture_centre`), checked: raise :class:`UnreachableFixtureError`
    if it lies farther from ``model``'s base than its
    :attr:`~spherecal.correction.RobotModel.reach` and :data:`REACH_MARGIN` of it, or is not finite: a fixture in
    millimetres (``[500, 0, 300]``), which no arm of this model reaches in any posture. Kinematics alone: the bound
    is the model's own, no IK is run.

    Raises:
        ShapeError: ``centre`` is not three numbers (:func:`fixture_centre`), naming the fixture and the shape.
        UnreachableFixtureError: out of reach, as above.
    """
    centre = fixture_centre(name, centre)
    away = float(np.linalg.norm(centre - model.base_transform[:3, 3]))
    limit = (1.0 + REACH_MARGIN) * model.reach
    if not away <= limit:  # a NaN too
        raise UnreachableFixtureError(
            f"fixture {name} at {np.round(centre, 4).tolist()} m is out of reach: {away:.4g} m from the base of "
            f"{model.name!r}, whose links and tool reach {model.reach:.3g} m at most (the unit of fixture positions "
            "is metres: millimetres given?)", name)
    return centre


def check_fixture(model: RobotModel, name: str, centre: np.ndarray) -> None:
    """Raise :class:`FixtureInsideRobotError` if ``centre`` (3,) [m] lies in the base column of ``model``.

    The base column is the segment from the base origin to the first joint's fixed point
    (modified DH: the origin of frame 1; standard DH: ``d1`` along the first axis, since
    frame 1 turns with joint 1 and carries ``a1``), thickened by :func:`base_radius`.
    """
    f = frames(model, np.zeros((1, model.n_joints)))
    a = f.origin[0, :, 0]
    b = f.origin[1, :, 0] if model.convention == "modified" else a + model.d[0] * f.z[0, :, 0]
    axis = b - a
    s = np.clip(np.dot(centre - a, axis) / max(np.dot(axis, axis), 1e-12), 0.0, 1.0)
    distance = np.linalg.norm(centre - (a + s * axis))
    radius = base_radius(model)
    if distance < radius:
        raise FixtureInsideRobotError(
            f"fixture {name} at {np.round(centre, 4).tolist()} m is inside the robot "
            f"({distance * 1e3:.0f} mm from the base column, need >= {radius * 1e3:.0f} mm)", name)
