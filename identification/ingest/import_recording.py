"""One import: a recording in, ``samples.csv`` and ``fixtures.yaml`` out, together or not at all.

Read (:mod:`.importers`, :mod:`.bag`), label by segmentation when the source has no labels
(:mod:`.segment`), drop duplicates, subsample, then write both files into a temporary folder beside
the output folder and rename it into place.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import numpy as np

from spherecal.correction.files.fixtures import FixtureSpec, nearest_name, write_fixtures
from spherecal.correction.files.outputs import OutputSet
from spherecal.correction.files.provenance import comment_block, provenance
from spherecal.correction.files.robots import load_robot
from spherecal.correction.files.samples import Dataset, DatasetError
from spherecal.correction.files.samples_csv import write_samples
from spherecal.correction.model import RobotModel

from ..selfcheck import MAX_SOCKET_NOISE
from ..tool_fit import pivot_tool, recentred_tool
from .bag import read_bag
from .importers import MUKCA_DISTANCE, Recording, RecordingError, read_joint_csv, read_mukca
from .segment import (
    NoFixtureError,
    Segment,
    SegmentationError,
    SegmentSettings,
    format_segments,
    labelled_spans,
    labels_of,
    revisit_notes,
    segment,
    still_point,
)

FORMATS = ("mukca", "bag", "csv")
#: Options of :class:`ImportOptions` used by some formats only -> those formats (the others are shaped by all).
FORMAT_OPTIONS: dict[str, tuple[str, ...]] = {
    "topic": ("bag",), "distance": ("mukca",), "rate": ("csv",), "segmentation": ("bag", "csv"),
    "spans": ("bag", "csv"),
}
#: Sampling rate of a CSV without time stamps when none is given [Hz].
DEFAULT_RATE = 1000.0


class IgnoredRateWarning(UserWarning):
    """A sampling rate was given for a recording whose own clock or labels decide (one line, naming the source)."""


class DescriptionWarning(UserWarning):
    """The robot file does not describe what was recorded: a tool point centimetres from the file's (another
    ``--tip-link``, an adapter), or samples no tool point puts at their sockets (another arm's file)."""


@dataclass(frozen=True)
class ImportOptions:
    """How a recording is imported.

    Attributes:
        topic: bag topic of ``sensor_msgs/JointState``.
        distance: MUKCa socket distance [m].
        rate: sampling rate of a CSV without time stamps [Hz]; None: not given, :data:`DEFAULT_RATE`. A rate given
            for a recording with a time column or fixture labels, or in another format, is not used: an
            :class:`IgnoredRateWarning` says so (the recording's stamps decide).
        segmentation: thresholds of the automatic split.
        spans: fixtures labelled by hand in time instead, ``(name, start, end)`` [s] since the recording's first sample
            (``--fixture NAME=START:END``; :func:`.segment.labelled_spans`): samples in no span are dropped.
        known_distances: measured centre distances ``(a, b, metres)`` between fixtures of the import
            (``--known-distance``), added to those the recording gives (a MUKCa placement's sockets).
        max_per_fixture: samples kept per fixture (random, seeded), None for all.
        dedup_tol: duplicate tolerance [rad].
        seed: seed of the subsampling.
    """

    topic: str = "/joint_states"
    distance: float = MUKCA_DISTANCE
    rate: float | None = None
    segmentation: SegmentSettings = field(default_factory=SegmentSettings)
    spans: tuple[tuple[str, float, float], ...] = ()
    known_distances: tuple[tuple[str, str, float], ...] = ()
    max_per_fixture: int | None = 500
    dedup_tol: float = 1e-4
    seed: int = 0

    @property
    def row_rate(self) -> float:
        """The rate [Hz] that times the rows of a CSV without time stamps: ``rate``, or :data:`DEFAULT_RATE`."""
        return DEFAULT_RATE if self.rate is None else self.rate


@dataclass(frozen=True)
class ImportResult:
    """What was imported: the dataset and fixtures written, and the segments found (if any)."""

    dataset: Dataset
    fixtures: FixtureSpec
    read: int
    segments: list[Segment]
    dropped_motion: int
    dropped_duplicates: int
    notes: tuple[str, ...] = ()
    remarks: tuple[str, ...] = ()

    def format(self) -> str:
        """The printed report."""
        lines = [f"read {self.read} samples"] + list(self.notes)
        if self.segments:
            how = ("labelled by --fixture into", "outside the spans") if self.segments[0].labelled else (
                "segmented into", "in motion")
            count = len(self.dataset.fixture_names)
            lines.append(f"{how[0]} {count} fixture{'s' * (count != 1)} ({self.dropped_motion} samples {how[1]} "
                         "dropped):")
            lines.append(format_segments(self.segments, self.dataset.counts()))
            lines += revisit_notes(self.segments)
        else:
            lines += [f"{name:<24} {count:>6} samples" for name, count in self.dataset.counts().items()]
        lines.append(f"dropped {self.dropped_duplicates} duplicates; kept {self.dataset.n_samples} samples")
        for a, b, value in self.fixtures.distances:
            lines.append(f"known distance {a} - {b}: {value * 1e3:.3f} mm")
        return "\n".join(lines + list(self.remarks))


def check_out_dir(out: str | os.PathLike, inputs: list[str | os.PathLike]) -> None:
    """Refuse an output folder that exists and is not empty, is a file, or holds (or is) an input."""
    out = Path(out).absolute()
    try:  # first: the comparisons below resolve it
        resolved = out.resolve()
    except (RuntimeError, OSError):  # a symlink loop (RuntimeError before Python 3.13)
        raise RecordingError(f"{out}: field '--out': a symbolic link loop; choose a new folder") from None
    for item in inputs:
        try:
            item = Path(item).resolve()  # links resolved: compare files, not strings
        except (RuntimeError, OSError):
            raise RecordingError(f"{item}: field 'SOURCE': cannot read: a symbolic link loop") from None
        if item == resolved or resolved in item.parents:
            raise RecordingError(f"{out}: field '--out': holds the input {item}; choose a new folder")
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise RecordingError(f"{out}: field '--out': exists and is not an empty folder; choose a new folder")
    for parent in out.parents:
        if parent.exists():
            if not parent.is_dir():
                raise RecordingError(f"{out}: field '--out': {parent} is not a folder")
            break


def read_source(source: str | os.PathLike, fmt: str, model: RobotModel, options: ImportOptions) -> Recording:
    """The recording at ``source`` (labels for MUKCa and a CSV with a fixture column)."""
    if fmt == "bag":
        return read_bag(source, model, options.topic)
    if fmt == "csv":
        return read_joint_csv(source, model)
    raise ValueError(f"unknown format {fmt!r}")


def label(recording: Recording, model: RobotModel,
          options: ImportOptions) -> tuple[Dataset, list[Segment], tuple[str, ...]]:
    """The labelled dataset: the recording's own labels, or fixtures found by :func:`.segment.segment` (at the
    point of the last link that stays still, with a line saying so, when the robot file's tool point does nowhere:
    :func:`_segment_at_still_point`), and those lines."""
    if recording.labels is not None:
        if options.spans:
            raise RecordingError(f"{recording.source}: field '--fixture': the recording's own 'fixture' column labels "
                                 "its samples; leave --fixture out")
        return recording.dataset(), [], ()
    t = recording.t
    rated = t is None
    if rated:
        t = np.arange(recording.q.shape[0]) / options.row_rate
    elif np.any(np.diff(t) < 0):
        k = int(np.flatnonzero(np.diff(t) < 0)[0]) + 1
        raise RecordingError(f"{recording.rows[k]}, field {recording.time_field!r}: time goes back ({t[k]:.6f} s "
                             f"after {t[k - 1]:.6f} s)")
    notes: tuple[str, ...] = ()
    try:
        if options.spans:
            segments = labelled_spans(model, recording.q, t, options.spans, recording.source, sources=recording.rows)
            limit = options.segmentation.max_spread
            notes = tuple(f"--fixture {seg.name}={seg.start:g}:{seg.end:g}: its nominal tool points lie up to "
                          f"{seg.spread_max * 1e3:.1f} mm from their mean (a ball held in a socket: within "
                          f"{limit * 1e3:g} mm): does the span hold the ball's transport too?"
                          for seg in segments if seg.spread_max > limit)
        else:
            try:
                segments = segment(model, recording.q, t, options.segmentation, recording.source,
                                   sources=recording.rows)
            except NoFixtureError as error:
                segments, notes = _segment_at_still_point(model, recording, t, options.segmentation, error)
    except SegmentationError as error:
        if not rated:
            raise
        raise SegmentationError(f"{error}; the rows are timed by --rate {options.row_rate:g} Hz (no time column): "
                                "check it, a wrong rate stretches or shrinks every window and duration") from None
    labels = labels_of(segments, recording.q.shape[0])
    keep = labels != ""
    names = tuple(dict.fromkeys(seg.name for seg in sorted(segments, key=lambda seg: seg.rows[0])))  # as they come:
    dataset = Dataset(labels=labels[keep], q=recording.q[keep], t=t[keep], source=recording.source,  # not sorted
                      fixture_names=names)  # out of a million labels again
    return dataset, segments, notes


def _segment_at_still_point(model: RobotModel, recording: Recording, t: np.ndarray, settings: SegmentSettings,
                            error: NoFixtureError) -> tuple[list[Segment], tuple[str, ...]]:
    """The fixtures of a recording whose robot file's tool point stays still nowhere, found at the point of the
    last link that does (:func:`.segment.still_point`: the ball beyond the flange an embedded arm ends at, a
    ``--tip-link`` naming another link than the ball's), and one line saying so. A review: a Panda's bag imported
    with ``--robot panda``, which the guide says is not refused, was refused 'no fixture found', naming no cause.

    Raises:
        NoFixtureError: no point of the last link stays still either (``error``, saying so).
        SegmentationError: what :func:`.segment.segment` refuses at that point.
    """
    found = still_point(model, recording.q, t, settings)
    if found is None:
        raise NoFixtureError(f"{error}; nor does any other point of the last link (a ball beyond the robot file's "
                             "tool point)") from None
    tool, stretches = found
    moved = (np.asarray(tool) - model.tool) * 1e3
    where = ", ".join(f"{v:+.1f}" for v in moved)
    segments = segment(replace(model, tool=np.asarray(tool, dtype=float)), recording.q, t, settings,
                       recording.source, sources=recording.rows)
    return segments, (
        f"the robot file's tool point stays still nowhere; a point {np.linalg.norm(moved):.1f} mm from it in the last "
        f"joint frame ({where} mm) does, in {stretches} stretches of {settings.min_duration:g} s: the ball's centre, "
        "beyond the link the robot file ends at (an embedded arm's flange, a --tip-link naming another link); "
        "segmented at that point (calibrate finds the ball from the samples too; --tip-link names the link at the "
        "ball's centre)",)


def import_recording(
    source: str | os.PathLike,
    fmt: str,
    model: RobotModel,
    out: str | os.PathLike,
    options: ImportOptions = ImportOptions(),
    inputs: list[str | os.PathLike] = (),
    extras: dict | None = None,
    recorded: dict | None = None,
) -> ImportResult:
    """Import a recording and write ``out/samples.csv`` and ``out/fixtures.yaml``.

    Args:
        source: the recording (see :data:`FORMATS`).
        fmt: ``mukca``, ``bag`` or ``csv``.
        model: the nominal robot (joint names and limits; its tool point for segmentation).
        out: folder to create (absent or empty; never one holding an input).
        options: see :class:`ImportOptions`.
        inputs: other input files that ``out`` must not hold (the robot file).
        extras: written into ``fixtures.yaml`` under ``import:``.
        recorded: the inputs of the provenance block written under ``import: provenance:``
            (:func:`correction.files.provenance.provenance`), built once the source is read: a folder's digest
            reads every file below it, never for a source the importer refuses (``/`` typed for a placement).
            What timed and split the recording is added to them (:func:`_timed_and_split`).

    Raises:
        RecordingError, SegmentationError, DatasetError: bad input (one line); nothing is written.
    """
    if fmt not in FORMATS:
        raise ValueError(f"unknown format {fmt!r}, expected one of {FORMATS}")
    check_out_dir(out, [source, *inputs])
    _outputs(Path(out), source, inputs)  # every output location checked before any work
    if fmt == "mukca":
        recording, spec = read_mukca(source, model, options.distance)
    else:
        recording, spec = read_source(source, fmt, model, options), None
    _warn_unused_rate(recording, fmt, options.rate)
    dataset, segments, found = label(recording, model, options)
    read, notes, timed = recording.q.shape[0], recording.notes + found, _timed_and_split(recording, options)
    del recording  # its angles are freed before the duplicates are sought (a 1.8 M-sample recording: 100 MB)
    deduplicated = dataset.deduplicated(options.dedup_tol)
    kept = deduplicated.subsampled(options.max_per_fixture, np.random.default_rng(options.seed))
    if spec is None:
        spec = FixtureSpec.unknown(kept.fixture_names)
    missing = [name for name in spec.names if name not in kept.fixture_names]
    if missing:
        raise DatasetError(f"{source}: field 'fixture': {missing[0]!r} has no samples left")
    spec = _with_known_distances(spec, options.known_distances)
    block = dict(extras or {})
    if recorded is not None:
        block["provenance"] = provenance(options.seed, recorded | timed)
    if segments:
        block["segments"] = {
            s.label: {"from_s": s.start, "to_s": s.end, "samples": int(len(s.rows)), "spread_max_m": s.spread_max}
            for s in segments
        }
    spec = FixtureSpec(spec.names, spec.positions, spec.distances, {"import": block} if block else {})
    _warn_description(kept, model, source)
    _write_together(_outputs(Path(out), source, inputs), kept, spec)
    return ImportResult(
        kept, spec, read, segments, read - dataset.n_samples, dataset.n_samples - deduplicated.n_samples,
        notes, _scale_note(fmt, spec, bool(segments)),
    )


def _with_known_distances(spec: FixtureSpec, given: tuple[tuple[str, str, float], ...]) -> FixtureSpec:
    """``spec`` with the measured distances ``given`` (``--known-distance``; a ROS user's trial had to edit
    fixtures.yaml after the import to give one).

    Raises:
        DatasetError: a name that is not a fixture of the import (naming them), or a pair given twice or already known.
    """
    distances = list(spec.distances)
    for a, b, value in given:
        for name in (a, b):
            if name not in spec.names:
                near = nearest_name(name, spec.names)
                hint = f"did you mean {near!r}? " if near else ""
                raise DatasetError(f"field '--known-distance': {a} {b} {value:g}: no fixture {name!r} in this import "
                                   f"({hint}its fixtures: {', '.join(spec.names)})")
        known = next(((x, y, v) for x, y, v in distances if {x, y} == {a, b}), None)
        if known is not None:
            raise DatasetError(f"field '--known-distance': {a} {b} {value:g}: the distance {known[0]}-{known[1]} is "
                               f"known already ({known[2]:g} m)")
        distances.append((a, b, float(value)))
    return FixtureSpec(spec.names, spec.positions, distances, spec.extras) if given else spec


def _scale_note(fmt: str, spec: FixtureSpec, segmented: bool) -> tuple[str, ...]:
    """One line when nothing imported fixes the absolute scale: one fixture, or several and no known distance
    (nor two known positions; one alone fixes nothing): calibrate then takes the scale from the
    nominal model (:func:`..build.build_problem` holds one fixture's distance from the joint-1 axis at the nominal
    model's and says so). The line says what calibrate can fit and how to add the distance that gives the scale."""
    names = spec.names
    if spec.distances or len(spec.positions) > 1 or not names:
        return ()
    if fmt == "mukca":
        how = ("record the plate's other socket as well (hole_0.csv and hole_1.csv in one placement folder, "
               "--distance apart) and import again")
    elif len(names) > 1:
        how = (f"measure two sockets' centre distance and import again with --known-distance {names[0]} "
               f"{names[1]} METRES (or give it in fixtures.yaml: distances: [[{names[0]}, {names[1]}, metres]])")
    elif segmented:
        how = ("carry the ball to a second socket in the recording (at least --min-separation away) and import it "
               f"again with --known-distance {names[0]} S2 METRES, the two sockets' distance")
    else:
        how = ("record a second socket under a fixture label of its own and import again with --known-distance "
               f"{names[0]} OTHER METRES, the two sockets' distance")
    if len(names) == 1:
        return (f"one fixture ({names[0]}): calibrate can fit the arm's errors about this one socket, for use near "
                "the recorded postures, but not its absolute scale: one socket gives no known distance (and one "
                f"known position fixes none), so the scale comes from the nominal model; for the scale, {how}",)
    return (f"no known distance ({len(names)} fixtures): calibrate can fit the arm's errors but not its absolute "
            "scale: without a known distance (and with at most one known position) it holds one fixture's distance "
            "from the joint-1 axis at the nominal model's, so the scale comes from the nominal model; for the "
            f"scale, {how}",)


def _warn_description(dataset: Dataset, model: RobotModel, source: str | os.PathLike) -> None:
    """One :class:`DescriptionWarning` when the nominal model does not describe the recording, what ``calibrate``
    says later, said where the robot file and tip link are chosen: the samples pin a tool point implausibly far from
    the file's (:func:`..tool_fit.recentred_tool`: a wrong ``--tip-link``, an adapter the file lacks), or even with
    the tool point they pin down they lie beyond :data:`..selfcheck.MAX_SOCKET_NOISE` per axis from their fixture's
    point (another arm's file: an iiwa14 URDF on a Panda's angles warned only of joint limits)."""
    if dataset.n_samples < 2:
        return
    pivot = pivot_tool(model, dataset)  # one fit for both tests
    _, note = recentred_tool(model, dataset, pivot=pivot)
    if note is not None:
        message = f"{note}; --tip-link names the link at the ball's centre"
    else:
        spread = pivot[1]
        if not spread > MAX_SOCKET_NOISE:
            return
        message = (f"the samples lie {spread * 1e3:.3g} mm per axis from their fixture's point with the best tool "
                   "point for them (a ball held in a socket: within a few mm): the robot file does not describe this "
                   "arm (another arm's file, its DH convention, its units?); calibrate will refuse it")
    warnings.warn(f"{source}: {message}", DescriptionWarning, stacklevel=3)


def _timed_and_split(recording: Recording, options: ImportOptions) -> dict:
    """What timed and split an unlabelled recording, for its provenance: the field its stamps came from
    (``time: column 'time'``, ``time: header.stamp``) or, without stamps, the ``rate`` [Hz] that timed it, and the
    segmentation thresholds. Nothing for a labelled one (MUKCa, a CSV with a fixture column): no clock and no
    threshold shaped it."""
    if recording.labels is not None:
        return {}
    if recording.t is not None:
        clock = {"time": recording.clock}
    else:
        clock = {"rate": options.row_rate}
    if options.spans:
        return clock | {"fixture": [f"{name}={start:g}:{end:g}" for name, start, end in options.spans]}
    return clock | vars(options.segmentation)


def _warn_unused_rate(recording: Recording, fmt: str, rate: float | None) -> None:
    """One :class:`IgnoredRateWarning` when ``rate`` [Hz] was given but the recording's own stamps or labels decide:
    the time column is used (its median rate said, and whether it disagrees), never the rate typed."""
    if rate is None:
        return
    if fmt != "csv":
        why = "MUKCa placements are labelled" if fmt == "mukca" else "a bag's messages carry their own time stamps"
    elif recording.labels is not None:
        why = "its fixture column labels the samples (nothing is segmented in time)"
    elif recording.t is not None:
        steps = np.diff(recording.t)
        steps = steps[steps > 0]
        if not steps.size:
            return  # one time stamp: the time column refuses or labels nothing later
        stamped = 1.0 / float(np.median(steps))
        differs = abs(stamped - rate) > 0.01 * rate
        why = (f"the time column was used (median {stamped:.4g} Hz{', not the rate given' if differs else ''}); "
               "leave --rate out")
    else:
        return  # a CSV without time stamps: the rate is used
    warnings.warn(f"{recording.source}: --rate {rate:g} Hz ignored: {why}", IgnoredRateWarning, stacklevel=3)


def import_files(source: str | os.PathLike, fmt: str, robot: str, out: str | os.PathLike,
                 options: ImportOptions = ImportOptions(), robot_options: dict | None = None) -> ImportResult:
    """:func:`import_recording` of ``robot`` loaded by name or file, with the provenance of the import recorded in
    ``fixtures.yaml`` (``import:``) and ``samples.csv``: source, robot and the options that shaped it.

    Args:
        source: the recording (see :data:`FORMATS`).
        fmt: ``mukca``, ``bag`` or ``csv``.
        robot: a robot file, a URDF or an embedded arm's name (:func:`correction.load_robot`).
        out: folder to create (absent or empty; never one holding an input).
        options: see :class:`ImportOptions`.
        robot_options: keyword arguments of :func:`correction.load_robot` (``tip_link``, ``base_link``,
            ``inertials``, ``report``).
    """
    model = load_robot(robot, **(robot_options or {}))
    chosen = _relevant(fmt, {f.name: getattr(options, f.name) for f in fields(options)
                             if f.name not in ("rate", "segmentation")})  # recorded where they were used
    recorded = {"source": Path(source), "robot": Path(robot), **chosen}
    inputs = [robot] if robot != "panda" else []
    return import_recording(source, fmt, model, out, options, inputs, {"format": fmt}, recorded)


def _relevant(fmt: str, options: dict) -> dict:
    """The options that shaped an import of ``fmt`` (for the provenance block; the clock and the segmentation:
    :func:`_timed_and_split`)."""
    return {k: v for k, v in options.items() if fmt in FORMAT_OPTIONS.get(k, (fmt,))}


def _outputs(out: Path, source, inputs) -> OutputSet:
    """``out/samples.csv`` and ``out/fixtures.yaml``, checked against the inputs."""
    return OutputSet({"--out": [out / "samples.csv", out / "fixtures.yaml"]}, {"SOURCE": source, "input": list(inputs)})


def _write_together(outputs: OutputSet, dataset: Dataset, spec: FixtureSpec) -> None:
    """Write both files together (staged beside their destination, then renamed)."""
    samples, fixtures = outputs.planned
    with outputs:
        made = spec.extras.get("import", {}).get("provenance")
        write_samples(outputs.stage(samples), dataset, comment_block(made) if made else "")
        write_fixtures(outputs.stage(fixtures), spec)
