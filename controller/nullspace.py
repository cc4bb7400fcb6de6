"""The null-space velocity controller: the QP of :mod:`controller.qp_ik` on a model's kinematics.

Its kinematics live in a MuJoCo model built from the model it is given (the NOMINAL one on a
real arm): ``mj_kinematics + mj_comPos + mj_jacSite`` cost a few microseconds, far less than
numpy per step.
"""

from __future__ import annotations

import mujoco
import numpy as np

from spherecal.correction import RobotModel, geometric_part, tool_point

from .ik import check_shape, check_target
from .plant import TIMESTEP, build_plant
from .qp_ik import (
    LIMIT_GAIN,
    LIMIT_MARGIN,
    MAX_VELOCITY,
    PersistentOSQP,
    QPSolveError,
    StepReport,
    build_problem,
    damped_task_velocity,
    equality_solution,
    fall_back,
    solve_qp,
    task_share,
    velocity_bounds,
)
from .rigid_fit import joint_side_terms

#: Gain of the primary task ``v = Kp (p_B - p)`` when a target is given [1/s].
POSITION_GAIN = 20.0


class NullSpaceController:
    """Joint velocity commands: tool-point task first, ``q_r`` strictly in its null space.

    Args:
        model: the kinematics the controller believes (nominal, or a calibrated model). Its Jacobian is the rigid
            chain's at the measured angles (MuJoCo); a target is reached by the model's own tool point, so an
            elastic calibration's sag (or a joint-angle scale) is aimed for (a numpy :func:`correction.tool_point`
            per step with a target: 0.40 ms against 0.04 ms for a rigid model; self-motion does not need it).
        solver: ``"osqp"`` (default, a persistent ``osqp.OSQP`` updated each step when
            ``persistent``) or any name in ``qpsolvers.available_solvers``.
        persistent: keep one OSQP instance set up (only with ``solver="osqp"``).
        fallback: on a failed QP use the damped pseudo-inverse with clamped limits and warn
            (:class:`ControllerFallbackWarning`); otherwise raise :class:`QPSolveError`.
        max_velocity: scalar or (n,) joint speed limit [rad/s].
        margin: distance kept from the position limits [rad].
        limit_gain: [1/s], see :func:`velocity_bounds`.
        dt: control period [s] (kept for users that integrate the command).
        closed_form: when no bound is active, return the QP's solution in closed form
            (:func:`controller.qp_ik.equality_solution`, exact; a whole step 24.7 us against 28.6 us) and call the
            QP solver only when a bound is active or near a singularity; False: always the solver.
    """

    def __init__(
        self,
        model: RobotModel,
        solver: str = "osqp",
        persistent: bool = True,
        fallback: bool = True,
        max_velocity: float | np.ndarray = MAX_VELOCITY,
        margin: float = LIMIT_MARGIN,
        limit_gain: float = LIMIT_GAIN,
        dt: float = TIMESTEP,
        closed_form: bool = True,
    ):
        import qpsolvers  # qpsolvers: only a non-persistent solver goes through it

        if solver not in qpsolvers.available_solvers:
            raise QPSolveError(f"QP solver {solver!r} is not installed; have {', '.join(qpsolvers.available_solvers)}")
        self.model = model
        self.solver = solver
        self.fallback = fallback
        self.max_velocity = max_velocity
        self.margin = margin
        self.limit_gain = limit_gain
        self.dt = dt
        self.closed_form = closed_form
        self._checked_target = b""  # the last target checked (check_target), as bytes
        self.report = StepReport()
        self.last_bounds: tuple[np.ndarray, np.ndarray] | None = None  # (lb, ub) of the last step [rad/s]
        # its kinematics are the rigid chain's at the measured angles, as a robot controller's are: an elastic model's
        # plant has a second hinge per joint (motor and link), which the controller does not command
        self._kin = build_plant(geometric_part(model))
        # a target is reached by the model's own tool point (an elastic arm's sags: 0.45 mm on a trial's calibration
        # aimed rigidly); the rigid chain's Jacobian steers it
        self._joint_side = bool(joint_side_terms(model))
        self._jac = np.zeros((3, self._kin.mj_model.nv))
        self._n = model.n_joints
        self._shape = (self._n,)
        self._angles = f"{self._n} joint angles [rad]"
        self._speeds = f"{self._n} joint velocities [rad/s]"
        self._zero3 = np.zeros(3)
        self._persistent = PersistentOSQP(self._n) if (solver == "osqp" and persistent) else None

    # ------------------------------------------------------------------ kinematics
    def kinematics(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Tool point (3,) [m] and Jacobian (3, n) [m/rad] of the controller's model at ``q``.

        The returned arrays are internal buffers, overwritten by the next call.
        """
        m, d = self._kin.mj_model, self._kin.mj_data
        d.qpos[: self._n] = q
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        mujoco.mj_jacSite(m, d, self._jac, None, self._kin.tool_site)
        return d.site_xpos[self._kin.tool_site], self._jac

    def _check(self, q: np.ndarray, q_r: np.ndarray) -> None:
        """``q`` and ``q_r`` each (n,), in that order (then :meth:`_task` checks the target): a :class:`ShapeError`
        naming the argument, every period (a shape comparison, about 0.1 us each)."""
        check_shape(q, self._shape, "q", self._angles)
        check_shape(q_r, self._shape, "q_r", self._speeds)

    def _task(self, q: np.ndarray, target: np.ndarray | None, gain: float) -> tuple[np.ndarray, np.ndarray]:
        """The Jacobian (3, n) [m/rad] at ``q`` ((n,), checked by :meth:`_check`) and the primary task velocity (3,)
        [m/s]: ``gain`` times the target's offset from the model's own tool point (:func:`correction.tool_point`: an
        elastic arm's sag and a joint-angle scale included; the rigid chain's when the model has neither), damped near
        a singularity; 0 without a target.

        Raises:
            ShapeError: ``target`` not (3,), naming it (its shape every period; its values once per target).
        """
        point, jac = self.kinematics(q)
        if target is None:
            return jac, self._zero3
        check_shape(target, (3,), "target", "3 coordinates [m]")
        key = np.asarray(target, dtype=float).tobytes()
        if key != self._checked_target:  # once per target, not every period: one in millimetres was driven toward
            # at the velocity limit (a controls trial)
            check_target(self.model, target)
            self._checked_target = key
        if self._joint_side:
            point = tool_point(self.model, q)
        return jac, damped_task_velocity(jac, gain * (np.asarray(target) - point))

    # ------------------------------------------------------------------------ step
    def bounds(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n,) lower and upper joint velocity bounds at ``q`` [rad/s]."""
        return velocity_bounds(q, self.model.lower, self.model.upper, self.max_velocity, self.margin,
                               self.limit_gain)

    def build(self, q: np.ndarray, q_r: np.ndarray, target: np.ndarray | None = None,
              gain: float = POSITION_GAIN):
        """The step's :class:`qpsolvers.Problem` (see :func:`build_problem`), to inspect or solve.

        Args:
            q: (n,) measured joint angles [rad].
            q_r: (n,) desired secondary joint velocity [rad/s].
            target: (3,) tool-point target [m]; None during self-motion (``v = 0``: never feed
                the model's tool position back against a fixture the chain already holds).
            gain: ``Kp`` [1/s].

        Raises:
            ShapeError: ``q``, ``q_r`` or ``target`` of another shape (the argument, the shape expected and given).
            SpherecalError: a target that is not finite or beyond twice the arm's reach (checked once per target).
        """
        self._check(q, q_r)
        jac, v = self._task(q, target, gain)
        lb, ub = self.bounds(q)
        return build_problem(jac.copy(), v, q_r, lb, ub)

    def step(self, q: np.ndarray, q_r: np.ndarray, target: np.ndarray | None = None,
             gain: float = POSITION_GAIN) -> np.ndarray:
        """(n,) joint velocity command [rad/s] for one control period (arguments and errors as :meth:`build`)."""
        self._check(q, q_r)
        jac, v = self._task(q, target, gain)
        lb, ub = self.last_bounds = self.bounds(q)
        if self.closed_form:
            qdot = equality_solution(jac, v, q_r)
            if qdot is not None and np.all(qdot >= lb) and np.all(qdot <= ub):
                self.report.steps += 1
                self.report.closed_form += 1
                self.report.status = "qp"
                return qdot
        qdot = self._solve(jac, v, q_r, lb, ub)
        if qdot is None and target is not None:  # too far for the bounds in one step: the same direction, slower
            share = task_share(jac, v, lb, ub)
            if 0.0 < share < 1.0:
                v = v * share
                qdot = self._solve(jac, v, q_r, lb, ub)
        self.report.steps += 1
        if qdot is not None:
            self.report.status = "qp"
            return qdot
        reason = self._persistent.last_status if self._persistent is not None else f"{self.solver} returned no solution"
        return fall_back(build_problem(jac.copy(), v, q_r, lb, ub), reason, self.fallback, self.report)

    def _solve(self, jac: np.ndarray, v: np.ndarray, q_r: np.ndarray, lb: np.ndarray, ub: np.ndarray):
        """The step's QP solved (the persistent OSQP, else :attr:`solver` through qpsolvers): (n,) or None."""
        if self._persistent is None:
            return solve_qp(build_problem(jac.copy(), v, q_r, lb, ub), self.solver)
        return self._persistent.solve(jac, v, q_r, lb, ub)
