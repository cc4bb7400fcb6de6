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


#: An iiwa14-like 7-joint arm (modified DH, KUKA's link lengths and limits), built inline: no Panda, no download.
IIWA = RobotModel(
    name="iiwa14_like",
    convention="modified",
    a=np.zeros(7),
    alpha=[0.0, -HALF_PI, HALF_PI, HALF_PI, -HALF_PI, -HALF_PI, HALF_PI],
    d=[0.36, 0.0, 0.42, 0.0, 0.4, 0.0, 0.0],
    theta=np.zeros(7),
    lower=np.deg2rad([-170, -120, -170, -120, -170, -120, -175]),
    upper=np.deg2rad([170, 120, 170, 120, 170, 120, 175]),
    tool=[0.0, 0.0, 0.126],
)


def _smallest_singular_value(model: RobotModel, q: np.ndarray, step: float = 1e-6) -> float:
    """The tool point's Jacobian by central differences (not correction's), its smallest singular value [m/rad]."""
    columns = [(tool_point(model, q + step * e) - tool_point(model, q - step * e)) / (2 * step)
               for e in np.eye(model.n_joints)]
    return float(np.linalg.svd(np.array(columns).T, compute_uv=False)[-1])


def test_a_seven_joint_arm_that_is_no_panda_starts_from_its_own_pose_and_self_moves_from_it(panda) -> None:
    """A controls review: every 7-joint arm started its reach IK at the Panda's ready pose (an iiwa14 too), and every
    other arm at the middle of its ranges (an iiwa14's zeros: stretched straight up, a singular posture). The start is
    the Panda's for an arm whose chain is the Panda's only; another arm's is found in its own limits, away from a
    singularity, and the null-space controller runs from it (self-motion on the tool point, no fallback)."""
    from spherecal.controller.home import HOME, derived_home, home, is_panda
    from spherecal.controller.nullspace import NullSpaceController
    from spherecal.correction import load_robot

    assert not is_panda(IIWA) and is_panda(panda) and is_panda(perturb(panda, np.random.default_rng(0)))
    assert is_panda(load_robot("fr3"))  # the Panda's chain, other limits: the same ready pose
    np.testing.assert_array_equal(home(panda), HOME)
    start = home(IIWA)
    np.testing.assert_array_equal(start, derived_home(IIWA))  # deterministic
    assert np.all(IIWA.within_limits(start[None])) and np.abs(start - HOME).max() > 0.1
    middle = 0.5 * (IIWA.lower + IIWA.upper)
    assert _smallest_singular_value(IIWA, middle) < 1e-9 < 0.1 < _smallest_singular_value(IIWA, start)
    assert tool_point(IIWA, start)[2] > 0.0  # above the table
    controller = NullSpaceController(IIWA)
    target = tool_point(IIWA, start)
    q, q_r = start.copy(), np.array([0.6, -0.4, 0.5, 0.3, -0.5, 0.4, 0.6])
    for _ in range(1500):
        q = q + 1e-3 * controller.step(q, q_r, target)
    assert np.linalg.norm(tool_point(IIWA, q) - target) < 1e-5 and controller.report.fallbacks == 0
    assert np.abs(q - start).max() > 0.2 and np.all(IIWA.within_limits(q[None]))


def test_the_iiwa_like_arm_reaches_and_holds_a_fixture_from_its_derived_start() -> None:
    from spherecal.controller.self_motion import SelfMotionSettings, collect_self_motion

    rng = np.random.default_rng(0)
    true = perturb(IIWA, rng)
    fixture = {"P1": np.array([0.5, 0.1, 0.45])}
    run = collect_self_motion(true, IIWA, fixture, rng, SelfMotionSettings(seconds=1.0, samples=100))
    assert run.q.shape == (100, 7) and np.all(true.within_limits(run.q)) and run.fallbacks == 0
    assert np.linalg.norm(tool_point(true, run.q) - fixture["P1"], axis=1).max() < 5e-5


def test_the_base_column_is_as_thick_as_the_arm_is_long(panda) -> None:
    """BASE_RADIUS (0.12 m) was every arm's; it now scales with the chain's length, the Panda's unchanged."""
    from dataclasses import replace

    import pytest

    from spherecal.controller.reach import (
        BASE_RADIUS,
        PANDA_CHAIN_LENGTH,
        FixtureInsideRobotError,
        base_radius,
        check_fixture,
    )

    assert PANDA_CHAIN_LENGTH == pytest.approx(panda.chain_length, abs=1e-12)
    assert base_radius(panda) == pytest.approx(BASE_RADIUS, abs=1e-12)
    assert base_radius(IIWA) == pytest.approx(0.12 * 1.18 / 1.286)
    half = replace(panda, a=0.5 * panda.a, d=0.5 * panda.d, tool=0.5 * panda.tool)
    assert base_radius(half) == pytest.approx(0.06)
    point = np.array([0.08, 0.0, 0.1])  # 80 mm from the column of either
    with pytest.raises(FixtureInsideRobotError, match=r"80 mm from the base column, need >= 120 mm"):
        check_fixture(panda, "P1", point)
    check_fixture(half, "P1", point)
    with pytest.raises(FixtureInsideRobotError, match=r"need >= 60 mm"):
        check_fixture(half, "P1", np.array([0.05, 0.0, 0.1]))
