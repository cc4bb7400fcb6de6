"""`spherecal import`: Turn a real recording (MUKCa folder, ROS bag, joint CSV) into samples.csv and fixtures.yaml."""

from __future__ import annotations

import argparse

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
    parser.add_argument("--topic", default="/joint_states", help="bag: sensor_msgs/JointState topic (/joint_states)")
    parser.add_argument(
        "--distance", type=at_most(10.0, "m"), default=0.050,
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
    group = parser.add_argument_group(
        "segmentation (bag, csv without a 'fixture' column): a fixture is where the NOMINAL tool point stays "
        "still; defaults measured on MUKCa's real Panda (nominal spread in a socket: 8 mm mean, 19 mm max)"
    )
    group.add_argument("--window", type=duration, default=0.5, help="stillness window [s] (default 0.5)")
    group.add_argument("--still-radius", type=segment_mm, default=3.0,
                       help="tool point within this of itself over a window [mm] (default 3)")
    group.add_argument("--min-duration", type=duration, default=2.0, help="shortest fixture [s] (default 2)")
    group.add_argument("--min-configurations", type=count(1), default=20,
                       help="fewest distinct configurations of a fixture (default 20)")
    group.add_argument("--max-spread", type=segment_mm, default=20.0,
                       help="refuse a fixture drifting further from its mean [mm] (default 20)")
    group.add_argument("--min-separation", type=segment_mm, default=30.0,
                       help="refuse two fixtures closer than this [mm] (default 30)")


def run(args: argparse.Namespace) -> int:
    """Import: read, label (or segment), deduplicate, subsample, then write both files together."""
    import time

    import numpy as np

    from spherecal.correction.files.samples import DEDUP_TOL
    from spherecal.identification.ingest.import_recording import ImportOptions, import_files
    from spherecal.identification.ingest.segment import SegmentSettings
    from spherecal.options import urdf_links

    clock = time.perf_counter()
    options = ImportOptions(
        topic=args.topic,
        distance=args.distance,
        rate=args.rate,
        segmentation=SegmentSettings(
            window=args.window,
            still_radius=args.still_radius * 1e-3,
            min_duration=args.min_duration,
            min_configurations=args.min_configurations,
            max_spread=args.max_spread * 1e-3,
            min_separation=args.min_separation * 1e-3,
        ),
        max_per_fixture=args.max_per_fixture,
        dedup_tol=DEDUP_TOL if args.dedup_deg is None else float(np.deg2rad(args.dedup_deg)),
        seed=args.seed,
    )
    result = import_files(args.source, args.format, args.robot, args.out, options, urdf_links(args))
    print(result.format())
    print(f"wrote {args.out}/samples.csv and {args.out}/fixtures.yaml in {time.perf_counter() - clock:.2f} s")
    return 0
