"""`spherecal validate`: Compare nominal and calibrated models against the truth, mocap data or socket samples.

Without ``--truth`` and ``--mocap``, ``--samples`` (and ``--fixtures``) alone: the socket-only check of
:mod:`spherecal.validation.sockets` (tool-point spread per socket, known-distance errors).
"""

from __future__ import annotations

import argparse

from spherecal.options import fail, recorded_options, urdf_links

HELP = "Compare nominal and calibrated models against the truth, motion-capture data or socket samples alone."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal validate`."""
    from spherecal.options import add_deprecated, add_seed, add_urdf_links, configurations, noise_mm

    parser.add_argument("--truth", help="robot file of the true robot (simulation)")
    parser.add_argument("--nominal", required=True, help="robot file of the nominal model ('panda': embedded)")
    parser.add_argument("--calibrated", required=True, help="robot file of the calibrated model")
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
    """Load and check every input, validate, print the table, then write the outputs."""

    import numpy as np

    from spherecal.correction import load_robot
    from spherecal.correction.files.provenance import provenance
    from spherecal.validation.inputs import check_models
    from spherecal.validation.mocap import check_mocap, read_mocap_csv
    from spherecal.validation.pipeline import record_validate_run, validate_models
    from spherecal.validation.progress import progress_bar

    if args.truth is None and args.mocap is None and args.samples is None:
        raise fail("give --truth (simulation), --mocap (recorded data) or --samples (socket-only)")
    if args.fixtures is not None and (args.truth is not None or args.mocap is not None or args.samples is None):
        raise fail("--fixtures goes with --samples alone (socket-only check)")
    from spherecal.options import planned_outputs

    outputs = planned_outputs(args, {"--out": args.out, "--rrd": args.rrd})
    files = {"nominal": args.nominal, "calibrated": args.calibrated}
    if args.truth is not None:
        files["truth"] = args.truth
    # --tip-link/--base-link describe the URDF among the models (a calibrated file is a robot file)
    urdf = [role for role, path in files.items() if str(path).lower().endswith(".urdf")] or ["nominal"]
    models = {role: load_robot(path, **(urdf_links(args) if role in urdf else {})) for role, path in files.items()}
    check_models(models, files)
    from spherecal.correction.files.robot_file import forced_calibration

    if forced_calibration(models["calibrated"]) and (args.truth is not None or args.mocap is not None):
        import warnings  # the socket-only branch says it among its remarks

        warnings.warn(forced_calibration(models["calibrated"]), stacklevel=1)
    if args.truth is None and args.mocap is None:
        from spherecal.commands.validate_sockets import run_sockets

        return run_sockets(args, models, outputs)
    n = models["nominal"].n_joints
    measurement = None
    if args.mocap is not None:
        measurement = read_mocap_csv(args.mocap, n)
        check_mocap(measurement, models["nominal"])
    self_motion = None
    if args.samples is not None:
        from spherecal.correction.files.samples_csv import read_samples

        dataset = read_samples(args.samples, models.get("truth", models["nominal"]))
        self_motion = {name: dataset.for_fixture(name) for name in dataset.fixture_names}

    total = args.configurations + sum(len(q) for q in (self_motion or {}).values()) if measurement is None else 0
    with progress_bar(total, "validation", "configurations", quiet=measurement is not None) as advance:
        report = validate_models(
            models["nominal"],
            models["calibrated"],
            np.random.default_rng(args.seed),
            truth=models.get("truth"),
            measurement=measurement,
            self_motion=self_motion,
            configurations=args.configurations,
            noise=args.mocap_noise * 1e-3,
            progress=advance,
        )
    print(report.format())
    if report.deviations is not None:
        print("\nparameter deviations from the truth:\n" + report.deviations.format())
    inputs = recorded_options(args)
    result = {"provenance": provenance(args.seed, inputs), "validation": report.to_dict()}

    drawn = "truth" if "truth" in models else "calibrated"
    title = f"{'True' if drawn == 'truth' else 'Calibrated'} robot and fixtures, validation configurations"

    def record(recording) -> None:
        record_validate_run(recording, report, models, drawn)

    from spherecal.commands.validate_sockets import write_validation

    write_validation(args, outputs, result, record, title)
    return 0
