"""ROS bags in: ``sensor_msgs/JointState`` messages of a ROS 2 (sqlite3, MCAP) or ROS 1 bag, no ROS install.

Read with the pure-Python ``rosbags`` library; joints are matched by name to the robot's
(:func:`.importers.match_joints`), extra joints (a gripper's fingers) are ignored. A message naming none
of the arm's joints (a gripper driver publishing its fingers alone on the same topic, interleaved with
the arm's messages) is skipped and counted: the import report says how many and what they named. So is a
message that names joints but carries no positions (its velocities or efforts alone: every array of a
``JointState`` is optional).

Messages alike but for their stamps and values are read at their byte offsets in arrays (:class:`_Layout`), one
of each kind deserialised to check it; a ROS 1 bag's messages are handed a chunk at a time (:mod:`.bag1`).
"""

from __future__ import annotations

import os
import struct
from array import array
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from spherecal.correction.files.csv_rows import RowNames
from spherecal.correction.files.text_input import read_text
from spherecal.correction.files.yaml_safe import MAX_FILE_BYTES, load_yaml, node_line
from spherecal.correction.model import RobotModel

from .bag_files import check_mcap, storage_files, storage_module
from .importers import (
    MAX_JOINT_SPEED,
    Recording,
    RecordingError,
    arm_joint_names,
    check_source,
    first_jump,
    holds_mukca,
    joint_name_candidates,
    match_joints,
    missing_joints,
    repeated_stamps,
)

#: Default topic.
TOPIC = "/joint_states"


