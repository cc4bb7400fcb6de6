"""QP differential IK with strict null-space priority (paper eq. 6), built then solved.

Decision variable: the joint velocity ``qdot`` (n,) [rad/s]. Problem (one control step)::

    minimise    1/2 |qdot - q_r|^2
    subject to  J qdot = v                       (primary task, strict: an equality)
                lb <= qdot <= ub                 (velocity and position limits over a step)

A target farther than the bounds allow in one step makes the equality infeasible: the controller then tracks the
largest share of ``v`` they allow (:func:`task_share`), the same direction, slower.

With no bound active the solution is ``J^+ v + (I - J^+ J) q_r``: the secondary velocity
``q_r`` projected into the null space of the tool-point task. :func:`equality_solution` gives it
in closed form; when it lies inside the bounds it *is* the QP's solution (the KKT conditions hold
with zero bound multipliers), so a controller needs the QP solver only when a bound is active.
``v = Kp (p_B - p)`` when a target is given and ``0`` during self-motion (the closed chain, not
the nominal model, keeps the tool on the fixture). Near singularities ``v`` is replaced by its
damped least-squares image ``J J^T (J J^T + lambda^2 I)^-1 v``, which stays in the range of ``J``.

:func:`build_problem` returns a :class:`qpsolvers.Problem` to inspect or solve with any
qpsolvers solver; :class:`PersistentOSQP` keeps one ``osqp.OSQP`` set up and only updates
its numbers each step (qpsolvers' OSQP path re-creates and refactorises it on every call).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import qpsolvers
import scipy.sparse as sparse

from spherecal.correction.errors import SpherecalError

#: Defaults of the controller.
MAX_VELOCITY = 2.0  # [rad/s] (the Panda allows 2.175-2.61)
LIMIT_MARGIN = 0.01  # [rad] kept from every position limit
LIMIT_GAIN = 20.0  # [1/s] at most this share of the distance to the margin is closed per second
DAMPING = 1e-3  # [m] lambda at a singularity (damped least squares)
MANIPULABILITY_THRESHOLD = 1e-3  # [m^3] below this sqrt(det(J J^T)), damping fades in
#: OSQP's default eps_abs (1e-3) is as large as a 1 ms joint step; these keep limits and the
#: equality exact to ~1e-10, and polishing finishes on the active set.
OSQP_SETTINGS = {
    "eps_abs": 1e-10,
    "eps_rel": 1e-10,
    "polishing": True,
    "warm_starting": True,
    "verbose": False,
    "max_iter": 4000,
    "check_termination": 5,
}


class QPSolveError(SpherecalError):
    """The differential-IK QP failed or was infeasible (and no fallback was allowed)."""


class ControllerFallbackWarning(UserWarning):
    """A QP step failed and the damped pseudo-inverse with clamped limits was used instead."""


def velocity_bounds(
    q: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    max_velocity: float | np.ndarray = MAX_VELOCITY,
    margin: float = LIMIT_MARGIN,
    gain: float = LIMIT_GAIN,
) -> tuple[np.ndarray, np.ndarray]:
    """Joint velocity bounds from velocity limits and position limits.

    ``qdot`` may close at most ``gain`` x the distance to ``limit -/+ margin`` per second, so
    the margin is approached exponentially and never crossed (``gain * dt << 1``).

    Args:
        q: (n,) joint angles [rad].
        lower, upper: (n,) position limits [rad].
        max_velocity: scalar or (n,) [rad/s].
        margin: [rad].
        gain: [1/s].

    Returns:
        ``(lb, ub)`` each (n,) [rad/s], ``-max_velocity <= lb <= ub <= max_velocity``, with
        ``lb <= 0 <= ub`` whenever ``q`` is inside the margins (outside, both push it back in).
    """
    margin = np.minimum(margin, 0.5 * (upper - lower))  # a locked joint (lower == upper) is held, not infeasible
    # both ends inside +-max_velocity: a joint more than max_velocity / gain past a limit (0.1 rad; a reading in
    # degrees) had ub < lb, OSQP refused the data and the fallback, clamped to them, commanded 4 rad/s (2216 from
    # degrees) against a limit of 2; now it is driven back at the velocity limit
    lb = np.clip(gain * (lower + margin - q), -max_velocity, max_velocity)
    ub = np.clip(gain * (upper - margin - q), -max_velocity, max_velocity)
    return lb, ub


def damped_task_velocity(jac: np.ndarray, v: np.ndarray, damping: float = DAMPING) -> np.ndarray:
    """The damped least-squares image of ``v`` (3,) through ``jac`` (3, n).

    ``lambda^2`` fades in as the manipulability ``w = sqrt(det(J J^T))`` drops below
    :data:`MANIPULABILITY_THRESHOLD` (Nakamura); far from singularities ``v`` is returned as is.
    """
    jjt = jac @ jac.T
    w = np.sqrt(max(np.linalg.det(jjt), 0.0))
    if w >= MANIPULABILITY_THRESHOLD or not np.any(v):
        return v
    lam2 = damping**2 * (1.0 - (w / MANIPULABILITY_THRESHOLD) ** 2)
    return jjt @ np.linalg.solve(jjt + lam2 * np.eye(jjt.shape[0]), v)


def equality_solution(jac: np.ndarray, v: np.ndarray, q_r: np.ndarray) -> np.ndarray | None:
    """The QP's solution with the bounds left out: ``q_r + J^T (J J^T)^-1 (v - J q_r)`` (n,) [rad/s].

    It is the QP's solution whenever it lies inside ``[lb, ub]``.

    Args:
        jac: (3, n) tool-point Jacobian [m/rad].
        v: (3,) primary task velocity [m/s].
        q_r: (n,) desired secondary joint velocity [rad/s].

    Returns:
        (n,) joint velocity, or None near a singularity (manipulability ``sqrt(det(J J^T))`` below
        :data:`MANIPULABILITY_THRESHOLD`), where the QP solver and the damped task decide.
    """
    jjt = jac @ jac.T
    if np.linalg.det(jjt) < MANIPULABILITY_THRESHOLD**2:
        return None
    return q_r + jac.T @ np.linalg.solve(jjt, v - jac @ q_r)


def build_problem(
    jac: np.ndarray, v: np.ndarray, q_r: np.ndarray, lb: np.ndarray, ub: np.ndarray
) -> qpsolvers.Problem:
    """The QP of one control step (see the module docstring).

    Args:
        jac: (3, n) tool-point Jacobian [m/rad].
        v: (3,) primary task velocity [m/s] (already damped).
        q_r: (n,) desired secondary joint velocity [rad/s].
        lb, ub: (n,) joint velocity bounds [rad/s].

    Returns:
        ``Problem(P=I, q=-q_r, A=jac, b=v, lb=lb, ub=ub)``.
    """
    n = jac.shape[1]
    return qpsolvers.Problem(
        P=np.eye(n), q=-np.asarray(q_r, dtype=float), A=np.asarray(jac, float), b=np.asarray(v, float),
        lb=np.asarray(lb, float), ub=np.asarray(ub, float),
    )


def damped_pinv_velocity(problem: qpsolvers.Problem, damping: float = DAMPING) -> np.ndarray:
    """Fallback: ``J^+_lambda b + (I - J^+_lambda J) (-q)``, clamped to ``[lb, ub]`` (n,)."""
    jac, v, q_r = problem.A, problem.b, -problem.q
    jinv = jac.T @ np.linalg.inv(jac @ jac.T + damping**2 * np.eye(jac.shape[0]))
    qdot = jinv @ v + q_r - jinv @ (jac @ q_r)
    return np.clip(qdot, problem.lb, problem.ub)


class PersistentOSQP:
    """One ``osqp.OSQP`` instance for problems of a fixed shape, updated in place each step.

    The constraint matrix is ``[J; I]`` (3+n, n) with a dense ``J`` block, kept in CSC form
    whose data array is rewritten from a preallocated (n, 4) buffer: column ``k`` holds
    ``J[0,k], J[1,k], J[2,k], 1``.
    """

    def __init__(self, n: int, m_task: int = 3, **settings):
        import osqp  # OSQP: loaded with the first persistent solver (start-up)

        self.n, self.m_task = n, m_task
        rows = m_task + 1
        indices = np.empty((n, rows), dtype=np.int64)
        indices[:, :m_task] = np.arange(m_task)
        indices[:, m_task] = m_task + np.arange(n)
        self._ax = np.zeros((n, rows))
        self._ax[:, m_task] = 1.0
        self._ax[:, :m_task] = 1.0  # placeholder non-zeros so the structure is set up dense
        a = sparse.csc_matrix((self._ax.ravel(), indices.ravel(), np.arange(0, n * rows + 1, rows)),
                              shape=(m_task + n, n))
        self._l = np.zeros(m_task + n)
        self._u = np.zeros(m_task + n)
        self._solver = osqp.OSQP()
        self._solver.setup(P=sparse.triu(sparse.eye(n), format="csc"), q=np.zeros(n), A=a,
                           l=-np.ones(m_task + n), u=np.ones(m_task + n), **{**OSQP_SETTINGS, **settings})
        # The extension object under the Python wrapper: its update/solve skip the wrapper's
        # derivative cache and result namespaces (about 15 us a step); the public API is used
        # for setup only.
        self._ext = self._solver._solver
        self._solved = osqp.SolverStatus.OSQP_SOLVED
        self.last_status = "not solved"
        self.last_iterations = 0

    def solve(self, jac: np.ndarray, v: np.ndarray, q_r: np.ndarray, lb: np.ndarray, ub: np.ndarray
              ) -> np.ndarray | None:
        """Solve the step's QP; returns (n,) ``qdot`` or None when OSQP did not solve it."""
        m = self.m_task
        self._ax[:, :m] = jac.T
        self._l[:m] = v
        self._u[:m] = v
        self._l[m:] = lb
        self._u[m:] = ub
        self._ext.update_data_vec(q=-q_r, l=self._l, u=self._u)
        self._ext.update_data_mat(P_x=None, P_i=None, A_x=self._ax.ravel(), A_i=None)
        self._ext.solve()
        info = self._ext.info
        self.last_iterations = info.iter
        if info.status_val != self._solved:
            self.last_status = info.status
            return None
        self.last_status = "solved"
        return self._ext.solution.x.copy()

    def solve_problem(self, problem: qpsolvers.Problem) -> np.ndarray | None:
        """Solve a :func:`build_problem` problem (same shape as set up)."""
        return self.solve(problem.A, problem.b, -problem.q, problem.lb, problem.ub)


