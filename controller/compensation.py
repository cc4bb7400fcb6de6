"""Correction in a controller: joint-space (calibrated IK) and Cartesian target compensation.

Two ways to use a calibrated model in a control loop:

* **Joint-space correction** (the controller lets you choose its joint targets or its
  kinematics): :func:`corrected_ik` is :func:`controller.ik.ik` with the calibrated model,
  checked against the nominal one and raising instead of returning a miss.
* **Cartesian compensation** (the controller keeps its own NOMINAL kinematics, like the
  Panda's Cartesian controllers): :func:`compensate` returns the target to command so that the
  real arm, described by the calibrated model, ends on the desired point.

The controller picks its own null-space posture, so the command must be consistent with the
configuration it will actually reach. The controller is modelled as nominal IK from the seed
(``q_k = ik(nominal, t_k, q_seed)``, or any ``controller(model, target, q_seed, orientation)``
you pass), and the command is iterated to a fixed point::

    t_0 = target
    q_k = controller(nominal, t_k, q_seed)          # where the nominal controller goes
    p_k = tool_point(calibrated, q_k)               # where the real arm then is
    t_{k+1} = t_k + (target - p_k)                  # (orientation: R_{k+1} = R_target R_k'^T R_k)

The map ``t -> p`` differs from the identity by the calibration's correction (millimetres,
varying slowly over the workspace), so each iteration shrinks the residual by about the
relative change of that correction: a few iterations reach ``1e-10`` m.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from spherecal.correction import JointAngleError, RobotModel, tool_point, tool_pose
from spherecal.correction.errors import ShapeError, SpherecalError
from spherecal.correction.files.samples import HARD_MARGIN
from spherecal.correction.rigid import rotation_angle
from spherecal.correction.tool import (
    TIP_MOVED,
    TOOL_MATCH_TOL,
    ToolError,
    adapter_question,
    calibrated_from,
    nominal_tool_of,
    samples_shift,
    swapped_tool,
    tools_apart,
)

from .ik import UnreachableError, check_joint_angles, check_target, ik

#: Default position [m] and orientation [rad] tolerance of the fixed point.
POSITION_TOL = 1e-9
ORIENTATION_TOL = 1e-8
#: Largest nominal/calibrated tool-point difference [m] accepted at the seed: a calibration
#: corrects millimetres; decimetres mean the two files describe different robots.
MAX_MODEL_DIFFERENCE = 0.05
#: Iterations without a better residual before the fixed point is given up.
STALL_ITERATIONS = 3
#: Above this joint motion per metre of command change [rad/m] the controller's posture is said
#: to jump (a smooth IK moves about 1/reach, a few rad/m).
JUMP_RATIO = 50.0
#: Controller evaluations spent locating a posture jump (position targets).
BISECTIONS = 16

#: ``controller(model, target (3,), q_seed (n,), orientation (3, 3) | None) -> q (n,)``.
Controller = Callable[[RobotModel, np.ndarray, np.ndarray, "np.ndarray | None"], np.ndarray]


class ModelMismatchError(SpherecalError):
    """The calibrated model does not describe the same robot as the nominal one."""


class CompensationError(SpherecalError):
    """The compensation fixed point was not reached within the iteration budget."""


@dataclass(frozen=True)
class CompensationResult:
    """Outcome of :func:`compensate`.

    Attributes:
        command: (3,) tool-point target to send to the nominal controller [m].
        command_orientation: (3, 3) orientation to send (None when none was asked).
        q: (n,) configuration the nominal controller is predicted to reach [rad].
        landing: (3,) calibrated tool point at ``q``: where the real arm ends [m].
        position_residual: ``|target - landing|`` [m].
        orientation_residual: angle between the target and the calibrated orientation at
            ``q`` [rad] (0 when no orientation was asked).
        iterations: controller evaluations after the first (0 when ``target`` itself is exact).
        history: (iterations + 1,) position residual of every iterate [m].
        converged: residuals within the tolerances. False only with ``strict=False``: the
            command is then the best iterate, and ``note`` says why no better one was found.
        note: "" when converged, else the one-line reason.
    """

    command: np.ndarray
    command_orientation: np.ndarray | None
    q: np.ndarray
    landing: np.ndarray
    position_residual: float
    orientation_residual: float
    iterations: int
    history: np.ndarray
    converged: bool = True
    note: str = ""

    @property
    def uncompensated_error(self) -> float:
        """``|target - landing|`` [m] had the target itself been sent (the first controller evaluation)."""
        return float(self.history[0])

    @property
    def gain(self) -> float:
        """How much nearer the target the compensated command puts the real arm [m]
        (:attr:`uncompensated_error` minus :attr:`position_residual`): what the calibration's full model,
        elastic terms included, is worth to this controller at this target."""
        return self.uncompensated_error - self.position_residual


def _straddle(best: CompensationResult, other_command: np.ndarray, other_q: np.ndarray, target: np.ndarray,
              nominal: RobotModel, calibrated: RobotModel, q_seed: np.ndarray, controller: Controller,
              history: list[float], evaluations: int = BISECTIONS) -> CompensationResult:
    """Best command near a posture jump: bisect between the best command and one of the other
    posture, keeping the best landing (the closest ones lie at the jump)."""
    a, b = best.command, other_command
    if np.allclose(other_q, best.q):
        return best
    for _ in range(evaluations):
        middle = 0.5 * (a + b)
        q = np.asarray(controller(nominal, middle, q_seed, None), dtype=float)
        landing = tool_point(calibrated, q)
        history.append(float(np.linalg.norm(target - landing)))
        if history[-1] < best.position_residual:
            best = replace(best, command=middle, q=q, landing=landing, position_residual=history[-1])
        if np.abs(q - best.q).max() <= np.abs(q - other_q).max():
            a = middle
        else:
            b = middle
    return best


def check_models(nominal: RobotModel, calibrated: RobotModel, source: str = "calibrated model") -> None:
    """Raise :class:`ModelMismatchError` unless both models describe the same arm.

    Same joint count, same DH convention and the same joint limits (a calibration changes
    geometry, not limits).

    Args:
        source: name of the calibrated file, for the message.
    """
    mismatch = nominal.mismatch(calibrated, limits=True)
    if mismatch is not None:
        field, what = mismatch
        raise ModelMismatchError(
            f"{source}: field {field}: {what} (the controller's model is {nominal.name!r}: a file of another robot?)"
        )


def check_roles(nominal: RobotModel, calibrated: RobotModel, call: str = "compensate") -> None:
    """Raise :class:`ModelMismatchError` when ``nominal`` and ``calibrated`` were passed swapped.

    Detected when the model passed as ``nominal`` is a calibration recorded as made from the model passed as
    ``calibrated`` (its ``calibration.nominal_tool`` is that model's tool within
    :data:`~spherecal.correction.tool.TOOL_MATCH_TOL`, :func:`correction.tool.calibrated_from`) and the model passed
    as ``calibrated`` records no calibration or tool swap (:func:`correction.tool.nominal_tool_of` is None): the
    robot file and its calibration, in the wrong order. Swapped, the command would be corrected the wrong way, twice
    the calibration's correction off, and no other check notices (both describe one arm, within millimetres).

    Not detected, as nothing tells the two apart: two models without records (a simulation's true robot and its
    nominal: :func:`correction.perturb` leaves none), a calibration from a file older than its ``nominal_tool``
    record, or two calibrations. Refused although meant, the one case known: a controller that runs calibration A of a
    robot file compensated toward a calibration B of the same file that lost its record (B converted to a URDF) and
    whose tool moved less than ``TOOL_MATCH_TOL`` (0.1 mm) from the file's; give B with its record (its robot file).

    Args:
        call: the function's name, for the message.
    """
    if calibrated_from(nominal, calibrated) and nominal_tool_of(calibrated) is None:
        raise ModelMismatchError(
            f"{call}: nominal and calibrated swapped? the model passed as nominal ({nominal.name!r}) is a calibration "
            "of the one passed as calibrated (its 'calibration' block records that model's tool as its robot file's, "
            "and that model records no calibration): pass the controller's model (the robot file) as nominal and the "
            "calibrated model as calibrated")


def _check_difference(nominal: RobotModel, calibrated: RobotModel, q: np.ndarray, source: str) -> None:
    """Refuse a calibrated model that does not end at the controller model's tool: its tool point more than
    :data:`MAX_MODEL_DIFFERENCE` from the nominal one's at the seed, or a calibration of another tool (its recorded
    nominal tool, :func:`correction.tool.nominal_tool_of`, further than :data:`~correction.tool.TOOL_MATCH_TOL` from
    the nominal's: a ball 40 mm beyond the flange is within the first check and 40 mm off every target)."""
    gap = float(np.linalg.norm(tool_point(nominal, q) - tool_point(calibrated, q)))
    apart = max(tools_apart(calibrated, nominal), _other_tip(calibrated, nominal))
    shift = _unstated_shift(calibrated, source)
    if gap <= MAX_MODEL_DIFFERENCE and apart <= TOOL_MATCH_TOL and shift is None:
        return
    swapped = replace(calibrated, tool=nominal.tool)  # the same arm with the controller's tool?
    same_tool = float(np.linalg.norm(tool_point(nominal, q) - tool_point(swapped, q)))
    if same_tool > MAX_MODEL_DIFFERENCE:
        raise ModelMismatchError(
            f"{source}: tool point differs from the controller's model by {gap * 1e3:.0f} mm at the seed "
            f"(more than {MAX_MODEL_DIFFERENCE * 1e3:.0f} mm): not a calibration of this robot")
    record = calibrated.extras.get("calibration")
    # the command carries the calibration's tool correction over (its nominal_tool); the call must be told it
    carried = (", nominal_tool=calibrated.extras['calibration']['nominal_tool']"
               if isinstance(record, dict) and "nominal_tool" in record else "")
    if shift is not None:  # and whether the offset at which the samples put the ball is an adapter
        carried += ", samples_tool=calibrated.extras['calibration']['samples_tool'], adapter=True or False"
    shown = _printed(nominal.tool)
    remedy = (f"put the controller's tool on it first: correction.with_tool(calibrated, "
              f"{shown.tolist()}{carried}).model or `spherecal tool CAL.yaml --offset "
              f"{' '.join(f'{v:g}' for v in shown)}{' --adapter or --no-adapter' if shift is not None else ''} "
              "--out NEW.yaml`")
    if shift is not None and apart <= TOOL_MATCH_TOL:
        raise ModelMismatchError(
            f"{source}: {adapter_question(shift)}: the controller's "
            f"tool is that robot file's, so its targets would be missed by up to {np.linalg.norm(shift) * 1e3:.1f} "
            f"mm one way or the other; {remedy}")
    if gap > MAX_MODEL_DIFFERENCE:
        tools = float(np.linalg.norm(nominal.tool - calibrated.tool))
        raise ModelMismatchError(
            f"{source}: tool point differs from the controller's model by {gap * 1e3:.0f} mm at the seed (more than "
            f"{MAX_MODEL_DIFFERENCE * 1e3:.0f} mm): its tool point is {tools * 1e3:.0f} mm from the controller "
            f"model's in the last frame: a calibration ends at its own tool (the ball); {remedy}")
    recorded = nominal_tool_of(calibrated)
    if recorded is None:  # two URDFs to different tip links (a calibrated URDF keeps no record)
        tips = (calibrated.extras["urdf"]["tip_link"], nominal.extras["urdf"]["tip_link"])
        raise ModelMismatchError(
            f"{source}: its tool is URDF link {tips[0]!r}, the controller model's {tips[1]!r}, {apart * 1e3:.1f} mm "
            f"apart in the last frame (the targets would be missed by about that): load both to the same link, or "
            f"{remedy}")
    raise ModelMismatchError(
        f"{source}: its tool point calibrates the tool at {_printed(recorded).tolist()} m in the last frame, "
        f"{apart * 1e3:.1f} mm from the controller model's {shown.tolist()} m "
        f"(the targets would be missed by about that): a calibration ends at its own tool (the ball); {remedy}")


