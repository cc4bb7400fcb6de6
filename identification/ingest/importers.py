"""Recordings in: MUKCa socket files and joint-angle CSV files, joints matched by name.

A :class:`Recording` is what a reader returns: joint angles in the robot's joint order, time
stamps if the source has them, and fixture labels if the source has them (a MUKCa folder, a CSV
with a ``fixture`` column); a recording without labels is split by :mod:`.segment`.

Errors are :class:`RecordingError`, one line naming the file, the row and the field.
"""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from spherecal.correction.files.csv_rows import (
    RowNames,
    block_rows,
    check_separator,
    is_skipped,
    iter_lines,
    parse_line,
    plain_values,
    read_rows,
)
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.samples import (
    LIMIT_BLOCK,
    LIMIT_TOL,
    Dataset,
    DatasetError,
    LimitExcess,
    configurations_digest,
)
from spherecal.correction.files.text_input import finite_number, plain_float
from spherecal.correction.model import RobotModel

#: Default MUKCa socket distance [m] (their printed plate: centres 50 mm apart).
MUKCA_DISTANCE = 0.050
#: Header names of a time column in a joint CSV (seconds; see :func:`read_joint_csv`).
TIME_COLUMNS = ("t", "time", "stamp", "timestamp", "%time")
#: Time values above this are nanoseconds (ROS stamps exported as integers), not seconds.
NANOSECONDS_ABOVE = 1e15
#: A time column named with its unit (``time_ns``, ``stamp [ms]``, ``__time`` of PlotJuggler) -> seconds per unit.
_TIMED = re.compile(r"^(t|time|stamp|timestamp|%time|__time)(?:[ _]?\[?(ns|us|µs|ms|s)\]?)?$", re.I)
_UNITS = {"ns": 1e-9, "us": 1e-6, "µs": 1e-6, "ms": 1e-3, "s": 1.0}
#: Sampling steps of a joint recording believed [s]: 10 kHz up to, not including, 1 Hz (a controller's 1 kHz, a
#: logger's 10 Hz); a step of exactly 1 is a 1 kHz stream stamped in milliseconds (a review: read as seconds, its
#: stillness segmentation failed on a '30314 s' stretch).
STEP_RANGE = (1e-4, 1.0)


#: Fastest joint motion believed between two samples [rad/s] (a cobot's joints reach 2-3 rad/s); faster is two
#: streams interleaved by their stamps (a clock reset, two recordings or two publishers in one bag) or a joint reading
#: that jumped (an encoder glitch).
MAX_JOINT_SPEED = 10.0
#: Smallest step checked against :data:`MAX_JOINT_SPEED` [rad] (encoder noise between close stamps is not a jump).
MIN_JUMP = 0.05


def first_jump(q: np.ndarray, t: np.ndarray) -> tuple[int, float, float] | None:
    """The first sample whose joints moved faster than :data:`MAX_JOINT_SPEED` (by more than :data:`MIN_JUMP`) from
    the one before: ``(its index, the largest joint step [rad], the time step [s])``, or None. ``q`` (T, n) [rad] and
    ``t`` (T,) [s] in time order."""
    if len(t) < 2:
        return None
    step = np.concatenate([np.abs(np.diff(q[k : k + LIMIT_BLOCK + 1], axis=0)).max(axis=1)  # in blocks: 2 of (T, n)
                           for k in range(0, len(q) - 1, LIMIT_BLOCK)])  # were 200 MB of a 1.8 M-sample recording
    dt = np.diff(t)
    jumps = np.flatnonzero((step > MIN_JUMP) & (step > MAX_JOINT_SPEED * dt))
    if not len(jumps):
        return None
    k = int(jumps[0])
    return k + 1, float(step[k]), float(dt[k])


class RecordingError(DatasetError):
    """A recording that cannot be imported; one line naming the file, row and field."""


def repeated_stamps(q: np.ndarray, t: np.ndarray, rows, field: str, noun: str) -> tuple[np.ndarray, tuple[str, ...]]:
    """Samples of a stream stamped as the one before: the same joints are a logger's repeat (dropped, one note
    saying how many), other joints cannot be ordered (refused), for CSV rows and bag messages alike.

    Args:
        q: (T, n) joint angles [rad] and ``t`` (T,) stamps [s], in time order (repeats next to each other).
        rows: (T,) where each sample came from, for the refusal.
        field: the time field named by the refusal (``time``, ``header.stamp``).
        noun: what a sample is in the source (``row``, ``message``).

    Returns:
        ``(keep, notes)``: (T,) bool, False for a repeat; one note when any was dropped.

    Raises:
        RecordingError: two samples with one stamp and other joint angles, naming the second.
    """
    same = np.diff(t) == 0
    if not same.any():
        return np.ones(len(t), dtype=bool), ()
    differ = same & np.any(q[1:] != q[:-1], axis=1)
    if differ.any():
        k = int(np.flatnonzero(differ)[0]) + 1
        step = float(np.abs(q[k] - q[k - 1]).max())
        raise RecordingError(
            f"{rows[k]}, field {field!r}: the same time as the one before ({t[k]:.6f} s) with other joint angles "
            f"(up to {step:.3g} rad apart): which came first cannot be told; give each {noun} its own time"
        )
    keep = np.concatenate([[True], ~same])
    return keep, (f"dropped {int(same.sum())} {noun}s repeating the one before (the same time and joint angles: a "
                  "logger's repeat)",)


