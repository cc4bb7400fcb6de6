"""Continuous hand-guiding streams for the importer tests, and ROS bags of them written with rosbags.

A stream: the TRUE robot's tool point held still in each socket while the joints move through the
null space (pseudo-inverse projection plus a Newton correction per step), joint-space transport
between sockets, and a pause in the air before the first socket.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from spherecal.correction import RobotModel, joint_jacobian, tool_point

Q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])


def self_motion(model: RobotModel, q0: np.ndarray, seconds: float, rate: float, rng, drift=(0.0, 0.0, 0.0)):
    """(T, n) configurations keeping the tool point at ``tool_point(q0) + drift * t`` (drift [m/s])."""
    n, drift = model.n_joints, np.asarray(drift, dtype=float)
    omega, phase = rng.uniform(0.5, 1.5, n), rng.uniform(0, 2 * np.pi, n)
    q, target, out = q0.copy(), tool_point(model, q0[None])[0], []
    for k in range(int(seconds * rate)):
        J = joint_jacobian(model, q[None])[0]
        pinv = np.linalg.pinv(J)
        v = 0.4 * np.sin(omega * k / rate + phase)
        q = q + (np.eye(n) - pinv @ J) @ v / rate
        for _ in range(2):
            q = q + np.linalg.pinv(joint_jacobian(model, q[None])[0]) @ (
                target + drift * k / rate - tool_point(model, q[None])[0]
            )
        out.append(q)
    return np.array(out)


def transport(q_from: np.ndarray, q_to: np.ndarray, seconds: float, rate: float) -> np.ndarray:
    """(T, n) raised-cosine joint-space motion (excluding both ends)."""
    s = (1 - np.cos(np.pi * np.arange(1, int(seconds * rate)) / (seconds * rate))) / 2
    return q_from + s[:, None] * (q_to - q_from)


def stream(
    model: RobotModel,
    sockets_dq1: list[float],
    rate: float = 200.0,
    seconds: float = 5.0,
    seed: int = 0,
    drift=(0.0, 0.0, 0.0),
):
    """A stream visiting one socket per joint-1 offset [rad] of :data:`Q0`.

    Returns:
        ``(t, q, truth)``: (T,) [s], (T, n) [rad], (T,) index of the socket a sample was in, -1 in motion.
    """
    rng = np.random.default_rng(seed)
    parts, truth = [np.repeat(Q0[None] + [0.3, 0, 0, 0, 0, 0, 0], int(rate), axis=0)], [np.full(int(rate), -1)]
    for j, dq1 in enumerate(sockets_dq1):
        start = Q0 + np.array([dq1, 0, 0, 0, 0, 0, 0])
        moving = transport(parts[-1][-1], start, 1.5, rate)
        held = self_motion(model, start, seconds, rate, rng, drift)
        parts += [moving, held]
        truth += [np.full(len(moving), -1), np.full(len(held), j)]
    q = np.concatenate(parts)
    return np.arange(len(q)) / rate + 1700000000.0, q, np.concatenate(truth)


FINGERS = ["panda_finger_joint1", "panda_finger_joint2"]


def write_bag(path: Path, kind: str, t: np.ndarray, q: np.ndarray, names: list[str], topic="/joint_states") -> Path:
    """Write ``sensor_msgs/JointState`` messages (names in a scrambled order, with the fingers) to a bag.

    Args:
        kind: ``"sqlite3"`` or ``"mcap"`` (ROS 2 bag folder) or ``"ros1"`` (a ``.bag`` file).
    """
    from rosbags.typesys import Stores, get_typestore

    order = [names[k] for k in (2, 0, 6, 1, 3, 5, 4) if k < len(names)] + FINGERS
    column = {name: i for i, name in enumerate(names)}
    ros1 = kind == "ros1"
    store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    JointState, Header, Time = (
        store.types[k] for k in ("sensor_msgs/msg/JointState", "std_msgs/msg/Header", "builtin_interfaces/msg/Time")
    )
    if ros1:
        from rosbags.rosbag1 import Writer

        writer = Writer(path)
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer

        plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
        writer = Writer(path, version=9, storage_plugin=plugin)
    with writer:
        connection = writer.add_connection(topic, JointState.__msgtype__, typestore=store)
        for k in range(len(t)):
            sec = int(t[k])
            stamp = Time(sec=sec, nanosec=int(round((t[k] - sec) * 1e9)))
            header = Header(seq=k, stamp=stamp, frame_id="") if ros1 else Header(stamp=stamp, frame_id="")
            position = np.array([q[k, column[name]] if name in column else 0.02 for name in order])
            message = JointState(
                header=header, name=order, position=position, velocity=np.zeros(len(order)), effort=np.zeros(len(order))
            )
            data = (
                store.serialize_ros1(message, JointState.__msgtype__)
                if ros1
                else store.serialize_cdr(message, JointState.__msgtype__)
            )
            writer.write(connection, int(t[k] * 1e9), data)
    return path