def _unstated_shift(calibrated: RobotModel, source: str) -> np.ndarray | None:
    """(3,) [m] the offset at which a calibrated file's samples put the ball from its robot file's tool
    (``calibration.samples_tool``, beyond :data:`~correction.tool.TIP_MOVED`) when no tool swap has said whether it
    is an adapter (:func:`correction.tool.with_tool`); else None. A MUKCa Panda calibrated with ``--tip-link
    panda_hand_tcp`` (the ball 41 mm beyond it) passed the 50 mm seed check and aimed its TCP 30 mm off."""
    block = calibrated.extras.get("calibration")
    if not isinstance(block, dict) or "samples_tool" not in block or swapped_tool(calibrated):
        return None
    try:
        return samples_shift(nominal_tool_of(calibrated), block.get("samples_tool"))
    except ToolError as error:
        raise ModelMismatchError(f"{source}: {error}") from None


def _printed(point: np.ndarray) -> np.ndarray:
    """A tool point (3,) [m] as a message prints it: to the nm, no float noise (-4.8e-33) and no -0."""
    return np.round(np.asarray(point, dtype=float), 9) + 0.0


def _other_tip(calibrated: RobotModel, nominal: RobotModel) -> float:
    """How far apart [m] the tools of two models loaded from URDFs to different tip links are, in the last frame, when
    that is beyond a calibration's correction (:data:`~correction.tool.TIP_MOVED`); else 0. A calibrated URDF
    (``export --into``) keeps no ``calibration.nominal_tool``: loaded to its ball against a controller's URDF to
    ``tool0`` it passed the 50 mm seed check 40 mm off (a review, iiwa14). Links of one point under two names pass."""
    tips = [m.extras["urdf"].get("tip_link") if isinstance(m.extras.get("urdf"), dict) else None
            for m in (calibrated, nominal)]
    if None in tips or tips[0] == tips[1] or nominal_tool_of(calibrated) is not None:
        return 0.0
    apart = float(np.linalg.norm(np.asarray(calibrated.tool, dtype=float) - nominal.tool))
    return apart if apart > TIP_MOVED else 0.0