@dataclass
class StepReport:
    """What the last control step did: ``status`` is ``"qp"`` or ``"fallback: <reason>"``;
    ``closed_form`` counts the steps solved by :func:`equality_solution` (no bound active)."""

    status: str = "qp"
    fallbacks: int = 0
    steps: int = 0
    closed_form: int = 0


def solve_qp(problem: qpsolvers.Problem, solver: str = "osqp") -> np.ndarray | None:
    """One step's problem solved by a qpsolvers solver (OSQP re-created on every call): (n,) or None."""
    opts = OSQP_SETTINGS if solver == "osqp" else {}
    if solver == "osqp":  # OSQP wants CSC; it is re-created and refactorised on every call
        problem = qpsolvers.Problem(sparse.csc_matrix(problem.P), problem.q, None, None,
                                    sparse.csc_matrix(problem.A), problem.b, problem.lb, problem.ub)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PendingDeprecationWarning)  # osqp's raise_error notice
        qdot = qpsolvers.solve_problem(problem, solver=solver, **opts).x
    return qdot if qdot is not None and np.all(np.isfinite(qdot)) else None


def task_share(jac: np.ndarray, v: np.ndarray, lb: np.ndarray, ub: np.ndarray) -> float:
    """The largest share ``s`` in [0, 1] of the task velocity ``v`` (3,) [m/s] whose minimum-norm joint step
    ``s J^+ v`` lies inside ``[lb, ub]`` (n,) [rad/s]; 0 when no share does (a joint past a limit, driven back:
    zero is outside its bounds). ``jac``: (3, n) [m/rad].

    A target farther than the velocity bounds allow in one step makes the strict task ``J qdot = v`` infeasible:
    the step then tracks ``s v`` (the same direction, slower) instead of leaving the QP for the pseudo-inverse
    fallback (a controls trial: 54 fallback warnings on the way to a target 0.2 rad of joint motion away).
    """
    if np.any(lb > 0.0) or np.any(ub < 0.0):
        return 0.0
    step = np.linalg.lstsq(jac, v, rcond=None)[0]
    over = np.where(step > ub, ub / np.where(step > ub, step, 1.0), 1.0)
    under = np.where(step < lb, lb / np.where(step < lb, step, 1.0), 1.0)
    return float(min(1.0, over.min(initial=1.0), under.min(initial=1.0)))


