"""Tool swap: calibrate with the ball, work with the gripper.

The tool point of a :class:`RobotModel` is a point fixed in the last DH frame ``n``; a calibration identifies
it together with the chain. Putting another tool on the calibrated arm replaces that point and keeps every
identified term of the chain (DH, Hayati, base, compliance, ...)::

    swap = with_tool(calibrated, [0.0, 0.0, 0.2104])      # the new tool point in frame n [m]
    swap.model                                             # the calibrated arm with the new tool
    swap.note                                              # what the calibration cannot vouch for

What a single-point tool cannot identify: the ball tells the calibration where its centre is for every
configuration, not how the last link is turned about that centre. A rotation of frame ``n`` about the ball
centre moves no recorded point (the last joint's motion shows only the direction of its own axis, and only
when the ball is off that axis), so it is held by the prior (the nominal description, spread
:data:`correction.layout.ANGLE` 0.2 deg per angle), and, for the Panda's on-axis ball, the last joint's own
``theta`` offset is not seen at all. At a new tool point a distance ``d`` from the ball centre such a rotation
``delta`` moves the tool by ``delta * d``: 0.2 deg is 0.10 mm at d = 30 mm (the Franka Hand's TCP, 30 mm
before MUKCa's ball), 0.7 mm at d = 200 mm. A new tool at the ball centre inherits the calibration's full
accuracy; the farther it is, the more its accuracy rests on the nominal orientation of the last frame.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace

import numpy as np

from .chain import link_frames
from .errors import SpherecalError
from .gravity import InertialsError, inertials_of
from .layout import ANGLE
from .model import RobotModel, matrix_rpy

#: Largest distance [m] and angle [rad] between the last frame of the tool's description and the
#: calibrated model's at zero angles: beyond a calibration's correction, the two name different frames.
FRAME_DISTANCE_TOL = 0.03
#: Largest angle [rad] (5 deg) between those frames (:data:`FRAME_DISTANCE_TOL`); also the largest ``angle`` that
#: :func:`with_tool` takes.
FRAME_ANGLE_TOL = np.deg2rad(5.0)


#: A calibrated tool point further than this from the robot file's tool [m] is where the samples put the ball (an
#: adapter or sensor the description lacks: identification.tool_fit), not a correction of the file's tool link.
TIP_MOVED = 0.010
#: Two nominal tool points further apart than this [m] are different tools (a URDF saved again rounds to a micrometre).
TOOL_MATCH_TOL = 1e-4


class ToolError(SpherecalError):
    """A tool that cannot be put on the model; the message names the field."""


class CarriedTipWarning(UserWarning):
    """The correction :func:`with_tool` carries to the new tool is beyond :data:`TIP_MOVED`: not a calibration's."""


@dataclass(frozen=True)
class ToolSwap:
    """Outcome of :func:`with_tool`.

    Attributes:
        model: the calibrated model with the new tool point.
        distance: ``|new tool - calibrated tool point|`` [m], in the last frame.
        unidentified: ``sin(angle) * distance`` [m]: the tool displacement of a rotation of the last frame about
            the old tool point by :func:`with_tool`'s ``angle`` (default the prior's spread, 0.2 deg): what the
            calibration cannot vouch for at the new tool.
        note: the above in one line, in mm, with the correction carried over when ``nominal_tool`` was given.
    """

    model: RobotModel
    distance: float
    unidentified: float
    note: str


#: Where a calibrated file records the nominal point of the tool it was calibrated with.
NOMINAL_TOOL = "calibration.nominal_tool"
#: Where a calibrated file records the tool point its samples showed, when that was beyond a calibration's
#: correction from the robot file's (the fit started there: :mod:`spherecal.identification.tool_fit`).
SAMPLES_TOOL = "calibration.samples_tool"