def _seed(q: np.ndarray, model: RobotModel, field: str) -> np.ndarray:
    """(n,) start joint angles [rad] as floats; a wrong shape, a NaN/inf angle (a joint reading lost on the way)
    or one more than a quarter turn (:data:`~spherecal.correction.files.samples.HARD_MARGIN`) outside the limits of
    a joint that has limits (another arm's reading, or degrees) raises, naming the joint, instead of an IK started
    nowhere ("misses by nan mm") or silently from the nearest limit. A wrong shape is a :class:`ShapeError` (a
    ``ValueError`` too, as elsewhere for joint angles), not a :class:`ModelMismatchError`: the models may well match."""
    q, n = np.asarray(q, dtype=float), model.n_joints
    if q.shape != (n,):
        raise ShapeError(f"{field}: expected {n} joint angles, got shape {q.shape}")
    bad = np.flatnonzero(~np.isfinite(q))
    if bad.size:
        raise SpherecalError(f"{field}: joint {bad[0] + 1} is {q[bad[0]]} (expected {n} finite joint angles [rad])")
    excess = np.maximum(model.lower - q, q - model.upper)
    far = np.flatnonzero((excess > HARD_MARGIN) & ~model.full_turn)
    if far.size:
        i = far[0]
        raise JointAngleError(f"{field}: joint {i + 1} is {q[i]:.6g} rad, {excess[i]:.3g} rad outside its limits "
                             f"[{model.lower[i]:.6g}, {model.upper[i]:.6g}] of {model.name} (more than a quarter "
                             "turn: a reading of another arm, or degrees?)")
    return q