def check_source(path: str | os.PathLike) -> Path:
    """``path`` as a :class:`~pathlib.Path`, refused first when nothing is there (every format says it alike).

    Raises:
        RecordingError: no file or folder at ``path`` (or a link to none).
    """
    path = Path(path)
    if not path.exists():
        raise RecordingError(f"{path}: field 'SOURCE': does not exist")
    return path


@dataclass(frozen=True, eq=False)
class Recording:
    """Joint angles read from a source, in the robot's joint order.

    Attributes:
        q: (T, n) joint angles [rad].
        t: (T,) time stamps [s], or None.
        labels: (T,) fixture label of every sample, or None (to be segmented).
        source: the file or folder read.
        rows: (T,) where each sample came from, for messages (``"file: row N"``; a sequence that makes each
            string when asked, for a long recording).
        notes: what the reader skipped and why (printed by the import report).
        clock: the field ``t`` was read from (``column 'time'``, ``header.stamp``), for the provenance; ``""``
            without time stamps.
        time_field: that field as a refusal names it (``time``, ``header.stamp``); ``""`` without time stamps.
    """

    q: np.ndarray
    t: np.ndarray | None
    labels: np.ndarray | None
    source: str
    rows: Sequence[str]
    notes: tuple[str, ...] = ()
    clock: str = ""
    time_field: str = ""

    def check_limits(self, model: RobotModel, names: list[str] | None = None, tol: float = LIMIT_TOL) -> None:
        """Refuse an angle that cannot be of its joint; warn ONCE, naming every joint, of angles past the
        limits within :data:`~spherecal.correction.files.samples.HARD_MARGIN` (used as recorded)."""
        excess = LimitExcess.of(model, names, tol)
        excess.add(self.q, lambda k: self.rows[k], RecordingError)
        excess.warn(self.source)

    def dataset(self) -> Dataset:
        """The labelled samples (labels must be set)."""
        if self.labels is None:
            raise ValueError("an unlabelled recording must be segmented first")
        return Dataset(labels=self.labels, q=self.q, t=self.t, source=self.source)


# ------------------------------------------------------------------------------ joint names
def joint_name_candidates(model: RobotModel) -> list[list[str]]:
    """Joint-name conventions the robot's joints may carry in a recording, most specific first.

    ``extras["joint_names"]`` (a model built from a URDF, or a robot file that lists them), then
    ``<prefix>_joint1..n`` for the robot's name and its last ``_`` part (the embedded
    ``franka_panda`` gives ``panda_joint1..7``), then ``joint1..n``, ``joint_1..n``, ``q1..qn``.
    """
    n = model.n_joints
    out: list[list[str]] = []
    names = model.extras.get("joint_names")
    if isinstance(names, list) and len(names) == n and all(isinstance(x, str) for x in names):
        out.append(list(names))
    prefixes = [model.name, model.name.split("_")[-1]] if model.name else []
    for prefix in dict.fromkeys(prefixes):
        out.append([f"{prefix}_joint{i + 1}" for i in range(n)])
    out += [[f"joint{i + 1}" for i in range(n)], [f"joint_{i + 1}" for i in range(n)], [f"q{i + 1}" for i in range(n)]]
    return out


def arm_joint_names(model: RobotModel) -> set[str]:
    """Every name any convention of :func:`joint_name_candidates` gives the robot's joints."""
    return {name for names in joint_name_candidates(model) for name in names}


def missing_joints(available, model: RobotModel) -> list[str]:
    """The robot's joints ``available`` lacks under the convention it matches best (none: it names them all)."""
    present = set(available)
    return min(([name for name in names if name not in present] for names in joint_name_candidates(model)), key=len)


