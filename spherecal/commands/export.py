"""`spherecal export`: Export a calibrated robot file as URDF, MJCF or YAML."""

from __future__ import annotations

import argparse

from spherecal.options import add_seed, add_urdf_links, urdf_links

HELP = "Export a calibrated robot file as URDF, MJCF or YAML."
FORMATS = ("urdf", "mjcf", "yaml")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal export`."""
    parser.add_argument("robot", metavar="CAL.yaml", help="robot file to export (calibrated or nominal), or 'panda'")
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
        help="prefix of URDF link and joint names (default: panda_); the MJCF keeps the plant's names",
    )
    parser.add_argument("--effort", default=None, metavar="E1,...,En",
                        help="URDF joint torque limits [Nm], comma-separated (default: Franka's, 7-joint arms)")
    parser.add_argument("--velocity", default=None, metavar="V1,...,Vn",
                        help="URDF joint velocity limits [rad/s], comma-separated (default: Franka's, 7-joint arms)")
    parser.add_argument("--samples", default=None,
                        help="urdf only: samples.csv of recorded joint angles the rigid fit must match "
                        "(default: the samples file the calibration names, if unchanged)")
    add_seed(parser, "the rigid fit's workspace sample")


def _limits(text: str | None, option: str) -> list[float] | None:
    """A comma-separated option as floats (None when not given)."""
    from spherecal.options import fail

    if text is None:
        return None
    try:
        return [float(v) for v in text.split(",")]
    except ValueError:
        raise fail(f"{option}: expected comma-separated numbers, got {text!r}") from None


def _into(into: str, out: str) -> tuple[str, str]:
    """The text of ``--into`` and its name; refused when ``--out`` would overwrite it."""
    import os
    from pathlib import Path

    from spherecal.correction.files.text_input import read_xml_text
    from spherecal.correction.files.urdf_write import ExportError

    source = Path(into)
    text = read_xml_text(source, ExportError)  # in the encoding it declares, written back in it
    if Path(out).resolve() == source.resolve() or (Path(out).exists() and os.path.samefile(out, source)):
        raise ExportError(f"--out: {out} is the --into file; write the calibrated URDF to another file")
    return text, str(source)


def run(args: argparse.Namespace) -> int:
    """Load, export; nothing is written unless the whole document was built."""
    from pathlib import Path

    from spherecal.controller.export import export_model, provenance_header
    from spherecal.correction import load_robot
    from spherecal.options import planned_outputs

    outputs = planned_outputs(args, {"--out": args.out})  # never over CAL.yaml, --into or --samples
    from spherecal.correction.files.outputs import check_suffix

    written, accepted = {"urdf": ("a URDF", (".urdf", ".xml")), "mjcf": ("an MJCF model", (".xml", ".mjcf")),
                         "yaml": ("a robot file (YAML)", (".yaml", ".yml"))}[args.format]
    check_suffix(args.out, "--out", f"{written} (--format {args.format})", accepted)
    model = load_robot(args.robot, **urdf_links(args))
    from spherecal.correction.files.robot_file import forced_calibration

    forced = forced_calibration(model)
    if forced:
        import warnings

        warnings.warn(forced, stacklevel=1)
    into = None if args.into is None else _into(args.into, args.out)
    exported = export_model(model, args.format, provenance_header(args.robot, args.format), args.prefix,
                            _limits(args.effort, "--effort"), _limits(args.velocity, "--velocity"), into,
                            args.samples, args.seed, Path(args.robot).parent)
    with outputs:
        path = outputs.write_bytes(args.out, exported.data)
    print(f"spherecal export: wrote {args.format} of {model.name!r} ({model.convention} DH) to {path}")
    for line in exported.notes:
        print(f"spherecal export: {line}")
    return 0
