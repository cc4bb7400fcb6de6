"""The socket-only branch of `spherecal validate` (no truth, no mocap): read, check, report, write."""

from __future__ import annotations

import argparse

from spherecal.correction import RobotModel
from spherecal.options import recorded_options


def write_validation(args: argparse.Namespace, outputs, result: dict, record, title: str) -> None:
    """Write ``--out`` (``result`` as JSON) and ``--rrd`` (``record(recording)`` fills it) together.

    Both are staged in ``outputs`` (an :class:`~spherecal.correction.files.outputs.OutputSet` checked before
    the validation ran) and renamed into place at the end: both files or neither, and a recording
    that cannot be written is a one-line error before anything appears.
    """
    import json

    recording = None
    with outputs:
        if args.out:
            outputs.write_text(args.out, json.dumps(result, indent=2) + "\n")
        if args.rrd or args.spawn:
            from spherecal.validation.viewer.recording import Recording

            recording = Recording(outputs.stage(args.rrd) if args.rrd else None, spawn=args.spawn,
                                  application_id="spherecal_validate", title=title)
            try:
                record(recording)
            except BaseException:
                recording.abort()
                raise
            recording.close()
    if args.out:
        print(f"report: {args.out}")
    if args.rrd:
        print(f"recording: {args.rrd}")


def run_sockets(args: argparse.Namespace, models: dict[str, RobotModel], outputs) -> int:
    """Validate ``models`` on ``--samples`` (and ``--fixtures``): print the tables, write ``--out``, ``--rrd``."""
    import warnings

    from spherecal.correction.files.fixtures import read_fixtures
    from spherecal.correction.files.provenance import provenance
    from spherecal.correction.files.samples_csv import read_samples
    from spherecal.validation.sockets import (
        fitted_fixtures,
        record_sockets,
        recorded_prediction,
        remarks,
        socket_validation,
    )

    models = {"nominal": models["nominal"], "calibrated": models["calibrated"]}
    dataset = read_samples(args.samples, models["nominal"])
    spec = None
    if args.fixtures is not None:
        spec = read_fixtures(args.fixtures)
        spec.check_against(dataset)
    calibrated = models["calibrated"]
    report = socket_validation(models, dataset, spec, fitted_fixtures(calibrated, dataset),
                               recorded_prediction(calibrated, args.calibrated))
    print(report.format())
    for remark in remarks(report, calibrated, models["nominal"]):
        warnings.warn(remark, stacklevel=1)
    inputs = recorded_options(args)
    result = {"provenance": provenance(args.seed, inputs), "sockets": report.to_dict()}

    def record(recording) -> None:
        record_sockets(recording, report, models, dataset)

    write_validation(args, outputs, result, record, "Calibrated robot and sockets (recorded configurations on 'time')")
    return 0