def match_joints(available: list[str], model: RobotModel, where: str) -> tuple[np.ndarray, list[str]]:
    """Positions of the robot's joints in ``available`` (extra names, e.g. fingers, are ignored).

    Args:
        available: names in the recording (message ``name`` field or CSV header).
        model: the robot.
        where: ``"file: row N"`` for the message.

    Returns:
        ``(index, names)``: (n,) int positions in ``available`` and the matched names.

    Raises:
        RecordingError: no convention matches every joint (names the first joint missing under the
            convention that matches most), or one of the matched joints is named twice.
    """
    lookup = {name: k for k, name in enumerate(available)}
    best: tuple[int, list[str]] | None = None
    for names in joint_name_candidates(model):
        found = [name in lookup for name in names]
        if all(found):
            for name in names:  # a joint named twice: which column is the arm's cannot be told
                if available.count(name) > 1:
                    first, second = [k + 1 for k, other in enumerate(available) if other == name][:2]
                    raise RecordingError(
                        f"{where}, field {name!r}: joint {name!r} is named twice (entries {first} and {second}); "
                        "which one is the arm's cannot be told"
                    )
            return np.array([lookup[name] for name in names], dtype=int), names
        if best is None or sum(found) > best[0]:
            best = (sum(found), names)
    assert best is not None
    missing = next(name for name in best[1] if name not in lookup)
    raise RecordingError(
        f"{where}, field {missing!r}: joint {missing!r} of {model.name} not in the recording "
        f"(has {', '.join(available[:12])}{', ...' if len(available) > 12 else ''})"
    )


# ------------------------------------------------------------------------------------ MUKCa
_HOLE = re.compile(r"hole_(\d+)\.csv$", re.I)  # HOLE_0.CSV of a Windows copy as well


def _hole_files(folder: Path) -> list[tuple[int, Path]]:
    """``(k, path)`` of every ``hole_<k>.csv`` in ``folder``, by ``k``.

    Raises:
        RecordingError: a ``hole_<k>.csv`` that is not a readable file (a folder, a dangling link, a link
            loop): the placement would silently lose a socket and its known distance.
    """
    found = []
    for p in folder.iterdir():
        m = _HOLE.match(p.name)
        if not m:
            continue
        try:
            regular = p.is_file()
        except OSError as error:  # a symlink loop (ELOOP) on some Python versions
            raise RecordingError(f"{p}: row 1, field 'q1': cannot read: {error.strerror or error}") from None
        if not regular:
            what = "a folder" if p.is_dir() else "a link that leads to no file (dangling or a loop)"
            raise RecordingError(f"{p}: row 1, field 'q1': cannot read: {what}, not a file of configurations")
        found.append((int(m.group(1)), p))
    found.sort()
    for (k, first), (j, second) in zip(found, found[1:], strict=False):
        if k == j:  # hole_1.csv beside hole_01.csv or HOLE_1.CSV: which one is the socket's cannot be told
            raise RecordingError(f"{second}: row 1, field 'q1': a second file of hole {k} beside {first.name}")
    return found


def _number(text: str, where: str) -> float:
    return finite_number(text, where, RecordingError)


#: Deepest placement folder searched below a MUKCa source (``robot/day1/front/hole_0.csv`` is 2 levels down).
MUKCA_DEPTH = 4
#: Most folders visited while searching (a source that is a whole disk is refused, not walked).
MUKCA_FOLDERS = 10_000
#: Extra values a headerless hole file's rows may carry after the joints (a gripper's two fingers, appended as
#: ROS's ``joint_states`` lists them), and the largest magnitude one may take (metres of a finger's travel, or
#: up to a radian of a gripper joint): anything else is not a finger.
FINGER_COLUMNS = 2
FINGER_MAX = 1.0


def _placements(root: Path) -> list[Path]:
    """Every folder holding ``hole_<k>.csv`` files at or below ``root`` (at most :data:`MUKCA_DEPTH` levels; a
    folder reached twice through links is read once), in name order.

    Raises:
        RecordingError: a placement folder that also holds placement folders (which did the user mean?), no
            placement, or more than :data:`MUKCA_FOLDERS` folders to search.
    """
    found: list[Path] = []
    seen: set[Path] = set()
    stack = [(root, 0)]
    while stack:
        folder, depth = stack.pop()
        real = folder.resolve()
        if real in seen:
            continue
        seen.add(real)
        if len(seen) > MUKCA_FOLDERS:
            raise RecordingError(f"{root}: field 'SOURCE': more than {MUKCA_FOLDERS} folders below it: give the "
                                 "folder of one arm's placements")
        if _hole_files(folder):
            found.append(folder)
        if depth < MUKCA_DEPTH:
            try:
                children = sorted(p for p in folder.iterdir() if p.is_dir())
            except OSError as error:
                raise RecordingError(f"{folder}: field 'SOURCE': cannot read: {error.strerror or error}") from None
            stack += [(child, depth + 1) for child in reversed(children)]
    for folder in found:  # a placement holding placements: reading either alone silently drops the other
        inner = [p for p in found if p != folder and folder in p.parents]
        if inner:
            raise RecordingError(
                f"{folder}: field 'SOURCE': holds hole_<k>.csv files and placement folders "
                f"({inner[0].relative_to(folder)}{', ...' if len(inner) > 1 else ''}) with their own; give one "
                "placement folder or a folder of placements")
    if not found:
        raise RecordingError(f"{root}: field 'hole_0.csv': no hole_<k>.csv here or in its sub-folders "
                             f"({MUKCA_DEPTH} levels searched)")
    return sorted(found)


