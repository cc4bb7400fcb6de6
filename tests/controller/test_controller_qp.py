"""The differential-IK QP: strict null-space priority, limits, solvers, fallback."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import qpsolvers

from spherecal.controller.nullspace import NullSpaceController
from spherecal.controller.qp_ik import ControllerFallbackWarning, QPSolveError, build_problem, velocity_bounds
from spherecal.correction import joint_jacobian, tool_point

Q0 = np.array([0.1, -0.3, 0.2, -2.0, 0.1, 1.8, 0.8])


def _projection(jac: np.ndarray, q_r: np.ndarray) -> np.ndarray:
    return q_r - np.linalg.pinv(jac) @ (jac @ q_r)


def test_controller_jacobian_matches_correction(panda, rng):
    controller = NullSpaceController(panda)
    for q in panda.random_configurations(20, rng):
        point, jac = controller.kinematics(q)
        assert np.abs(point - tool_point(panda, q)).max() < 1e-12
        assert np.abs(jac - joint_jacobian(panda, q)).max() < 1e-12


@pytest.mark.parametrize("closed_form", [False, True])
@pytest.mark.parametrize("solver,persistent", [("osqp", True), ("osqp", False), ("daqp", False)])
def test_null_space_motion_is_strict_and_a_projection(panda, rng, solver, persistent, closed_form):
    if solver not in qpsolvers.available_solvers:
        pytest.skip(f"{solver} not installed")
    controller = NullSpaceController(panda, solver=solver, persistent=persistent, closed_form=closed_form)
    for _ in range(50):
        q = Q0 + rng.normal(0.0, 0.1, 7)
        q_r = rng.normal(0.0, 0.3, 7)
        qdot = controller.step(q, q_r)  # target None: zero position error
        jac = joint_jacobian(panda, q)
        assert np.linalg.norm(jac @ qdot) < 1e-9
        lb, ub = controller.bounds(q)
        projected = _projection(jac, q_r)
        assert np.all(projected > lb + 1e-3) and np.all(projected < ub - 1e-3)  # no bound active
        assert np.abs(qdot - projected).max() < 1e-8
    assert controller.report.fallbacks == 0
    assert controller.report.closed_form == (50 if closed_form else 0)  # the solver ran when asked to


def test_closed_form_is_used_only_with_no_bound_active(panda, rng):
    # near a limit the projection crosses a bound: the QP solver decides, and its answer differs
    fast, solver = NullSpaceController(panda), NullSpaceController(panda, closed_form=False)
    q = Q0.copy()
    q[3] = panda.upper[3] - 0.012  # 2 mm inside the margin: ub of joint 4 is 0.04 rad/s
    q_r = np.zeros(7)
    q_r[3] = 1.0
    jac = joint_jacobian(panda, q)
    assert _projection(jac, q_r)[3] > controller_ub(solver, q)[3]  # the unconstrained answer would cross it
    qdot, reference = fast.step(q, q_r), solver.step(q, q_r)
    assert fast.report.closed_form == 0 and np.abs(qdot - reference).max() < 1e-8
    assert qdot[3] <= controller_ub(solver, q)[3] + 1e-9 and np.linalg.norm(jac @ qdot) < 1e-9
    for q in panda.random_configurations(20, rng) * 0.3 + Q0 * 0.7:  # well inside: the same numbers
        q_r = rng.normal(0.0, 0.3, 7)
        assert np.abs(fast.step(q, q_r) - solver.step(q, q_r)).max() < 1e-9


def controller_ub(controller, q):
    return controller.bounds(q)[1]


def test_position_task_reaches_target(panda):
    controller = NullSpaceController(panda)
    q = Q0.copy()
    target = tool_point(panda, q) + np.array([0.02, -0.01, 0.015])
    for _ in range(400):
        q = q + 1e-3 * controller.step(q, np.zeros(7), target=target)
    assert np.linalg.norm(tool_point(panda, q) - target) < 1e-5


def test_limits_hold_when_pushed(panda):
    controller = NullSpaceController(panda)
    q = Q0.copy()
    q[3] = panda.upper[3] - 0.02  # elbow near its upper limit
    push = np.zeros(7)
    push[3] = 2.0
    for _ in range(2000):
        qdot = controller.step(q, push)
        lb, ub = controller.bounds(q)
        assert np.all(qdot >= lb - 1e-9) and np.all(qdot <= ub + 1e-9)
        q = q + 1e-3 * qdot
    assert np.all(panda.within_limits(q))
    assert q[3] <= panda.upper[3] - controller.margin + 1e-9


def test_bounds_shape_and_sign(panda):
    lb, ub = velocity_bounds(Q0, panda.lower, panda.upper, 2.0, 0.01, 20.0)
    assert np.all(lb <= 0) and np.all(ub >= 0) and np.all(lb >= -2.0) and np.all(ub <= 2.0)


def test_build_problem_is_inspectable(panda):
    jac = joint_jacobian(panda, Q0)
    problem = build_problem(jac, np.zeros(3), np.ones(7), -np.ones(7), np.ones(7))
    assert np.allclose(problem.P, np.eye(7)) and np.allclose(problem.q, -1.0) and problem.A.shape == (3, 7)
    x = qpsolvers.solve_problem(problem, solver="daqp").x
    assert np.abs(x - _projection(jac, np.ones(7))).max() < 1e-9


def test_infeasible_step_falls_back_and_says_so(panda):
    # a joint past its limit is driven back (0 is outside its bounds), so no share of the task fits either
    q = Q0.copy()
    q[3] = panda.upper[3] + 0.05
    controller = NullSpaceController(panda, max_velocity=1e-6)
    target = tool_point(panda, q) + np.array([0.1, 0.0, 0.0])
    with pytest.warns(ControllerFallbackWarning, match="damped pseudo-inverse"):
        qdot = controller.step(q, np.zeros(7), target=target)
    assert np.all(np.abs(qdot) <= 1e-6 + 1e-12)
    assert controller.report.fallbacks == 1 and controller.report.status.startswith("fallback")
    strict = NullSpaceController(panda, max_velocity=1e-6, fallback=False)
    with pytest.raises(QPSolveError, match="fallback is off"):
        strict.step(q, np.zeros(7), target=target)


def test_a_target_too_far_for_the_bounds_is_tracked_at_the_share_they_allow(panda):
    # at 1e-6 rad/s the strict task toward a target 0.1 m away is infeasible: the step tracks the largest share of it
    controller = NullSpaceController(panda, max_velocity=1e-6)
    point, jac = controller.kinematics(Q0)
    target = point + np.array([0.1, 0.0, 0.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error", ControllerFallbackWarning)
        qdot = controller.step(Q0, np.zeros(7), target=target)
    assert np.abs(qdot).max() <= 1e-6 + 1e-12 and controller.report.fallbacks == 0
    moved = jac @ qdot  # along the target's direction, slower
    assert np.allclose(moved / np.linalg.norm(moved), [1.0, 0.0, 0.0], atol=1e-6)


def test_unknown_solver_is_refused(panda):
    with pytest.raises(QPSolveError, match="not installed"):
        NullSpaceController(panda, solver="no_such_solver")


def test_damping_keeps_a_singular_step_bounded(panda):
    q = np.zeros(7)
    q[3] = panda.upper[3] - 0.02  # elbow nearly straight, wrist aligned: near-singular
    controller = NullSpaceController(panda)
    point, jac = controller.kinematics(q)
    target = point + np.array([0.0, 0.0, 0.05])  # straight out along the stretched arm
    # unreachable at the speed limit: the strict equality is tracked at the share of it the bounds allow
    with warnings.catch_warnings():
        warnings.simplefilter("error", ControllerFallbackWarning)
        qdot = controller.step(q, np.zeros(7), target=target)
    assert np.all(np.isfinite(qdot)) and np.abs(qdot).max() <= controller.max_velocity + 1e-9
    lb, ub = controller.bounds(q)
    assert np.all(qdot >= lb - 1e-9) and np.all(qdot <= ub + 1e-9)
