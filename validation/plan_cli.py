"""`spherecal plan`: Rank candidate fixture positions by the calibration accuracy they predict."""

from __future__ import annotations

import argparse

HELP = "Rank candidate fixture positions by the calibration accuracy they predict."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal plan`."""
    from spherecal.identification.options import non_negative, positive, seed

    parser.add_argument("--robot", default="panda", help="nominal robot file or 'panda' (default)")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--candidates", default=None,
                       help="YAML: candidates: {C1: {position: [x, y, z], joint_range: [share per joint]}} [m]")
    where.add_argument("--grid", default=None, help="box grid 'xmin,xmax,nx;ymin,ymax,ny;zmin,zmax,nz' [m]")
    where.add_argument("--predict", default=None, metavar="SAMPLES_CSV",
                       help="instead of planning: predicted accuracy of this recorded or simulated data set")
    where.add_argument("--analysis", default=None, metavar="MARKDOWN",
                       help="instead of planning: regenerate the experiment-design analysis into this file "
                            "(docs/experiment_design.md)")
    parser.add_argument("--spec", default=None, help="fixtures.yaml of --predict (known positions, distances)")
    parser.add_argument("--fixtures", type=int, default=3, help="number of fixtures wanted, 1..4 (default 3)")
    parser.add_argument("--noise", type=non_negative, default=0.3, help="fixture noise std per axis [mm] (default 0.3)")
    parser.add_argument("--samples", type=int, default=500, help="samples to be recorded per fixture (default 500)")
    parser.add_argument("--motion", choices=("kinematic", "controller"), default="kinematic",
                        help="self-motion at a candidate: kinematic projection (default, the whole manifold) or "
                             "the null-space controller on the MuJoCo plant for --seconds")
    parser.add_argument("--seconds", type=positive, default=3.0, help="controller self-motion per candidate [s] (3)")
    parser.add_argument("--seed", type=seed, default=0, help="seed of everything random (default 0)")
    parser.add_argument("--rrd", default=None, help="write a Rerun recording of the candidates coloured by score")
    parser.add_argument("--workers", type=int, default=2, help="worker processes of --analysis (2)")


def _fail(message: str):
    from spherecal.correction.errors import SpherecalError

    return SpherecalError(message)


def run(args: argparse.Namespace) -> int:
    """Plan (or predict, or regenerate the analysis) and print the result."""
    import time

    import numpy as np

    from spherecal.correction import load_robot

    if not args.noise >= 0:
        raise _fail(f"--noise must be >= 0, got {args.noise}")
    if args.samples < 10:
        raise _fail(f"--samples must be >= 10, got {args.samples}")
    if not args.seconds > 0:
        raise _fail(f"--seconds must be > 0, got {args.seconds}")
    from spherecal.validation.inputs import check_out_file

    for option, path in (("--rrd", args.rrd), ("--analysis", args.analysis)):
        if path is not None:
            check_out_file(path, option)
    if args.analysis is not None:
        from spherecal.validation.analysis import AnalysisConfig, write_analysis

        path = write_analysis(args.analysis, AnalysisConfig(seed=args.seed, workers=args.workers))
        print(f"written: {path}")
        return 0
    model = load_robot(args.robot)
    rng = np.random.default_rng(args.seed)
    if args.predict is not None:
        return _predict(args, model)
    from spherecal.validation.plan import grid_candidates, plan, read_candidates

    if args.candidates is None and args.grid is None:
        raise _fail("give --candidates C.yaml or --grid 'xmin,xmax,nx;ymin,ymax,ny;zmin,zmax,nz'")
    candidates = read_candidates(args.candidates, model.n_joints) if args.candidates else grid_candidates(args.grid)
    if not 1 <= args.fixtures <= 4:
        raise _fail(f"--fixtures must be in 1..4, got {args.fixtures}")
    start = time.perf_counter()
    result = plan(model, candidates, args.fixtures, rng, args.noise * 1e-3, args.samples, args.motion, args.seconds)
    print(format_plan(result))
    if args.rrd:
        from spherecal.validation.provenance import comment_block, provenance

        inputs = {k: v for k, v in vars(args).items() if not k.startswith("_") and k != "command"}
        path = write_recording(args.rrd, result, comment_block(provenance(args.seed, inputs)))
        print(f"written: {path}")
    print(f"wall time {time.perf_counter() - start:.1f} s (survey {result.seconds['survey']:.1f} s, "
          f"scoring {result.seconds['score']:.1f} s, motion: {result.motion})")
    return 0 if result.best is not None else 1


def _predict(args: argparse.Namespace, model) -> int:
    from spherecal.correction.fixtures import read_fixtures
    from spherecal.correction.samples_csv import read_samples
    from spherecal.identification.prediction import predict_accuracy

    dataset = read_samples(args.predict, model)
    spec = read_fixtures(args.spec) if args.spec else None
    print(predict_accuracy(model, dataset, spec, noise=args.noise * 1e-3).summary())
    return 0


def format_plan(result) -> str:
    """The ranked candidate table and the chosen set (mm, %)."""
    lines = [
        f"{len(result.surveys)} candidates, {sum(s.reachable for s in result.surveys)} reachable; "
        f"self-motion: {result.motion}; noise {result.noise * 1e3:.3g} mm, {result.samples} samples per fixture",
        "predicted mean / 95th percentile tool-point error after registration [mm] of each candidate ALONE "
        "(scale from the nominal model), and the share of each joint's range its self-motion covers [%]",
        f"{'rank':>4} {'name':<8} {'x':>7} {'y':>7} {'z':>7} | {'mean':>7} {'p95':>7} | "
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
    import numpy as np

    from spherecal.validation.recording import Recording

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