def _warn_several_groups(root: Path, placements: list[Path]) -> None:
    """One warning when placements nested deeper than one level come from several folders below ``root``: two days'
    recordings of one arm, or several arms' (MUKCa's data folder: panda_1, panda_6), which must not be mixed."""
    groups: dict[str, int] = {}
    for folder in placements:
        parts = folder.relative_to(root).parts
        if len(parts) > 1:
            groups[parts[0]] = groups.get(parts[0], 0) + 1
    if len(groups) > 1:
        listed = ", ".join(f"{name}: {count}" for name, count in groups.items())
        warnings.warn(f"{root}: field 'SOURCE': placements in {len(groups)} folders below it ({listed} placements), "
                      "imported as one arm's recordings; if they are several arms', import each arm's folder alone",
                      stacklevel=3)


def _placement_name(root: Path, folder: Path) -> str:
    """A placement's fixture prefix: its folder name, or its path below ``root`` when deeper than one level
    (``day1/front``: two recordings of a placement named alike stay two)."""
    if folder == root:
        return folder.name
    return folder.relative_to(root).as_posix()


def _check_one_field(field: str, where: str) -> None:
    """Refuse a row of one field holding the values separated otherwise than by commas (``;``, a tab, spaces:
    numpy's ``savetxt`` default), which would be read as one value or a header."""
    check_separator([field], where, RecordingError)
    parts = field.split()
    if len(parts) > 1 and all(_is_number(part) for part in parts):
        raise RecordingError(f"{where}, field 'q1': the values are separated by spaces, not commas (numpy's savetxt "
                             "without delimiter=','?): MUKCa's hole files are comma-separated")


def _hole_rows(file: Path, model: RobotModel) -> tuple[list[list[float]], list[str], list[str]]:
    """Joint angles [rad], ``"file: row N"`` and notes of one ``hole_<k>.csv``.

    Rows are the robot's joint angles in its order. A first row of names (a header) names the columns: they are
    matched to the robot's joints as a joint CSV's (any order; others ignored). Without one, rows of up to
    :data:`FINGER_COLUMNS` more values, each within :data:`FINGER_MAX`, carry a gripper's fingers after the joints:
    the joints are read, the fingers named in a note.
    """
    n = model.n_joints
    q: list[list[float]] = []
    rows: list[str] = []
    notes: list[str] = []
    names = [f"q{i + 1}" for i in range(n)]
    columns: list[int] = list(range(n))
    width = fingers = 0
    for line, fields in read_rows(file, RecordingError):  # streamed; blank lines, comments skipped
        where = f"{file}: row {line}"
        while len(fields) > 1 and not fields[-1].strip():  # a separator ending the row (some exporters write one)
            fields = fields[:-1]
        if not width:
            width = len(fields)
            if width == 1:
                _check_one_field(fields[0], where)
            if not any(_is_number(f) for f in fields):  # a header naming the columns
                index, names = _match_columns([f.strip() for f in fields], model, where)
                columns = [int(k) for k in index]
                notes.append(f"{file.name}: row {line} is a header: columns matched to the joints by name")
                continue
            if width != n and not n < width <= n + FINGER_COLUMNS:
                raise RecordingError(f"{where}, field 'q*': {width} joint angles, {model.name} has {n}"
                                     + (" (decimal commas?)" if width == 2 * n else ""))
            fingers = width - n
            if fingers:
                notes.append(f"{file.name}: {width} values per row: the first {n} read as {model.name}'s joints, "
                             f"the last {fingers} (a gripper's fingers) not used")
        if len(fields) != width:
            raise RecordingError(f"{where}, field 'q*': {len(fields)} joint angles, {model.name} has {n}" if width == n
                                 else f"{where}, field 'q*': {len(fields)} values, the file's first row has {width}")
        q.append([_number(fields[k], f"{where}, field {names[i]!r}") for i, k in enumerate(columns)])
        for j in range(n, n + fingers):
            if abs(_number(fields[j], f"{where}, field 'q{j + 1}'")) > FINGER_MAX:
                raise RecordingError(
                    f"{where}, field 'q{j + 1}': {width} values per row, {model.name} has {n} joints, and "
                    f"{fields[j].strip()} is no gripper finger's (at most {FINGER_MAX:g}): another arm's file?")
        rows.append(where)
    return q, rows, notes


