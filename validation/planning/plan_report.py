"""The plan for humans: the ranked candidate table and a Rerun recording of the candidates."""

from __future__ import annotations

import numpy as np

from spherecal.controller.home import home
from spherecal.correction import RobotModel
from spherecal.correction.files.provenance import comment_block
from spherecal.validation.viewer.recording import Recording
from spherecal.validation.viewer.recording_shapes import SCALE_STEPS, colour_ramp, scale_labels

from .plan import Plan, one_branch
from .postures import least_cramped

#: Colour of a candidate with no prediction (unreachable, or not identifiable alone).
GREY = (150, 150, 150)


#: Share of the draws of the parameter error outside the range :func:`what_it_counts` gives on each side.
TAIL = 0.05


def what_it_counts(prediction, survey: str) -> list[str]:
    """What a predicted accuracy is: the range one calibration's mean error falls in, and what it counts and leaves
    out, each line for humans (mm). A review: a plan predicted 0.214 mm and validate then measured 0.341 mm on the
    same setup, with nothing saying that the prediction is the fixtures' noise alone, without the motion capture's
    noise that validate's first column holds.

    Args:
        prediction: an :class:`identification.prediction.Prediction` (its ``errors``: configurations x draws [m]).
        survey: how the configurations were had, in words (``"the whole self-motion manifold"``).
    """
    low, high = np.quantile(prediction.errors.mean(axis=0), [TAIL, 1 - TAIL]) * 1e3
    draws = prediction.errors.shape[1]
    return [
        f"one calibration's mean error: {low:.4f} to {high:.4f} mm ({TAIL:.0%} to {1 - TAIL:.0%} of {draws} draws of "
        "its parameter error; the mean above is their average)",
        f"what it counts: the fixtures' noise ({prediction.noise * 1e3:.3g} mm per axis, independent from sample to "
        f"sample) and the parameters left at nominal, over {survey}, against the exact tool point",
        "not counted, so expect more: the arm's error beyond the model (joint-angle errors, elasticity: calibrate "
        "estimates it from its residuals), noise correlated from sample to sample (hand guiding, a compliant socket), "
        "and the noise of what a validation measures against: compare this with validate's 'vs exact tool point' "
        "column (a simulation); its 'vs mocap' mean holds the motion capture's noise as well, about the root of the "
        "sum of squares of the two (the exact figure's and its 'mocap floor')",
    ]


def format_prediction(prediction, survey: str = "the recorded configurations") -> str:
    """``plan --predict``'s text: the prediction's summary, then :func:`what_it_counts`."""
    return "\n".join([prediction.summary(), *what_it_counts(prediction, survey)])


def format_plan(result) -> str:
    """The ranked candidate table and the chosen set (mm, %)."""
    lines = [
        f"{len(result.surveys)} candidates, {sum(s.reachable for s in result.surveys)} reachable; "
        f"self-motion: {result.motion}; noise {result.noise * 1e3:.3g} mm, {result.samples} samples per fixture",
        "predicted mean / 95th percentile tool-point error after registration [mm] of each candidate ALONE "
        "(scale from the nominal model), and the share of each joint's range its self-motion covers [%] "
        "(a range longer than a turn counted as one turn: the kinematics sees no more)",
        f"{'rank':>4} {'name':<8} {'x [m]':>7} {'y [m]':>7} {'z [m]':>7} | {'mean':>7} {'p95':>7} | "
        + " ".join(f"{'q' + str(j + 1):>4}" for j in range(len(result.surveys[0].coverage) if result.surveys else 0))
        + " | note",
    ]
    chosen = set(result.best.names) if result.best else set()
    for k, s in enumerate(result.ranked()):
        x, y, z = s.candidate.position
        cov = " ".join(f"{c * 100:4.0f}" for c in s.coverage)
        if s.alone is not None:
            err = f"{s.alone.mean * 1e3:7.3f} {s.alone.p95 * 1e3:7.3f}"
            note = "chosen" if s.candidate.name in chosen else ""
            rank = str(k + 1)
        else:
            err, rank = f"{'-':>7} {'-':>7}", "-"
            note = ("unreachable: " if not s.reachable else "") + s.reason
        if s.candidate.joint_range is not None:
            note = (note + " " if note else "") + "joint range " + ",".join(f"{r:g}" for r in s.candidate.joint_range)
        lines.append(f"{rank:>4} {s.candidate.name:<8} {x:7.3f} {y:7.3f} {z:7.3f} | {err} | {cov} | {note}")
    if result.best is None:
        lines.append(f"no plan: fewer reachable candidates than the {len(chosen) or 'requested'} fixtures wanted")
        return "\n".join(lines)
    best = result.best
    p = best.prediction
    distances = ", ".join(f"{a}-{b}" for a, b in best.distances) or "none"
    lines += [
        "",
        f"best set ({result.search} search): {', '.join(best.names)}; measure distances: {distances}",
        f"  predicted error: mean {p.mean * 1e3:.4f} mm, 95th percentile {p.p95 * 1e3:.4f} mm",
    ]
    if best.without_distances is not None:
        w = best.without_distances
        lines.append(f"  without any distance: mean {w.mean * 1e3:.4f} mm, 95th percentile {w.p95 * 1e3:.4f} mm")
    lines.append("  " + p.summary().replace("\n", "\n  "))
    n_joints = result.surveys[0].q.shape[1]
    if result.motion != "kinematic":
        survey = "the null-space controller's self-motion at each fixture (--seconds of it)"
    elif one_branch(n_joints):
        survey = (f"one hand-guided walk through the self-motion at each fixture, in one branch (a {n_joints}-joint "
                  "arm's branches are not joined by any motion with the ball held; a recording that covers less does "
                  "worse: plan --predict on it)")
    else:
        survey = ("the whole self-motion manifold at each fixture (a recording that covers less does worse: plan "
                  "--predict on it)")
    lines.extend("  " + line for line in what_it_counts(p, survey))
    return "\n".join(lines)