def point_of(value, where: str) -> np.ndarray:
    """(3,) the finite coordinates [m] of a point in the last frame, as given in ``value``.

    Raises:
        ToolError: anything else (text, two numbers, a nan), one line starting with ``where`` (``"field '--offset'"``,
            ``"cal.yaml: field 'calibration.nominal_tool'"``).
    """
    try:
        point = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        point = np.full(0, np.nan)
    if point.shape != (3,) or not np.all(np.isfinite(point)):
        shown = np.ravel(point).tolist() if point.size else value
        raise ToolError(f"{where}: expected 3 finite coordinates [m] in the last frame, got {shown!r}")
    return point


def with_tool(model: RobotModel, tool: np.ndarray, payload: dict | None = None,
              angle: float = ANGLE.prior_std, nominal_tool: np.ndarray | None = None, field: str = "tool",
              samples_tool: np.ndarray | None = None, adapter: bool | None = None,
              source: str | None = None) -> ToolSwap:
    """Put another tool point on a (calibrated) model.

    The calibrated tool point carries more than the ball's mounting: the last joint's ``d`` and ``theta``
    are redundant with it and held at nominal, so the flange's own error along and about the last axis is
    in the tool point too (MUKCa's Panda: ``tool_z`` moves 1.6 mm). With ``nominal_tool`` (the old tool's
    nominal position, which the calibration started from) that correction is carried over:
    ``new = model.tool + (tool - nominal_tool)``, ``tool`` being the new tool's nominal position, as a
    description gives it (right when both tools hang from the same flange, e.g. a ball held by the gripper).

    Args:
        model: the calibrated model: its tool point is the one it was calibrated with (e.g. the ball), or, on a
            model an earlier swap gave another tool, the one that swap recorded (:func:`calibrated_tool`): the new
            tool goes on the calibrated one, its correction carried once (a review: a second ``with_tool`` with
            ``nominal_tool`` on a swapped file carried it twice, 30 mm off, and the controller took it).
        tool: (3,) the new tool point in the last DH frame [m] (its nominal position when ``nominal_tool``
            is given, else the point itself).
        payload: the new ``payload`` block (``{mass: kg, com: [x, y, z] m}`` in the last frame, optionally
            ``inertia: [ixx, ixy, ixz, iyy, iyz, izz] kg m^2``) for gravity torques, checked as a robot file's, or None
            to keep the model's (say so to the user: an elastic model's sag depends on it).
        angle: unidentified rotation of the last frame to translate into millimetres [rad], in ``[0,
            FRAME_ANGLE_TOL]`` (5 deg).
        nominal_tool: (3,) the calibrated tool's nominal position in the last frame [m]
            (``calibration.nominal_tool`` of a calibrated file), or None to put ``tool`` as given.
        field: what the caller calls ``tool`` in a refusal (``--offset`` on the command line).
        samples_tool: (3,) where the calibration's samples put the ball in the last frame [m]
            (``calibration.samples_tool``, recorded when that is beyond :data:`TIP_MOVED` from ``nominal_tool``), or
            None. One ball cannot tell an adapter or sensor between the flange and every tool from the ball's own
            mount or a ``--tip-link`` that named another link, so ``adapter`` must say which:
        adapter: True: that offset is an adapter every tool sits on, carried to the new tool (``model.tool -
            nominal_tool``); False: the ball's own, not carried (only ``model.tool - samples_tool``, the
            calibration's correction). Needed, and recorded in ``tool_swap``, only when ``samples_tool`` is given
            and beyond :data:`TIP_MOVED` from ``nominal_tool``.
        source: the calibrated file ``samples_tool`` came from, named in the refusal that asks for ``adapter``.

    Returns:
        :class:`ToolSwap`: ``model`` with the new tool point (``swap.model.tool``, (3,) [m] in the last frame), its
        ``payload`` replaced when given, and a ``tool_swap`` block in ``extras`` recording the calibrated tool, the
        new one and the correction carried ([m]); the distance and the unidentified displacement [m] and a note.

    Warns:
        CarriedTipWarning: with ``nominal_tool`` and no ``samples_tool``, a carried correction beyond
            :data:`TIP_MOVED` (an adapter the robot file lacks, carried to the new tool as it is).

    Raises:
        ToolError: a ``payload`` the gravity torques would refuse, an ``adapter`` that is not a bool or None, an
            ``angle`` outside ``[0, FRAME_ANGLE_TOL]`` (degrees), ``adapter`` not given where it is needed (the
            controller would aim the offset off, one way or the other: a MUKCa Panda calibrated with ``--tip-link
            panda_hand_tcp`` aimed 30 mm off), a tool that is not 3 finite numbers, or a tool or ``nominal_tool``
            farther from the last frame than the arm is long (:attr:`RobotModel.chain_length`: millimetres typed for
            metres; no real tool outreaches the arm carrying it, and on a small arm this bound is tighter than any
            fixed one of a few metres), or a ``tool_swap`` block whose ``calibrated_tool`` is malformed
            (:func:`calibrated_tool`).

    Example::

        cal = load_robot("cal.yaml")
        swap = with_tool(cal, [0.0, 0.0, 0.2104], nominal_tool=cal.extras["calibration"]["nominal_tool"])
        swap.model.tool          # (3,) the new calibrated tool point [m]
        print(swap.note)
    """
    tool = _within_arm(point_of(tool, f"field '{field}'"), model, f"field '{field}'", "the new tool point")
    if adapter is not None and not isinstance(adapter, (bool, np.bool_)):  # "no" is truthy: it carried the offset
        raise ToolError(f"field 'adapter': expected True, False or None, got {adapter!r}")
    if not (0.0 <= angle <= FRAME_ANGLE_TOL):  # also a nan
        raise ToolError(f"field 'angle': expected a rotation in [0, {FRAME_ANGLE_TOL:.4g}] rad (at most "
                        f"{np.rad2deg(FRAME_ANGLE_TOL):.0f} deg: beyond, another frame), got {angle!r} (degrees? "
                        "the angle is in rad)")
    if payload is not None:
        _check_payload(model, payload)
    calibrated = calibrated_tool(model)
    model = replace(model, tool=calibrated)
    carried = np.zeros(3)
    stated = {}
    if nominal_tool is not None:
        where = f"field '{NOMINAL_TOOL}'"  # millimetres carried -107 m over to the new tool (a user trial)
        nominal_tool = _within_arm(point_of(nominal_tool, where), model, where, "the calibrated tool's nominal point")
        carried = calibrated - nominal_tool
        shift = samples_shift(nominal_tool, samples_tool)
        if shift is not None:
            if adapter is None:
                raise ToolError(f"{f'{source}: ' if source else ''}field '--adapter': {adapter_question(shift)}: "
                                "say which")
            stated = {"adapter": bool(adapter), "samples_shift": [float(v) for v in shift]}
            if not adapter:
                carried = carried - shift
        tool = tool + carried
        if np.linalg.norm(carried) > TIP_MOVED and not stated:
            warnings.warn(
                f"the calibration's tool point is {np.linalg.norm(carried) * 1e3:.1f} mm from the robot file's tool it "
                f"started from ({NOMINAL_TOOL}), more than a calibration corrects ({TIP_MOVED * 1e3:.0f} mm): the ball "
                "sat on an adapter or sensor the robot file lacks, or the calibration's --tip-link named another link; "
                "that offset is carried to the new tool as it is: right only if the new tool sits on the same adapter "
                "and its point is given from the robot file's tool link", CarriedTipWarning, stacklevel=2)
    distance = float(np.linalg.norm(tool - calibrated))
    extras = dict(model.extras)
    if payload is not None:
        extras["payload"] = payload
    extras["tool_swap"] = {"calibrated_tool": [float(v) for v in calibrated], "tool": [float(v) for v in tool],
                           "carried_correction": [float(v) for v in carried], **stated}
    unidentified = float(np.sin(angle) * distance)
    note = (f"new tool {distance * 1e3:.1f} mm from the calibrated tool point: a single-point tool does not "
            f"(fully) identify the rotation of the last frame about that point, so at the new tool each "
            f"{np.rad2deg(angle):.1f} deg of it (the prior's spread) is {unidentified * 1e3:.2f} mm the calibration "
            f"cannot vouch for")
    if nominal_tool is not None:
        own = carried - shift if stated.get("adapter") else carried  # the adapter's offset: said, not in doubt
        shown = ", ".join(f"{v * 1e3:+.3f}" for v in own)
        note += (f"; the calibration's correction of the old tool point, ({shown}) mm in the last frame (the "
                 f"flange's own error is in it), is carried to the new tool: one ball cannot tell the flange's error "
                 f"(the new tool shares it) from the ball's own mount (it does not), so the new tool may be off by up "
                 f"to {np.linalg.norm(own) * 1e3:.2f} mm more")
        if stated:
            how = "carried: an adapter every tool sits on" if adapter else "not carried: the ball's own mount"
            note += (f"; the {np.linalg.norm(shift) * 1e3:.1f} mm at which the samples put the ball from the robot "
                     f"file's tool is {how}")
    return ToolSwap(replace(model, tool=tool, extras=extras), distance, unidentified, note)


