"""`spherecal import`: Turn a real recording (MUKCa folder, ROS bag, joint CSV) into samples.csv and fixtures.yaml."""

from __future__ import annotations

import argparse

from spherecal.options import check_folder, check_robot_names, fail, named, urdf_links

HELP = "Turn a real recording (MUKCa folder, ROS bag, joint CSV) into samples.csv and fixtures.yaml."

FORMATS = ("mukca", "bag", "csv")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal import`."""
    from spherecal.options import add_robot, add_seed, at_most, count, duration, segment_mm

    parser.add_argument(
        "source",
        metavar="SOURCE",
        help="mukca: a placement folder (hole_0.csv, hole_1.csv) or a folder of them; bag: a ROS 2 bag folder "
        "(sqlite3 or MCAP) or a ROS 1 .bag file; csv: a CSV whose header names the joints",
    )
    parser.add_argument("--format", required=True, choices=FORMATS, help="what SOURCE is")
    add_robot(parser, default=None)
    parser.add_argument("--out", required=True, help="folder to create with samples.csv and fixtures.yaml")
    # the format-specific options default to None: given for another format, they are refused (see run)
    parser.add_argument("--topic", default=None, help="bag: sensor_msgs/JointState topic (/joint_states)")
    parser.add_argument(
        "--distance", type=at_most(10.0, "m"), default=None,
        help="mukca: socket centre distance per placement [m] (default 0.050)",
    )
    parser.add_argument("--max-per-fixture", type=count(1), default=500, metavar="N",
                        help="keep at most N samples per fixture (default 500)")
    parser.add_argument(
        "--dedup-deg", type=at_most(10.0, "deg", allow_zero=True), default=None,
        help="drop samples within this of an earlier one, every joint [deg] (default 0.00573 = 1e-4 rad)",
    )
    add_seed(parser, "the subsampling")
    parser.add_argument(
        "--rate", type=at_most(1e6, "Hz"), default=None,
        help="csv without a time column: sampling rate [Hz] (default 1000); a recording's time column is used "
        "instead, with a warning when --rate is given",
    )
    parser.add_argument(
        "--fixture", action="append", type=_span, default=None, metavar="NAME=START:END",
        help="bag, csv without a 'fixture' column: label the samples from START to END seconds after the recording's "
        "first sample [s] (the clock of the import's table) as fixture NAME, instead of segmenting; repeat it for each "
        "socket (a NAME given twice is one socket visited twice); samples in no span are dropped",
    )
    parser.add_argument(
        "--known-distance", action="append", nargs=3, default=None, metavar=("A", "B", "METRES"),
        help="the measured distance between the centres of fixtures A and B [m], written into fixtures.yaml (it gives "
        "calibrate the arm's absolute scale); the names as this import gives them: --fixture's, a CSV's fixture "
        "column's, S1, S2, ... in recording order when segmented, MUKCa's PLACEMENT_h0/_h1; repeat it for each pair",
    )
    group = parser.add_argument_group(
        "segmentation (bag, csv without a 'fixture' column): a fixture is where the NOMINAL tool point stays "
        "still; defaults measured on MUKCa's real Panda (nominal spread in a socket: 8 mm mean, 19 mm max)"
    )
    group.add_argument("--window", type=duration, default=None, help="stillness window [s] (default 0.5)")
    group.add_argument("--still-radius", type=segment_mm, default=None,
                       help="tool point within this of itself over a window [mm] (default 3)")
    group.add_argument("--min-duration", type=duration, default=None, help="shortest fixture [s] (default 2)")
    group.add_argument("--min-configurations", type=count(1), default=None,
                       help="fewest distinct configurations of a fixture (default 20)")
    group.add_argument("--max-spread", type=segment_mm, default=None,
                       help="refuse a fixture drifting further from its mean [mm] (default 20)")
    group.add_argument("--min-separation", type=segment_mm, default=None,
                       help="refuse two fixtures closer than this [mm] (default 30)")


def _span(text: str) -> tuple[str, float, float]:
    """``--fixture NAME=START:END``: a fixture name and a time span [s] since the recording's first sample."""
    import math

    from spherecal.correction.files.fixtures import _name_problem

    name, equals, span = text.rpartition("=")
    start, colon, end = span.partition(":")
    try:
        values = (float(start), float(end)) if equals and colon else None
    except ValueError:
        values = None
    if values is None or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"expected NAME=START:END, seconds since the recording's first sample "
                                         f"(S1=6.5:25.5), got {text!r}")
    problem = _name_problem(name)
    if problem:
        raise argparse.ArgumentTypeError(f"the fixture name {name!r} {problem}")
    if not 0 <= values[0] < values[1]:
        raise argparse.ArgumentTypeError(f"expected 0 <= START < END [s], got {text!r}")
    return name, values[0], values[1]


def _known_distance(a: str, b: str, metres: str) -> tuple[str, str, float]:
    """``--known-distance A B METRES``: two fixture names and their centres' distance [m] (0 < METRES <= 10)."""
    import math

    try:
        value = float(metres)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and 0.0 < value <= 10.0):
        raise fail(f"field '--known-distance': {a} {b} {metres}: expected a distance in metres, above 0 and at most "
                   "10 (A B METRES)")
    if a == b:
        raise fail(f"field '--known-distance': {a} {b} {metres}: a fixture's distance to itself")
    return a, b, value


#: Segmentation options given in millimetres (:class:`SegmentSettings` holds metres).
MILLIMETRES = ("still_radius", "max_spread", "min_separation")


def run(args: argparse.Namespace) -> int:
    """Import: read, label (or segment), deduplicate, subsample, then write both files together."""
    import time
    from dataclasses import fields

    import numpy as np

    from spherecal.correction.files.samples import DEDUP_TOL
    from spherecal.identification.ingest.import_recording import ImportOptions, import_files
    from spherecal.identification.ingest.segment import SegmentSettings

    check_robot_names(args)  # an unknown robot name, by its option
    check_folder(args.out, writes=("samples.csv", "fixtures.yaml"))
    clock = time.perf_counter()
    given = _format_options(args, [f.name for f in fields(SegmentSettings)])
    segmentation = {k: v * 1e-3 if k in MILLIMETRES else v for k, v in given.pop("segmentation", {}).items()}
    options = ImportOptions(
        **given,
        known_distances=tuple(_known_distance(*triple) for triple in args.known_distance or ()),
        segmentation=SegmentSettings(**segmentation),
        max_per_fixture=args.max_per_fixture,
        dedup_tol=DEDUP_TOL if args.dedup_deg is None else float(np.deg2rad(args.dedup_deg)),
        seed=args.seed,
    )
    result = import_files(args.source, args.format, args.robot, args.out, options, urdf_links(args))
    print(result.format())
    print(f"wrote {args.out}/samples.csv and {args.out}/fixtures.yaml in {time.perf_counter() - clock:.2f} s")
    return 0


def _format_options(args: argparse.Namespace, segmentation: list[str]) -> dict:
    """The format-specific options given, as :class:`ImportOptions` takes them (``segmentation``: the thresholds
    given, as typed); the others keep the library's defaults.

    Raises:
        OptionError: an option given that the chosen format does not use (``--topic`` with ``--format mukca``),
            one line naming it and the formats it applies to.
    """
    from spherecal.identification.ingest.import_recording import FORMAT_OPTIONS  # numpy: not at --help

    dests = {"topic": ["topic"], "distance": ["distance"], "rate": ["rate"], "segmentation": segmentation,
             "spans": ["fixture"]}
    given: dict = {}
    for name, formats in FORMAT_OPTIONS.items():
        typed = {dest: getattr(args, dest) for dest in dests[name] if getattr(args, dest) is not None}
        if typed and args.format not in formats:
            raise fail(f"field '{named(args, next(iter(typed)))}': applies to --format {' or '.join(formats)} only, "
                       f"not {args.format}; leave it out")
        if typed:
            given[name] = (typed if name == "segmentation" else tuple(typed["fixture"]) if name == "spans"
                           else typed[name])
    if "spans" in given and "segmentation" in given:
        raise fail(f"field '{named(args, next(iter(given['segmentation'])))}': the fixtures are labelled by --fixture, "
                   "nothing is segmented; leave it out")
    return given