def read_mukca(
    path: str | os.PathLike, model: RobotModel, distance: float = MUKCA_DISTANCE
) -> tuple[Recording, FixtureSpec]:
    """Read a MUKCa placement folder (``hole_0.csv``, ``hole_1.csv``) or a folder of them.

    Each ``hole_<k>.csv`` has one configuration per row, joint angles [rad] in the URDF's joint order (the
    robot's order), and may start with a header naming the joints, or carry a gripper's fingers after them
    (:func:`_hole_rows`). Placements are the folders holding hole files at or below ``path`` (one level for
    MUKCa's ``robot/placement``, deeper for ``robot/day/placement``: :func:`_placements`). Fixtures are named
    ``<placement>_h<k>``, ``<placement>`` the folder's path below ``path``; ``hole_0`` and ``hole_1`` of a
    placement are ``distance`` apart (MUKCa's plate); other holes (a third socket) have no known distance.

    Args:
        path: a placement folder or a folder of placement folders.
        model: the robot (joint count and limits).
        distance: socket centre distance [m], > 0.

    Returns:
        The labelled recording (no time stamps) and the fixtures with their known distances.

    Raises:
        RecordingError: no such folder, no hole files, a row with the wrong number of fields or a bad number, an
            angle outside the joint limits.
    """
    root = check_source(path)
    if not root.is_dir():
        raise RecordingError(f"{root}: field 'SOURCE': a MUKCa source is a folder (placement or folder of them)")
    placements = _placements(root)
    _warn_several_groups(root, placements)
    q: list[list[float]] = []
    labels: list[str] = []
    rows: list[str] = []
    names: list[str] = []
    notes: list[str] = []
    distances: list[tuple[str, str, float]] = []
    for folder in placements:
        holes = _hole_files(folder)
        placement = _placement_name(root, folder)
        if "," in placement:
            raise RecordingError(f"{folder}: field 'placement': a folder name with a comma cannot name a fixture")
        for k, file in holes:
            name = f"{placement}_h{k}"
            found, where, said = _hole_rows(file, model)
            if not found:
                raise RecordingError(f"{file}: row 1, field 'q1': no configurations")
            q += found
            rows += where
            labels += [name] * len(found)
            notes += said
            names.append(name)
        numbers = [k for k, _ in holes]
        if 0 in numbers and 1 in numbers:  # the plate's two sockets; a third one's distance is not known
            distances.append((f"{placement}_h0", f"{placement}_h1", float(distance)))
        elif len(holes) >= 2:  # hole_0 and hole_2 are not the two sockets --distance apart
            notes.append(f"{folder.name}: no hole_0.csv and hole_1.csv pair: no known distance (holes "
                         f"{', '.join(map(str, numbers))}: which two are --distance apart is not known)")
    recording = Recording(np.array(q, dtype=float), None, np.array(labels), str(root), tuple(rows),
                          tuple(dict.fromkeys(notes)))
    recording.check_limits(model)
    seen: dict[str, str] = {}
    for name in names:  # a hole file copied for another socket: the fit would find two sockets at one point
        index = np.flatnonzero(recording.labels == name)
        digest = configurations_digest(recording.q[index])
        if digest in seen:
            raise RecordingError(f"{rows[index[0]]}, field 'q*': the same {len(index)} configurations as fixture "
                                 f"{seen[digest]} (one recording copied for two sockets?)")
        seen[digest] = name
    return recording, FixtureSpec(names=tuple(names), distances=distances)