def _within_arm(point: np.ndarray, model: RobotModel, where: str, what: str) -> np.ndarray:
    """``point`` (3,) [m] in the last frame, refused when farther from it than the arm is long
    (:attr:`RobotModel.chain_length`: millimetres typed for metres; no real tool outreaches the arm carrying it)."""
    largest = float(np.abs(point).max())
    distance = largest * float(np.linalg.norm(point / largest)) if largest > 0 else 0.0  # 1e300 squared is inf
    if distance > model.chain_length:
        raise ToolError(
            f"{where}: {what} {np.array2string(point, precision=4)} m is {distance:.4g} m from the last frame, more "
            f"than the arm itself ({model.chain_length:.3g} m, sum of |a| and |d|) (millimetres? the offset is in m)")
    return point


def _check_payload(model: RobotModel, payload) -> None:
    """Refuse a ``payload`` block the gravity torques would refuse at their first use (:func:`correction.gravity.
    inertials_of`: a mapping ``{mass: kg >= 0, com: (3,) m, inertia: (6,) kg m^2 optional}``, a centre of mass within
    10 m, a plausible mass for the arm), here, where it is given."""
    probe = replace(model, extras={"inertials": [{"mass": 0.0}] * model.n_joints, "payload": payload})
    try:
        inertials_of(probe, source=model.name)
    except InertialsError as error:
        raise ToolError(str(error)) from None


