"""ROS bags in: ``sensor_msgs/JointState`` messages of a ROS 2 (sqlite3, MCAP) or ROS 1 bag, no ROS install.

Read with the pure-Python ``rosbags`` library; joints are matched by name to the robot's
(:func:`.importers.match_joints`), extra joints (a gripper's fingers) are ignored.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from spherecal.correction.model import RobotModel

from .importers import Recording, RecordingError, match_joints

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

    path = Path(path)
    if not path.exists():
        raise RecordingError(f"{path}: cannot read: No such file or directory")
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
            for k, (connection, timestamp, raw) in enumerate(reader.messages(connections=connections)):
                message = reader.deserialize(raw, connection.msgtype)
                where = f"{path}: {topic} message {k + 1}"
                names = tuple(message.name)
                position = np.asarray(message.position, dtype=float)
                if position.shape != (len(names),):
                    raise RecordingError(f"{where}, field 'position': {position.size} positions for {len(names)} names")
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
    if not values:
        raise RecordingError(f"{path}: field '--topic': no messages on {topic!r}")
    t = np.array(stamps)
    order = np.argsort(t, kind="stable")
    recording = Recording(np.array(values)[order], t[order], None, str(path), tuple(rows[i] for i in order))
    recording.check_limits(model)
    return recording