# -------------------------------------------------------------------------------- joint CSV
def read_joint_csv(path: str | os.PathLike, model: RobotModel) -> Recording:
    """Read a CSV of joint angles whose header names the joints.

    Header: the robot's joint names (e.g. ``panda_joint1..7`` as franka_ros names them) or
    ``q1..qn``, in any order, other columns (fingers, velocities) ignored; an optional time
    column (``t``, ``time``, ``stamp``, ``timestamp`` [s]; values above 1e15 are nanoseconds; or named with
    its unit: ``time_ns``, ``stamp_us``, ``time [ms]``, PlotJuggler's ``__time`` [s]) and an optional
    ``fixture`` column (then the recording is labelled). ``samples.csv`` is such a file.

    Raises:
        RecordingError: no such file, no header, a joint missing from it, a row with a missing field or a bad
            number, an empty fixture label, an angle outside the joint limits; stamps of an unlabelled
            recording whose median step is outside :data:`STEP_RANGE` (milliseconds or microseconds in a
            column read as seconds or nanoseconds).
    """
    path = check_source(path)
    if path.is_dir():  # iter_lines said 'cannot read: Is a directory', naming no field nor what the folder is
        bag = (path / "metadata.yaml").is_file() or any(path.glob("*.db3")) or any(path.glob("*.mcap"))
        hint = ": it is a ROS 2 bag, use --format bag" if bag else ": it holds MUKCa per-socket files, use --format " \
            "mukca" if holds_mukca(path) else ""
        raise RecordingError(f"{path}: field 'SOURCE': a folder, not a CSV file{hint}")
    header: list[str] | None = None
    # joints, stamps and line numbers grow in place, block by block (a list of blocks and their concatenation were
    # 230 MB of a 1.8 M-row CSV, and the blocks freed stayed in the heap)
    angles, stamps, lines = _Growing(), _Growing(), _Growing(dtype=np.int64)
    labels: list[np.ndarray] = []
    first = 1
    for block in iter_lines(path, RecordingError):  # streamed: an error stops the reading
        start, first = first, first + len(block)
        if header is None:
            for k, line in enumerate(block):
                if not is_skipped(line) or line.lstrip().startswith("#"):  # a header may start with '#'
                    where = f"{path}: row {start + k}"
                    if _comment_before_header(line, model, where):  # provenance lines of samples.csv
                        continue
                    header = [f.strip() for f in parse_line(line, where, RecordingError)]
                    check_separator(header, where, RecordingError)
                    if all(_is_number(f) for f in header):
                        raise RecordingError(
                            f"{where}, field 'header': numbers, not a header naming the joints "
                            "(a MUKCa hole_<k>.csv? import its folder with --format mukca)"
                        )
                    index, names = _match_columns(header, model, where)
                    time_col, unit = _time_column(header)
                    label_col = header.index("fixture") if "fixture" in header else None
                    columns = ([time_col] if time_col is not None else []) + list(index)
                    block, start = block[k + 1 :], start + k + 1
                    break
            if header is None or not block:
                continue
        data = plain_values(block, len(header), columns)
        if data is not None:
            found = np.arange(start, start + len(block))
            names_ = [line.split(",")[label_col].strip() for line in block] if label_col is not None else []
            if "" in names_:
                data = None
        if data is None:  # not plain: line by line, naming the row and field of the first problem
            data, found, names_ = _careful_block(block, start, path, header, columns, label_col)
        if time_col is not None:
            stamps.add(data[:, 0])
            data = data[:, 1:]
        angles.add(data)
        lines.add(found)
        labels.append(np.array(names_, dtype=str))
    if header is None:
        raise RecordingError(f"{path}: row 1, field 'header': empty file (expected a header naming the joints)")
    if not angles.size:
        raise RecordingError(f"{path}: row 2, field {header[index[0]]!r}: no samples after the header")
    values = angles.array()
    t = stamps.array() if time_col is not None else None
    label_values = np.concatenate(labels) if label_col is not None else None
    if t is not None and unit is not None:
        t = t * _UNITS[unit.lower()]
    elif t is not None and np.nanmax(np.abs(t)) > NANOSECONDS_ABOVE:
        t = t * 1e-9
    rows = RowNames(path, lines.array())
    if t is not None and label_values is None:  # the stamps will segment the recording: they must be seconds
        _check_step(t, path, header[time_col], rows)
    recording = Recording(values, t, label_values, str(path), rows,
                          clock=f"column {header[time_col]!r}" if time_col is not None else "",
                          time_field=header[time_col] if time_col is not None else "")
    recording.check_limits(model, names)
    if t is not None and label_values is None and np.all(np.diff(t) >= 0):  # a stream to segment: no jumps in it,
        _refuse_jump(recording, header[time_col])  # and a row stamped as the one before is a repeat or refused
        keep, notes = repeated_stamps(recording.q, t, recording.rows, header[time_col], "row")
        if not keep.all():  # a copy of every array only when a row is dropped
            recording = replace(recording, q=recording.q[keep], t=t[keep], rows=rows.select(keep), notes=notes)
    return replace(recording, notes=recording.notes + _more_joints(header, names, path))


def holds_mukca(folder: Path) -> bool:
    """Whether ``folder`` holds MUKCa per-socket files (``hole_*.csv``), itself or one level down: the hint of a
    refusal that was given it as another format."""
    return any(folder.glob("hole_*.csv")) or any(folder.glob("*/hole_*.csv"))


