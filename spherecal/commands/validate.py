"""`spherecal validate`: Compare nominal and calibrated models against the truth, mocap data or socket samples.

Without ``--truth`` and ``--mocap``, ``--samples`` (and ``--fixtures``) alone: the socket-only check of
:mod:`spherecal.validation.sockets` (tool-point spread per socket, known-distance errors).
"""

from __future__ import annotations

import argparse

from spherecal.options import check_robot_names, recorded_options, refuse_given, start_viewer, urdf_links

HELP = "Compare nominal and calibrated models against the truth, motion-capture data or socket samples alone."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal validate`."""
    from spherecal.options import add_deprecated, add_seed, add_urdf_links, configurations, noise_mm

    parser.add_argument("--truth", help="robot file of the true robot (simulation)")
    parser.add_argument("--nominal", required=True,
                        help="nominal model, as calibrate's --robot: a robot file (YAML), a URDF (.urdf, with "
                        "--tip-link) or an embedded arm: panda, fr3, iiwa14, gen3lite")
    parser.add_argument("--calibrated", required=True,
                        help="calibrated model: calibrate's --out (a URDF export of it records no training "
                        "samples: every socket then counts as held out)")
    add_urdf_links(parser)
    parser.add_argument("--mocap", help="recorded mocap CSV: [t,] q1..qn, x, y, z (tool point in the mocap frame, m)")
    parser.add_argument(
        "--samples",
        help="samples.csv: with --truth, self-motion sets to validate on as well; alone (no --truth, no --mocap), "
        "socket samples NOT used in the fit: spread per socket and known-distance errors, no mocap needed",
    )
    parser.add_argument("--fixtures", help="fixtures.yaml of --samples (known distances [m]) for the socket-only check")
    parser.add_argument("--configurations", type=configurations, default=5000,
                        help="random workspace configurations (default 5000)")
    parser.add_argument("--mocap-noise", type=noise_mm, default=0.3,
                        help="simulated motion-capture marker noise std [mm] (default 0.3)")
    add_deprecated(parser, "--noise", "--mocap-noise", noise_mm)
    add_seed(parser, "the simulated mocap")
    parser.add_argument("--out", help="write the report as JSON (metres) to this file")
    parser.add_argument("--rrd", help="save a Rerun recording to this file")
    parser.add_argument("--spawn", action="store_true", help="stream to a live Rerun viewer")


def run(args: argparse.Namespace) -> int:
    """Validate (one library call: read, check, compare, write), printing the tables before the files appear."""
    from spherecal.options import planned_outputs
    from spherecal.validation.validate_files import ValidateConfig, validate_files

    if args.truth is None or args.mocap is not None:  # a review: '--configurations' without --truth did nothing
        refuse_given(args, ("configurations", "mocap_noise", "seed"),
                     "only with --truth and no --mocap (it sets the simulated motion capture)")
    check_robot_names(args)  # an unknown robot name, by its option
    links = urdf_links(args)
    config = ValidateConfig(
        nominal=args.nominal, calibrated=args.calibrated, truth=args.truth, mocap=args.mocap, samples=args.samples,
        fixtures=args.fixtures, configurations=args.configurations, noise=args.mocap_noise * 1e-3, seed=args.seed,
        out=args.out, rrd=args.rrd, spawn=args.spawn, tip_link=links["tip_link"], base_link=links["base_link"],
        inertials=links["inertials"], options=recorded_options(args),
    )
    outputs = planned_outputs(args, {"--out": args.out, "--rrd": args.rrd})
    start_viewer(args, "or write the recording with --rrd FILE and open it elsewhere")
    validate_files(config, outputs, show=_show, report=links["report"])
    if args.out:
        print(f"report: {args.out}")
    if args.rrd:
        print(f"recording: {args.rrd}")
    return 0


def _show(report) -> None:
    """Print a validation's tables: the comparison (and the parameter deviations from a truth) or the sockets'."""
    print(report.format())
    if getattr(report, "deviations", None) is not None:
        print("\nparameter deviations from the truth:\n" + report.deviations.format())
