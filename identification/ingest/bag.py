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
from dataclasses import replace
from itertools import compress

import numpy as np

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
    stamps: list[float] = []
    rows: list[str] = []
    values: list[np.ndarray] = []
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
            cache: dict[tuple[str, ...], np.ndarray] = {}
            arm = arm_joint_names(model)
            skipped: dict[tuple[str, ...], int] = {}  # names of messages without any arm joint -> count
            unpositioned = 0  # messages with names but no positions (a driver publishing velocities or efforts)
            partial: dict[tuple[str, ...], list] = {}  # names of some of the arm's joints -> [count, first message]
            for k, (connection, timestamp, raw) in enumerate(reader.messages(connections=connections)):
                message = reader.deserialize(raw, connection.msgtype)
                where = f"{path}: {topic} message {k + 1}"
                names = tuple(message.name)
                position = np.asarray(message.position, dtype=float)
                if not position.size and names:  # JointState's arrays are optional: velocities or efforts alone
                    unpositioned += 1
                    continue
                if position.shape != (len(names),):
                    raise RecordingError(f"{where}, field 'position': {position.size} positions for {len(names)} names")
                if names not in cache and arm.isdisjoint(names):  # another device's joints (a gripper)
                    skipped[names] = skipped.get(names, 0) + 1
                    continue
                if names not in cache and missing_joints(names, model):  # the arm's state split over messages
                    partial.setdefault(names, [0, k + 1])[0] += 1
                    continue
                if names not in cache:
                    cache[names] = match_joints(list(names), model, where)[0]
                q = position[cache[names]]
                if not np.all(np.isfinite(q)):
                    raise RecordingError(f"{where}, field 'position': not finite")
                stamp = message.header.stamp
                seconds = stamp.sec + stamp.nanosec * 1e-9
                stamps.append(seconds if seconds > 0 else timestamp * 1e-9)
                values.append(q)
                rows.append(where)
    except RecordingError:
        raise
    except (AnyReaderError, OSError) as error:
        raise RecordingError(f"{path}: cannot read the bag: {error}") from None
    except Exception as error:  # rosbags' own reader and deserialisation errors have no common base
        if not type(error).__module__.startswith("rosbags"):
            raise
        raise RecordingError(f"{path}: cannot read the bag: {error}") from None
    others = "; ".join(f"{count} naming {', '.join(names[:4]) or 'no joint'}{', ...' if len(names) > 4 else ''}"
                       for names, count in skipped.items())
    some = "; ".join(f"{count} naming {', '.join(names[:4])}{', ...' if len(names) > 4 else ''} (not "
                     f"{', '.join(missing_joints(names, model)[:3])})" for names, (count, _) in partial.items())
    if not values and partial:
        first = min(k for _, k in partial.values())
        if len(partial) == 1 or missing_joints(set().union(*partial), model):  # a joint missing from the topic
            names = next(names for names, (_, k) in partial.items() if k == first)
            match_joints(list(names), model, f"{path}: {topic} message {first}")  # raises, naming that joint
        raise RecordingError(
            f"{path}: {topic} message {first}, field 'name': no message names all of the arm's joints ({some}): "
            "joint angles split over messages are not of one instant; record all of the arm's joints in one message"
        )
    if not values:
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
    t = np.array(stamps)
    order = np.argsort(t, kind="stable")
    q, t, rows = np.array(values)[order], t[order], [rows[i] for i in order]
    recording = Recording(q, t, None, str(path), tuple(rows), notes, clock="header.stamp",
                          time_field="header.stamp")
    recording.check_limits(model)  # first: degrees in a radians field jump too, and this says which it is
    _refuse_interleaved(q, t, rows, stamps)  # before the stamps alike: two streams' clash is named as theirs
    keep, repeats = repeated_stamps(q, t, rows, "header.stamp", "message")
    return replace(recording, q=q[keep], t=t[keep], rows=tuple(compress(rows, keep)), notes=notes + repeats)


def _refuse_interleaved(q: np.ndarray, t: np.ndarray, rows: list[str], stamps: list[float]) -> None:
    """Refuse joint angles that jump faster than :data:`MAX_JOINT_SPEED` between stamp-ordered messages.

    Args:
        q: (T, n) joint angles in stamp order [rad].
        t: (T,) sorted stamps [s].
        rows: (T,) the message each sample came from, in stamp order.
        stamps: (T,) the stamps in the bag's own order [s] (to name where time went back).

    Raises:
        RecordingError: one line naming the message, the jump and, when the stamps went back in the bag's
            order, the first message where they did.
    """
    found = first_jump(q, t)
    if found is None:
        return
    k, step, dt = found
    back = np.flatnonzero(np.diff(stamps) < 0)
    why = (f"its stamps go back {stamps[back[0]] - stamps[back[0] + 1]:.3f} s at message {back[0] + 2} (a clock "
           "reset or two recordings in one bag?)" if len(back) else
           "a clock reset, two recordings in one bag or two publishers on one topic? Or, back where it was a few "
           "messages on, one joint reading that jumped (an encoder glitch)")
    raise RecordingError(
        f"{rows[k]}, field 'header.stamp': the joints move {step:.3g} rad in {dt:.3g} s from the "
        f"message stamped before it (faster than {MAX_JOINT_SPEED:g} rad/s): messages of two streams interleaved by "
        f"their stamps; {why}"
    )