def read_bag(path: str | os.PathLike, model: RobotModel, topic: str = TOPIC) -> Recording:
    """Read the robot's joint angles from a bag.

    Args:
        path: a ROS 2 bag folder (sqlite3 or MCAP storage) or a ROS 1 ``.bag`` file.
        model: the robot (joint names, limits).
        topic: the ``sensor_msgs/JointState`` topic.

    Returns:
        An unlabelled recording, in time order; ``t`` [s] from the message header stamps (the bag's
        receive time where a stamp is zero), ``rows`` naming the message number on the topic.

    Raises:
        RecordingError: unreadable bag (a damaged storage file named: an MCAP file truncated or not MCAP, by its
            magic bytes, :mod:`.bag_files`), no such topic, another message type, a message whose
            ``position`` does not match its ``name``, a missing joint (named), an angle outside
            the limits.
    """
    from rosbags.highlevel import AnyReader, AnyReaderError  # rosbags loads in ~0.3 s: only when a bag is read
    from rosbags.typesys import Stores, get_typestore  # (same)

    path = check_source(path)
    if path.name == "metadata.yaml" and path.is_file():  # rosbags: "Unrecognized storage format '.yaml'"
        raise RecordingError(f"{path}: field 'SOURCE': the bag's metadata.yaml; give the bag's folder, {path.parent}")
    if path.is_file() and path.suffix.lower() == ".csv":  # rosbags: "Unrecognized storage format '.csv'"
        raise RecordingError(f"{path}: field 'SOURCE': a CSV file, not a bag (a ROS 1 .bag file or a ROS 2 bag "
                             "folder): use --format csv")
    unindexed: tuple[str, ...] = ()
    info = None
    if path.is_dir() and not (path / "metadata.yaml").is_file():  # rosbags would say the folder is a missing file
        path, unindexed = _without_metadata(path)
    elif path.is_dir():
        info = _check_metadata(path / "metadata.yaml")
    files = storage_files(path, info)
    for file in files:  # rosbags: 'File end magic is invalid.' of a truncated MCAP file, naming the folder only
        check_mcap(file)
    try:
        found = _read_ros1(path, model, topic) if path.suffix == ".bag" and path.is_file() else None
        if found is None:  # a ROS 2 bag, or a ROS 1 bag that rosbags' reader reads message by message
            # rosbags 0.11.9 counts every topic's messages when it opens a .db3 (Sqlite3Reader._open: topics LEFT JOIN
            # messages GROUP BY, over an index SQLite builds of all rows: 1.1 s of a 1.8 M-message bag's 1.3 s open,
            # +6 MiB) whatever metadata.yaml says, with no option to skip it; messages() reads the topic's rows only
            with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
                connections, topic = _connections(reader.connections, topic, path)
                messages = _Messages(model, f"{path}: {topic} message ")  # as RowNames names them
                messages.read_checked(lambda: messages.read(reader, connections))
        else:
            messages, topic = found
    except RecordingError:
        raise
    except (AnyReaderError, OSError) as error:
        raise RecordingError(_damaged(path, files, error, str(error))) from None
    except Exception as error:  # rosbags' own reader and deserialisation errors have no common base
        origin = _raised_by_rosbags(error)
        if not origin:
            raise
        said = str(error) or f"{type(error).__name__} in {origin}"
        raise RecordingError(_damaged(path, files, error, said)) from None
    skipped, partial, unpositioned = messages.skipped, messages.partial, messages.unpositioned
    others = "; ".join(f"{count} naming {', '.join(names[:4]) or 'no joint'}{', ...' if len(names) > 4 else ''}"
                       for names, count in skipped.items())
    some = "; ".join(f"{count} naming {', '.join(names[:4])}{', ...' if len(names) > 4 else ''} (not "
                     f"{', '.join(missing_joints(names, model)[:3])})" for names, (count, _) in partial.items())
    if not messages.count and partial:
        first = min(k for _, k in partial.values())
        if len(partial) == 1 or missing_joints(set().union(*partial), model):  # a joint missing from the topic
            names = next(names for names, (_, k) in partial.items() if k == first)
            match_joints(list(names), model, f"{path}: {topic} message {first}")  # raises, naming that joint
        raise RecordingError(
            f"{path}: {topic} message {first}, field 'name': no message names all of the arm's joints ({some}): "
            "joint angles split over messages are not of one instant; record all of the arm's joints in one message"
        )
    if not messages.count:
        if unpositioned and not skipped:
            raise RecordingError(f"{path}: {topic} message 1, field 'position': none of the {unpositioned} messages "
                                 "carries joint positions (velocities or efforts only)")
        if skipped:
            expected = " or ".join(dict.fromkeys(names[0] for names in joint_name_candidates(model)))
            raise RecordingError(
                f"{path}: {topic} message 1, field 'name': no message names the arm's first joint ({expected}); "
                f"the topic carries {others}"
            )
        raise RecordingError(f"{path}: field '--topic': no messages on {topic!r}")
    notes = unindexed + (
        (f"skipped {sum(skipped.values())} messages on {topic} without any of the arm's joints ({others}): "
         "another device (a gripper) publishing on the same topic",) if skipped else ()
    ) + ((f"skipped {unpositioned} messages on {topic} without positions (velocities or efforts only)",)
         if unpositioned else ()) + ((f"skipped {sum(c for c, _ in partial.values())} messages on {topic} naming "
                                      f"only some of the arm's joints ({some})",) if partial else ())
    numbers, stamps, q = messages.arrays()
    order = np.argsort(stamps, kind="stable")
    if np.any(order != np.arange(order.size)):  # (a copy of q otherwise)
        q = q[order]
    t, rows = stamps[order], RowNames(path, numbers[order], f"{topic} message")
    recording = Recording(q, t, None, str(path), rows, notes, clock="header.stamp", time_field="header.stamp")
    recording.check_limits(model)  # first: degrees in a radians field jump too, and this says which it is
    _refuse_interleaved(q, t, rows, stamps, numbers)  # before the stamps alike: two streams' clash is named as theirs
    keep, repeats = repeated_stamps(q, t, rows, "header.stamp", "message")
    if keep.all():
        return replace(recording, notes=notes + repeats)
    return replace(recording, q=q[keep], t=t[keep], rows=rows.select(keep), notes=notes + repeats)


#: The one top-level key of a ROS 2 bag's ``metadata.yaml``.
METADATA_KEY = "rosbag2_bagfile_information"


def _damaged(path: Path, files: list[Path], error: BaseException, said: str) -> str:
    """The refusal of a bag rosbags could not read (``said``: what it said of ``error``): naming the bag's one storage
    file (``files``) as damaged when rosbags' storage layer raised it (an MCAP file damaged inside, an SQLite file
    that is not a database), else ``path`` (the folder, or a ROS 1 bag)."""
    if len(files) == 1 and storage_module(error):
        return f"{files[0]}: cannot read the bag: a damaged storage file ({said})"
    return f"{path}: cannot read the bag: {said}"


