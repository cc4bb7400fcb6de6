"""Any serial DH arm, not only the Panda: a 6-joint standard-DH arm through simulate and calibrate."""

from __future__ import annotations

import numpy as np

from spherecal.correction import RobotModel, perturb, registered_errors, tool_point
from spherecal.identification.calibrate import calibrate
from spherecal.identification.synthetic import make_dataset

HALF_PI = np.pi / 2
#: A UR5-like arm (standard DH), with a tool point off the last axis.
UR5 = RobotModel(
    name="ur5",
    convention="standard",
    a=[0.0, -0.425, -0.39225, 0.0, 0.0, 0.0],
    alpha=[HALF_PI, 0.0, 0.0, HALF_PI, -HALF_PI, 0.0],
    d=[0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823],
    theta=np.zeros(6),
    lower=[-6.28, -6.28, -3.14, -6.28, -6.28, -6.28],
    upper=[6.28, 6.28, 3.14, 6.28, 6.28, 6.28],
    tool=[0.0, 0.05, 0.1],
)


def test_six_joint_arm_self_motion_stays_on_its_fixture() -> None:
    from spherecal.controller.self_motion import SelfMotionSettings, collect_self_motion

    rng = np.random.default_rng(0)
    true = perturb(UR5, rng)
    fixture = {"P1": np.array([0.45, 0.2, 0.3])}
    run = collect_self_motion(true, UR5, fixture, rng, SelfMotionSettings(seconds=1.0, samples=100))
    assert run.q.shape == (100, 6)
    assert np.all(true.within_limits(run.q))
    deviation = np.linalg.norm(tool_point(true, run.q) - fixture["P1"], axis=1)
    assert deviation.max() < 5e-5


def test_six_joint_arm_calibrates() -> None:
    true = perturb(UR5, np.random.default_rng(1))
    centres = {"P1": (0.45, 0.2, 0.3), "P2": (0.3, -0.4, 0.2), "P3": (-0.2, 0.45, 0.4)}
    dataset, spec = make_dataset(true, centres, per_fixture=300, rng=np.random.default_rng(2))
    result = calibrate(UR5, dataset, spec)
    q = true.random_configurations(2000, np.random.default_rng(3))
    calibrated = registered_errors(tool_point(result.model, q), tool_point(true, q))
    nominal = registered_errors(tool_point(UR5, q), tool_point(true, q))
    assert calibrated.mean() < 1e-6 < nominal.mean()
    # the parallel shoulder-elbow-wrist axes leave d2, d3 (only their sum with d4 counts) unidentified
    assert {"d1", "theta1"} <= set(result.fixed)
    assert sum(name in result.fixed for name in ("d2", "d3", "d4")) >= 2


def test_base_column_of_a_standard_arm_with_a_shoulder_offset_is_vertical() -> None:
    """Standard DH: frame 1 turns with joint 1, so with a1 != 0 its origin is off the base column."""
    from dataclasses import replace

    import pytest

    from spherecal.controller.reach import FixtureInsideRobotError, check_fixture

    arm = replace(UR5, a=[0.3, -0.425, -0.39225, 0.0, 0.0, 0.0])  # an industrial arm's shoulder offset
    check_fixture(arm, "P1", np.array([0.3, 0.0, 0.2]))  # 0.3 m from the column: was refused
    for centre in ([0.0, 0.05, 0.05], [0.0, -0.05, 0.08]):
        with pytest.raises(FixtureInsideRobotError):
            check_fixture(arm, "P2", np.array(centre))


def test_locked_joint_is_held_and_the_others_explore(panda) -> None:
    """lower == upper (a joint locked for the campaign) crashed the reach IK and made the QP infeasible."""
    from dataclasses import replace

    from spherecal.controller.self_motion import SelfMotionSettings, collect_self_motion

    lower, upper = panda.lower.copy(), panda.upper.copy()
    lower[6] = upper[6] = 0.0
    arm = replace(panda, lower=lower, upper=upper)
    run = collect_self_motion(arm, arm, {"P1": np.array([0.5, 0.0, 0.4])}, np.random.default_rng(0),
                              SelfMotionSettings(seconds=1.5, samples=50))
    assert np.abs(run.trajectory_q[:, 6]).max() < 1e-3
    assert run.coverage[0, 6] == 0.0 and run.coverage[0, :6].max() > 0.05
    assert run.max_violation.max() < 5e-4
