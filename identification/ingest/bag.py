"""ROS bags in: ``sensor_msgs/JointState`` messages of a ROS 2 (sqlite3, MCAP) or ROS 1 bag, no ROS install.

Read with the pure-Python ``rosbags`` library; joints are matched by name to the robot's
(:func:`.importers.match_joints`), extra joints (a gripper's fingers) are ignored. A message naming none
of the arm's joints (a gripper driver publishing its fingers alone on the same topic, interleaved with
the arm's messages) is skipped and counted: the import report says how many and what they named. So is a
message that names joints but carries no positions (its velocities or efforts alone: every array of a
``JointState`` is optional).
"""

from __future__ import annotations

import os
import struct
from array import array
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from spherecal.correction.files.csv_rows import RowNames
from spherecal.correction.model import RobotModel

from .importers import (
    MAX_JOINT_SPEED,
    Recording,
    RecordingError,
    arm_joint_names,
    check_source,
    first_jump,
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
        RecordingError: unreadable bag, no such topic, another message type, a message whose
            ``position`` does not match its ``name``, a missing joint (named), an angle outside
            the limits.
    """
    from rosbags.highlevel import AnyReader, AnyReaderError  # rosbags loads in ~0.3 s: only when a bag is read
    from rosbags.typesys import Stores, get_typestore  # (same)

    path = check_source(path)
    if path.is_dir() and not (path / "metadata.yaml").is_file():  # rosbags would say the folder is a missing file
        mukca = any(path.glob("hole_*.csv")) or any(path.glob("*/hole_*.csv"))
        hint = "; it holds MUKCa per-socket files: use --format mukca" if mukca else ""
        raise RecordingError(
            f"{path}: cannot read the bag: a ROS 2 bag folder holds a metadata.yaml, this one has none{hint}"
        )
    try:
        with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
            connections = [c for c in reader.connections if c.topic == topic]
            if not connections and not topic.startswith("/"):  # 'joint_states' typed for '/joint_states'
                connections = [c for c in reader.connections if c.topic == "/" + topic]
                topic = "/" + topic if connections else topic
            if not connections:
                topics = sorted({c.topic for c in reader.connections})
                raise RecordingError(
                    f"{path}: field '--topic': no topic {topic!r} in the bag (has {', '.join(topics)})"
                )
            for connection in connections:
                if connection.msgtype.replace("/msg/", "/") != "sensor_msgs/JointState":
                    raise RecordingError(
                        f"{path}: field '--topic': {topic!r} carries {connection.msgtype}, "
                        "expected sensor_msgs/JointState"
                    )
            messages = _Messages(model, f"{path}: {topic} message ")  # as RowNames names them
            try:
                messages.read(reader, connections)
            except Exception:  # an earlier message's angle that is not finite is refused first, as it was read first
                messages.check_finite()
                raise
            messages.check_finite()
    except RecordingError:
        raise
    except (AnyReaderError, OSError) as error:
        raise RecordingError(f"{path}: cannot read the bag: {error}") from None
    except Exception as error:  # rosbags' own reader and deserialisation errors have no common base
        if not type(error).__module__.startswith("rosbags"):
            raise
        raise RecordingError(f"{path}: cannot read the bag: {error}") from None
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
    notes = (
        (f"skipped {sum(skipped.values())} messages on {topic} without any of the arm's joints ({others}): "
         "another device (a gripper) publishing on the same topic",) if skipped else ()
    ) + ((f"skipped {unpositioned} messages on {topic} without positions (velocities or efforts only)",)
         if unpositioned else ()) + ((f"skipped {sum(c for c, _ in partial.values())} messages on {topic} naming "
                                      f"only some of the arm's joints ({some})",) if partial else ())
    numbers, stamps, q = messages.arrays()
    order = np.argsort(stamps, kind="stable")
    q, t, rows = q[order], stamps[order], RowNames(path, numbers[order], f"{topic} message")
    recording = Recording(q, t, None, str(path), rows, notes, clock="header.stamp", time_field="header.stamp")
    recording.check_limits(model)  # first: degrees in a radians field jump too, and this says which it is
    _refuse_interleaved(q, t, rows, stamps, numbers)  # before the stamps alike: two streams' clash is named as theirs
    keep, repeats = repeated_stamps(q, t, rows, "header.stamp", "message")
    return replace(recording, q=q[keep], t=t[keep], rows=rows.select(keep), notes=notes + repeats)


@dataclass
class _Group:
    """The messages read with one list of joint names: their numbers, stamps and ``position`` arrays."""

    index: np.ndarray  # the arm's joints' places in the names
    size: int  # names (= positions) per message
    numbers: array = field(default_factory=lambda: array("q"))  # 1-based message number on the topic
    sec: array = field(default_factory=lambda: array("q"))  # header.stamp
    nanosec: array = field(default_factory=lambda: array("q"))
    received: array = field(default_factory=lambda: array("q"))  # the bag's receive time [ns]
    positions: bytearray = field(default_factory=bytearray)  # little-endian float64, ``size`` per message
    blocks: list = field(default_factory=list)  # (numbers, sec, nanosec, received, positions): read in arrays

    def parts(self):
        """``(numbers, sec, nanosec, received, positions)`` of the group's messages, a block at a time (in no particular
        order): the ones deserialised, then each block read in arrays."""
        one = [np.frombuffer(getattr(self, name), dtype=np.int64) for name in ("numbers", "sec", "nanosec", "received")]
        yield (*one, np.frombuffer(self.positions, dtype="<f8").reshape(-1, self.size))
        yield from self.blocks

    def columns(self) -> tuple[np.ndarray, ...]:
        """``(numbers, sec, nanosec, received, q)`` of every message of the group (in no particular order), ``q``
        (K, n) the arm's joint angles [rad]."""
        parts = [(*part[:4], part[4][:, self.index]) for part in self.parts()]
        return tuple(np.concatenate([p[i] for p in parts]).astype(float if i == 4 else np.int64, copy=False)
                     for i in range(5))


