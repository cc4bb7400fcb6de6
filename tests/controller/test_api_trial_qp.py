"""A controls engineer's trial of the QP differential IK (``controller.nullspace``, ``controller.qp_ik``): what it
commands from a reading outside the joint limits, checked against the velocity limit it is given."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from spherecal.controller.ik import UnreachableError
from spherecal.controller.nullspace import NullSpaceController
from spherecal.controller.qp_ik import MAX_VELOCITY, ControllerFallbackWarning, task_share, velocity_bounds
from spherecal.correction import load_robot, tool_point


@pytest.fixture(scope="module")
def panda():
    return load_robot("panda")


@pytest.mark.parametrize("beyond", [0.0, 0.05, 0.2, 1.0, 100.0])
def test_bounds_stay_ordered_and_within_the_velocity_limit(panda, beyond) -> None:
    """A joint ``beyond`` rad past its upper limit (a reading in degrees: 100 rad): the position bound asked
    ``20 * (upper - margin - q)``, -4 rad/s at 0.2 rad, below the lower bound -2 rad/s: OSQP printed "ERROR in
    osqp_update_data_vec: Problem data validation" and the fallback, clamped to the crossed bounds, commanded -4 rad/s
    (-2216 rad/s from a Panda reading in degrees) against a velocity limit of 2."""
    q = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    q[1] = panda.upper[1] + beyond
    q[3] = panda.lower[3] - beyond
    lb, ub = velocity_bounds(q, panda.lower, panda.upper)
    assert np.all(lb <= ub)
    assert np.all(lb >= -MAX_VELOCITY) and np.all(ub <= MAX_VELOCITY)
    assert ub[1] < 0 and lb[3] > 0  # still driven back inside
    controller = NullSpaceController(panda)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ControllerFallbackWarning)
        for target in (None, tool_point(panda, np.clip(q, panda.lower, panda.upper)) + [0.0, 0.0, 0.01]):
            qdot = controller.step(q, np.zeros(7), target)
            assert np.all(np.abs(qdot) <= MAX_VELOCITY + 1e-9), qdot


def test_bounds_inside_the_limits_are_unchanged(panda) -> None:
    """Inside the limits (every reading a controller sees) the bounds are what they were: the velocity limit or the
    approach to the margin, whichever is tighter (written out here)."""
    q = panda.random_configurations(200, np.random.default_rng(1))
    for qk in q:
        lb, ub = velocity_bounds(qk, panda.lower, panda.upper)
        margin = 0.01
        np.testing.assert_array_equal(lb, np.maximum(-MAX_VELOCITY, 20.0 * (panda.lower + margin - qk)))
        np.testing.assert_array_equal(ub, np.minimum(MAX_VELOCITY, 20.0 * (panda.upper - margin - qk)))


def _elastic(panda):
    from spherecal.correction import perturb
    from spherecal.correction.elastic import with_compliance

    return with_compliance(perturb(panda, np.random.default_rng(7)), [0.0, 3e-5, 2e-5, 3e-5, 0.0, 0.0, 0.0])


def test_qp_ik_of_an_elastic_model_lands_its_sagging_arm_on_the_target(panda) -> None:
    """The QP differential IK given an elastic calibration aimed its rigid chain at the target: the arm, which sags,
    ended 0.45 mm off on a trial's calibration, and ``DifferentialIKFlow`` raised UnreachableError ("stops 0.445 mm
    away") for a target it reaches. Checked against MuJoCo: the model's own plant, its motors held at the answer,
    settles (springs against gravity) with its tool site on the target."""
    from spherecal.controller.compensation import DifferentialIKFlow
    from spherecal.controller.plant import build_plant
    from tests.controller.settle import settle

    model = _elastic(panda)
    q_seed = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    target = tool_point(model, q_seed + 0.05)
    q = DifferentialIKFlow()(model, target, q_seed)
    assert np.linalg.norm(tool_point(model, q) - target) < 1e-10
    plant = build_plant(model)
    plant.set_state(q)
    settle(plant, 3000)
    assert np.linalg.norm(plant.tool_position() - target) < 2e-6  # the model's first-order sag against MuJoCo's
    controller, q_loop = NullSpaceController(model), q_seed.copy()  # the controller's own loop
    for _ in range(3000):
        q_loop = q_loop + 1e-3 * controller.step(q_loop, np.zeros(7), target)
    assert np.linalg.norm(tool_point(model, q_loop) - target) < 1e-10


def test_ik_refuses_inputs_of_the_wrong_shape_in_its_own_words(panda) -> None:
    """``controller.ik.ik`` (the public IK) let numpy speak: a 6-angle start raised "operands could not be broadcast",
    a 2-coordinate target "cannot reshape array", a NaN target returned a NaN miss as a result, restarts without a
    generator a bare ValueError. Each is now a SpherecalError naming the field."""
    from spherecal.controller.ik import ik
    from spherecal.correction import SpherecalError

    q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    target = tool_point(panda, q0 + 0.05)
    for kwargs, field in (({"q0": q0[:6]}, "q0"), ({"target": target[:2]}, "target"),
                          ({"target": [np.nan, 0.0, 0.5]}, "target"), ({"q0": np.full(7, np.inf)}, "q0"),
                          ({"restarts": 3}, "rng"), ({"orientation": np.eye(4)}, "orientation")):
        with pytest.raises(SpherecalError, match=field):
            ik(panda, **{"target": target, "q0": q0, **kwargs})
    result = ik(panda, target, q0)
    assert result.converged and np.linalg.norm(tool_point(panda, result.q) - target) < 1e-10



def test_a_far_target_is_approached_slower_not_through_the_fallback(panda) -> None:
    """A target 0.2 rad of joint motion away asks ``Kp (p_B - p)`` faster than the velocity bounds allow: the strict
    task was infeasible and every such step left the QP for the pseudo-inverse fallback (54 warnings in a trial).
    The step now tracks the largest share of the task velocity the bounds allow: same target, no fallback, and
    every command within the velocity limit."""
    controller = NullSpaceController(panda)
    q = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    target = tool_point(panda, q + 0.2)
    fastest = 0.0
    with warnings.catch_warnings():
        warnings.simplefilter("error", ControllerFallbackWarning)
        for _ in range(3000):
            qdot = controller.step(q, np.zeros(7), target)
            fastest = max(fastest, float(np.abs(qdot).max()))
            q = q + qdot * 1e-3
            if np.linalg.norm(tool_point(panda, q) - target) < 1e-6:
                break
    assert np.linalg.norm(tool_point(panda, q) - target) < 1e-6
    assert fastest <= MAX_VELOCITY + 1e-9 and controller.report.fallbacks == 0
    # the share: the minimum-norm step at it touches a bound, and a joint driven back from past a limit gets none
    jac = np.random.default_rng(0).standard_normal((3, 7))
    v = np.array([3.0, -1.0, 2.0])
    lb, ub = -np.ones(7), np.ones(7)
    share = task_share(jac, v, lb, ub)
    step = share * np.linalg.pinv(jac) @ v
    assert 0 < share < 1 and np.isclose(np.abs(step).max(), 1.0) and np.all(np.abs(step) <= 1 + 1e-12)
    assert task_share(jac, 1e-6 * v, lb, ub) == 1.0
    lb[2] = 0.5
    assert task_share(jac, v, lb, ub) == 0.0


def test_a_target_in_millimetres_is_refused_by_the_qp_controller(panda) -> None:
    """h2's controls trial: `NullSpaceController.step` took a target in millimetres and drove toward it at the velocity
    limit. It is refused as compensate refuses one (checked once per target, not every period)."""
    controller = NullSpaceController(panda)
    q = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    in_mm = tool_point(panda, q) * 1e3
    with pytest.raises(UnreachableError, match=r"from the base of 'franka_panda'.*\(millimetres\? targets are in "):
        controller.step(q, np.zeros(7), in_mm)
    with pytest.raises(UnreachableError):  # and again: a refused target is not remembered as checked
        controller.step(q, np.zeros(7), in_mm)
    assert np.all(np.isfinite(controller.step(q, np.zeros(7), in_mm * 1e-3)))


def test_arrays_of_the_wrong_shape_are_named_every_period(panda) -> None:
    """A controls review: ``NullSpaceController.step`` and ``DifferentialIKFlow`` let numpy speak for arrays of the
    wrong shape ("could not broadcast input array from shape (6,) into shape (7,)", an IndexError), since their
    shapes were not checked every period. Each is now our ShapeError (a ValueError too) naming the argument, the
    shape expected and the shape given; a (1, 3) target, the same bytes as a (3,) one already checked, included."""
    from spherecal.controller.compensation import DifferentialIKFlow
    from spherecal.correction import ShapeError

    controller = NullSpaceController(panda)
    q = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    target = tool_point(panda, q + 0.01)
    controller.step(q, np.zeros(7), target)  # the target's values are checked and remembered
    cases = (
        ((q[:6], np.zeros(7), None), r"q: expected 7 joint angles \[rad\], got shape \(6,\)"),
        ((q[None], np.zeros(7), target), r"q: expected 7 joint angles \[rad\], got shape \(1, 7\)"),
        ((q, np.zeros(6), None), r"q_r: expected 7 joint velocities \[rad/s\], got shape \(6,\)"),
        ((q, np.zeros(7), target[None]), r"target: expected 3 coordinates \[m\], got shape \(1, 3\)"),
        ((q, np.zeros(7), target[:2]), r"target: expected 3 coordinates \[m\], got shape \(2,\)"),
        # two wrong at once: q, then q_r, then the target (the order kept when q_r's check left _task)
        ((q[:6], np.zeros(6), target[:2]), r"^q: expected 7 joint angles \[rad\], got shape \(6,\)"),
        ((q, np.zeros(6), target[:2]), r"^q_r: expected 7 joint velocities \[rad/s\], got shape \(6,\)"),
    )
    for call in (controller.step, controller.build):
        for args, message in cases:
            with pytest.raises(ShapeError, match=message):
                call(*args)
    flow = DifferentialIKFlow()
    for args, message in (((target, q[:6]), r"q_seed: expected 7 finite joint angles \[rad\], got shape \(6,\)"),
                          ((target[None], q), r"target: expected 3 finite coordinates \[m\], got shape \(1, 3\)")):
        with pytest.raises(ShapeError, match=message) as raised:
            flow(panda, *args)
        assert isinstance(raised.value, ValueError) and "\n" not in str(raised.value)
    # lists of the right length are arrays to numpy, and the command is the array's
    np.testing.assert_array_equal(controller.step(list(q), [0.0] * 7, list(target)),
                                  controller.step(q, np.zeros(7), target))
    assert np.linalg.norm(tool_point(panda, flow(panda, list(target), list(q))) - target) < 1e-10
