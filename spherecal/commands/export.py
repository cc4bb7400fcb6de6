"""`spherecal export`: Export a calibrated robot file as URDF, MJCF or YAML."""

from __future__ import annotations

import argparse

from spherecal.options import add_seed, add_urdf_links, check_robot_names, given, urdf_links

HELP = "Export a calibrated robot file as URDF, MJCF or YAML."
FORMATS = ("urdf", "mjcf", "yaml")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal export`."""
    parser.add_argument("robot", metavar="CAL.yaml",
                        help="robot file to export (calibrated or nominal), a URDF (with --tip-link) or an embedded "
                        "arm: panda, fr3, iiwa14, gen3lite")
    add_urdf_links(parser)
    parser.add_argument("--format", choices=FORMATS, required=True,
                        help="output format; urdf (kinematics and the robot file's link inertials) holds the best "
                        "rigid fit to a model with joint compliance, mjcf the whole model (the rigid fit of one with "
                        "a joint-angle scale or a negative compliance, which a hinge cannot carry), yaml the whole "
                        "model")
    parser.add_argument("--out", required=True, metavar="FILE", help="output file (written atomically)")
    parser.add_argument(
        "--into",
        default=None,
        metavar="ORIGINAL.urdf",
        help="urdf only: write the calibration into this URDF of the same arm, changing only the joint "
        "origins of the calibrated chain and of the fixed joint into the tip link (meshes, inertials, "
        "gripper, limits, names kept)",
    )
    parser.add_argument(
        "--prefix",
        default=None,
        help="prefix of URDF link and joint names (default: panda_ for a Franka arm, else the robot's name, and "
        "the joints keep the names its description gave them); the MJCF keeps the plant's names",
    )
    parser.add_argument("--effort", default=None, metavar="E1,...,En",
                        help="URDF joint torque limits [Nm], comma-separated, each > 0 and at most 1e6 (ten times "
                        "the strongest industrial arm's shoulder) (default: Franka's for a Franka arm; required for "
                        "another arm)")
    parser.add_argument("--velocity", default=None, metavar="V1,...,Vn",
                        help="URDF joint velocity limits [rad/s], comma-separated, each > 0 and at most 100 (the "
                        "fastest robot joints turn about 63 rad/s) (default: Franka's for a Franka arm; required for "
                        "another arm)")
    parser.add_argument("--samples", default=None,
                        help="urdf only: samples.csv of recorded joint angles the rigid fit must match "
                        "(default: the samples file the calibration names, if unchanged)")
    add_seed(parser, "the rigid fit's workspace sample (a URDF of a model with joint-side terms, an MJCF of one a "
             "hinge cannot carry; refused for the others, which draw nothing)")


def run(args: argparse.Namespace) -> int:
    """Export (one library call: load, build, write; nothing is written unless the whole document was built)."""
    from spherecal.controller.export_file import ExportConfig, export_file
    from spherecal.options import planned_outputs

    check_robot_names(args, robot="CAL.yaml")  # an unknown robot name, by its positional CAL.yaml
    outputs = planned_outputs(args, {"--out": args.out})  # never over CAL.yaml, --into or --samples
    links = urdf_links(args)
    config = ExportConfig(
        robot=args.robot, output_format=args.format, out=args.out, into=args.into, prefix=args.prefix,
        effort=args.effort, velocity=args.velocity, samples=args.samples,
        seed=args.seed if "seed" in given(args) else None,  # refused where nothing random is drawn
        tip_link=links["tip_link"], base_link=links["base_link"], inertials=links["inertials"],
    )
    result = export_file(config, outputs, report=links["report"])
    model = result.model
    print(f"spherecal export: wrote {args.format} of {model.name!r} ({model.convention} DH) to {result.path}")
    for line in result.notes:
        print(f"spherecal export: {line}")
    return 0
