"""Recording guidance for humans and files: the ranked table, ``plan.json`` and a Rerun recording."""

from __future__ import annotations

import numpy as np

from spherecal.correction import tool_point
from spherecal.correction.files.provenance import comment_block
from spherecal.validation.viewer.recording_shapes import SCALE_STEPS, colour_ramp, scale_labels

from . import guidance as guidance_module
from .guidance import mm_text

#: Parameters named per candidate in the table.
PINNED_SHOWN = 3


def _pinned(judged) -> str:
    items = [f"{n} (new)" if r == 0 else f"{n} x{r:.2f}" for n, r in judged.pinned[:PINNED_SHOWN]]
    more = len(judged.pinned) - PINNED_SHOWN
    return ", ".join(items) + (f" +{more}" if more > 0 else "") if items else "-"


def format_guidance(guidance) -> str:
    """The ranked table (mm), the refused candidates (one line each) and the stop line."""
    r, now = guidance.recorded, guidance.baseline
    where = {"held-out": "the other candidates' workspace (held out)",
             "sockets": "the other candidates' sockets (held out)"}.get(guidance_module.JUDGED_ON, "the same")
    what = ("predicted rms spread at the candidates' sockets (MUKCa's test MAE, with the sockets' noise "
            f"{now.noise * 1e3:.3g} mm)" if guidance_module.JUDGED_ON == "sockets"
            else "predicted rms tool-point error over the candidates' workspace")
    counts = sum(r.dataset.counts().values())
    lines = [
        f"recording so far: {len(r.dataset.fixture_names)} sockets, {counts} samples; calibration model "
        f"{r.model_choice}; measured noise {r.noise * 1e3:.3g} mm per axis",
        f"candidates: {len(guidance.ranking) + len(guidance.refused)}, {len(guidance.ranking)} recordable, "
        f"{guidance.per_socket} hand-guided configurations per socket",
        f"{what} [mm] now: {now.error * 1e3:.4f} "
        f"(parameters {now.parameters * 1e3:.4f}, unexplained {now.unexplained * 1e3:.4f}); each candidate's error "
        f"and gain over {where}",
        f"{'rank':>4} {'candidate':<16} {'x [m]':>7} {'y [m]':>7} {'z [m]':>7} | {'error':>7} {'gain':>7} "
        f"{'own':>7} | pins down (std ratio to now)   [own: the gain of the calibration's own error, the sockets' "
        "noise left out: what the last line weighs]",
    ]
    for k, j in enumerate(guidance.ranking):
        x, y, z = j.placement.centre
        lines.append(f"{k + 1:>4} {j.placement.name:<16} {x:7.3f} {y:7.3f} {z:7.3f} | {j.error * 1e3:7.4f} "
                     f"{mm_text(j.gain, '7.4f')} {mm_text(j.own_gain, '7.4f')} | {_pinned(j)}")
    lines.extend(f"refused: {j.reason}" for j in guidance.refused)
    lines.append(guidance.stop_line())
    return "\n".join(lines)


def guidance_json(guidance, provenance: dict | None = None) -> dict:
    """``plan.json``: ``ranking`` best first (``name``, ``predicted_error_m``, ``gain_m``, sockets [m],
    distances [m], pinned parameters), ``refused``, the recording's figures and the stop decision."""
    r = guidance.recorded

    def entry(j) -> dict:
        return {
            "name": j.placement.name,
            "predicted_error_m": j.error,
            "gain_m": j.gain,
            "own_gain_m": j.own_gain,
            "parameters_rms_m": j.parameters,
            "unexplained_rms_m": j.unexplained,
            "sockets": {k: [float(v) for v in p] for k, p in j.placement.sockets.items()},
            "distances": [[a, b, d] for a, b, d in j.placement.distances],
            "pinned": [{"parameter": n, "std_ratio": ratio} for n, ratio in j.pinned],
        }

    return {
        "ranking": [entry(j) for j in guidance.ranking],
        "refused": [{"name": j.placement.name, "reason": j.reason} for j in guidance.refused],
        "recorded": {
            "predicted_error_m": guidance.baseline.error,
            "noise_m": r.noise,
            "socket_noise_m": r.socket_noise,
            "joint_error_rad": r.joint_error,
            "judged_on": guidance_module.JUDGED_ON,
            "postures": guidance_module.POSTURES,
            "per_socket": r.per_socket,
            "model": r.model_choice,
            "samples_per_fixture": {k: int(v) for k, v in r.dataset.counts().items()},
        },
        "stop": {"worth_it": guidance.worth_it, "line": guidance.stop_line(), "noise_floor_m": guidance.floor,
                 "min_gain_m": guidance.min_gain},
        "configurations_per_socket": guidance.per_socket,
        "timings_s": dict(guidance.seconds),
        **({"provenance": provenance} if provenance else {}),
    }


