"""Export a (calibrated) robot model as URDF, MJCF or the robot file (YAML).

* ``urdf`` (:func:`correction.files.urdf_write.robot_to_urdf`, or the user's own URDF with only its joint
  origins rewritten, :func:`correction.files.urdf_into.urdf_into`): rigid kinematics, so a model with
  joint-side terms (compliance, ...) is written as its best rigid approximation (:mod:`.rigid_fit`), and
  :attr:`Export.notes` says how much that loses. Standalone, each link carries the model's inertial (mass,
  centre of mass, inertia tensor), so MuJoCo, Gazebo or an RNEA load it as is; without inertials a note says
  what a dynamics stack needs. ``into`` keeps the user's own inertials.
* ``mjcf``: the controller's plant (:func:`controller.plant.build_mjcf`; elastic joints kept as flexible
  hinges): bodies ``link0..n`` with the model's inertials (the URDF's bodies), hinges ``joint1..n``, site
  ``tool``. A hinge's angle is the recorded one and a spring cannot push (:func:`mjcf_lost_terms`): a model with
  a joint-angle scale or a negative compliance is written as its best rigid fit, as for a URDF, and
  :attr:`Export.notes` says how much that loses.
* ``yaml``: the robot file, every term kept.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spherecal.correction import DatasetError, RobotModel, dump_robot, read_samples
from spherecal.correction.elastic import compliance_of
from spherecal.correction.files.provenance import comment_block, matches_record, provenance
from spherecal.correction.files.text_input import xml_bytes
from spherecal.correction.files.urdf_into import urdf_into
from spherecal.correction.files.urdf_write import (
    ExportError,
    dynamics_note,
    names_and_limits,
    provenance_comment,
    robot_to_urdf,
    xml_comment,
)
from spherecal.correction.scale import scale_of
from spherecal.correction.tool import nominal_tool_of

from .rigid_fit import RigidFit, joint_side_terms, rigid_approximation
from .stiffness import MAX_FLEX_STIFFNESS

FORMATS = ("urdf", "mjcf", "yaml")


@dataclass(frozen=True)
class Export:
    """An exported document.

    Attributes:
        text: the document.
        notes: lines for the user (what the URDF could not carry and what that costs, where the recorded
            configurations came from).
        fit: the rigid approximation written to a URDF (None for the other formats).
    """

    text: str
    notes: tuple[str, ...] = ()
    fit: RigidFit | None = None

    @property
    def data(self) -> bytes:
        """The document's bytes: UTF-8, or the encoding its XML declaration names (a Latin-1 URDF exported with
        ``into`` stays a Latin-1 file)."""
        return xml_bytes(self.text)


def provenance_header(source: str, output_format: str, seed: int | None = None,
                      inputs: dict[str, str | os.PathLike | dict] | None = None) -> str:
    """Comment lines naming the input files (and their SHA-256), the seed and the versions that wrote the export.

    Args:
        source: the robot file exported.
        output_format: ``urdf``, ``mjcf`` or ``yaml``; an XML format's header says how its command line's double
            hyphens are written (:func:`correction.files.urdf_write.xml_comment`).
        seed: the seed of the rigid fit's workspace samples (:func:`fit_seed`); None when nothing was drawn.
        inputs: the other files the export read, by role (``into``: the URDF written into; ``samples``: the
            rigid fit's recorded configurations): a file name (hashed here), or its ``{"path", "sha256"}`` record
            when the digest is known already (:func:`correction.files.provenance.input_record`).
    """
    block = comment_block(provenance(seed, {"robot": Path(source), **{
        k: v if isinstance(v, dict) else Path(v) for k, v in (inputs or {}).items()}}))
    xml = "" if output_format == "yaml" else " (a double hyphen written '- -': an XML comment cannot hold two in a row)"
    return f"spherecal export to {output_format} of {source}{xml}\n{block}"


def fit_seed(model: RobotModel, output_format: str, seed: int) -> int | None:
    """``seed`` when :func:`export_model` draws the rigid fit's workspace samples with it, else None (a YAML
    export, a model without joint-side terms, an MJCF that carries every term: nothing random is drawn)."""
    if output_format == "yaml" or not joint_side_terms(model):
        return None
    return None if output_format == "mjcf" and not mjcf_lost_terms(model) else seed


def recorded_configurations(model: RobotModel, samples: str | os.PathLike | None = None,
                            folder: str | os.PathLike | None = None,
                            found: tuple[Path | None, str] | None = None) -> tuple[np.ndarray | None, str]:
    """The joint angles the model was calibrated on, for the rigid fit.

    Args:
        samples: a samples file; None: the one the calibrated file's ``calibration.provenance.inputs.samples`` names,
            if it still exists with the recorded SHA-256 (tried as written, then beside ``folder``, the
            calibrated file's folder, and relative to it and to its parent; the digest must match).
        found: what :func:`calibration_samples` gave for ``model`` and ``folder`` when the caller asked already (it
            hashes the file: not again); None: asked here.

    Returns:
        ``(q (K, n) [rad] or None, one line saying where they came from)``.

    Raises:
        DatasetError: an unreadable ``samples`` file (one line naming file, row and field).
    """
    if samples is not None:
        q = read_samples(samples, model).q
        return q, f"{len(q)} recorded configurations from {samples}"
    path, why = calibration_samples(model, folder) if found is None else found
    if path is None:
        return None, why
    try:
        q = read_samples(path, model).q
    except DatasetError as error:
        return None, f"no recorded configurations ({error})"
    return q, f"{len(q)} recorded configurations from {path} (the calibration's samples)"


def calibration_samples(model: RobotModel, folder: str | os.PathLike | None = None) -> tuple[Path | None, str]:
    """The samples file the calibrated ``model`` was made from, when it is still there unchanged: the one its
    ``calibration.provenance.inputs.samples`` names, tried as written, then beside ``folder`` (the calibrated file's),
    relative to it and to its parent, each accepted only with the recorded SHA-256. ``(None, why not)`` otherwise."""
    record = samples_record(model)
    path = record.get("path")
    if not path:
        return None, "no recorded configurations (the file names no samples; --samples FILE to give them)"
    candidates = [Path(path)]
    if folder is not None:  # calibrated elsewhere: beside the file, or from its parent; the digest decides
        candidates += [Path(folder) / Path(path).name]
        if not Path(path).is_absolute():
            candidates += [Path(folder) / path, Path(folder).parent / path]
    tried: set[Path] = set()
    for candidate in candidates:  # the first that matches; each file hashed once ('.' as folder: one file thrice)
        if candidate.resolve() in tried:
            continue
        tried.add(candidate.resolve())
        if matches_record(candidate, record):
            return candidate, ""
    return None, f"no recorded configurations ({path} is gone or changed since the calibration)"


def samples_record(model: RobotModel) -> dict:
    """The calibrated file's record of its samples, ``{"path", "sha256"}`` (``calibration.provenance.inputs.samples``);
    ``{}`` when it has none."""
    made = (model.extras.get("calibration") or {}).get("provenance") or {}
    record = (made.get("inputs") or {}).get("samples") or {}
    return record if isinstance(record, dict) else {}


def _unread(samples: str | os.PathLike | None, model: RobotModel, why: str) -> tuple[str, ...]:
    """One note when a ``samples`` file is given that no rigid fit reads (``why``: the export is the whole model). A
    note, not a refusal: whether a fit runs depends on the calibrated file's terms, not on the command (a script
    exporting every model with its samples, as bench/mukca.py does, stays valid)."""
    if samples is None:
        return ()
    return (f"--samples {samples} not read: {model.name!r}: {why}; no rigid fit reads recorded configurations",)


def _other_tools(model: RobotModel) -> tuple[str, ...]:
    """One line for an export ``--into`` a user's URDF of a calibration that moved its tool point: the correction
    sits on the tip link's joint alone, and the URDF's other tool links keep their nominal offsets, while ``spherecal
    tool`` carries it to another tool (:func:`correction.tool.with_tool`; a review measured the two TCPs 0.75 mm
    apart on an iiwa14, 1.6 mm on a Gen3 lite)."""
    nominal = nominal_tool_of(model)
    if nominal is None or "tool_swap" in model.extras:
        return ()
    carried = np.asarray(model.tool, dtype=float) - nominal
    if np.linalg.norm(carried) < 1e-6:
        return ()
    shift = ", ".join(f"{v * 1e3:+.3f}" for v in carried)
    return (f"the calibrated tool point moved ({shift}) mm in the last frame: written on the tip link's joint only, "
            "the URDF's other tool links (a flange, a gripper) keep their nominal offsets; `spherecal tool CAL.yaml "
            "--urdf URDF --tip-link LINK` carries the correction to another tool (the flange's own error along and "
            "about the last axis is in it)",)


def mjcf_lost_terms(model: RobotModel) -> tuple[str, ...]:
    """Names of the joint-side parameters an MJCF hinge cannot carry: a non-zero joint-angle scale ``s{i}`` (the
    hinge's angle is the recorded one, not ``(1 + s) q``) and a negative compliance ``c{i}`` (a spring of negative
    stiffness; :func:`controller.plant.build_mjcf` leaves such a joint rigid) beyond ``-1 / MAX_FLEX_STIFFNESS``
    (nearer 0 either way a joint is a rigid hinge, :func:`.stiffness.stiffness_of`: a compliance at float noise,
    -4e-26 rad/Nm, sent a whole elastic model to the rigid fit). Empty: the MJCF is the whole model."""
    scale, compliance = scale_of(model), compliance_of(model)
    stiff = 1.0 / MAX_FLEX_STIFFNESS
    return (tuple(f"s{i + 1}" for i in np.flatnonzero(scale))
            + tuple(f"c{i + 1}" for i in np.flatnonzero(compliance < -stiff)))


def export_model(model: RobotModel, output_format: str, header: str = "", prefix: str | None = None,
                 effort: list[float] | None = None, velocity: list[float] | None = None,
                 into: tuple[str, str] | None = None, samples: str | os.PathLike | None = None,
                 seed: int = 0, folder: str | os.PathLike | None = None,
                 found: tuple[Path | None, str] | None = None) -> Export:
    """The exported document of a model.

    Args:
        model: the (calibrated) model.
        output_format: ``urdf``, ``mjcf`` or ``yaml`` (see the module docstring).
        header: comment lines on top (inputs, versions: :func:`provenance_header`).
        prefix: URDF name prefix (:func:`correction.files.urdf_write.default_prefix` when None, the joints keeping
            their own names); refused for the other formats.
        effort, velocity: (n,) URDF joint limits [N m], [rad/s]; Franka's for a Franka arm when None,
            required for other arms; refused for the other formats and with ``into``.
        into: ``(text, source)`` of the user's URDF of the same arm, whose joint origins are rewritten.
        samples: samples file for the rigid fit (default: the calibration's own, :func:`recorded_configurations`).
        seed: seed of the rigid fit's workspace samples.
        folder: the calibrated file's folder (where a relative samples path of its calibration block is
            looked for after the working folder).
        found: :func:`calibration_samples` of ``model`` and ``folder`` when the caller has it (not looked for, and
            hashed, again); None: looked for here when a rigid fit needs it.

    Raises:
        ExportError: an invalid format, prefix, limits, or an option the format does not take (``samples`` that no
            rigid fit reads get a note, :func:`_unread`).
    """
    if output_format not in FORMATS:
        raise ExportError(f"field '--format': unknown format {output_format!r}, expected one of {FORMATS}")
    if output_format != "urdf":
        for option, value in (("--prefix", prefix), ("--effort", effort), ("--velocity", velocity),
                              ("--into", into), ("--samples", None if output_format == "mjcf" else samples)):
            if value is not None:
                raise ExportError(f"field '{option}': only the urdf format takes it, not {output_format}")
        if output_format == "yaml":
            return Export(dump_robot(model, header=header))
        from spherecal.controller.plant import build_mjcf  # mujoco: the plant module imports it

        comments = [xml_comment(header)] if header.strip() else []
        lost = mjcf_lost_terms(model)
        dynamics = _dynamics(model, output_format)
        if not lost:
            return Export("\n".join(comments + [provenance_comment(model), build_mjcf(model, inertials=True)]),
                          (*dynamics, *_unread(samples, model, "its MJCF carries every term")))
        recorded, where = recorded_configurations(model, samples, folder, found)  # a scale: the hinges' rigid fit
        fit = rigid_approximation(model, recorded, seed=seed)
        notes = (fit.summary("MJCF") + f" (a hinge turns by the recorded angle and its spring cannot push: "
                 f"{', '.join(lost)})", f"rigid fit: {where}", *dynamics)
        return Export("\n".join(comments + [provenance_comment(model), build_mjcf(fit.model, inertials=True)]),
                      notes, fit)
    if into is not None:
        for option, value in (("--prefix", prefix), ("--effort", effort), ("--velocity", velocity)):
            if value is not None:
                raise ExportError(f"field '{option}': not with --into (the URDF keeps its own names and limits)")
    else:
        names_and_limits(model, prefix, effort, velocity)  # refused before the rigid fit, not after it
    recorded, where = (None, "") if not joint_side_terms(model) else recorded_configurations(model, samples, folder,
                                                                                               found)
    fit = rigid_approximation(model, recorded, seed=seed)
    notes = (fit.summary(), f"rigid fit: {where}") if fit.terms else _unread(
        samples, model, "it has no joint-side terms (compliance, joint-angle scale): its URDF is exact")
    rigid = fit.model
    if into is not None:
        text = urdf_into(rigid, into[0], into[1], header)
        notes += _other_tools(rigid)
    else:
        text = robot_to_urdf(rigid, prefix=prefix, effort=effort, velocity=velocity, header=header)
        notes += _dynamics(rigid)
    return Export(text, notes, fit)


def _dynamics(model: RobotModel, output_format: str = "urdf") -> tuple[str, ...]:
    """:func:`correction.files.urdf_write.dynamics_note` as notes (none when every body is complete)."""
    if output_format == "mjcf":
        from spherecal.controller.plant import LINK_MASS  # mujoco: the plant module imports it

        line = dynamics_note(model, f"the MJCF's links weigh a placeholder {LINK_MASS:g} kg each at their origins")
    else:
        line = dynamics_note(model)
    return () if line is None else (line,)
