"""Cartesian compensation and corrected IK: fixed point, orientation, named errors."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from spherecal.controller.compensation import (
    CompensationError,
    ModelMismatchError,
    compensate,
    corrected_ik,
    nominal_ik_controller,
)
from spherecal.controller.ik import UnreachableError
from spherecal.correction import RobotModel, load_robot, perturb, to_standard, tool_point, tool_pose
from spherecal.correction.errors import ShapeError, SpherecalError


@pytest.fixture
def robots(panda, rng):
    true = perturb(panda, rng)
    return panda, true, rng


def _case(model, rng, inset=0.1, spread=0.3):
    q_goal = rng.uniform(model.lower + inset, model.upper - inset)
    q_seed = np.clip(q_goal + rng.normal(0.0, spread, model.n_joints), model.lower + inset, model.upper - inset)
    return q_goal, q_seed


def test_compensated_command_lands_the_calibrated_arm_on_target(robots):
    nominal, calibrated, rng = robots
    for _ in range(10):
        q_goal, q_seed = _case(calibrated, rng)
        target = tool_point(calibrated, q_goal)
        result = compensate(target, nominal, calibrated, q_seed)
        # Independent of the result's own bookkeeping: run the nominal controller on the command.
        q = nominal_ik_controller(nominal, result.command, q_seed)
        assert np.linalg.norm(tool_point(calibrated, q) - target) < 1e-9
        assert np.linalg.norm(tool_point(nominal, q) - result.command) < 1e-9  # nominal reaches its command
        assert np.linalg.norm(result.command - target) > 1e-3  # and the command is millimetres off target
        assert 2 <= result.iterations <= 12 and result.history[0] > 1e-3 > 1e-9 > result.history[-1]
        assert np.all(np.diff(np.log(result.history)) < 0)  # contracts every iteration
        np.testing.assert_allclose(result.landing, tool_point(calibrated, result.q), atol=0)


def test_identical_models_need_no_iteration(robots):
    nominal, _, rng = robots
    q_goal, q_seed = _case(nominal, rng)
    target = tool_point(nominal, q_goal)
    result = compensate(target, nominal, nominal, q_seed)
    assert result.iterations == 0 and np.array_equal(result.command, target)


def test_orientation_is_compensated_too(robots):
    nominal, calibrated, rng = robots
    q_goal, q_seed = _case(calibrated, rng, spread=0.1)
    pose = tool_pose(calibrated, q_goal)
    result = compensate(pose[:3, 3], nominal, calibrated, q_seed, orientation=pose[:3, :3])
    q = nominal_ik_controller(nominal, result.command, q_seed, result.command_orientation)
    reached = tool_pose(calibrated, q)
    assert np.linalg.norm(reached[:3, 3] - pose[:3, 3]) < 1e-9
    assert np.abs(reached[:3, :3] - pose[:3, :3]).max() < 1e-8
    nominal_rotation = tool_pose(nominal, q)[:3, :3]
    assert np.abs(nominal_rotation - result.command_orientation).max() < 1e-8  # the controller meets its command
    assert np.abs(result.command_orientation - pose[:3, :3]).max() > 1e-4  # which differs from the target


def test_works_for_the_standard_convention_and_a_custom_controller(robots):
    nominal, calibrated, rng = robots
    nominal, calibrated = to_standard(nominal), to_standard(calibrated)
    calls = []

    def controller(model, target, q_seed, orientation):
        calls.append(model)
        return nominal_ik_controller(model, target, q_seed, orientation)

    q_goal, q_seed = _case(calibrated, rng)
    target = tool_point(calibrated, q_goal)
    result = compensate(target, nominal, calibrated, q_seed, controller=controller)
    assert result.position_residual < 1e-9 and all(model is nominal for model in calls)
    assert len(calls) == result.iterations + 1


def test_corrected_ik_puts_the_calibrated_tool_point_on_target(robots):
    nominal, calibrated, rng = robots
    q_goal, q_seed = _case(calibrated, rng)
    target = tool_point(calibrated, q_goal)
    q = corrected_ik(calibrated, target, q_seed, nominal=nominal)
    assert np.linalg.norm(tool_point(calibrated, q) - target) < 1e-9
    assert calibrated.within_limits(q)


def _one_line(error: pytest.ExceptionInfo) -> str:
    message = str(error.value)
    assert "\n" not in message and isinstance(error.value, SpherecalError)
    return message


def test_unreachable_target_raises(robots):
    nominal, calibrated, rng = robots
    _, q_seed = _case(nominal, rng)
    far = np.array([1.5, 0.0, 0.5])  # the Panda reaches about 0.86 m from the shoulder
    with pytest.raises(UnreachableError) as error:
        compensate(far, nominal, calibrated, q_seed)
    assert "out of reach" in _one_line(error)
    with pytest.raises(UnreachableError):
        corrected_ik(calibrated, far, q_seed)


def test_a_file_of_another_robot_raises(robots, panda):
    nominal, calibrated, rng = robots
    q_goal, q_seed = _case(nominal, rng)
    target = tool_point(calibrated, q_goal)
    six = RobotModel(name="six", convention="modified", a=panda.a[:6], alpha=panda.alpha[:6], d=panda.d[:6],
                     theta=panda.theta[:6], lower=panda.lower[:6], upper=panda.upper[:6], tool=panda.tool)
    cases = {
        "6 joints": six,
        "field convention: 'standard'": to_standard(calibrated),
        "joints[3].upper": replace(calibrated, upper=calibrated.upper + np.eye(7)[3] * 0.1),
        "not a calibration of this robot": perturb(nominal, rng, 0.05, 0.05, 0.05),
    }
    for fragment, other in cases.items():
        with pytest.raises(ModelMismatchError) as error:
            compensate(target, nominal, other, q_seed)
        assert fragment in _one_line(error), fragment
    with pytest.raises(ModelMismatchError, match="6 joints"):
        corrected_ik(six, target, q_seed[:6], nominal=nominal)
    # a seed of the wrong shape is not a model mismatch (the models match): ShapeError, a ValueError too, naming the
    # argument and the shape, in compensate and corrected_ik alike (was ModelMismatchError)
    with pytest.raises(ShapeError, match=r"^q_seed: expected 7 joint angles, got shape \(6,\)$") as error:
        compensate(target, nominal, calibrated, q_seed[:6])
    assert not isinstance(error.value, ModelMismatchError) and isinstance(error.value, ValueError)
    with pytest.raises(ShapeError, match=r"^q0: expected 7 joint angles, got shape \(1, 7\)$") as error:
        corrected_ik(calibrated, target, q_seed[None], nominal=nominal)
    assert not isinstance(error.value, ModelMismatchError)
    with pytest.raises(SpherecalError, match="target"):
        compensate(np.array([0.3, np.nan, 0.5]), nominal, calibrated, q_seed)


def test_no_convergence_is_an_error_not_a_silent_command(robots):
    nominal, calibrated, rng = robots
    q_goal, q_seed = _case(calibrated, rng)
    with pytest.raises(CompensationError) as error:
        compensate(tool_point(calibrated, q_goal), nominal, calibrated, q_seed, max_iter=1)
    assert "after 1 evaluations" in _one_line(error)


def test_a_controller_whose_posture_jumps_is_named_and_best_effort_is_flagged(robots):
    """A controller choosing between two postures by the sign of a command coordinate: the
    landings straddle the target, no command is exact, and that is said, never hidden."""
    nominal, calibrated, rng = robots
    q_goal, q_seed = _case(calibrated, rng, spread=0.05)
    target = tool_point(calibrated, q_goal)
    other_seed = np.clip(q_seed + np.array([0.0, 0.0, 0.6, 0.0, 0.0, 0.0, 0.0]), nominal.lower, nominal.upper)

    def branch(start):
        return lambda model, command, seed, orientation: nominal_ik_controller(model, command, start, orientation)

    # each posture's exact command lies in the other posture's half-space: no fixed point exists
    x_a = compensate(target, nominal, calibrated, q_seed, controller=branch(q_seed)).command[0]
    x_b = compensate(target, nominal, calibrated, q_seed, controller=branch(other_seed)).command[0]
    assert abs(x_a - x_b) > 1e-5

    def jumpy(model, command, seed, orientation):
        on_a_side = (command[0] - 0.5 * (x_a + x_b)) * (x_a - x_b) > 0
        return nominal_ik_controller(model, command, other_seed if on_a_side else seed, orientation)

    with pytest.raises(CompensationError) as error:
        compensate(target, nominal, calibrated, q_seed, controller=jumpy)
    assert "posture jumps" in _one_line(error)
    result = compensate(target, nominal, calibrated, q_seed, controller=jumpy, strict=False)
    assert not result.converged and "posture jumps" in result.note
    # the best effort beats the uncompensated command and is what its fields say
    assert result.position_residual < result.history[0]
    q = jumpy(nominal, result.command, q_seed, None)
    assert np.linalg.norm(tool_point(calibrated, q) - target) == pytest.approx(result.position_residual, abs=1e-12)


def test_differential_ik_flow_is_a_controller_model(robots):
    from spherecal.controller.compensation import DifferentialIKFlow

    nominal, calibrated, rng = robots
    q_goal, q_seed = _case(calibrated, rng, spread=0.1)
    target = tool_point(calibrated, q_goal)
    flow = DifferentialIKFlow()
    q = flow(nominal, target, q_seed)
    assert np.linalg.norm(tool_point(nominal, q) - target) < 1e-11 and nominal.within_limits(q)
    result = compensate(target, nominal, calibrated, q_seed, controller=flow)
    assert np.linalg.norm(tool_point(calibrated, flow(nominal, result.command, q_seed)) - target) < 1e-9
    with pytest.raises(SpherecalError, match="orientation"):
        flow(nominal, target, q_seed, np.eye(3))


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda n, c, q: corrected_ik(c, [0.5, 0.0, 0.4], 0.0, nominal=n), r"q0: .* got shape \(\)"),
        (lambda n, c, q: compensate([0.5, 0.0, 0.4], n, c, q[None]), r"q_seed: .* got shape \(1, 7\)"),
        (lambda n, c, q: corrected_ik(c, [0.5, 0.0, 0.4], q, orientation=-np.eye(3)), "orientation: .*rotation"),
        (lambda n, c, q: compensate([0.5, 0.0, 0.4], n, c, q, max_iter=-1), "max_iter"),
    ],
)
def test_bad_arguments_are_one_line_errors(robots, call, message):
    nominal, calibrated = robots[:2]
    with pytest.raises(SpherecalError, match=message):
        call(nominal, calibrated, np.array([0.1, -0.5, 0.2, -2.0, 0.1, 1.6, 0.3]))


@pytest.mark.parametrize("bad", [np.nan, np.inf, "degrees"])
def test_a_lost_joint_reading_in_the_seed_is_named_not_an_ik_from_nowhere(robots, bad):
    # a NaN seed made the IK "miss by nan mm" (UnreachableError of a reachable target); an inf one was clipped
    # to the limits and answered with RuntimeWarnings, as if the arm stood there
    nominal, calibrated, _ = robots
    q_seed = nominal.lower + 0.5 * (nominal.upper - nominal.lower)
    target = tool_point(nominal, q_seed)
    q_seed[2] = np.rad2deg(q_seed[2] + 0.1) if bad == "degrees" else bad  # 0.1 rad: 5.7 "rad", far past 2.9
    expected = "-?[0-9.]+ rad, [0-9.]+ rad outside its limits" if bad == "degrees" else rf"{bad} \(expected 7 finite"
    for call in (lambda: corrected_ik(calibrated, target, q_seed, nominal=nominal),
                 lambda: compensate(target, nominal, calibrated, q_seed)):
        with pytest.raises(SpherecalError, match=rf"q(0|_seed): joint 3 is {expected}"):
            call()


def test_corrected_ik_from_a_stretched_out_seed_reaches_a_reachable_target():
    # the Panda stretched out (q4 at its -0.07 rad limit, the rest 0) is a singular seed the Gauss-Newton steps stall
    # at, 92 mm short of a target the arm reaches: the correction tries starts near the seed and returns the nearest
    # converged configuration; a target out of the arm's reach is still refused
    panda = load_robot("panda")
    seed = np.array([0.0, 0.0, 0.0, -0.0698, 0.0, 0.0, 0.0])
    target = tool_point(panda, np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8]))
    q = corrected_ik(panda, target, seed)
    assert np.linalg.norm(tool_point(panda, q) - target) < 1e-6
    assert np.all(q >= panda.lower) and np.all(q <= panda.upper)
    with pytest.raises(UnreachableError):
        corrected_ik(panda, np.array([2.0, 0.0, 0.3]), seed)


def test_a_target_the_seeds_ik_stalls_short_of_names_what_may_reach_it() -> None:
    """From a singular seed held by a joint limit the nominal controller's model (IK from the seed, no restarts)
    stalls short of a target the arm reaches: the refusal says so and names corrected_ik (a review read 'out of reach'
    of targets corrected_ik reached to 1e-11 m)."""
    from spherecal.controller.compensation import nominal_ik_controller

    panda = load_robot("panda")
    q_seed = np.array([0.0, 0.0, 0.0, -0.0698, 0.0, 0.0, 0.0])  # stretched out, q4 at its limit: singular
    target = tool_point(panda, np.array([1.852, 0.646, 1.664, -2.497, 1.752, 0.704, -2.425]))
    reached = corrected_ik(panda, target, q_seed, nominal=panda)
    assert np.linalg.norm(tool_point(panda, reached) - target) < 1e-9
    with pytest.raises(UnreachableError, match="IK from the seed without restarts, stalls there .* corrected_ik"):
        nominal_ik_controller(panda, target, q_seed)


def test_a_target_in_millimetres_and_a_seed_in_degrees_are_named_as_such() -> None:
    """A user trial: a target given in mm ([484, 0, 412]) ended 'misses by 634888 mm' after the IK's restarts, and a
    seed in degrees raised a plain SpherecalError where tool_point raises JointAngleError."""
    from spherecal.correction import JointAngleError

    panda = load_robot("panda")
    calibrated = perturb(panda, np.random.default_rng(2))
    q = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    metres = tool_point(panda, q)
    for call in (lambda t, s: corrected_ik(calibrated, t, s), lambda t, s: compensate(t, panda, calibrated, s)):
        with pytest.raises(UnreachableError, match=r"m from the base of 'franka_panda', whose links and tool reach "
                                                   r"[\d.]+ m at most \(millimetres\? targets are in metres\)"):
            call(metres * 1e3, q)
        with pytest.raises(JointAngleError, match=r"joint 2 is -17.1887 rad.*degrees\?"):
            call(metres, np.degrees(q))
        call(metres + 0.01, q)  # a target in metres within reach: no refusal


def test_nominal_and_calibrated_passed_swapped_are_refused_when_the_records_tell(panda, tmp_path):
    """A controls review: compensate(target, calibrated, nominal) ran and returned a command corrected the wrong
    way (twice the calibration's correction off the target) with no word. A calibration written by the workflow and
    read back records the robot file's tool it started from; the robot file records nothing: that order is refused,
    in corrected_ik too. Models without records (a simulation's truth) cannot be told apart and still run."""
    from spherecal.controller.compensation import check_roles
    from spherecal.correction import save_robot
    from spherecal.identification.synthetic import make_dataset
    from spherecal.identification.workflow import WorkflowOptions, run_workflow

    true = perturb(panda, np.random.default_rng(3))
    dataset, spec = make_dataset(true, per_fixture=150, rng=np.random.default_rng(4), noise=1e-4)
    calibrated = load_robot(save_robot(run_workflow(panda, dataset, spec, WorkflowOptions()).model,
                                       tmp_path / "cal.yaml"))
    q_seed = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    target = tool_point(calibrated, q_seed + 0.05)
    right = compensate(target, panda, calibrated, q_seed)
    landing = tool_point(calibrated, nominal_ik_controller(panda, right.command, q_seed))
    assert np.linalg.norm(landing - target) < 1e-9 < 1e-3 < np.linalg.norm(right.command - target)
    for call in (lambda: compensate(target, calibrated, panda, q_seed),
                 lambda: corrected_ik(panda, target, q_seed, nominal=calibrated)):
        with pytest.raises(ModelMismatchError, match=r"nominal and calibrated swapped\? the model passed as nominal "
                                                     r"\('franka_panda'\) is a calibration of the one passed") as error:
            call()
        assert "\n" not in str(error.value)
    check_roles(panda, calibrated)  # the right order
    check_roles(calibrated, calibrated)  # a calibration against itself: its tool is not its file's
    check_roles(true, panda)  # no records: nothing tells, nothing refused
    check_roles(panda, true)
    assert compensate(target, true, panda, q_seed).converged
