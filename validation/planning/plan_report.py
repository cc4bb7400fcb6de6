"""The plan for humans: the ranked candidate table and a Rerun recording of the candidates."""

from __future__ import annotations

import numpy as np

from spherecal.validation.viewer.recording import Recording


def format_plan(result) -> str:
    """The ranked candidate table and the chosen set (mm, %)."""
    lines = [
        f"{len(result.surveys)} candidates, {sum(s.reachable for s in result.surveys)} reachable; "
        f"self-motion: {result.motion}; noise {result.noise * 1e3:.3g} mm, {result.samples} samples per fixture",
        "predicted mean / 95th percentile tool-point error after registration [mm] of each candidate ALONE "
        "(scale from the nominal model), and the share of each joint's range its self-motion covers [%]",
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
    return "\n".join(lines)


def write_recording(path: str, result, provenance: str = "") -> str:
    """The candidates coloured by predicted error alone (green good, red poor, grey unreachable),
    the chosen set as the fixtures (labelled spheres), the printed plan and its provenance as a
    table, in the layout of every recording (:mod:`validation.blueprint`)."""
    title = "Candidate fixtures, coloured by predicted error"
    recording = Recording(path, application_id="spherecal_plan", title=title)
    try:
        rr = recording.rr
        surveys = result.surveys
        positions = np.array([s.candidate.position for s in surveys])
        values = np.array([s.alone.mean if s.alone is not None else np.nan for s in surveys])
        ok = np.isfinite(values)
        colours = np.tile([150, 150, 150], (len(surveys), 1))
        if ok.any():
            span = np.ptp(np.log(values[ok])) or 1.0
            share = (np.log(values[ok]) - np.log(values[ok]).min()) / span
            colours[ok] = np.stack([255 * share, 255 * (1 - share), 40 + 0 * share], axis=1)
        labels = [f"{s.candidate.name} {v * 1e3:.3f} mm" if np.isfinite(v) else f"{s.candidate.name} unreachable"
                  for s, v in zip(surveys, values, strict=True)]
        recording.stream.log("world/candidates", rr.Points3D(positions, colors=colours.astype(np.uint8),
                                                             labels=labels, radii=0.01), static=True)
        recording.extend_bounds("world", positions)
        if result.best is not None:
            chosen = [s.candidate for s in surveys if s.candidate.name in result.best.names]
            recording.fixtures([c.name for c in chosen], np.array([c.position for c in chosen]))
        text = f"{provenance}\n\n{format_plan(result)}" if provenance else format_plan(result)
        recording.text("plan", text, "The plan: candidates ranked by predicted error (mm)")
    except BaseException:
        recording.abort()
        raise
    return str(recording.close())
