"""``spherecal validate`` as a library call, files in and files out: the nominal and calibrated models compared
against the truth (simulation), recorded motion-capture data, or socket samples alone (:func:`validate_files`).

Every input is read and checked before anything is computed; the ``--out`` report (JSON, metres) and the
``--rrd`` recording are staged in an :class:`~spherecal.correction.files.outputs.OutputSet` and appear together
or not at all.
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from spherecal.correction import RobotModel
from spherecal.correction.files.fixtures import read_fixtures
from spherecal.correction.files.outputs import OutputSet
from spherecal.correction.files.provenance import provenance
from spherecal.correction.files.robot_file import forced_calibration
from spherecal.correction.files.robots import is_urdf, load_robot
from spherecal.correction.files.samples_csv import read_samples

from .inputs import ValidationInputError, check_models
from .mocap import check_mocap, read_mocap_csv
from .pipeline import ValidationReport, record_validate_run, validate_models
from .progress import progress_bar
from .sockets import SocketReport, fitted_fixtures, record_sockets, recorded_prediction, remarks, socket_validation

#: The title of the socket-only recording.
SOCKETS_TITLE = "Calibrated robot and sockets (recorded configurations on 'time')"


@dataclass(frozen=True)
class ValidateConfig:
    """What ``spherecal validate`` compares, on what, and where it writes.

    Attributes:
        nominal: robot file of the nominal model (a URDF, or ``"panda"``: embedded).
        calibrated: robot file of the calibrated model.
        truth: robot file of the true robot (simulation), or None.
        mocap: recorded mocap CSV (``[t,] q1..qn, x, y, z`` [rad, m]), or None.
        samples: samples.csv: with ``truth``, self-motion sets validated on as well; alone (no ``truth``, no
            ``mocap``), socket samples not used in the fit (the socket-only check).
        fixtures: fixtures.yaml of ``samples`` (known distances [m]), socket-only check only.
        configurations: random workspace configurations (simulation).
        noise: simulated motion-capture marker noise std [m].
        seed: seed of the simulated mocap (recorded in the report's provenance).
        out: the JSON report (metres) to write, or None.
        rrd: the Rerun recording to write, or None.
        spawn: stream to a live Rerun viewer.
        tip_link, base_link, inertials: the URDF among the models: its chain and inertials
            (:func:`correction.load_robot`).
        options: the run's options as its provenance block records them (file paths as :class:`~pathlib.Path`).
    """

    nominal: str
    calibrated: str
    truth: str | None = None
    mocap: str | None = None
    samples: str | None = None
    fixtures: str | None = None
    configurations: int = 5000
    noise: float = 0.3e-3
    seed: int = 0
    out: str | None = None
    rrd: str | None = None
    spawn: bool = False
    tip_link: str | None = None
    base_link: str | None = None
    inertials: str | None = None
    options: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        """Refuse a comparison without a reference, and known distances outside the socket-only check.

        Raises:
            ValidationInputError: none of ``truth``, ``mocap`` and ``samples``, ``fixtures`` given with
                ``truth`` or ``mocap`` or without ``samples``, or ``samples`` with ``mocap`` (the recorded
                measurement is compared alone: the self-motion sets would be read and left out).
        """
        if self.truth is None and self.mocap is None and self.samples is None:
            raise ValidationInputError("field '--truth': give --truth (simulation), --mocap (recorded data) or "
                                       "--samples (socket-only)")
        if self.fixtures is not None and (self.truth is not None or self.mocap is not None or self.samples is None):
            raise ValidationInputError("field '--fixtures': goes with --samples alone (socket-only check)")
        if self.samples is not None and self.mocap is not None:
            raise ValidationInputError("field '--samples': not with --mocap (the recorded measurement is compared "
                                       "alone; the self-motion sets go with --truth, socket samples with no --truth)")


def validate_files(config: ValidateConfig, outputs: OutputSet,
                   show: Callable[[ValidationReport | SocketReport], None] | None = None,
                   report: Callable[[str], None] | None = None) -> ValidationReport | SocketReport:
    """Read and check every input of ``config``, validate, then write ``config.out`` and ``config.rrd``.

    Without ``truth`` and ``mocap``, the socket-only check of :mod:`spherecal.validation.sockets` on ``samples``
    (its remarks are warnings); otherwise :func:`~spherecal.validation.pipeline.validate_models`.

    Args:
        config: the inputs, the options and the outputs.
        outputs: the outputs, checked before the call (``--out``, ``--rrd``); staged and renamed into place
            together at the end.
        show: called with the report before the files are written.
        report: printer of the one line saying where a URDF's inertials came from.

    Returns:
        The :class:`~spherecal.validation.pipeline.ValidationReport` (truth, mocap) or the
        :class:`~spherecal.validation.sockets.SocketReport` (socket-only).

    Raises:
        spherecal.correction.errors.SpherecalError: an input that cannot be read or does not fit the others
            (one line naming the file); nothing is written.
    """
    simulated_or_recorded = config.truth is not None or config.mocap is not None
    files = {"nominal": config.nominal, "calibrated": config.calibrated}
    if config.truth is not None:
        files["truth"] = config.truth
    # tip_link/base_link describe the URDF among the models (a calibrated file is a robot file)
    urdf = [role for role, path in files.items() if is_urdf(path)] or ["nominal"]  # .urdf, or a <robot> file
    links = {"tip_link": config.tip_link, "base_link": config.base_link, "inertials": config.inertials,
             "report": report}
    models = {role: load_robot(path, **(links if role in urdf else {})) for role, path in files.items()}
    check_models(models, files)
    forced = forced_calibration(models["calibrated"])
    if forced and simulated_or_recorded:
        warnings.warn(forced, stacklevel=1)  # socket-only: among its remarks
    if not simulated_or_recorded:
        return _validate_sockets(config, models, outputs, show)
    measurement = None
    if config.mocap is not None:
        measurement = read_mocap_csv(config.mocap, models["nominal"].n_joints)
        check_mocap(measurement, models["nominal"])
    self_motion = None
    if config.samples is not None:
        dataset = read_samples(config.samples, models.get("truth", models["nominal"]))
        self_motion = {name: dataset.for_fixture(name) for name in dataset.fixture_names}

    total = config.configurations + sum(len(q) for q in (self_motion or {}).values()) if measurement is None else 0
    with progress_bar(total, "validation", "configurations", quiet=measurement is not None) as advance:
        result = validate_models(
            models["nominal"],
            models["calibrated"],
            np.random.default_rng(config.seed),
            truth=models.get("truth"),
            measurement=measurement,
            self_motion=self_motion,
            configurations=config.configurations,
            noise=config.noise,
            progress=advance,
        )
    if show is not None:
        show(result)
    drawn = "truth" if "truth" in models else "calibrated"
    title = f"{'True' if drawn == 'truth' else 'Calibrated'} robot and fixtures, validation configurations"
    _write(config, outputs, {"provenance": provenance(config.seed, config.options), "validation": result.to_dict()},
           lambda recording: record_validate_run(recording, result, models, drawn), title)
    return result


def _validate_sockets(config: ValidateConfig, models: dict[str, RobotModel], outputs: OutputSet,
                      show: Callable[[SocketReport], None] | None) -> SocketReport:
    """The socket-only check of ``models`` on ``config.samples`` (and ``config.fixtures``), then the writing."""
    models = {"nominal": models["nominal"], "calibrated": models["calibrated"]}
    dataset = read_samples(config.samples, models["nominal"])
    spec = None
    if config.fixtures is not None:
        spec = read_fixtures(config.fixtures)
        spec.check_against(dataset)
    calibrated = models["calibrated"]
    result = socket_validation(models, dataset, spec, fitted_fixtures(calibrated, dataset),
                               recorded_prediction(calibrated, config.calibrated))
    if show is not None:
        show(result)
    for remark in remarks(result, calibrated, models["nominal"]):
        warnings.warn(remark, stacklevel=1)
    _write(config, outputs, {"provenance": provenance(config.seed, config.options), "sockets": result.to_dict()},
           lambda recording: record_sockets(recording, result, models, dataset), SOCKETS_TITLE)
    return result


def _write(config: ValidateConfig, outputs: OutputSet, result: dict, record: Callable[[object], None],
           title: str) -> None:
    """Write ``config.out`` (``result`` as JSON) and ``config.rrd`` (``record(recording)`` fills it) together.

    Both are staged in ``outputs`` and renamed into place at the end: both files or neither, and a recording
    that cannot be written is a one-line error before anything appears.
    """
    with outputs:
        if config.out:
            outputs.write_text(config.out, json.dumps(result, indent=2) + "\n")
        if config.rrd or config.spawn:
            from spherecal.validation.viewer.recording import Recording  # rerun

            recording = Recording(outputs.stage(config.rrd) if config.rrd else None, spawn=config.spawn,
                                  application_id="spherecal_validate", title=title, run=result["provenance"])
            try:
                recording.provenance(result["provenance"])  # as the JSON report records it
                record(recording)
            except BaseException:
                recording.abort()
                raise
            recording.close()