def arm_posture(model: RobotModel, result: Plan) -> tuple[np.ndarray, str]:
    """(n,) the posture [rad] the plan's recording draws ``model`` in, and where it is, in words: the least cramped
    (:func:`.postures.least_cramped`) of the surveyed self-motion samples at the best reachable candidate (the table's
    first), its tool point on it; ``model``'s home pose (:func:`controller.home.home`) when none was reachable."""
    reached = [s for s in result.ranked() if s.reachable and len(s.q)]
    if not reached:
        return home(model), "the arm at its home pose"
    return least_cramped(model, reached[0].q), f"the arm reaching {reached[0].candidate.name}"


def write_recording(path: str, result, info: dict | None = None, model: RobotModel | None = None) -> str:
    """The candidates coloured by predicted error alone on the ramp of the Errors views
    (:func:`validation.viewer.recording_shapes.colour_ramp`: blue the least, red the most; grey unreachable) with
    its colour scale labelled in mm beside them, the chosen set as the fixtures (wire spheres around their
    candidates, labelled with the candidate's error), the printed plan and its provenance as a table, in the layout
    of every recording (:mod:`validation.blueprint`). ``info``: the run's provenance block (shown below the plan;
    the recording id is derived from it, :func:`validation.viewer.recording.recording_id`), or None. ``model``: the
    arm planned for, drawn as the demo draws it (:meth:`validation.viewer.recording.Recording.self_motion`) in
    :func:`arm_posture`, named in the view's title (without it a user could not tell where the arm stands among
    its candidates); None: no arm."""
    title = "Candidate fixtures, coloured by predicted error alone"
    arm = None if model is None else arm_posture(model, result)
    title += "" if arm is None else f"; {arm[1]}"
    provenance = "" if info is None else comment_block(info)
    recording = Recording(path, application_id="spherecal_plan", title=title, run=info)
    try:
        rr = recording.rr
        surveys = result.surveys
        positions = np.array([s.candidate.position for s in surveys])
        values = np.array([s.alone.mean if s.alone is not None else np.nan for s in surveys]) * 1e3  # mm
        ok = np.isfinite(values)
        low, high = (float(values[ok].min()), float(values[ok].max())) if ok.any() else (0.0, 1.0)
        span = high - low if high > low else 1.0
        colours = np.tile(np.array(GREY, dtype=np.uint8), (len(surveys), 1))
        colours[ok] = colour_ramp((values[ok] - low) / span)
        chosen = set(result.best.names) if result.best is not None else set()
        # a chosen candidate is named by its fixture's sphere: two labels at one point were drawn one over the other
        labels = ["" if s.candidate.name in chosen else
                  f"{s.candidate.name} {v:.3f} mm" if np.isfinite(v) else f"{s.candidate.name} unreachable"
                  for s, v in zip(surveys, values, strict=True)]
        recording.stream.log("world/candidates", rr.Points3D(positions, colors=colours, labels=labels, radii=0.01),
                             static=True)
        recording.extend_bounds("world", positions)
        if arm is not None:  # one posture at time 0
            recording.self_motion(model, np.zeros(1), arm[0][None])
        if chosen:
            picked = [(s.candidate, v) for s, v in zip(surveys, values, strict=True) if s.candidate.name in chosen]
            recording.fixtures([f"{c.name} {v:.3f} mm (chosen)" for c, v in picked],
                               np.array([c.position for c, _ in picked]))
        grey = "; grey: unreachable" if not ok.all() else ""
        recording.colour_legend(
            "colour_scale", positions, colour_ramp(np.linspace(0.0, 1.0, SCALE_STEPS)),
            scale_labels(low, high, lambda v: f"{v:.3f} mm"),
            f"colour: predicted mean error\nof each candidate ALONE{grey}")
        # the ranking first, the provenance below it (on top, the ranking began 15 lines down: h6's review)
        text = f"{format_plan(result)}\n\n{provenance}" if provenance else format_plan(result)
        recording.text("plan", text, "The plan: candidates ranked by predicted error (mm)")
    except BaseException:
        recording.abort()
        raise
    return str(recording.close())