def samples_shift(nominal_tool: np.ndarray, samples_tool: np.ndarray | None) -> np.ndarray | None:
    """(3,) how far the samples put the ball from the robot file's tool, ``samples_tool - nominal_tool`` [m] in the
    last frame, when beyond :data:`TIP_MOVED`; None otherwise (nothing recorded, or a calibration's correction).

    Args:
        nominal_tool: (3,) the robot file's tool point in the last frame [m].
        samples_tool: (3,) where the samples put the ball, in the last frame [m], or None.

    Raises:
        ToolError: a ``samples_tool`` that is not 3 finite numbers.
    """
    if samples_tool is None:
        return None
    shift = point_of(samples_tool, f"field '{SAMPLES_TOOL}'") - np.asarray(nominal_tool, dtype=float)
    return shift if float(np.linalg.norm(shift)) > TIP_MOVED else None


def adapter_question(shift: np.ndarray) -> str:
    """Why a tool swap (or a controller) not told what ``shift`` is refuses: an adapter every tool sits on, or
    the ball's own mount (the caller names the field that answers).

    Args:
        shift: (3,) :func:`samples_shift` [m], in the last frame.

    Returns:
        One line of text, in mm.
    """
    shown = ", ".join(f"{v * 1e3:.1f}" for v in shift)
    return (f"the calibration's samples put the ball {np.linalg.norm(shift) * 1e3:.1f} mm from the "
            f"robot file's tool ([{shown}] mm in the last frame, {SAMPLES_TOOL}), more than a calibration corrects "
            f"({TIP_MOVED * 1e3:.0f} mm); one ball cannot tell whether an adapter or sensor between the flange and "
            "every tool put it there (carried to the new tool: --adapter, adapter=True) or the ball's own mount or a "
            "--tip-link that named another link (not carried: --no-adapter, adapter=False)")