def write_guidance_recording(path: str, guidance, info: dict | None = None) -> str:
    """The calibrated arm through the recorded configurations, the recorded sockets, and every candidate's
    sockets coloured by gain (:func:`validation.viewer.recording_shapes.colour_ramp`, 0 = the best gain;
    grey: refused), the best candidate's sockets marked and labelled (``world/next``: record it next, or not worth
    it), with the table as a text panel. ``info``: the run's provenance block (shown below the table; the recording id
    is derived from it, :func:`validation.viewer.recording.recording_id`), or None."""
    from spherecal.validation.viewer.recording import Recording  # Rerun: only for --rrd

    provenance = "" if info is None else comment_block(info)
    recording = Recording(path, application_id="spherecal_plan", title="Recorded sockets and candidates by gain",
                          run=info)
    try:
        r = guidance.recorded
        names = list(r.centres)
        recording.fixtures(names, np.array([r.centres[n] for n in names]))
        recording.samples(tool_point(r.model, r.dataset.q), r.dataset.labels)
        recording.self_motion(r.model, np.arange(r.dataset.n_samples, dtype=float), r.dataset.q)
        judged = guidance.ranking + guidance.refused
        points = np.array([p for j in judged for p in j.placement.sockets.values()])
        gains = np.array([j.gain for j in guidance.ranking])
        top = gains.max() if gains.size and gains.max() > 0 else 1.0
        colours = [colour_ramp(np.array([1.0 - max(j.gain, 0.0) / top]))[0] for j in guidance.ranking]
        colours += [np.array([150, 150, 150], np.uint8)] * len(guidance.refused)
        each = [len(j.placement.sockets) for j in judged]
        labels = [f"{j.placement.name} {mm_text(j.gain, '+.3f')} mm" if not j.reason else f"{j.placement.name} refused"
                  for j in judged for _ in j.placement.sockets]
        recording.stream.log("world/candidates", recording.rr.Points3D(
            points, colors=np.repeat(np.array(colours), each, axis=0), labels=labels, radii=0.012), static=True)
        if guidance.ranking:  # the colours' meaning beside what can be recorded: blue the most gain, red none
            steps = np.linspace(0.0, 1.0, SCALE_STEPS)
            grey = "\ngrey: refused" if guidance.refused else ""
            recording.colour_legend(
                "colour_scale", points[: sum(each[: len(guidance.ranking)])], colour_ramp(steps),
                scale_labels(max(gains.max(), 0.0) * 1e3, 0.0, lambda v: f"{v:+.4f} mm"),  # all red: none gains
                f"colour: the table's 'gain' [mm],\neach candidate recorded as well{grey}")
        if guidance.ranking:  # the camera frames what can be recorded, not a refused far-away candidate
            recording.extend_bounds("world", points[: sum(each[: len(guidance.ranking)])])
            # the answer, where a reviewer sees it: among dozens of candidates Rerun shows no label (a reviewer trial)
            best = guidance.ranking[0]
            verdict = "record next" if guidance.worth_it else "best, not worth recording"
            at = np.array(list(best.placement.sockets.values()))
            recording.stream.log("world/next", recording.rr.Points3D(
                at, colors=[255, 255, 255], radii=0.02, show_labels=True,
                labels=[f"{verdict}: {best.placement.name} ({mm_text(best.own_gain, '+.3f')} mm own)"]
                + [""] * (len(at) - 1)),  # once: the plate's sockets are centimetres apart, their labels stacked
                static=True)
        text = format_guidance(guidance)
        # the ranking first, the provenance below it (on top, the ranking began 15 lines down: h6's review)
        recording.text("plan", f"{text}\n\n{provenance}" if provenance else text,
                       "What to record next: candidates by predicted gain (mm)")
    except BaseException:
        recording.abort()
        raise
    return str(recording.close())
