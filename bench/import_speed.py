"""`spherecal import` of a long recording: wall time and peak memory, as a joint CSV, a ROS 2 bag and a ROS 1 bag.

Builds (once; kept in ``--data``) a continuous hand-guiding recording of the embedded Panda at ``--rate`` Hz for
``--minutes`` minutes (default 30 min at 1 kHz: 1.8 M samples): ``--sockets`` sockets 60 mm apart, each visited
several times (self-motion about the held tool point, then the arm at rest in the socket, its readings a few
µrad of encoder noise apart: the repeats a still arm records), joint-space transport between them. Written as

- ``recording.csv``: ``time,panda_joint1..7,panda_finger_joint1,panda_finger_joint2`` (every digit of each float);
- ``recording_bag/``: a ROS 2 bag (sqlite3, or ``--storage mcap``) of ``sensor_msgs/JointState`` on
  ``/joint_states``, the arm's seven joints and the gripper's two fingers in one message as a real Panda's
  ``joint_states`` carry them (velocities and efforts too), stamped in ``header.stamp``;
- ``recording.bag``: the same messages in a ROS 1 bag (what franka_ros records on Noetic), ``header.seq`` counting.

Then runs ``spherecal import SOURCE --format csv|bag --robot panda --out OUT`` ``--repeats`` times each (``--formats
csv,bag,bag1``: the ROS 1 bag is imported with ``--format bag``) in a fresh
process and reports the median wall time and the peak resident memory of the import process
(``os.wait4``'s ``ru_maxrss``). The outputs of the last run of each (``samples.csv``, ``fixtures.yaml`` less
the printed report) are kept in ``--keep`` when given, to ``cmp`` against
another commit's.

Prints a table and the machine load (``uptime``) and writes ``bench/import_speed.json``.

    .venv/bin/python bench/import_speed.py [--minutes 30] [--repeats 3] [--data /tmp/rec] [--keep /tmp/out]

Measures the spherecal installed in the running Python (an editable install: the commit checked out); old
against new is two runs at two commits, with ``--data`` kept and ``--keep`` for each.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import bench_common  # one BLAS thread
import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

JOINTS = [f"panda_joint{i + 1}" for i in range(7)]
FINGERS = ["panda_finger_joint1", "panda_finger_joint2"]
#: Order of the names in a message (the driver's, not the robot's: matched by name).
ORDER = [JOINTS[k] for k in (2, 0, 6, 1, 3, 5, 4)] + FINGERS
Q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
START = 1_700_000_000.0  # stamps of 2023, as a bag's


# ------------------------------------------------------------------------------ the recording
def self_motion(model, q0: np.ndarray, seconds: float, rate: float, rng, coarse: float = 20.0) -> np.ndarray:
    """(T, n) configurations keeping ``model``'s tool point at ``q0``'s: null-space motion solved at ``coarse`` Hz
    (a Newton correction per step), interpolated linearly to ``rate`` (the point stays within a fraction of a mm)."""
    from spherecal.correction import joint_jacobian, tool_point

    n = model.n_joints
    omega, phase = rng.uniform(0.5, 1.5, n), rng.uniform(0, 2 * np.pi, n)
    q, target = q0.copy(), tool_point(model, q0[None])[0]
    coarse_q = [q.copy()]
    for k in range(int(seconds * coarse)):
        J = joint_jacobian(model, q[None])[0]
        pinv = np.linalg.pinv(J)
        v = 0.3 * np.sin(omega * k / coarse + phase)
        q = q + (np.eye(n) - pinv @ J) @ v / coarse
        for _ in range(2):
            q = q + np.linalg.pinv(joint_jacobian(model, q[None])[0]) @ (target - tool_point(model, q[None])[0])
        coarse_q.append(q.copy())
    coarse_q = np.array(coarse_q)
    fine = np.arange(int(seconds * rate)) / rate * coarse
    return np.stack([np.interp(fine, np.arange(len(coarse_q)), coarse_q[:, i]) for i in range(n)], axis=1)


def transport(q_from: np.ndarray, q_to: np.ndarray, seconds: float, rate: float) -> np.ndarray:
    """(T, n) raised-cosine joint-space motion (excluding both ends)."""
    s = (1 - np.cos(np.pi * np.arange(1, int(seconds * rate)) / (seconds * rate))) / 2
    return q_from + s[:, None] * (q_to - q_from)


def recording(minutes: float, rate: float, sockets: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``(t, q)``: (T,) stamps [s] and (T, 7) joint angles [rad] of the Panda visiting ``sockets`` sockets in turn
    (visits of 45 s self-motion and 15 s at rest, 3 s transport) until ``minutes`` are recorded."""
    from spherecal.correction import load_robot, tool_point

    model = load_robot("panda")
    rng = np.random.default_rng(seed)
    radius = np.hypot(*tool_point(model, Q0[None])[0][:2])
    step = 2 * np.arcsin(0.06 / 2 / radius)  # 60 mm between neighbouring sockets
    starts = [Q0 + np.array([(j - (sockets - 1) / 2) * step, 0, 0, 0, 0, 0, 0]) for j in range(sockets)]
    total = int(minutes * 60 * rate)
    parts, count, visit = [np.repeat(Q0[None] + [0.3, 0, 0, 0, 0, 0, 0], int(rate), axis=0)], int(rate), 0
    while count < total:
        start = starts[visit % sockets]
        moving = transport(parts[-1][-1], start, 3.0, rate)
        held = self_motion(model, start, 45.0, rate, rng)
        rest = held[-1] + rng.normal(0.0, 2e-6, (int(15 * rate), 7))  # at rest: encoder noise only
        parts += [moving, held, rest]
        count += len(moving) + len(held) + len(rest)
        visit += 1
    q = np.concatenate(parts)[:total]
    return START + np.arange(total) / rate, q


