"""`spherecal plan`: Rank candidate fixture positions by the calibration accuracy they predict."""

from __future__ import annotations

import argparse

from spherecal.options import fail, urdf_links

HELP = "Rank candidate fixture positions by the calibration accuracy they predict."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal plan`."""
    from spherecal.options import add_per_fixture, add_robot, add_seconds, add_seed, count, noise_mm

    add_robot(parser)
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--candidates", default=None,
                       help="YAML: candidates: {C1: {position: [x, y, z], joint_range: [share per joint]}} [m]")
    where.add_argument("--grid", default=None, help="box grid 'xmin,xmax,nx;ymin,ymax,ny;zmin,zmax,nz' [m]")
    where.add_argument("--predict", default=None, metavar="SAMPLES_CSV",
                       help="instead of planning: predicted accuracy of this recorded or simulated data set")
    where.add_argument("--analysis", default=None, metavar="MARKDOWN",
                       help="instead of planning: regenerate the experiment-design analysis into this file "
                            "(docs/experiment_design.md)")
    parser.add_argument("--fixtures", default=None, action=_FixturesOption, metavar="FIXTURES_YAML",
                        help="fixtures.yaml of --predict: known positions [m] and distances [m]")
    parser.add_argument("--spec", dest="fixtures", default=None, help=argparse.SUPPRESS)  # the old name
    parser.add_argument("--fixture-count", type=count(1), default=3, metavar="N",
                        help="number of fixtures wanted, 1..4 (default 3)")
    parser.add_argument("--noise", type=noise_mm, default=0.3, help="fixture noise std per axis [mm] (default 0.3)")
    add_per_fixture(parser, 500, "samples to be recorded per fixture")
    parser.add_argument("--motion", choices=("kinematic", "controller"), default="kinematic",
                        help="self-motion at a candidate: kinematic projection (default, the whole manifold) or "
                             "the null-space controller on the MuJoCo plant for --seconds")
    add_seconds(parser, 3.0, "controller self-motion per candidate")
    add_seed(parser)
    parser.add_argument("--rrd", default=None, help="write a Rerun recording of the candidates coloured by score")
    parser.add_argument("--workers", type=count(1, 64), default=2, help="worker processes of --analysis (default 2)")


class _FixturesOption(argparse.Action):
    """``--fixtures``: a fixtures.yaml file, as in every command. Its old meaning here, a count
    (``--fixtures 3``), still works with a deprecation warning (now ``--fixture-count``)."""

    def __call__(self, parser, namespace, values, option_string=None):
        if values.strip().isdigit():
            from spherecal.options import warn

            warn("--fixtures N (a count) is deprecated in plan, use --fixture-count N; --fixtures names a file")
            namespace.fixture_count = int(values)
        else:
            namespace.fixtures = values


def run(args: argparse.Namespace) -> int:
    """Plan (or predict, or regenerate the analysis) and print the result."""
    import time

    import numpy as np

    from spherecal.correction import load_robot

    if args.per_fixture < 10:
        raise fail(f"--per-fixture must be >= 10, got {args.per_fixture}")
    from spherecal.options import planned_outputs

    outputs = planned_outputs(args, {"--rrd": args.rrd, "--analysis": args.analysis})
    if args.analysis is not None:
        from spherecal.validation.planning.analysis import AnalysisConfig, write_analysis

        with outputs:
            write_analysis(outputs.stage(args.analysis), AnalysisConfig(seed=args.seed, workers=args.workers))
        print(f"written: {args.analysis}")
        return 0
    model = load_robot(args.robot, **urdf_links(args))
    rng = np.random.default_rng(args.seed)
    if args.predict is not None:
        return _predict(args, model)
    from spherecal.validation.planning.candidates import grid_candidates, read_candidates
    from spherecal.validation.planning.plan import plan

    if args.candidates is None and args.grid is None:
        raise fail("give --candidates C.yaml or --grid 'xmin,xmax,nx;ymin,ymax,ny;zmin,zmax,nz'")
    candidates = read_candidates(args.candidates, model.n_joints) if args.candidates else grid_candidates(args.grid)
    if not 1 <= args.fixture_count <= 4:
        raise fail(f"--fixture-count must be in 1..4, got {args.fixture_count}")
    start = time.perf_counter()
    result = plan(
        model, candidates, args.fixture_count, rng, args.noise * 1e-3, args.per_fixture, args.motion, args.seconds
    )
    from spherecal.validation.planning.plan_report import format_plan, write_recording

    print(format_plan(result))
    if result.best is None:  # the table above says which candidates failed; the refusal is one line on stderr
        reachable = sum(s.reachable for s in result.surveys)
        raise fail(f"no plan: {reachable} of {len(result.surveys)} candidates reachable, fewer than the "
                   f"{args.fixture_count} fixtures wanted (--fixture-count)")
    if args.rrd:
        from spherecal.validation.provenance import comment_block, provenance

        inputs = {k: v for k, v in vars(args).items() if not k.startswith("_") and k != "command"}
        with outputs:  # staged, renamed into place once Rerun has written it all
            write_recording(outputs.stage(args.rrd), result, comment_block(provenance(args.seed, inputs)))
        print(f"written: {args.rrd}")
    print(f"wall time {time.perf_counter() - start:.1f} s (survey {result.seconds['survey']:.1f} s, "
          f"scoring {result.seconds['score']:.1f} s, motion: {result.motion})")
    return 0 if result.best is not None else 1


def _predict(args: argparse.Namespace, model) -> int:
    from spherecal.correction.files.fixtures import read_fixtures
    from spherecal.correction.files.samples_csv import read_samples
    from spherecal.identification.prediction import predict_accuracy

    dataset = read_samples(args.predict, model)
    spec = read_fixtures(args.fixtures) if args.fixtures else None
    print(predict_accuracy(model, dataset, spec, noise=args.noise * 1e-3).summary())
    return 0
