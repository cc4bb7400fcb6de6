"""``spherecal export`` as a library call, file in and file out: a robot file exported as URDF, MJCF or YAML
(:func:`export_file`); nothing is written unless the whole document was built."""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from spherecal.correction import RobotModel, load_robot
from spherecal.correction.files.outputs import OutputError, OutputSet, check_suffix
from spherecal.correction.files.provenance import matched_record
from spherecal.correction.files.robot_file import forced_calibration
from spherecal.correction.files.text_input import read_xml_text
from spherecal.correction.files.urdf_write import LIMITS, ExportError

from .export import calibration_samples, export_model, fit_seed, provenance_header, samples_record

#: Per format: what the file holds, the name endings that fit it (the first is suggested) and, for a format read
#: by its ending, why another is refused (check_suffix; MuJoCo reads an MJCF, spherecal a robot file, by content).
#: A URDF is not written as .xml, the MJCF export's ending (a user: '--format urdf --out arm.xml' was written);
#: spherecal still reads one so named by its <robot> root.
SUFFIXES = {"urdf": ("a URDF", (".urdf",), "Rerun opens a URDF only by that ending"),
            "mjcf": ("an MJCF model", (".xml", ".mjcf"), ""),
            "yaml": ("a robot file (YAML)", (".yaml", ".yml"), "")}


@dataclass(frozen=True)
class ExportConfig:
    """What ``spherecal export`` exports, how, and where.

    Attributes:
        robot: the robot file to export (calibrated or nominal), a URDF, or an embedded arm's name.
        output_format: ``urdf``, ``mjcf`` or ``yaml`` (:mod:`spherecal.controller.export`).
        out: the file to write.
        into: urdf only: the user's URDF of the same arm whose joint origins are rewritten (None: standalone).
        prefix: URDF link and joint name prefix (None: ``panda_``).
        effort: URDF joint torque limits as given, ``"E1,...,En"`` [N m] (None: Franka's, 7-joint arms).
        velocity: URDF joint velocity limits as given, ``"V1,...,Vn"`` [rad/s] (None: Franka's, 7-joint arms).
        samples: urdf only: samples.csv the rigid fit must match (None: the calibration's own, if unchanged).
        seed: seed of the rigid fit's workspace sample (None: not given, 0; given for an export that draws nothing,
            it is refused).
        tip_link, base_link, inertials: a URDF ``robot``: its chain and inertials (:func:`correction.load_robot`).
    """

    robot: str
    output_format: str
    out: str
    into: str | None = None
    prefix: str | None = None
    effort: str | None = None
    velocity: str | None = None
    samples: str | None = None
    seed: int | None = None
    tip_link: str | None = None
    base_link: str | None = None
    inertials: str | None = None


@dataclass(frozen=True)
class ExportedFile:
    """What :func:`export_file` wrote.

    Attributes:
        path: the written file.
        model: the exported model.
        notes: lines for the user (what the format could not carry and what that costs, where the recorded
            configurations came from).
    """

    path: Path
    model: RobotModel
    notes: tuple[str, ...]


def export_file(config: ExportConfig, outputs: OutputSet, report: Callable[[str], None] | None = None) -> ExportedFile:
    """Check the output's name, load and export ``config.robot``, then write ``config.out``.

    Args:
        config: the model, the format, its options and the output.
        outputs: the output (``--out``), checked before the call (never over the robot file, ``into`` or
            ``samples``); written atomically at the end.
        report: printer of the one line saying where a URDF's inertials came from.

    Returns:
        The written file, the model and the notes of :class:`spherecal.controller.export.Export`.

    Raises:
        spherecal.correction.errors.SpherecalError: an output named for another format, an input that cannot be
            read, limits that are not numbers, an option the format does not take (one line); nothing is written.
    """
    written, accepted, read_by_ending = SUFFIXES[config.output_format]
    if config.output_format == "urdf" and Path(config.out).suffix.lower() == ".xml":  # check_suffix: 'read as XML'
        raise OutputError(f"{config.out}: field '--out': {written} (--format urdf) named .xml would be taken for an "
                          f"MJCF model (--format mjcf writes .xml); name it {accepted[0]}")
    check_suffix(config.out, "--out", f"{written} (--format {config.output_format})", accepted,
                 read_by_ending=read_by_ending)
    model = load_robot(config.robot, tip_link=config.tip_link, base_link=config.base_link,
                       inertials=config.inertials, report=report)
    forced = forced_calibration(model)
    if forced:
        warnings.warn(forced, stacklevel=1)
    into = None if config.into is None else _into(config.into, config.out)
    seed = fit_seed(model, config.output_format, 0 if config.seed is None else config.seed)
    unused = ()
    if seed is None and config.seed is not None:  # the document is the same for every seed
        why = (f"the {config.output_format} export of {model.name!r} draws nothing random (only a rigid fit does: "
               "a URDF of a model with joint-side terms, compliance or a joint-angle scale, or an MJCF of one whose "
               "scale or negative compliance a hinge cannot carry)")
        if config.output_format == "yaml":  # the format itself: a mistake in the command
            raise ExportError(f"field '--seed': {why}")
        unused = (f"--seed {config.seed} not used: {why}",)  # the file's content decides: a script's option, said
    read: dict[str, str | Path | dict] = {} if config.into is None else {"into": config.into}
    found = None
    if seed is not None:  # the rigid fit reads the recorded configurations: --samples, or the calibration's own file
        if config.samples is not None:
            read["samples"] = config.samples  # hashed by the provenance, read by the fit
        else:  # found by its recorded digest (the one hash), then recorded and read without hashing it again
            found = calibration_samples(model, Path(config.robot).parent)
            if found[0] is not None:
                read["samples"] = matched_record(found[0], samples_record(model))
    header = provenance_header(config.robot, config.output_format, seed, read)
    exported = export_model(model, config.output_format, header,
                            config.prefix, _limits(config.effort, "effort"), _limits(config.velocity, "velocity"),
                            into, config.samples, seed or 0, Path(config.robot).parent, found)
    with outputs:
        path = outputs.write_bytes(config.out, exported.data)
    return ExportedFile(path, model, exported.notes + unused)


def _limits(text: str | None, field: str) -> list[float] | None:
    """Comma-separated ``effort`` or ``velocity`` limits (``field``) as floats (None when not given); their range is
    checked with the joint count (:func:`spherecal.correction.files.urdf_write.names_and_limits`).

    Raises:
        ExportError: a value that is not a number (one line naming the option and its unit).
    """
    if text is None:
        return None
    try:
        return [float(v) for v in text.split(",")]
    except ValueError:
        option, unit = LIMITS[field][:2]
        raise ExportError(f"field '{option}': expected comma-separated numbers [{unit}], got {text!r}") from None


def _into(into: str, out: str) -> tuple[str, str]:
    """The text of ``into`` and its name.

    Raises:
        ExportError: ``out`` would overwrite it.
    """
    source = Path(into)
    text = read_xml_text(source, ExportError)  # in the encoding it declares, written back in it
    if Path(out).resolve() == source.resolve() or (Path(out).exists() and os.path.samefile(out, source)):
        raise ExportError(f"{out}: field '--out': is the --into file; write the calibrated URDF to another file")
    return text, str(source)