def _target(target: np.ndarray, orientation: np.ndarray | None,
            model: RobotModel) -> tuple[np.ndarray, np.ndarray | None]:
    """The target [m] and orientation checked; a target farther from the base than the arm's links and tool reach
    at all (a target in millimetres: a user trial got 'misses by 634888 mm') is refused, naming the distance."""
    target = check_target(model, target)
    if orientation is None:
        return target, None
    orientation = np.asarray(orientation, dtype=float)
    if (orientation.shape != (3, 3) or not np.allclose(orientation @ orientation.T, np.eye(3), atol=1e-9)
            or np.linalg.det(orientation) < 0):
        raise SpherecalError("orientation: expected a (3, 3) rotation matrix (orthonormal, det +1)")
    return target, orientation


def nominal_ik_controller(model: RobotModel, target: np.ndarray, q_seed: np.ndarray,
                          orientation: np.ndarray | None = None) -> np.ndarray:
    """The default controller model: :func:`controller.ik.ik` from the seed, no restarts.

    Raises:
        UnreachableError: the IK does not converge (target outside the model's workspace).
    """
    result = ik(model, target, q_seed, orientation=orientation)
    if not result.converged:
        raise UnreachableError(
            f"target {np.round(target, 4).tolist()} m: out of reach of {model.name!r} from the seed "
            f"(IK misses by {result.position_error * 1e3:.3f} mm, {np.rad2deg(result.orientation_error):.3f} deg): the "
            "nominal controller, modelled as IK from the seed without restarts, stalls there (a joint limit, a "
            "singular posture); a seed nearer the target, or corrected_ik (it tries starts around the seed), may "
            "reach it"
        )
    return result.q


