"""Postures of an arm whose tool point reaches a point: random configurations inside the joint limits projected onto
it (:func:`identification.synthetic.project_to_point`). Kinematics alone (no MuJoCo): the plan's restricted
candidates start their window from one, the simulations' default fixtures are kept or moved by whether one exists,
the plan's recording draws the arm in one."""

from __future__ import annotations

import numpy as np

from spherecal.controller.reach import UnreachableFixtureError, check_fixture
from spherecal.correction import RobotModel
from spherecal.identification.synthetic import project_to_point

#: Random start configurations of :func:`reaches`, drawn with :data:`REACH_SEED` (the same answer every run).
REACH_SEEDS, REACH_SEED = 64, 0


def reach_configuration(
    model: RobotModel, centre: np.ndarray, rng: np.random.Generator, seeds: int = 200, freeze: bool = False
) -> np.ndarray:
    """(n,) a configuration [rad] whose tool point is on ``centre`` (3,) [m], as far from the joint limits as the
    seeds find: of ``seeds`` random configurations drawn from ``rng`` and projected onto ``centre``, the converged one
    whose joint nearest its limit is farthest from it (in shares of its range).

    Args:
        freeze: :func:`identification.synthetic.project_to_point`'s (a converged seed takes no more steps).

    Raises:
        UnreachableFixtureError (from the controller package's family): no seed reaches it inside the joint limits.
    """
    q, ok = project_to_point(model, model.random_configurations(seeds, rng), centre, freeze=freeze)
    if not ok.any():
        where = np.round(centre, 4).tolist()
        raise UnreachableFixtureError(f"no configuration inside the joint limits reaches {where} m")
    return least_cramped(model, q[ok])


def least_cramped(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """(n,) the configuration of ``q`` (K, n) [rad], K >= 1, whose joint nearest its limit is farthest from it, in
    shares of that joint's range (the first of equals)."""
    share = np.minimum(q - model.lower, model.upper - q) / (model.upper - model.lower)
    return q[np.argmax(share.min(axis=1))]


def reaches(model: RobotModel, point: np.ndarray) -> bool:
    """Whether ``point`` (3,) [m] lies outside ``model``'s base column (:func:`controller.reach.check_fixture`) and
    :func:`reach_configuration` finds a configuration reaching it from :data:`REACH_SEEDS` seeds (drawn with
    :data:`REACH_SEED`: the same answer every run). For points placed by the program, not by a user: no distance
    check, whose refusal asks about millimetres."""
    try:
        check_fixture(model, "", point)
        reach_configuration(model, point, np.random.default_rng(REACH_SEED), REACH_SEEDS, freeze=True)
    except UnreachableFixtureError:
        return False
    return True