class _Growing:
    """Rows appended block by block into one array that grows in place (``ndarray.resize``: a realloc, which moves
    no page of a large array on Linux), so that a long recording is held once, not as its blocks beside their
    concatenation.

    Attributes:
        size: rows appended so far.
    """

    def __init__(self, dtype: type = float):
        self._data: np.ndarray | None = None
        self._dtype = dtype
        self.size = 0

    def add(self, block: np.ndarray) -> None:
        """Append (B,) or (B, m) rows (the same m every time)."""
        end = self.size + len(block)
        if self._data is None:
            self._data = np.empty((max(len(block), 1), *block.shape[1:]), dtype=self._dtype)
        if end > len(self._data):  # at least doubled: a few reallocs for a long recording
            self._data.resize((max(end, 2 * len(self._data)), *self._data.shape[1:]), refcheck=False)
        self._data[self.size : end] = block
        self.size = end

    def array(self) -> np.ndarray:
        """The rows appended, (size,) or (size, m) (the buffer trimmed to them; nothing more may be appended)."""
        data, self._data = self._data, None
        if data is None:
            return np.empty(0, dtype=self._dtype)
        data.resize((self.size, *data.shape[1:]), refcheck=False)
        return data


def _more_joints(header: list[str], names: list[str], path) -> tuple[str, ...]:
    """One note when the header goes on numbering the arm's joints past the last one (``q8, q9`` beside ``q1..q7``):
    those columns are not read, and a file of an arm with more joints would be read wrong (a review: a ``q1..q9``
    CSV read for a 7-joint arm dropped two columns without a word)."""
    match = re.fullmatch(r"(.*?)(\d+)", names[-1]) if names else None
    if match is None:
        return ()
    stem, last = match.group(1).lower(), int(match.group(2))
    more = [f for f in header if (m := re.fullmatch(r"(.*?)(\d+)", f.strip())) and m.group(1).lower() == stem
            and int(m.group(2)) > last]
    if not more:
        return ()
    return (f"{path}: columns {', '.join(more)} go on after the arm's {names[0]}..{names[-1]} and are not read "
            f"(a gripper's or a rail's? a file of an arm with more joints would be read wrong: check the robot file)",)


def _refuse_jump(recording: Recording, field: str) -> None:
    """Refuse a continuous recording whose joints jump faster than :data:`MAX_JOINT_SPEED` between two rows, as a
    bag's are refused (a review: a 0.08 rad one-row jump of joint 7 was refused in a bag, passed in a CSV).

    Raises:
        RecordingError: one line naming the row, the jump and its likely causes.
    """
    found = first_jump(recording.q, recording.t)
    if found is None:
        return
    k, step, dt = found
    raise RecordingError(
        f"{recording.rows[k]}, field {field!r}: the joints move {step:.3g} rad in {dt:.3g} s from the row before "
        f"(faster than {MAX_JOINT_SPEED:g} rad/s): a joint reading that jumped (an encoder glitch: remove the row), "
        "or two recordings in one file"
    )


#: A column of a topic exported by PlotJuggler: ``/joint_states/panda_joint1/position``.
_TOPIC_POSITION = re.compile(r"^(?:.*/)?([^/]+)/position$")


def _in_robot_case(header: list[str], model: RobotModel) -> list[str] | None:
    """``header`` with each name that equals one of the robot's joint names ignoring case written as the robot
    writes it (``Panda_Joint1`` -> ``panda_joint1``); None when nothing changes or when it is ambiguous: two
    header names, or two of the robot's names, that equal each other ignoring case."""
    known: dict[str, set[str]] = {}
    for name in arm_joint_names(model):
        known.setdefault(name.casefold(), set()).add(name)
    hits = [name.casefold() for name in header if name.casefold() in known]
    if len(set(hits)) != len(hits) or any(len(known[folded]) > 1 for folded in hits):
        return None
    respelled = [next(iter(known[name.casefold()])) if name.casefold() in known else name for name in header]
    return None if respelled == header else respelled


def _match_any_case(header: list[str], model: RobotModel, where: str) -> tuple[np.ndarray, list[str]]:
    """:func:`match_joints`, and when it finds a joint missing, again with the header's names in the robot's
    case where that is unambiguous (:func:`_in_robot_case`: a spreadsheet's ``Panda_Joint1``)."""
    try:
        return match_joints(header, model, where)
    except RecordingError as error:
        respelled = _in_robot_case(header, model)
        if respelled is None:
            raise
        try:
            return match_joints(respelled, model, where)
        except RecordingError:
            raise error from None