class DifferentialIKFlow:
    """Controller model of a velocity-level differential-IK controller (the QP of
    :class:`controller.nullspace.NullSpaceController` with no secondary task), integrated
    kinematically from the seed until the tool point of ``model`` is on the command.

    Its null-space posture is the end of that flow, not the Gauss-Newton answer of
    :func:`controller.ik.ik`: pass an instance as ``compensate(..., controller=...)`` when the
    controller in the loop is such a QP. Position targets only.

    Args:
        seconds: longest integration [s].
        tol: tool-point tolerance of the end point [m].
        dt: integration step [s] (the controller's period).

    Calling it, ``flow(model, target (3,) [m], q_seed (n,) [rad], orientation=None) -> q (n,) [rad]``, raises
    :class:`~spherecal.correction.errors.ShapeError` for a ``target`` or ``q_seed`` of another shape (naming it, with
    the shape expected and given), :class:`SpherecalError` for one that is not finite or a target beyond twice the
    arm's reach, :class:`UnreachableError` when the flow stops short of the target.
    """

    def __init__(self, seconds: float = 4.0, tol: float = 1e-11, dt: float | None = None):
        from .plant import TIMESTEP  # MuJoCo: only the closed-loop path needs it

        self.seconds, self.tol, self.dt = seconds, tol, TIMESTEP if dt is None else dt
        self._controllers: dict[int, object] = {}
        self.fallbacks = 0

    def __call__(self, model: RobotModel, target: np.ndarray, q_seed: np.ndarray,
                 orientation: np.ndarray | None = None) -> np.ndarray:

        from .nullspace import NullSpaceController  # MuJoCo and OSQP: only the closed-loop path needs them
        from .qp_ik import ControllerFallbackWarning  # OSQP: only the closed-loop path needs it

        if orientation is not None:
            raise SpherecalError("orientation: DifferentialIKFlow models position-only controllers")
        target = check_target(model, target)  # once per call, not per integration step
        q, rest = check_joint_angles(model, q_seed, "q_seed").copy(), np.zeros(model.n_joints)
        controller = self._controllers.get(id(model))
        if controller is None or controller.model is not model:
            controller = self._controllers[id(model)] = NullSpaceController(model)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ControllerFallbackWarning)
            for step in range(int(round(self.seconds / self.dt))):
                q = q + self.dt * controller.step(q, rest, target)
                if step % 50 == 0 and np.linalg.norm(tool_point(model, q) - target) < self.tol:
                    break
        self.fallbacks += len(caught)
        miss = float(np.linalg.norm(tool_point(model, q) - target))
        if miss > self.tol:
            raise UnreachableError(
                f"target {np.round(target, 4).tolist()} m: the differential-IK flow of {model.name!r} stops "
                f"{miss * 1e3:.3g} mm away after {self.seconds:g} s"
            )
        return q


