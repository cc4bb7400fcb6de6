"""`spherecal plan`: Rank candidate fixture positions by the calibration accuracy they predict."""

from __future__ import annotations

import argparse

from spherecal.options import check_per_fixture, fail, given, mark_given, recorded_options, refuse_given, urdf_links

HELP = ("Rank candidate fixture positions by the calibration accuracy they predict; with --samples, what to record "
        "next on a real arm")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal plan`."""
    from spherecal.options import MAX_PER_FIXTURE, add_robot, add_seconds, add_seed, add_workers, count, noise_mm

    add_robot(parser)
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--candidates", default=None,
                       help="YAML: candidates: {C1: {position: [x, y, z], joint_range: [share per joint]}} [m]; "
                            "with --samples also plate placements {left: {sockets: {a: [x, y, z], b: [x, y, z]}, "
                            "distances: [[a, b, metres]]}}")
    where.add_argument("--grid", default=None,
                       help="box grid 'xmin,xmax,nx;ymin,ymax,ny;zmin,zmax,nz' [m], or 'auto' (5 x 5 x 5 over where "
                            "the arm's tool point reaches in front of and above its base, x, z >= 0: any arm's size)")
    where.add_argument("--predict", default=None, metavar="SAMPLES_CSV",
                       help="instead of planning: predicted accuracy of this recorded or simulated data set")
    where.add_argument("--analysis", default=None, metavar="MARKDOWN",
                       help="instead of planning: regenerate the experiment-design analysis into this file "
                            "(docs/experiment_design.md)")
    parser.add_argument("--fixtures", default=None, action=_FixturesOption, metavar="FIXTURES_YAML",
                        help="fixtures.yaml of --predict or --samples: known positions [m] and distances [m]")
    _add_guidance(parser)
    parser.add_argument("--spec", dest="fixtures", default=None, help=argparse.SUPPRESS)  # the old name
    parser.add_argument("--fixture-count", type=count(1), default=3, metavar="N",
                        help="number of fixtures wanted, 1..4 (default 3)")
    parser.add_argument("--noise", type=noise_mm, default=0.3, help="fixture noise std per axis [mm] (default 0.3)")
    parser.add_argument("--per-fixture", type=count(1, MAX_PER_FIXTURE), default=500, metavar="N",
                        help="samples to be recorded per fixture (default 500)")
    parser.add_argument("--motion", choices=("kinematic", "controller"), default="kinematic",
                        help="self-motion at a candidate: kinematic projection (default, the whole manifold; one "
                             "hand-guided walk on an arm of 6 joints or fewer) or the null-space controller on the "
                             "MuJoCo plant for --seconds")
    add_seconds(parser, 3.0, "controller self-motion per candidate")
    add_seed(parser)
    parser.add_argument("--rrd", default=None, help="write a Rerun recording of the candidates coloured by score")
    parser.add_argument("--fixtures-out", default=None, metavar="FIXTURES_YAML",
                        help="in a plan from scratch: write the chosen fixtures as a fixtures.yaml for simulate "
                             "--fixtures (positions [m]; the distances to measure under 'plan:'); not for calibrate, "
                             "which would take the planned positions for measured centres")
    add_workers(parser, "candidates' surveys", also=" and for --analysis")


def _add_guidance(parser: argparse.ArgumentParser) -> None:
    """The options of recording guidance (``--samples``: what has been recorded on the real arm)."""
    from spherecal.options import count, non_negative

    parser.add_argument("--samples", default=None, action=_SamplesOption, metavar="SAMPLES_CSV",
                        help="samples.csv recorded so far: rank --candidates and --plate-grid placements by the "
                             "accuracy the calibration would reach with each recorded as well")
    parser.add_argument("--plate-grid", default=None, metavar="GRID",
                        help="with --samples: the recorded plate (its sockets' layout) centred at the points of the "
                             "box grid 'xmin,xmax,nx;ymin,ymax,ny;zmin,zmax,nz' [m], or 'auto' (5 x 5 over the reach "
                             "at the recorded plate's height, on its side of the base)")
    parser.add_argument("--plate-orientations", type=count(1, 12), default=2, metavar="N",
                        help="with --plate-grid: turns of the plate about the vertical per grid point (default 2)")
    parser.add_argument("--per-socket", type=count(1, 5000), default=None, metavar="N",
                        help="with --samples: configurations recorded per candidate socket (default: as many as "
                             "the recording has per socket)")
    parser.add_argument("--min-gain", type=non_negative, default=0.01,
                        help="with --samples: smallest gain worth another placement [mm] (default 0.01)")
    parser.add_argument("--out", default=None, metavar="PLAN_JSON",
                        help="with --samples: write the ranking (best first, predicted error [m]) as JSON")


class _SamplesOption(argparse.Action):
    """``--samples``: the recording so far (a samples.csv). Its old meaning here, a count (``--samples 500``),
    still works with a deprecation warning (now ``--per-fixture``)."""

    def __call__(self, parser, namespace, values, option_string=None):
        if values.strip().isdigit():
            from spherecal.options import MAX_PER_FIXTURE, count, warn

            warn("--samples is deprecated, use --per-fixture for a count (--samples names a samples.csv)")
            try:
                namespace.per_fixture = count(1, MAX_PER_FIXTURE)(values)
            except argparse.ArgumentTypeError as error:
                parser.error(f"argument {option_string}: {error}")
            mark_given(namespace, "per_fixture", option_string, values)
        else:
            namespace.samples = values
            mark_given(namespace, "samples", option_string, values)


class _FixturesOption(argparse.Action):
    """``--fixtures``: a fixtures.yaml file, as in every command. Its old meaning here, a count
    (``--fixtures 3``), still works with a deprecation warning (now ``--fixture-count``)."""

    def __call__(self, parser, namespace, values, option_string=None):
        if values.strip().isdigit():
            from spherecal.options import warn

            warn("--fixtures N (a count) is deprecated in plan, use --fixture-count N; --fixtures names a file")
            namespace.fixture_count = int(values)
            mark_given(namespace, "fixture_count", option_string, values)
        else:
            namespace.fixtures = values
            mark_given(namespace, "fixtures", option_string, values)


#: The robot and its URDF chain and inertials (argparse destinations).
_ROBOT = ("robot", "tip_link", "base_link", "inertials")
#: Per kind of run (:func:`_kind`): the options it uses (argparse destinations); any other given is refused.
USES = {
    "--analysis": ("analysis", "seed", "workers"),  # its own arms and settings; the built-in pool only
    "--predict": ("predict", *_ROBOT, "fixtures", "noise"),
    "--samples": ("samples", *_ROBOT, "fixtures", "candidates", "grid", "plate_grid", "plate_orientations",
                  "per_socket", "min_gain", "noise", "seed", "out", "rrd"),
    "a plan from scratch": (*_ROBOT, "candidates", "grid", "fixture_count", "noise", "per_fixture", "motion",
                            "seconds", "seed", "workers", "scheduler", "rrd", "fixtures_out"),
}


def _kind(args: argparse.Namespace) -> str:
    """Which run the options ask for: a key of :data:`USES`."""
    for option in ("--analysis", "--predict", "--samples"):
        if getattr(args, option[2:]) is not None:
            return option
    return "a plan from scratch"


def refuse_unused(args: argparse.Namespace) -> None:
    """Refuse a given option the run would not use, in one line naming it and the runs that use it ('field
    '--out': only with --samples, not in a plan from scratch'): a review found 'plan --out' without --samples
    accepted and nothing written.

    Raises:
        OptionError: such an option.
    """
    kind = _kind(args)
    for dest, option in given(args).items():
        if dest not in USES[kind]:
            users = [name for name, uses in USES.items() if dest in uses]
            where = f"with {kind}" if kind.startswith("--") else f"in {kind}"
            raise fail(f"field '{option}': only {' or '.join(_phrase(u) for u in users)}, not {where}")
    if kind == "a plan from scratch" and args.motion != "controller":
        refuse_given(args, ("seconds",), "only with --motion controller (the kinematic survey runs no controller)")
    if kind == "--samples" and args.plate_grid is None:
        refuse_given(args, ("plate_orientations",), "only with --plate-grid (the turns of the plate over its grid)")


def _phrase(kind: str) -> str:
    return f"with {kind}" if kind.startswith("--") else f"in {kind} (no --analysis, --predict or --samples)"


def run(args: argparse.Namespace) -> int:
    """Plan (or predict, or regenerate the analysis, or guide the recording) and print the result."""
    import time

    from spherecal.options import check_robot_names, planned_outputs
    from spherecal.validation.planning import plan_files

    refuse_unused(args)
    check_robot_names(args)  # an unknown robot name, by its option
    check_per_fixture(args, 10, simulated=False)
    outputs = planned_outputs(args, {"--rrd": args.rrd, "--analysis": args.analysis, "--out": args.out,
                                     "--fixtures-out": args.fixtures_out})
    plan_files.refuse_foreign_outputs({"--out": args.out, "--analysis": args.analysis, "--rrd": args.rrd,
                                       "--fixtures-out": args.fixtures_out})
    if args.analysis is not None:
        from spherecal.validation.planning.analysis import AnalysisConfig, write_analysis

        with outputs:
            write_analysis(outputs.stage(args.analysis), AnalysisConfig(seed=args.seed, workers=args.workers))
        print(f"written: {args.analysis}")
        return 0
    links = urdf_links(args)
    if args.predict is not None:
        from spherecal.validation.planning.plan_report import format_prediction

        print(format_prediction(plan_files.predict_files(args.robot, args.predict, args.fixtures, args.noise * 1e-3,
                                                         **links)))
        return 0
    if args.samples is not None:
        from spherecal.validation.planning.guidance_report import format_guidance

        plan_files.guide_files(
            args.robot, args.samples, args.fixtures, args.candidates, args.plate_grid, args.plate_orientations,
            args.per_socket, args.min_gain * 1e-3, args.noise * 1e-3, args.seed, recorded_options(args), args.out,
            args.rrd, outputs, grid=args.grid, show=lambda guidance: print(format_guidance(guidance)), **links)
        for name in (args.out, args.rrd):
            if name:
                print(f"written: {name}")
        return 0
    from spherecal.validation.planning.plan_report import format_plan

    start = time.perf_counter()
    result = plan_files.plan_files(
        args.robot, args.candidates, args.grid, args.fixture_count, args.seed, args.noise * 1e-3, args.per_fixture,
        args.motion, args.seconds, recorded_options(args), args.workers, args.scheduler, args.rrd, outputs,
        show=lambda result: print(format_plan(result)), fixtures_out=args.fixtures_out, **links)
    for name in (args.rrd, args.fixtures_out):
        if name:
            print(f"written: {name}")
    print(f"wall time {time.perf_counter() - start:.1f} s (survey {result.seconds['survey']:.1f} s, "
          f"scoring {result.seconds['score']:.1f} s, motion: {result.motion})")
    return 0