def _match_columns(header: list[str], model: RobotModel, where: str) -> tuple[np.ndarray, list[str]]:
    """:func:`match_joints` of a CSV header (names in any case, :func:`_match_any_case`); a header that names no
    convention's joints is tried again with its topic columns read as joint names
    (``/joint_states/<joint>/position``, PlotJuggler's export)."""
    try:
        return _match_any_case(header, model, where)
    except RecordingError:
        plain = [m.group(1) if (m := _TOPIC_POSITION.match(name)) else name for name in header]
        if plain == header:
            raise
        try:
            return _match_any_case(plain, model, where)
        except RecordingError as error:
            if "named twice" in str(error):  # two topics' columns of one joint: say that, not 'missing'
                raise error from None
        raise


def _comment_before_header(line: str, model: RobotModel, where: str) -> bool:
    """Whether a ``#`` line before the header is a comment (the provenance block spherecal writes first in
    samples.csv), not a header that starts with ``#`` (``# time,panda_joint1,...`` of numpy's savetxt)."""
    if not line.lstrip().startswith("#"):
        return False
    try:
        fields = [f.strip().lstrip("#").strip() for f in parse_line(line, where, RecordingError)]
    except RecordingError:
        return True
    return bool(missing_joints(fields, model)) and bool(
        missing_joints([_TOPIC_POSITION.sub(r"\1", f) for f in fields], model))


def _time_column(header: list[str]) -> tuple[int | None, str | None]:
    """``(index, unit)`` of the header's time column: one of :data:`TIME_COLUMNS` (unit None: seconds, or
    nanoseconds above :data:`NANOSECONDS_ABOVE`), else a name with its unit (``time_ns``, ``stamp [ms]``)."""
    for name in TIME_COLUMNS:
        if name in header:
            return header.index(name), None
    for k, name in enumerate(header):
        match = _TIMED.match(name)
        if match:
            return k, match.group(2) or ("s" if match.group(1) == "__time" else None)
    return None, None


def _check_step(t: np.ndarray, path: Path, field: str, rows) -> None:
    """Refuse time stamps whose typical step is not a joint recording's in seconds (:data:`STEP_RANGE`).

    Raises:
        RecordingError: one line naming the column, the median step and the unit it suggests.
    """
    steps = np.diff(t)
    steps = steps[steps > 0]
    if not steps.size:
        return
    step = float(np.median(steps))
    low, high = STEP_RANGE
    if low <= step < high:
        return
    guesses = [(1e-9, "nanoseconds"), (1e-6, "microseconds"), (1e-3, "milliseconds")]
    likely = next((unit for scale, unit in guesses if low <= step * scale < high), None) if step >= high else (
        "microseconds read as nanoseconds" if low <= step * 1e3 < high else None)
    k = int(np.flatnonzero(np.diff(t) > 0)[0]) + 1
    raise RecordingError(
        f"{rows[k]}, field {field!r}: samples {step:.3g} s apart (median), a joint recording's are "
        f"{low:g} s to under {high:g} s: the column is not in seconds{f' ({likely}?)' if likely else ''}; give "
        "seconds, nanoseconds as integers above 1e15, or name the unit in the header (time_ns, time_us, time_ms)"
    )


def _is_number(text: str) -> bool:
    try:
        plain_float(text)
    except ValueError:
        return False
    return True


def _careful_block(block: list[str], start: int, path: Path, header: list[str], columns: list[int],
                   label_col: int | None) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """A block of a joint CSV line by line (csv module): values of ``columns``, lines, labels."""
    values: list[list[float]] = []
    found: list[int] = []
    labels: list[str] = []
    for line, fields in block_rows(block, start, path, RecordingError):
        where = f"{path}: row {line}"
        if len(fields) < len(header):
            missing = header[len(fields)]
            raise RecordingError(f"{where}, field {missing!r}: {len(fields)} fields, the header has {len(header)}")
        extra = next((k for k in range(len(header), len(fields)) if fields[k].strip()), None)
        if extra is not None:  # a value past the header's columns: a row shifted, or two rows run together (empty
            # fields there, a logger's trailing comma, hold nothing to misread)
            raise RecordingError(f"{where}, field 'column {extra + 1}': {len(fields)} fields, the header has "
                                 f"{len(header)} (a value past the last named column)")
        if [f.strip() for f in fields] == header:
            raise RecordingError(f"{where}, field {header[columns[0]]!r}: the header again (two files concatenated? "
                                 "a recording has one header; merge the rows without it)")
        values.append([_number(fields[i], f"{where}, field {header[i]!r}") for i in columns])
        if label_col is not None:
            label = fields[label_col].strip()
            if not label:
                raise RecordingError(f"{where}, field 'fixture': empty fixture name")
            labels.append(label)
        found.append(line)
    return np.array(values, dtype=float).reshape(len(found), len(columns)), np.array(found, dtype=int), labels
