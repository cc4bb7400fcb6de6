"""IK with a given model: the corrected-IK mechanism on the true plant."""

from __future__ import annotations

import numpy as np

from spherecal.controller.ik import ik
from spherecal.controller.plant import build_plant
from spherecal.correction import perturb, rpy_matrix, tool_point, tool_pose

HOME = np.array([0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785])


def test_corrected_ik_lands_on_the_true_plant(panda):
    rng = np.random.default_rng(7)
    true = perturb(panda, rng)
    plant = build_plant(true)
    misses_nominal, misses_true = [], []
    for target in ([0.5, 0.2, 0.3], [0.4, -0.3, 0.5], [0.6, 0.0, 0.2]):
        nominal = ik(panda, target, HOME)
        corrected = ik(true, target, HOME)
        assert nominal.converged and corrected.converged
        misses_nominal.append(np.linalg.norm(plant.tool_points(nominal.q)[0] - target))
        misses_true.append(np.linalg.norm(plant.tool_points(corrected.q)[0] - target))
    assert min(misses_nominal) > 1e-3  # millimetres off through the nominal model
    assert max(misses_true) < 1e-6  # within a micrometre through the true model


def test_ik_with_orientation_and_limits(panda, rng):
    target_rotation = rpy_matrix([np.pi, 0.0, 0.3])
    result = ik(panda, [0.5, 0.1, 0.3], HOME, orientation=target_rotation)
    assert result.converged
    pose = tool_pose(panda, result.q)
    assert np.abs(pose[:3, 3] - [0.5, 0.1, 0.3]).max() < 1e-9
    assert np.abs(pose[:3, :3] - target_rotation).max() < 1e-8
    assert panda.within_limits(result.q)[0]


def test_ik_reports_unreachable(panda, rng):
    result = ik(panda, [1.5, 0.0, 0.3], HOME, restarts=2, rng=rng)
    assert not result.converged and result.position_error > 0.3
    assert panda.within_limits(result.q)[0]
    assert np.linalg.norm(tool_point(panda, result.q) - [1.5, 0.0, 0.3]) == np.float64(result.position_error)


def test_ik_half_turn_of_the_tool_is_not_reported_as_reached(panda):
    """A target orientation exactly 180 deg away had a zero rotation error: 'converged' at the start."""
    q0 = np.array([0.1, -0.5, 0.2, -2.0, 0.1, 1.6, 0.3])
    start = tool_pose(panda, q0)
    flip = np.diag([-1.0, -1.0, 1.0])  # half turn about the tool's z (joint 7's axis)
    for target in (start[:3, :3] @ flip, start[:3, :3] @ np.diag([1.0, -1.0, -1.0])):
        result = ik(panda, start[:3, 3], q0, orientation=target)
        reached = tool_pose(panda, result.q)[:3, :3]
        angle = np.arccos(np.clip((np.trace(target @ reached.T) - 1) / 2, -1, 1))
        assert result.converged == (angle < 1e-6), (result, angle)
    assert ik(panda, start[:3, 3], q0, orientation=start[:3, :3] @ flip).converged  # reachable: joint 7 turns