def _check_metadata(meta: Path) -> dict:
    """Refuse a ``metadata.yaml`` that is not a ROS 2 bag's, naming it (rosbags said "Invalid bag metadata: 'NoneType'
    object is not subscriptable" of an empty one, and named the folder only); return its ``rosbag2_bagfile_information``
    mapping.

    Raises:
        RecordingError: unreadable, invalid YAML (its row), or no ``rosbag2_bagfile_information`` mapping.
    """
    data, root = load_yaml(read_text(meta, RecordingError, limit=MAX_FILE_BYTES), str(meta), RecordingError)
    if isinstance(data, dict) and isinstance(data.get(METADATA_KEY), dict):
        return data[METADATA_KEY]
    got = ("an empty file" if data is None else f"keys {', '.join(map(repr, list(data)[:3]))}"
           if isinstance(data, dict) else f"a {type(data).__name__}")
    row = node_line(root, METADATA_KEY, key_line=True) if isinstance(data, dict) else 1
    raise RecordingError(f"{meta}: row {row}, field {METADATA_KEY!r}: not a ROS 2 bag's metadata ({got}); "
                         f"`ros2 bag reindex {meta.parent}` writes it again from the storage file")


def _without_metadata(path: Path) -> tuple[Path, tuple[str, ...]]:
    """The one storage file of a ROS 2 bag folder without its ``metadata.yaml`` (``ros2 bag record`` writes it when it
    stops: a recording killed, or its terminal closed, leaves the folder without one; a review of a ROS 2 trial), read
    as a bag of its own, and a line saying so.

    Raises:
        RecordingError: no storage file (MUKCa files named), or several (a split recording: ``ros2 bag reindex``).
    """
    files = sorted(f for f in path.iterdir() if f.suffix in (".db3", ".mcap") and f.is_file())
    if len(files) == 1:
        return files[0], (f"{path} has no metadata.yaml (a recording stopped before ros2 bag record wrote it?): read "
                          f"its one storage file, {files[0].name}",)
    if files:
        shown = ", ".join(f.name for f in files[:3]) + (", ..." if len(files) > 3 else "")
        raise RecordingError(
            f"{path}: cannot read the bag: a ROS 2 bag folder holds a metadata.yaml, this one has none and "
            f"{len(files)} storage files ({shown}): `ros2 bag reindex {path}` writes it (a recording stopped before "
            "ros2 bag record did)"
        )
    hint = "; it holds MUKCa per-socket files: use --format mukca" if holds_mukca(path) else ""
    raise RecordingError(
        f"{path}: cannot read the bag: a ROS 2 bag folder holds a metadata.yaml, this one has none{hint}"
    )


def _connections(connections: list, topic: str, path: Path) -> tuple[list, str]:
    """The bag's connections of ``topic`` (``joint_states`` typed for ``/joint_states`` too) and the topic's name.

    Raises:
        RecordingError: no such topic, a topic of another message type.
    """
    chosen = [c for c in connections if c.topic == topic]
    if not chosen and not topic.startswith("/"):  # 'joint_states' typed for '/joint_states'
        chosen = [c for c in connections if c.topic == "/" + topic]
        topic = "/" + topic if chosen else topic
    if not chosen:
        topics = sorted({c.topic for c in connections})
        raise RecordingError(f"{path}: field '--topic': no topic {topic!r} in the bag (has {', '.join(topics)})")
    for connection in chosen:
        if connection.msgtype.replace("/msg/", "/") != "sensor_msgs/JointState":
            raise RecordingError(
                f"{path}: field '--topic': {topic!r} carries {connection.msgtype}, expected sensor_msgs/JointState"
            )
    return chosen, topic


def _raised_by_rosbags(error: Exception) -> str:
    """The rosbags module ``error`` comes from (its type's, or the one whose code raised it: a ROS 1 bag whose record
    time disagrees with its index stops in rosbags on a bare ``assert``), or "" for an error of ours or Python's."""
    if type(error).__module__.startswith("rosbags"):
        return type(error).__module__
    frame = error.__traceback__
    while frame is not None and frame.tb_next is not None:
        frame = frame.tb_next
    module = "" if frame is None else str(frame.tb_frame.f_globals.get("__name__", ""))
    return module if module.startswith("rosbags") else ""