def write_csv(path: Path, t: np.ndarray, q: np.ndarray) -> None:
    """``time,panda_joint1..7,panda_finger_joint1,panda_finger_joint2``, every float with all its digits."""
    with open(path, "w") as handle:
        handle.write("time," + ",".join(JOINTS + FINGERS) + "\n")
        for first in range(0, len(t), 100_000):
            rows = zip(t[first:first + 100_000].tolist(), q[first:first + 100_000].tolist(), strict=True)
            handle.writelines(f"{tt!r},{','.join(map(repr, row))},0.04,0.04\n" for tt, row in rows)


def write_bag(path: Path, t: np.ndarray, q: np.ndarray, storage: str = "sqlite3") -> None:
    """A ROS 2 bag of ``sensor_msgs/JointState`` on ``/joint_states`` (names in :data:`ORDER`). One message is
    serialised by rosbags; the others are it with their stamp and positions written in (CDR has fixed offsets for
    a fixed set of names), which builds 1.8 M messages in a minute instead of ten."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    JointState, Header, Time = (
        store.types[k] for k in ("sensor_msgs/msg/JointState", "std_msgs/msg/Header", "builtin_interfaces/msg/Time")
    )
    marker = np.arange(1, len(ORDER) + 1) * 1.2345678901234567e3
    template = store.serialize_cdr(
        JointState(header=Header(stamp=Time(sec=1, nanosec=2), frame_id=""), name=ORDER, position=marker,
                   velocity=np.zeros(len(ORDER)), effort=np.zeros(len(ORDER))), JointState.__msgtype__)
    at = bytes(template).find(marker.astype("<f8").tobytes())
    assert at > 0 and bytes(template)[4:12] == np.array([1, 2], "<u4").tobytes()
    column = [JOINTS.index(name) if name in JOINTS else -1 for name in ORDER]
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        connection = writer.add_connection("/joint_states", JointState.__msgtype__, typestore=store)
        base = np.frombuffer(bytes(template), dtype=np.uint8)
        for first in range(0, len(t), 50_000):
            tt, qq = t[first:first + 50_000], q[first:first + 50_000]
            sec, nanosec = _stamps(tt)
            position = np.where(np.array(column) >= 0, qq[:, np.maximum(column, 0)], 0.04)
            block = np.tile(base, (len(tt), 1))
            block[:, 4:8] = np.ascontiguousarray(sec, dtype="<i4").view(np.uint8).reshape(-1, 4)
            block[:, 8:12] = np.ascontiguousarray(nanosec, dtype="<u4").view(np.uint8).reshape(-1, 4)
            position = np.ascontiguousarray(position, dtype="<f8")
            block[:, at:at + 8 * len(ORDER)] = position.view(np.uint8).reshape(len(tt), -1)
            stamps = (sec * 1_000_000_000 + nanosec).tolist()
            for k, row in enumerate(block):
                writer.write(connection, stamps[k], row.tobytes())


def write_bag1(path: Path, t: np.ndarray, q: np.ndarray) -> None:
    """A ROS 1 bag (``.bag``, what ``rosbag record`` writes on Noetic: uncompressed 1 MiB chunks) of
    ``sensor_msgs/JointState`` on ``/joint_states`` (names in :data:`ORDER`), ``header.seq`` counting up as a
    publisher's does. As :func:`write_bag`: one message serialised by rosbags, the others it with their seq, stamp
    and positions written in (ROS 1 serialisation is packed: fixed offsets for a fixed set of names)."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    JointState, Header, Time = (
        store.types[k] for k in ("sensor_msgs/msg/JointState", "std_msgs/msg/Header", "builtin_interfaces/msg/Time")
    )
    marker = np.arange(1, len(ORDER) + 1) * 1.2345678901234567e3
    template = bytes(store.serialize_ros1(
        JointState(header=Header(seq=0, stamp=Time(sec=1, nanosec=2), frame_id=""), name=ORDER, position=marker,
                   velocity=np.zeros(len(ORDER)), effort=np.zeros(len(ORDER))), JointState.__msgtype__))
    at = template.find(marker.astype("<f8").tobytes())
    assert at > 0 and template[:12] == np.array([0, 1, 2], "<u4").tobytes()
    column = [JOINTS.index(name) if name in JOINTS else -1 for name in ORDER]
    with Writer(path) as writer:
        connection = writer.add_connection("/joint_states", JointState.__msgtype__, typestore=store)
        base = np.frombuffer(template, dtype=np.uint8)
        for first in range(0, len(t), 50_000):
            tt, qq = t[first:first + 50_000], q[first:first + 50_000]
            sec, nanosec = _stamps(tt)
            position = np.where(np.array(column) >= 0, qq[:, np.maximum(column, 0)], 0.04)
            block = np.tile(base, (len(tt), 1))
            head = np.stack([first + np.arange(len(tt)), sec, nanosec], axis=1).astype("<u4")
            block[:, :12] = head.view(np.uint8).reshape(-1, 12)
            position = np.ascontiguousarray(position, dtype="<f8")
            block[:, at:at + 8 * len(ORDER)] = position.view(np.uint8).reshape(len(tt), -1)
            stamps = (sec * 1_000_000_000 + nanosec).tolist()
            for k, row in enumerate(block):
                writer.write(connection, stamps[k], row.tobytes())