def calibrated_tool(model: RobotModel) -> np.ndarray:
    """(3,) the tool point the model was calibrated with [m]: its own, or, on a model whose tool an earlier
    :func:`with_tool` replaced, the one that swap recorded (a second swap starts from the calibration, not from
    the first swap's tool, whose carried correction it would count again). A ``tool_swap`` block whose ``tool``
    is no longer the model's (a calibration started from a swapped model) is stale and ignored.

    Raises:
        ToolError: a ``tool_swap`` block whose ``calibrated_tool`` is not 3 finite numbers.
    """
    swap = model.extras.get("tool_swap")
    own = np.asarray(model.tool, dtype=float)
    if not isinstance(swap, dict) or "calibrated_tool" not in swap:
        return own
    try:  # a block whose tool is no longer the model's (a calibration started from a swapped model) is stale
        if not np.allclose(np.asarray(swap.get("tool"), dtype=float), own, rtol=0.0, atol=1e-12):
            return own
    except (TypeError, ValueError):
        return own
    try:
        calibrated = np.asarray(swap["calibrated_tool"], dtype=float)
    except (TypeError, ValueError):
        calibrated = np.full(1, np.nan)
    if calibrated.shape != (3,) or not np.all(np.isfinite(calibrated)):
        raise ToolError(f"tool_swap.calibrated_tool: expected 3 finite coordinates [m], got "
                        f"{swap['calibrated_tool']!r}")
    return calibrated


def tool_in_frame(description: RobotModel, model: RobotModel) -> np.ndarray:
    """The tool point of ``description`` (another description of the same arm, e.g. its URDF up to the
    gripper's TCP) in ``model``'s last DH frame [m].

    The point is taken in ``description``'s own last frame: that frame must be ``model``'s (the same DH
    construction, as when both come from the same URDF or robot file), checked at zero angles within
    :data:`FRAME_DISTANCE_TOL` and :data:`FRAME_ANGLE_TOL`.

    Raises:
        ToolError: other joint count or convention, or last frames that are not the same frame.
    """
    mismatch = model.mismatch(description)
    if mismatch is not None and mismatch[0] != "beta":
        raise ToolError(f"tool description: {mismatch[0]}: {mismatch[1]}")
    zero = np.zeros(model.n_joints)
    mine, theirs = link_frames(model, zero)[-1], link_frames(description, zero)[-1]
    gap = float(np.linalg.norm(mine[:3, 3] - theirs[:3, 3]))
    turn = float(np.linalg.norm(matrix_rpy(mine[:3, :3].T @ theirs[:3, :3])))
    if gap > FRAME_DISTANCE_TOL or turn > FRAME_ANGLE_TOL:
        raise ToolError(f"tool description: its last frame is {gap * 1e3:.0f} mm and {np.rad2deg(turn):.1f} deg from "
                        f"the model's at zero angles (at most {FRAME_DISTANCE_TOL * 1e3:.0f} mm, "
                        f"{np.rad2deg(FRAME_ANGLE_TOL):.0f} deg): not the same arm, or another DH construction")
    return np.array(description.tool, dtype=float)