def _read_ros1(path: Path, model: RobotModel, topic: str) -> tuple[_Messages, str] | None:
    """The messages of a ROS 1 bag read a chunk at a time (:mod:`.bag1`), and the topic's name; None when the bag
    has anything that reader leaves to rosbags' (then read as before, message by message, its errors said as
    rosbags says them).

    Raises:
        RecordingError: as :func:`read_bag`.
    """
    from .bag1 import IndexedReader, Unusual, blocks, typestore  # bag1 imports rosbags: only when a bag is read

    try:
        reader = IndexedReader(path)
        reader.open()
    except Exception:  # whatever it is, rosbags' AnyReader says it
        return None
    try:
        store = typestore(reader)
        connections, topic = _connections(reader.connections, topic, path)
        messages = _Messages(model, f"{path}: {topic} message ")
        if len({c.msgtype for c in connections}) != 1:
            return None
        msgtype = connections[0].msgtype
        messages.read_checked(lambda: messages.read_blocks(
            blocks(reader, connections), lambda raw: store.deserialize_ros1(raw, msgtype)))
    except Unusual:
        return None
    finally:
        reader.close()
    return messages, topic


def _stamps(sec: np.ndarray, nanosec: np.ndarray, received: np.ndarray) -> np.ndarray:
    """(K,) stamps [s]: ``header.stamp`` (``sec``, ``nanosec`` (K,)), or the bag's receive time ``received`` (K,) [ns]
    where it is zero."""
    seconds = sec + nanosec * 1e-9
    return np.where(seconds > 0, seconds, received * 1e-9)