@dataclass
class _Layout:
    """The fixed bytes of CDR ``JointState`` messages alike but for their stamps and arrays' values: a message whose
    bytes match them everywhere else has the same names and array lengths, and needs no deserialising (its stamp
    and positions are read at fixed offsets)."""

    head: bytes  # the encapsulation (little-endian CDR)
    middle: bytes  # from the frame_id's length to the positions' count
    velocity: bytes  # velocity's count, at ``at_velocity``
    effort: bytes  # effort's count, at ``at_effort``
    at_velocity: int
    at_effort: int
    at_position: int  # where the positions start
    length: int  # of the whole message
    names: tuple[str, ...]
    group: _Group | None = None  # the arm's messages of these names (None: another device's, no positions, ...)
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

    def flush(self) -> None:
        """Read the stamps and positions of the messages matched into the group's arrays, all at once."""
        if not self.raw:
            return
        data = np.frombuffer(b"".join(self.raw), dtype=np.uint8).reshape(-1, self.length)
        stamps = np.ascontiguousarray(data[:, 4:12]).view(np.dtype([("sec", "<i4"), ("nanosec", "<u4")]))[:, 0]
        positions = np.ascontiguousarray(data[:, self.at_position:self.at_velocity]).view("<f8")
        numbers, received = (np.frombuffer(self.numbers, dtype=np.int64).copy(),
                             np.frombuffer(self.received, dtype=np.int64).copy())
        self.group.blocks.append((numbers, stamps["sec"].astype(np.int64), stamps["nanosec"].astype(np.int64),
                                  received, positions.astype(float, copy=False)))
        self.raw, self.numbers, self.received = [], array("q"), array("q")


#: Messages of one layout kept as bytes before their stamps and positions are read into arrays, all at once.
_BLOCK = 20_000
_HEADER = struct.Struct("<iI")  # header.stamp's sec and nanosec, after the 4-byte encapsulation
_COUNT = struct.Struct("<I")


def _cdr_layout(raw: bytes, message) -> _Layout | None:
    """The :class:`_Layout` of a little-endian CDR ``JointState`` message, when parsing its bytes by hand gives
    exactly what ``message`` (rosbags' deserialisation of them) holds; None otherwise (then every message of its
    kind is deserialised)."""
    try:
        if raw[:2] != b"\x00\x01":
            return None

        def align(at: int, size: int) -> int:  # CDR aligns from the end of the encapsulation
            return 4 + ((at - 4 + size - 1) // size) * size

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
            names.append(raw[at + 4 : at + 3 + size].decode())
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
                and end <= len(raw) <= end + 3)
    except (struct.error, UnicodeDecodeError, AttributeError, TypeError, ValueError):
        return None
    if not same:
        return None
    return _Layout(raw[:4], raw[12:at_count + 4], raw[at_velocity:at_velocity + 4], raw[at_effort:at_effort + 4],
                   at_velocity, at_effort, at_position, len(raw), tuple(names))


class _Messages:
    """The ``JointState`` messages of a topic, read into arrays (never a Python object per message): those naming
    the arm's joints grouped by their names, the others counted (skipped: another device's; partial: some of the
    arm's joints; unpositioned: no positions). Deserialises one message of each :class:`_Layout` only (the first,
    to check it) and reads the others' stamps and positions at their offsets; a ROS 1 bag's messages, or ones
    of no layout, are deserialised."""

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
            layout = _cdr_layout(bytes(raw), message) if reader.is2 and len(layouts) < 16 else None
            self._add(message, k, timestamp)
            if layout is not None:
                layout.group = self.groups.get(layout.names) if layout.positioned else None
                layouts.append(layout)
                last = layout

    def _other(self, names: tuple[str, ...], positioned: bool, k: int) -> None:
        """Count a message of ``names`` that is not the arm's: without positions, another device's, or some of the
        arm's joints only (``positioned`` and not disjoint from the arm: :meth:`_add` judged its names so)."""
        if not positioned and names:
            self.unpositioned += 1
        elif self.arm.isdisjoint(names):
            self.skipped[names] = self.skipped.get(names, 0) + 1
        else:
            self.partial.setdefault(names, [0, k + 1])[0] += 1

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
            group = self.groups[names] = _Group(match_joints(list(names), self.model, where)[0], len(names))
        stamp = message.header.stamp
        group.numbers.append(k + 1)
        group.sec.append(stamp.sec)
        group.nanosec.append(stamp.nanosec)
        group.received.append(timestamp)
        group.positions += position.astype("<f8").tobytes()
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
        numbers, sec, nanosec, received, q = groups[0] if len(groups) == 1 else (
            np.concatenate([g[i] for g in groups]) for i in range(5))
        del groups
        order = np.argsort(numbers, kind="stable")
        if np.any(order != np.arange(order.size)):
            numbers, sec, nanosec, received, q = numbers[order], sec[order], nanosec[order], received[order], q[order]
        seconds = sec + nanosec * 1e-9
        stamps = np.where(seconds > 0, seconds, received * 1e-9)
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
        bad = np.concatenate([numbers[~np.isfinite(positions[:, g.index]).all(axis=1)]
                              for g in self.groups.values() for numbers, *_, positions in g.parts()])
        if bad.size:
            raise RecordingError(f"{self.where}{int(bad.min())}, field 'position': not finite")


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

