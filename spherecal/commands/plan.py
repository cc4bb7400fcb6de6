"""`spherecal plan`: Rank candidate fixture positions by the calibration accuracy they predict."""

from __future__ import annotations

import argparse

from spherecal import options as _options

HELP = "Rank candidate fixture positions by the calibration accuracy they predict."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal plan`."""
    from spherecal.options import non_negative, positive, seed

    parser.add_argument("--robot", default="panda", help="nominal robot file, URDF (.urdf) or 'panda' (default)")
    _options.add_urdf_links(parser)
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
    model = load_robot(args.robot, **_options.urdf_links(args))
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
    from spherecal.validation.plan_report import format_plan, write_recording

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