def _stamps(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(sec, nanosec)`` (int64) of stamps ``t`` [s]."""
    sec = np.floor(t).astype(np.int64)
    nanosec = np.round((t - sec) * 1e9).astype(np.int64)
    over = nanosec >= 1_000_000_000
    return sec + over, nanosec - over * 1_000_000_000


def build(folder: Path, minutes: float, rate: float, sockets: int, storage: str) -> dict:
    """The CSV, the ROS 2 bag and the ROS 1 bag in ``folder`` (kept when already there); what was built."""
    csv, bag, made = folder / "recording.csv", folder / "recording_bag", folder / "recording.json"
    bag1 = folder / "recording.bag"
    wanted = {"minutes": minutes, "rate": rate, "sockets": sockets, "storage": storage}
    if (made.is_file() and json.loads(made.read_text()).get("inputs") == wanted and csv.is_file() and bag.is_dir()
            and bag1.is_file()):
        return json.loads(made.read_text())
    shutil.rmtree(bag, ignore_errors=True)
    bag1.unlink(missing_ok=True)
    folder.mkdir(parents=True, exist_ok=True)
    clock = time.perf_counter()
    t, q = recording(minutes, rate, sockets)
    made_q = time.perf_counter() - clock
    write_csv(csv, t, q)
    made_csv = time.perf_counter() - clock - made_q
    write_bag(bag, t, q, storage)
    made_bag = time.perf_counter() - clock - made_q - made_csv
    write_bag1(bag1, t, q)
    made_bag1 = time.perf_counter() - clock - made_q - made_csv - made_bag
    info = {"inputs": wanted, "samples": len(t),
            "seconds": {"stream": made_q, "csv": made_csv, "bag": made_bag, "bag1": made_bag1},
            "csv_mb": csv.stat().st_size / 1e6, "bag_mb": sum(p.stat().st_size for p in bag.rglob("*")) / 1e6,
            "bag1_mb": bag1.stat().st_size / 1e6}
    made.write_text(json.dumps(info, indent=2) + "\n")
    return info


# ------------------------------------------------------------------------------------ timing
def run_import(source: Path, fmt: str, out: Path) -> tuple[float, float, int, str, str]:
    """One ``spherecal import`` (the installed tree's: check out the commit to measure) in a fresh process:
    (wall [s], peak RSS [MB], exit code, stdout, stderr)."""
    code = "import sys; from spherecal.cli import main; sys.exit(main())"
    argv = [sys.executable, "-c", code, "import", str(source), "--format", fmt, "--robot", "panda", "--out", str(out)]
    env = dict(os.environ)
    with tempfile.TemporaryFile() as stdout, tempfile.TemporaryFile() as stderr:
        clock = time.perf_counter()
        child = subprocess.Popen(argv, stdout=stdout, stderr=stderr, env=env, cwd=tempfile.gettempdir())
        _, status, usage = os.wait4(child.pid, 0)
        seconds = time.perf_counter() - clock
        child.returncode = os.waitstatus_to_exitcode(status)
        stdout.seek(0)
        stderr.seek(0)
        return seconds, usage.ru_maxrss / 1024, child.returncode, stdout.read().decode(), stderr.read().decode()


def keep_outputs(out: Path, keep: Path, name: str, printed: str, warned: str) -> None:
    """The outputs of a run as written, and what it printed, as ``keep/<format>.*`` (to diff against another
    commit's: only the provenance's time and commit should differ)."""
    keep.mkdir(parents=True, exist_ok=True)
    for file in ("samples.csv", "fixtures.yaml"):
        shutil.copyfile(out / file, keep / f"{name}.{file}")
    (keep / f"{name}.stdout").write_text(printed)
    (keep / f"{name}.stderr").write_text(warned)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=30.0)
    parser.add_argument("--rate", type=float, default=1000.0, help="samples per second [Hz]")
    parser.add_argument("--sockets", type=int, default=4)
    parser.add_argument("--storage", choices=("sqlite3", "mcap"), default="sqlite3")
    parser.add_argument("--repeats", type=int, default=3, help="imports of each recording (the median is reported)")
    parser.add_argument("--formats", default="csv,bag,bag1", help="csv, bag (ROS 2), bag1 (ROS 1)")
    parser.add_argument("--data", help="folder of the recordings, kept (default: a temporary folder)")
    parser.add_argument("--keep", help="folder to copy the last run's outputs and printed report into")
    parser.add_argument("--out", default=str(HERE / "import_speed.json"))
    args = parser.parse_args()
    root = ROOT
    with tempfile.TemporaryDirectory() as scratch:
        data = Path(args.data) if args.data else Path(scratch) / "data"
        info = build(data, args.minutes, args.rate, args.sockets, args.storage)
        print(f"recording: {info['samples']} samples ({args.minutes:g} min at {args.rate:g} Hz, {args.sockets} "
              f"sockets); CSV {info['csv_mb']:.0f} MB, bag {info['bag_mb']:.0f} MB ({args.storage}), ROS 1 bag "
              f"{info['bag1_mb']:.0f} MB; tree: {root}")
        results = {}
        for fmt in args.formats.split(","):
            source = data / {"csv": "recording.csv", "bag": "recording_bag", "bag1": "recording.bag"}[fmt]
            runs = []
            for k in range(args.repeats):
                out = data / "runs" / f"out_{fmt}"  # one path: the provenance's command line alike at every commit
                shutil.rmtree(out, ignore_errors=True)
                seconds, peak, code, printed, warned = run_import(source, "bag" if fmt == "bag1" else fmt, out)
                if code != 0:
                    raise SystemExit(f"import --format {fmt} failed ({code}):\n{printed}\n{warned}")
                runs.append({"seconds": seconds, "peak_mb": peak})
                print(f"  {fmt} run {k + 1}: {seconds:.2f} s, {peak:.0f} MB", flush=True)
            if args.keep:
                keep_outputs(out, Path(args.keep), fmt, printed, warned)
            results[fmt] = {"median_seconds": statistics.median(r["seconds"] for r in runs),
                            "peak_mb": max(r["peak_mb"] for r in runs), "runs": runs,
                            "summary": [s for s in printed.splitlines() if s.startswith(("read ", "dropped "))]}
    load = subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()
    print(f"{'format':<7} {'median [s]':>10} {'peak RSS [MB]':>14}  ({args.repeats} runs)")
    for fmt, r in results.items():
        print(f"{fmt:<7} {r['median_seconds']:10.2f} {r['peak_mb']:14.0f}  {'; '.join(r['summary'])}")
    print(f"load: {load}")
    report = {"recording": info, "root": str(root), "uptime": load, "results": results}
    bench_common.write_json(args.out, report, seed=0, inputs={**info["inputs"], "root": str(root)})
    print(f"written: {args.out}")


if __name__ == "__main__":
    main()