@dataclass
class _Group:
    """The messages read with one list of joint names: their numbers, stamps and the arm's joint angles.

    Only the arm's joints are kept (``index``: their places in the names, in the model's order), and the stamp as one
    float (:func:`_stamps`): a Panda's messages carry 9 positions (the fingers too) and the blocks held them all with
    four int64 columns (number, sec, nanosec, receive time) until joined, 104 bytes a message where 72 do."""

    index: np.ndarray  # the arm's joints' places in the names
    numbers: array = field(default_factory=lambda: array("q"))  # 1-based message number on the topic
    stamps: array = field(default_factory=lambda: array("d"))  # [s] (:func:`_stamps`)
    q: array = field(default_factory=lambda: array("d"))  # the arm's joint angles [rad], n per message
    blocks: list = field(default_factory=list)  # (numbers, stamps, q): read in arrays

    def parts(self):
        """``(numbers, stamps, q)`` of the group's messages, a block at a time (in no particular order): the ones
        deserialised, then each block read in arrays; ``q`` (K, n) [rad]."""
        yield (np.frombuffer(self.numbers, dtype=np.int64), np.frombuffer(self.stamps, dtype=float),
               np.frombuffer(self.q, dtype=float).reshape(-1, len(self.index)))
        yield from self.blocks

    def columns(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(numbers, stamps, q)`` of every message of the group (the deserialised ones, then the blocks in the order
        read), ``q`` (K, n) the arm's joint angles [rad]. Each block is let go once copied (the blocks and their copies
        side by side, then concatenated, were a read's memory peak)."""
        parts, self.blocks = [*self.parts()][::-1], []
        total = sum(len(part[0]) for part in parts)
        out = (np.empty(total, dtype=np.int64), np.empty(total), np.empty((total, len(self.index))))
        at = 0
        while parts:
            part = parts.pop()
            for column, values in zip(out, part, strict=True):
                column[at : at + len(values)] = values
            at += len(part[0])
        return out


@dataclass
class _Layout:
    """The fixed bytes of serialised ``JointState`` messages alike but for their stamps and arrays' values (and a ROS 1
    message's ``header.seq``): a message whose bytes match them everywhere else has the same names and array lengths,
    and needs no deserialising (its stamp and positions are read at fixed offsets).

    Both serialisations put ``header.stamp``'s ``sec`` (int32) and ``nanosec`` (uint32) at bytes 4-12 and the
    ``frame_id`` at 12: after CDR's 4-byte encapsulation, after ROS 1's ``header.seq`` (uint32, not read)."""

    head: bytes  # the encapsulation (little-endian CDR); b"" in ROS 1 (the seq, that changes, is not compared)
    middle: bytes  # from the frame_id's length to the positions' count
    velocity: bytes  # velocity's count, at ``at_velocity``
    effort: bytes  # effort's count, at ``at_effort``
    at_velocity: int
    at_effort: int
    at_position: int  # where the positions start
    length: int  # of the whole message
    names: tuple[str, ...]
    group: _Group | None = None  # the arm's messages of these names (None: another device's, no positions, ...)
    arm: slice | np.ndarray = field(default_factory=lambda: slice(None))  # the group's joints' places in the names
    raw: list = field(default_factory=list)  # messages matched and not yet read into ``group``
    numbers: array = field(default_factory=lambda: array("q"))  # theirs
    received: array = field(default_factory=lambda: array("q"))

    @property
    def positioned(self) -> bool:
        """Its messages carry positions."""
        return self.at_velocity > self.at_position

    def matches(self, raw: bytes) -> bool:
        return (len(raw) == self.length and raw.startswith(self.middle, 12) and raw.startswith(self.head)
                and raw.startswith(self.velocity, self.at_velocity) and raw.startswith(self.effort, self.at_effort))

    def matching(self, data: np.ndarray) -> np.ndarray:
        """(K,) bool: which of the messages ``data`` (K, length) bytes (uint8) :meth:`matches`."""
        same = np.ones(len(data), dtype=bool)
        for start, value in ((0, self.head), (12, self.middle), (self.at_velocity, self.velocity),
                             (self.at_effort, self.effort)):
            if value:
                same &= (data[:, start : start + len(value)] == np.frombuffer(value, dtype=np.uint8)).all(axis=1)
        return same

    def read(self, data: np.ndarray, numbers: np.ndarray, received: np.ndarray) -> tuple[np.ndarray, ...]:
        """``(numbers, stamps, q)`` (a :class:`_Group` block) of messages of this layout: ``data`` (K, length) their
        bytes (uint8), ``numbers`` and ``received`` [ns] (K,) theirs; ``q`` (K, n) the arm's joint angles [rad]."""
        stamps = np.ascontiguousarray(data[:, 4:12]).view(np.dtype([("sec", "<i4"), ("nanosec", "<u4")]))[:, 0]
        positions = np.ascontiguousarray(data[:, self.at_position:self.at_velocity]).view("<f8")
        return (np.asarray(numbers, dtype=np.int64),
                _stamps(stamps["sec"].astype(np.int64), stamps["nanosec"].astype(np.int64),
                        np.asarray(received, dtype=np.int64)),
                positions[:, self.arm].astype(float, copy=False))

    def flush(self) -> None:
        """Read the stamps and positions of the messages matched into the group's arrays, all at once."""
        if not self.raw:
            return
        data = np.frombuffer(b"".join(self.raw), dtype=np.uint8).reshape(-1, self.length)
        self.group.blocks.append(self.read(data, np.frombuffer(self.numbers, dtype=np.int64).copy(),
                                           np.frombuffer(self.received, dtype=np.int64).copy()))
        self.raw, self.numbers, self.received = [], array("q"), array("q")


#: Messages of one layout kept as bytes before their stamps and positions are read into arrays, all at once.
_BLOCK = 20_000
_HEADER = struct.Struct("<iI")  # header.stamp's sec and nanosec, after the encapsulation (CDR) or the seq (ROS 1)
_COUNT = struct.Struct("<I")


def _layout_of(raw: bytes, message, cdr: bool) -> _Layout | None:
    """The :class:`_Layout` of a ``JointState`` message, little-endian CDR (``cdr``: ROS 2) or ROS 1 (packed, little
    endian, no padding, strings without a terminating NUL), when parsing its bytes by hand gives exactly what
    ``message`` (rosbags' deserialisation of them) holds; None otherwise (then every message of its kind is
    deserialised)."""
    try:
        if cdr and raw[:2] != b"\x00\x01":
            return None

        def align(at: int, size: int) -> int:  # CDR aligns from the end of the encapsulation; ROS 1 does not align
            return 4 + ((at - 4 + size - 1) // size) * size if cdr else at

        def count(at: int) -> tuple[int, int]:
            at = align(at, 4)
            return _COUNT.unpack_from(raw, at)[0], at

        def doubles(at: int) -> tuple[int, int, int]:  # (count's offset, values' offset, end)
            n, at = count(at)
            values = align(at + 4, 8) if n else at + 4
            return at, values, values + 8 * n

        size, at = count(12)
        at += 4 + size
        n, at = count(at)
        at += 4
        names = []
        for _ in range(n):
            size, at = count(at)
            names.append(raw[at + 4 : at + 4 + size - (1 if cdr else 0)].decode())  # CDR counts a NUL
            at += 4 + size
        at_count, at_position, at = doubles(at)
        at_velocity, velocity, at = doubles(at)
        at_effort, effort, end = doubles(at)
        sec, nanosec = _HEADER.unpack_from(raw, 4)
        stamp = message.header.stamp
        same = (tuple(names) == tuple(message.name) and (sec, nanosec) == (stamp.sec, stamp.nanosec)
                and raw[at_position:at_velocity] == np.asarray(message.position, dtype="<f8").tobytes()
                and raw[velocity:at_effort] == np.asarray(message.velocity, dtype="<f8").tobytes()
                and raw[effort:end] == np.asarray(message.effort, dtype="<f8").tobytes()
                and (end <= len(raw) <= end + 3 if cdr else len(raw) == end))
    except (struct.error, UnicodeDecodeError, AttributeError, TypeError, ValueError):
        return None
    if not same:
        return None
    return _Layout(raw[:4] if cdr else b"", raw[12:at_count + 4], raw[at_velocity:at_velocity + 4],
                   raw[at_effort:at_effort + 4], at_velocity, at_effort, at_position, len(raw), tuple(names))


class _Messages:
    """The ``JointState`` messages of a topic, read into arrays (never a Python object per message): those naming
    the arm's joints grouped by their names, the others counted (skipped: another device's; partial: some of the
    arm's joints; unpositioned: no positions). Deserialises one message of each :class:`_Layout` only (the first,
    to check it) and reads the others' stamps and positions at their offsets, in a ROS 2 or a ROS 1 bag alike;
    messages of no layout are deserialised."""

    def __init__(self, model: RobotModel, where: str):
        self.model, self.where = model, where
        self.arm = arm_joint_names(model)
        self.groups: dict[tuple[str, ...], _Group] = {}
        self.skipped: dict[tuple[str, ...], int] = {}  # names of messages without any arm joint -> count
        self.unpositioned = 0  # messages with names but no positions (a driver publishing velocities or efforts)
        self.partial: dict[tuple[str, ...], list] = {}  # names of some of the arm's joints -> [count, first message]
        self.count = 0  # messages of the arm read
        self.layouts: list[_Layout] = []

    def read(self, reader, connections) -> None:
        """Read every message of ``connections``, in the bag's order.

        Raises:
            RecordingError: a message whose ``position`` does not match its ``name``, a joint named twice, ...
                (as :func:`read_bag` says), naming the message.
        """
        layouts = self.layouts
        last: _Layout | None = None
        for k, (connection, timestamp, raw) in enumerate(reader.messages(connections=connections)):
            if last is not None:  # the bytes of the last message's layout: kept, read at its offsets in arrays
                if type(raw) is not bytes:
                    raw = bytes(raw)
                matched = last.matches(raw)
                if not matched:  # another layout seen before, or none (deserialised below)
                    found = next((other for other in layouts if other is not last and other.matches(raw)), None)
                    last, matched = (last, False) if found is None else (found, True)
                if matched:
                    if last.group is None:
                        self._other(last.names, last.positioned, k)
                        continue
                    last.raw.append(raw)
                    last.numbers.append(k + 1)
                    last.received.append(timestamp)
                    self.count += 1
                    if len(last.raw) >= _BLOCK:
                        last.flush()
                    continue
            message = reader.deserialize(raw, connection.msgtype)
            last = self._deserialised(bytes(raw), message, k, timestamp, reader.is2) or last

    def read_checked(self, read) -> None:
        """``read()`` (:meth:`read`, :meth:`read_blocks`), then :meth:`check_finite`: an earlier message's angle that
        is not finite is refused first, as it was read first, before what ``read`` raises too."""
        try:
            read()
        except Exception:
            self.check_finite()
            raise
        self.check_finite()

    def _deserialised(self, raw: bytes, message, k: int, timestamp: int, cdr: bool) -> _Layout | None:
        """Sort a message deserialised (:meth:`_add`) and keep its layout, the first ones' (None: no new layout)."""
        layout = _layout_of(raw, message, cdr) if len(self.layouts) < 16 else None
        self._add(message, k, timestamp)
        if layout is None:
            return None
        layout.group = self.groups.get(layout.names) if layout.positioned else None
        if layout.group is not None:
            index = layout.group.index
            layout.arm = slice(None) if np.array_equal(index, np.arange(len(layout.names))) else index
        self.layouts.append(layout)
        return layout

    def read_blocks(self, blocks, deserialize) -> None:
        """Read a ROS 1 bag's messages handed a run of one chunk's at a time (:func:`.bag1.blocks`), in the bag's
        order, as :meth:`read` does: the messages of a known layout in arrays, every other one deserialised
        (``deserialize(raw)``) and sorted on its own, in turn.

        Raises:
            RecordingError: as :meth:`read`.
        """
        for block in blocks:
            which = np.full(len(block.numbers), -1)  # the layout each message has (its place in self.layouts)
            for i in range(len(self.layouts)):
                self._match(block, i, which, 0)
            pending, done = np.flatnonzero(which < 0), 0
            while True:
                u = int(pending[0]) if pending.size else len(which)
                if u > done:
                    self._take(block, which, done, u)
                if u == len(which):
                    break
                raw = block.chunk[block.start[u] : block.start[u] + block.size[u]].tobytes()
                k = int(block.numbers[u]) - 1
                if self._deserialised(raw, deserialize(raw), k, int(block.received[u]), False) is not None:
                    self._match(block, len(self.layouts) - 1, which, u + 1)
                    pending = u + 1 + np.flatnonzero(which[u + 1 :] < 0)
                else:
                    pending = pending[1:]
                done = u + 1

    def _match(self, block, i: int, which: np.ndarray, first: int) -> None:
        """Mark the messages of ``block`` from ``first`` on that have no layout yet and layout ``i``'s bytes."""
        layout = self.layouts[i]
        candidates = first + np.flatnonzero((which[first:] < 0) & (block.size[first:] == layout.length))
        if candidates.size:
            which[candidates[layout.matching(_rows(block.chunk, block.start[candidates], layout.length))]] = i

    def _take(self, block, which: np.ndarray, first: int, end: int) -> None:
        """Read the messages ``first .. end - 1`` of ``block``, each of a known layout, in arrays: each layout's in
        the order of their first message (the counts of another device's names kept in the order they came)."""
        kinds, starts = np.unique(which[first:end], return_index=True)
        for i in kinds[np.argsort(starts)]:
            layout, mine = self.layouts[i], first + np.flatnonzero(which[first:end] == i)
            numbers = block.numbers[mine]
            if layout.group is None:
                self._other(layout.names, layout.positioned, int(numbers[0]) - 1, len(mine))
                continue
            data = _rows(block.chunk, block.start[mine], layout.length)
            layout.group.blocks.append(layout.read(data, numbers, block.received[mine]))
            self.count += len(mine)

    def _other(self, names: tuple[str, ...], positioned: bool, k: int, count: int = 1) -> None:
        """Count ``count`` messages of ``names``, the first ``k``, that are not the arm's: without positions, another
        device's, or some of the arm's joints only (``positioned`` and not disjoint from the arm: :meth:`_add`
        judged its names so)."""
        if not positioned and names:
            self.unpositioned += count
        elif self.arm.isdisjoint(names):
            self.skipped[names] = self.skipped.get(names, 0) + count
        else:
            self.partial.setdefault(names, [0, k + 1])[0] += count

    def _add(self, message, k: int, timestamp: int) -> None:
        """Sort a deserialised message (the checks of every message: see :meth:`read`)."""
        where = f"{self.where}{k + 1}"
        names = tuple(message.name)
        position = np.asarray(message.position, dtype=float)
        if not position.size and names:  # JointState's arrays are optional: velocities or efforts alone
            self._other(names, False, k)
            return
        if position.shape != (len(names),):
            raise RecordingError(f"{where}, field 'position': {position.size} positions for {len(names)} names")
        group = self.groups.get(names)
        if group is None:
            # another device's joints (a gripper), or the arm's state split over messages
            if self.arm.isdisjoint(names) or missing_joints(names, self.model):
                self._other(names, True, k)
                return
            group = self.groups[names] = _Group(match_joints(list(names), self.model, where)[0])
        stamp = message.header.stamp
        group.numbers.append(k + 1)
        group.stamps.append(float(_stamps(np.int64(stamp.sec), np.int64(stamp.nanosec), np.int64(timestamp))))
        group.q.extend(position[group.index])
        self.count += 1

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(numbers, stamps, q)`` of the arm's messages in the bag's order: (K,) message numbers, (K,) stamps [s]
        (``header.stamp``, or the bag's receive time where it is zero) and (K, n) joint angles [rad]."""
        for layout in self.layouts:
            layout.flush()
        self.layouts = []  # they hold their groups
        groups = []
        for names in list(self.groups):  # each group's blocks let go once read
            groups.append(self.groups.pop(names).columns())
        numbers, stamps, q = groups[0] if len(groups) == 1 else (
            np.concatenate([g[i] for g in groups]) for i in range(3))
        del groups
        order = np.argsort(numbers, kind="stable")
        if np.any(order != np.arange(order.size)):
            numbers, stamps, q = numbers[order], stamps[order], q[order]
        return numbers, stamps, q

    def check_finite(self) -> None:
        """Refuse the first message read whose arm's angles are not all finite.

        Raises:
            RecordingError: naming the message.
        """
        if not self.count:
            return
        for layout in self.layouts:
            layout.flush()
        bad = np.concatenate([numbers[~np.isfinite(q).all(axis=1)]
                              for g in self.groups.values() for numbers, _, q in g.parts()])
        if bad.size:
            raise RecordingError(f"{self.where}{int(bad.min())}, field 'position': not finite")


def _rows(chunk: np.ndarray, start: np.ndarray, width: int) -> np.ndarray:
    """(K, width) the bytes ``chunk[s : s + width]`` for each ``s`` of ``start`` (K,): a view when the rows lie evenly
    spaced (a chunk's messages of one layout alone), gathered otherwise."""
    if len(start) > 1 and np.all(np.diff(start) == start[1] - start[0]) and start[1] > start[0]:
        return np.lib.stride_tricks.as_strided(chunk[start[0]:], (len(start), width), (int(start[1] - start[0]), 1),
                                               writeable=False)
    return chunk[start[:, None] + np.arange(width)]


def _refuse_interleaved(q: np.ndarray, t: np.ndarray, rows: Sequence[str], stamps: np.ndarray,
                        numbers: np.ndarray) -> None:
    """Refuse joint angles that jump faster than :data:`MAX_JOINT_SPEED` between stamp-ordered messages.

    Args:
        q: (T, n) joint angles in stamp order [rad].
        t: (T,) sorted stamps [s].
        rows: (T,) the message each sample came from, in stamp order.
        stamps: (T,) the stamps in the bag's own order [s] (to name where time went back).
        numbers: (T,) their messages' numbers on the topic (a gripper's messages between them count too).

    Raises:
        RecordingError: one line naming the message, the jump and, when the stamps went back in the bag's
            order, the first message where they did.
    """
    found = first_jump(q, t)
    if found is None:
        return
    k, step, dt = found
    back = np.flatnonzero(np.diff(stamps) < 0)
    why = (f"its stamps go back {stamps[back[0]] - stamps[back[0] + 1]:.3f} s at message {numbers[back[0] + 1]} "
           "(a clock reset or two recordings in one bag?)" if len(back) else
           "a clock reset, two recordings in one bag or two publishers on one topic? Or, back where it was a few "
           "messages on, one joint reading that jumped (an encoder glitch)")
    raise RecordingError(
        f"{rows[k]}, field 'header.stamp': the joints move {step:.3g} rad in {dt:.3g} s from the "
        f"message stamped before it (faster than {MAX_JOINT_SPEED:g} rad/s): messages of two streams interleaved by "
        f"their stamps; {why}"
    )