def solve_step(
    problem: qpsolvers.Problem,
    solver: str = "osqp",
    persistent: PersistentOSQP | None = None,
    fallback: bool = True,
    report: StepReport | None = None,
) -> np.ndarray:
    """Solve one step's problem; on failure fall back (and say so) or raise.

    Args:
        problem: from :func:`build_problem`.
        solver: a qpsolvers solver name (``qpsolvers.available_solvers``); ignored when
            ``persistent`` is given.
        persistent: a :class:`PersistentOSQP` to use instead of qpsolvers.
        fallback: use :func:`damped_pinv_velocity` with a :class:`ControllerFallbackWarning`
            when the QP fails; otherwise raise :class:`QPSolveError`.
        report: updated in place with the status and counts.

    Returns:
        (n,) joint velocity [rad/s].
    """
    if persistent is not None:
        qdot = persistent.solve_problem(problem)
        reason = persistent.last_status
    else:
        qdot, reason = solve_qp(problem, solver), f"{solver} returned no solution"
    if report is not None:
        report.steps += 1
    if qdot is not None and np.all(np.isfinite(qdot)):
        if report is not None:
            report.status = "qp"
        return qdot
    return fall_back(problem, reason, fallback, report)


def fall_back(problem: qpsolvers.Problem, reason: str, fallback: bool, report: StepReport | None) -> np.ndarray:
    """After a failed QP: raise :class:`QPSolveError`, or warn and return :func:`damped_pinv_velocity`."""
    if not fallback:
        raise QPSolveError(f"differential IK: QP solver failed ({reason}) and fallback is off")
    message = f"fallback: damped pseudo-inverse with clamped limits ({reason})"
    if report is not None:
        report.status = message
        report.fallbacks += 1
    warnings.warn(message, ControllerFallbackWarning, stacklevel=3)
    return damped_pinv_velocity(problem)
