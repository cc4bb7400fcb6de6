"""`spherecal export`: Export a calibrated robot file as URDF, MJCF or YAML."""

from __future__ import annotations

import argparse

from spherecal.options import add_urdf_links, urdf_links

HELP = "Export a calibrated robot file as URDF, MJCF or YAML."
FORMATS = ("urdf", "mjcf", "yaml")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal export`."""
    parser.add_argument("robot", metavar="CAL.yaml", help="robot file to export (calibrated or nominal), or 'panda'")
    add_urdf_links(parser)
    parser.add_argument("--format", choices=FORMATS, required=True, help="output format")
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
                        help="URDF joint torque limits [N m], comma-separated (default: Franka's, 7-joint arms)")
    parser.add_argument("--velocity", default=None, metavar="V1,...,Vn",
                        help="URDF joint velocity limits [rad/s], comma-separated (default: Franka's, 7-joint arms)")


def provenance_header(source: str, output_format: str) -> str:
    """Comment lines naming the input file (and its SHA-256) and the versions that wrote the export."""
    from spherecal.correction.files.provenance import input_record, versions

    digest = input_record(source)["sha256"]
    packages = ", ".join(f"{k} {v}" for k, v in versions(("spherecal", "numpy", "scipy", "mujoco")).items())
    return (
        f"spherecal export to {output_format} of {source}\n"
        f"input sha256: {digest}\n"
        f"versions: {packages}"
    )


def _limits(text: str | None, option: str) -> list[float] | None:
    """A comma-separated option as floats (None when not given)."""
    from spherecal.correction.files.urdf_write import ExportError

    if text is None:
        return None
    try:
        return [float(v) for v in text.split(",")]
    except ValueError:
        raise ExportError(f"{option}: expected comma-separated numbers, got {text!r}") from None


def export_text(model, output_format: str, prefix: str | None = None, header: str = "",
                effort: list[float] | None = None, velocity: list[float] | None = None) -> str:
    """The exported document of a model as text.

    Args:
        model: the (calibrated) :class:`correction.RobotModel`.
        output_format: ``urdf`` (:func:`correction.urdf.robot_to_urdf`), ``mjcf`` (the
            controller's plant, :func:`controller.plant.build_mjcf`: bodies ``link0..n``, hinges
            ``joint1..n``, site ``tool``) or ``yaml`` (the robot file, normalised).
        prefix: URDF name prefix (``panda_`` when None); refused for the other formats.
        header: comment lines on top (inputs, versions).
        effort, velocity: (n,) URDF joint limits [N m], [rad/s]; Franka's for a 7-joint arm when
            None, required for other arms; refused for the other formats.

    Raises:
        correction.urdf.ExportError: an invalid prefix, limits or format.
    """
    from spherecal.correction import dump_robot
    from spherecal.correction.files.urdf_write import (
        PANDA_EFFORT,
        ExportError,
        provenance_comment,
        robot_to_urdf,
        xml_comment,
    )

    if output_format == "urdf":
        n = model.n_joints
        for option, values in (("--effort", effort), ("--velocity", velocity)):
            if values is None and n != len(PANDA_EFFORT):
                raise ExportError(f"{option}: no default for a {n}-joint robot, give {n} comma-separated values")
        return robot_to_urdf(model, prefix="panda_" if prefix is None else prefix, effort=effort, velocity=velocity,
                             header=header)
    for option, value in (("--prefix", prefix), ("--effort", effort), ("--velocity", velocity)):
        if value is not None:
            raise ExportError(f"{option}: only the urdf format takes it, not {output_format}")
    if output_format == "yaml":
        return dump_robot(model, header=header)
    if output_format == "mjcf":
        from spherecal.controller.plant import build_mjcf

        comments = [xml_comment(header)] if header.strip() else []
        return "\n".join(comments + [provenance_comment(model), build_mjcf(model)])
    raise ExportError(f"--format: unknown format {output_format!r}, expected one of {FORMATS}")


def into_text(model, into: str, out: str, header: str = "") -> str:
    """The URDF ``into`` with the calibrated joint origins (:func:`correction.urdf_into.urdf_into`).

    Raises:
        correction.urdf.ExportError: ``out`` is ``into``, or ``into`` does not match the model.
    """
    import os
    from pathlib import Path

    from spherecal.correction.files.urdf_into import urdf_into
    from spherecal.correction.files.urdf_write import ExportError

    source = Path(into)
    try:
        text = source.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise ExportError(f"{into}: cannot read: {getattr(error, 'strerror', None) or error}") from None
    if Path(out).resolve() == source.resolve() or (Path(out).exists() and os.path.samefile(out, source)):
        raise ExportError(f"--out: {out} is the --into file; write the calibrated URDF to another file")
    return urdf_into(model, text, str(source), header)


def run(args: argparse.Namespace) -> int:
    """Load, validate and export; nothing is written unless the whole document was built."""
    from spherecal.correction import load_robot
    from spherecal.correction.files.urdf_write import ExportError
    from spherecal.options import planned_outputs

    outputs = planned_outputs(args, {"--out": args.out})  # never over CAL.yaml or --into
    model = load_robot(args.robot, **urdf_links(args))
    from spherecal.correction.files.robot_file import forced_calibration

    if forced_calibration(model):
        import warnings

        warnings.warn(forced_calibration(model), stacklevel=1)
    effort, velocity = _limits(args.effort, "--effort"), _limits(args.velocity, "--velocity")
    header = provenance_header(args.robot, args.format)
    if args.into is not None:
        if args.format != "urdf":
            raise ExportError(f"--into: only the urdf format takes it, not {args.format}")
        for option, value in (("--prefix", args.prefix), ("--effort", effort), ("--velocity", velocity)):
            if value is not None:
                raise ExportError(f"{option}: not with --into (the URDF keeps its own names and limits)")
        text = into_text(model, args.into, args.out, header)
    else:
        text = export_text(model, args.format, args.prefix, header, effort, velocity)
    with outputs:
        path = outputs.write_text(args.out, text)
    print(f"spherecal export: wrote {args.format} of {model.name!r} ({model.convention} DH) to {path}")
    from spherecal.correction.elastic import compliance_of

    compliance = compliance_of(model)
    if args.format == "urdf" and compliance.any():
        joints = ", ".join(f"c{i + 1} {c:.3g}" for i, c in enumerate(compliance) if c)
        print(f"spherecal export: a URDF cannot express joint compliance ({joints} rad/Nm): this is the geometric "
              f"part only; the yaml and mjcf formats keep the elastic model")
    return 0