def corrected_ik(
    calibrated: RobotModel,
    target: np.ndarray,
    q0: np.ndarray,
    orientation: np.ndarray | None = None,
    nominal: RobotModel | None = None,
) -> np.ndarray:
    """Joint-space correction: joint angles that put the REAL tool point on ``target``.

    :func:`controller.ik.ik` with the calibrated model, for a control loop that accepts joint
    targets. With ``nominal`` given, the calibrated model is first checked to be a calibration
    of that robot.

    Args:
        calibrated: the calibrated model.
        target: (3,) desired tool point in the world [m].
        q0: (n,) start, usually the current joint angles [rad].
        orientation: optional (3, 3) desired orientation of the last frame.
        nominal: the controller's own model, for :func:`check_models`.

    Returns:
        (n,) joint angles inside the limits [rad].

    Raises:
        ModelMismatchError: ``calibrated`` is not a calibration of ``nominal``, or the two were passed swapped
            (:func:`check_roles`).
        ShapeError: ``q0`` is not (n,) joint angles of ``calibrated`` (named, with the shape given).
        SpherecalError: a NaN or infinite target coordinate, a NaN, infinite or far out of range start angle (named).
        UnreachableError: no joint angles reach the target from the seed nor from starts near it (outside the
            workspace).
    """
    target, orientation = _target(target, orientation, calibrated)
    q0 = _seed(q0, calibrated, "q0")
    if nominal is not None:
        check_models(nominal, calibrated)
        check_roles(nominal, calibrated, "corrected_ik")
        _check_difference(nominal, calibrated, q0, "calibrated model")
    try:
        return nominal_ik_controller(calibrated, target, q0, orientation)
    except UnreachableError:
        nearby = _nearby_ik(calibrated, target, q0, orientation)  # q0: (n,) floats, checked by _seed
        if nearby is None:
            raise
        return nearby


#: :func:`corrected_ik`'s nearby starts when the seed itself stalls: how many, and their spread per joint [rad].
NEARBY_STARTS, NEARBY_SPREAD = 16, 0.3


def _nearby_ik(model: RobotModel, target: np.ndarray, q0: np.ndarray, orientation: np.ndarray | None):
    """The converged IK nearest ``q0`` (n,) [rad] from :data:`NEARBY_STARTS` starts around it (seeded, inside the
    limits), or None. A seed at a singularity held by a joint limit (the Panda stretched out, q4 at its -0.07 rad
    limit) stalls the Gauss-Newton steps short of a target the arm reaches (92 mm off); starts near it find the
    configuration near the seed, not a far branch a uniform restart would."""
    rng = np.random.default_rng(0)
    starts = np.clip(q0 + rng.normal(0.0, NEARBY_SPREAD, (NEARBY_STARTS, q0.size)), model.lower, model.upper)
    found = [r.q for r in (ik(model, target, s, orientation=orientation) for s in starts) if r.converged]
    return min(found, key=lambda q: float(np.linalg.norm(q - q0))) if found else None