def calibrated_from(model: RobotModel, reference: RobotModel) -> bool:
    """``model`` is a calibration whose file records ``reference``'s tool as its robot file's (``calibration.
    nominal_tool``; not a tool ``spherecal tool`` replaced): its own tool is then the one its samples showed,
    which may be centimetres away (a ball on a sensor or adapter the description lacks:
    :mod:`spherecal.identification.tool_fit`), and the arms are compared alone (:func:`with_tool_of`)."""
    if isinstance(model.extras.get("tool_swap"), dict):
        return False
    recorded = nominal_tool_of(model)  # the calibration's record; None when absent or hand-edited out of shape
    return recorded is not None and bool(np.allclose(recorded, reference.tool, rtol=0.0, atol=TOOL_MATCH_TOL))


def swapped_tool(model: RobotModel) -> bool:
    """``model``'s tool is one :func:`with_tool` put on it (its ``tool_swap`` block is current, not stale)."""
    swap = model.extras.get("tool_swap")
    try:
        return isinstance(swap, dict) and bool(np.allclose(np.asarray(swap.get("tool"), dtype=float), model.tool,
                                                           rtol=0.0, atol=1e-12))
    except (TypeError, ValueError):
        return False


def nominal_tool_of(model: RobotModel) -> np.ndarray | None:
    """(3,) the nominal position [m] in the last frame of the tool whose calibrated point ``model`` carries: the new
    tool as :func:`with_tool` was given it (its ``tool_swap`` block's tool less the correction it carried), else the
    robot file's tool the calibration started from (``calibration.nominal_tool``). None for a model that records
    neither (a nominal model) or a record that is not 3 finite numbers (:func:`point_of` refuses it where it is
    used)."""
    swap = model.extras.get("tool_swap")
    block = model.extras.get("calibration")
    try:
        if swapped_tool(model):  # not stale (:func:`calibrated_tool`)
            point = np.asarray(swap["tool"], dtype=float) - np.asarray(swap.get("carried_correction", 0.0), dtype=float)
        elif isinstance(block, dict) and block.get("nominal_tool") is not None:
            point = np.asarray(block["nominal_tool"], dtype=float)
        else:
            return None
    except (TypeError, ValueError, KeyError):
        return None
    return point if point.shape == (3,) and np.all(np.isfinite(point)) else None


def tools_apart(model: RobotModel, reference: RobotModel) -> float:
    """How far [m] the nominal point of ``model``'s tool (:func:`nominal_tool_of`) is from ``reference``'s tool point,
    in the last frame; 0 when ``model`` records none. Beyond :data:`TOOL_MATCH_TOL` the two end at different tools
    (a calibration with the ball against a controller's flange or gripper), however close the points look: a ball
    40 mm beyond an iiwa's flange passed a 50 mm check of the tool points."""
    point = nominal_tool_of(model)
    return 0.0 if point is None else float(np.linalg.norm(point - np.asarray(reference.tool, dtype=float)))


def with_tool_of(model: RobotModel, reference: RobotModel) -> RobotModel:
    """``model`` with ``reference``'s tool point: the arms compared alone."""
    return replace(model, tool=np.array(reference.tool, dtype=float))


def arm_of(model: RobotModel, reference: RobotModel) -> RobotModel:
    """``model`` as compared with ``reference`` to tell whether both describe one arm: with ``reference``'s tool
    when it is a calibration of ``reference`` (:func:`calibrated_from`: its tool is where its samples put the
    ball), else as it is."""
    return with_tool_of(model, reference) if calibrated_from(model, reference) else model


def tip_moved(model: RobotModel, reference: RobotModel) -> float:
    """How far [m] a calibration of ``reference`` (:func:`calibrated_from`) found the ball from ``reference``'s tool
    point; 0 for any other model. Beyond :data:`TIP_MOVED` it is an adapter or sensor the description lacks."""
    if not calibrated_from(model, reference):
        return 0.0
    return float(np.linalg.norm(np.asarray(model.tool, dtype=float) - reference.tool))
