"""The socket-only branch of `spherecal validate` (no truth, no mocap): read, check, report, write."""

from __future__ import annotations

import argparse

from spherecal.correction import RobotModel


def run_sockets(args: argparse.Namespace, models: dict[str, RobotModel]) -> int:
    """Validate ``models`` on ``--samples`` (and ``--fixtures``): print the tables, write ``--out``, ``--rrd``."""
    import json
    from pathlib import Path

    from spherecal.correction import atomic_write_text
    from spherecal.correction.fixtures import read_fixtures
    from spherecal.correction.samples_csv import read_samples
    from spherecal.validation.provenance import provenance
    from spherecal.validation.sockets import fitted_fixtures, record_sockets, socket_validation

    models = {"nominal": models["nominal"], "calibrated": models["calibrated"]}
    dataset = read_samples(args.samples, models["nominal"])
    spec = None
    if args.fixtures is not None:
        spec = read_fixtures(args.fixtures)
        spec.check_against(dataset)
    report = socket_validation(models, dataset, spec, fitted_fixtures(models["calibrated"]))
    print(report.format())
    if args.out:
        inputs = {k: Path(v) if isinstance(v, str) and Path(v).is_file() else v for k, v in vars(args).items()}
        inputs = {k: v for k, v in inputs.items() if not k.startswith("_") and k != "command"}
        result = {"provenance": provenance(args.seed, inputs), "sockets": report.to_dict()}
        print(f"report: {atomic_write_text(args.out, json.dumps(result, indent=2) + chr(10))}")
    if args.rrd or args.spawn:
        from spherecal.validation.recording import Recording

        title = "Calibrated robot and sockets (recorded configurations on 'time')"
        recording = Recording(args.rrd, spawn=args.spawn, application_id="spherecal_validate", title=title)
        try:
            record_sockets(recording, report, models, dataset)
        except BaseException:
            recording.abort()
            raise
        path = recording.close()
        if path is not None:
            print(f"recording: {path}")
    return 0