def compensate(
    target: np.ndarray,
    nominal: RobotModel,
    calibrated: RobotModel,
    q_seed: np.ndarray,
    orientation: np.ndarray | None = None,
    controller: Controller | None = None,
    tol: float = POSITION_TOL,
    orientation_tol: float = ORIENTATION_TOL,
    max_iter: int = 20,
    strict: bool = True,
) -> CompensationResult:
    """The Cartesian target to give a nominal-kinematics controller so the real arm lands on ``target``.

    Args:
        target: (3,) desired tool point of the real arm in the world [m].
        nominal: the kinematics the controller uses.
        calibrated: the calibrated model (the real arm).
        q_seed: (n,) the controller's start configuration [rad] (its current joint angles).
        orientation: optional (3, 3) desired orientation of the last frame of the real arm.
        controller: model of the controller, ``controller(model, target, q_seed, orientation) -> q``;
            :func:`nominal_ik_controller` by default. It must raise a :class:`SpherecalError`
            for a target it cannot reach.
        tol: position tolerance of the fixed point [m].
        orientation_tol: orientation tolerance [rad].
        max_iter: most controller evaluations after the first; the iteration also stops when
            :data:`STALL_ITERATIONS` in a row do not improve on the best residual.
        strict: raise :class:`CompensationError` when the tolerance is not met; otherwise return
            the best iterate with ``converged=False`` and the reason in ``note``.

    Returns:
        :class:`CompensationResult` with the command, the predicted configuration, iterations
        and residuals.

    A controller whose posture choice jumps between nearby commands (a Gauss-Newton IK whose
    path branches, seen on 1 target in 200 of the README's landing run with :func:`controller.ik.ik`
    from a seed 0.3 rad away) may have no command at all that lands on the target: the landings of the two
    branches straddle it. The iteration then alternates between the branches; it is stopped,
    and the error (or the ``note``) names the jump.

    Raises:
        ModelMismatchError: the calibrated model is of another robot (joint count, convention,
            limits) or differs from the nominal one by more than :data:`MAX_MODEL_DIFFERENCE`; or the two were
            passed swapped, when their records tell (:func:`check_roles` says when they do and when not).
        ShapeError: ``q_seed`` is not (n,) joint angles of ``nominal`` (named, with the shape given).
        SpherecalError: a NaN or infinite target coordinate, a NaN, infinite or far out of range seed angle (named).
        UnreachableError: the nominal controller cannot reach a command (target outside the
            workspace).
        CompensationError: (``strict`` only) the residual is still above ``tol`` at the end.
        SpherecalError: ``max_iter`` below 0, ``tol`` or ``orientation_tol`` not above 0.
    """
    target, orientation = _target(target, orientation, nominal)
    check_models(nominal, calibrated)
    check_roles(nominal, calibrated)
    q_seed = _seed(q_seed, nominal, "q_seed")
    if max_iter < 0:
        raise SpherecalError(f"max_iter: expected >= 0 controller evaluations, got {max_iter}")
    for name, value, unit in (("tol", tol, "m"), ("orientation_tol", orientation_tol, "rad")):
        if not value > 0.0:  # also a nan; a trial's tol=-1 ran 13 evaluations to a residual of 3e-15 mm, then raised
            raise SpherecalError(f"{name}: expected a tolerance > 0 [{unit}], got {value!r}")
    _check_difference(nominal, calibrated, q_seed, "calibrated model")
    controller = controller or nominal_ik_controller
    command, command_rot = target.copy(), None if orientation is None else orientation.copy()
    history: list[float] = []
    best: CompensationResult | None = None
    jump, stalled, previous = 0.0, 0, None
    for iteration in range(max_iter + 1):
        q = np.asarray(controller(nominal, command, q_seed, command_rot), dtype=float)
        pose = tool_pose(calibrated, q)
        miss = target - pose[:3, 3]
        history.append(float(np.linalg.norm(miss)))
        turn = None if orientation is None else orientation @ pose[:3, :3].T
        angle = 0.0 if turn is None else float(rotation_angle(turn))
        current = CompensationResult(command, command_rot, q, pose[:3, 3], history[-1], angle, iteration,
                                     np.array(history))
        if history[-1] <= tol and angle <= orientation_tol:
            return current
        if previous is not None:  # joint motion per metre of command change: ~1/reach unless the posture jumps
            step = float(np.linalg.norm(command - previous[0]))
            jump = max(jump, float(np.abs(q - previous[1]).max()) / step if step > 0 else 0.0)
        previous = (command, q)
        if best is None or history[-1] + angle < best.position_residual + best.orientation_residual:
            best, stalled = current, 0
        else:
            stalled += 1
        if iteration == max_iter or stalled >= STALL_ITERATIONS:
            break
        command = command + miss
        if turn is not None:
            command_rot = turn @ command_rot
    if jump > JUMP_RATIO and orientation is None:
        best = _straddle(best, previous[0], previous[1], target, nominal, calibrated, q_seed, controller, history)
    why = (
        f"the nominal controller's posture jumps between nearby commands ({jump:.0f} rad of joint motion per m "
        "of command change), its landings straddle the target"
        if jump > JUMP_RATIO
        else "near a singularity or the workspace boundary?"
    )
    note = (
        f"target {np.round(target, 4).tolist()} m: best compensation residual {best.position_residual * 1e3:.3g} mm "
        f"(orientation {np.rad2deg(best.orientation_residual):.2g} deg) after {len(history) - 1} evaluations, "
        f"tolerance {tol * 1e3:.2g} mm; {why}"
    )
    if strict:
        raise CompensationError(note)
    return replace(best, iterations=len(history) - 1, history=np.array(history), converged=False, note=note)
