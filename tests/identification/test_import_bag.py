"""`spherecal import` of continuous recordings: ROS 2 (sqlite3, MCAP) and ROS 1 bags, joint CSV files,
automatic segmentation into fixtures, and the refusals (ambiguous split, drift, missing joint)."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.cli import main
from spherecal.correction import load_robot, perturb, tool_point
from spherecal.correction.files.fixtures import read_fixtures
from spherecal.correction.files.samples_csv import read_samples
from spherecal.identification.ingest import bag as bag_module
from spherecal.identification.ingest.bag import read_bag
from spherecal.identification.ingest.importers import RecordingError
from tests.refusal import refused

from .recordings import Q0, stream, write_bag
from .test_import_mukca import DATA, PANDA

NAMES = [f"panda_joint{i + 1}" for i in range(7)]


def _offset(true, distance: float) -> float:
    """Joint-1 offset [rad] that moves the tool point of Q0 by ``distance`` [m]."""
    p = tool_point(true, Q0[None])[0]
    return float(2 * np.arcsin(distance / 2 / np.hypot(p[0], p[1])))


@pytest.fixture(scope="module")
def recording():
    """Two sockets 50 mm apart on a perturbed 'true' Panda (the nominal tool point then moves ~2 mm)."""
    nominal = load_robot(PANDA)
    true = perturb(nominal, np.random.default_rng(3))
    t, q, truth = stream(true, [0.0, _offset(true, 0.05)])
    return true, t, q, truth


def _check_split(out, true, t, q, truth) -> None:
    dataset = read_samples(out / "samples.csv", load_robot(PANDA))
    assert dataset.fixture_names == ("S1", "S2") and read_fixtures(out / "fixtures.yaml").names == ("S1", "S2")
    row = {value: k for k, value in enumerate(t)}
    for j, name in enumerate(("S1", "S2")):
        rows = np.array([row[value] for value in dataset.t[dataset.labels == name]])
        assert np.all(truth[rows] == j)  # only samples held in socket j, none from the transport
        np.testing.assert_array_equal(dataset.for_fixture(name), q[rows])
        assert rows.size >= 0.8 * np.count_nonzero(truth == j)  # most of the socket kept
        centre = tool_point(true, q[truth == j][:1])[0]
        assert np.abs(tool_point(true, q[rows]) - centre).max() < 1e-9


@pytest.mark.parametrize("kind", ["sqlite3", "mcap", "ros1"])
def test_a_bag_with_two_sockets_is_split_into_two_fixtures(recording, kind, tmp_path, capsys) -> None:
    true, t, q, truth = recording
    bag = write_bag(tmp_path / ("rec.bag" if kind == "ros1" else "rec"), kind, t, q, NAMES)
    out = tmp_path / "out"
    argv = ["import", str(bag), "--format", "bag", "--robot", str(PANDA), "--out", str(out)]
    assert main(argv + ["--max-per-fixture", "100000"]) == 0
    printed = capsys.readouterr().out
    assert "segmented into 2 fixtures" in printed and "spread mean [mm]" in printed
    _check_split(out, true, t, q, truth)


def test_a_csv_without_labels_is_segmented_and_one_with_labels_is_not(recording, tmp_path) -> None:
    true, t, q, truth = recording
    header = "time,panda_finger_joint1," + ",".join(reversed(NAMES))
    rows = [f"{float(t[k])!r},0.02," + ",".join(repr(float(v)) for v in q[k, ::-1]) for k in range(len(t))]
    (tmp_path / "rec.csv").write_text(header + "\n" + "\n".join(rows) + "\n")
    argv = ["import", str(tmp_path / "rec.csv"), "--format", "csv", "--robot", str(PANDA), "--max-per-fixture", "9999"]
    assert main(argv + ["--out", str(tmp_path / "a")]) == 0
    _check_split(tmp_path / "a", true, t, q, truth)
    labels = np.where(truth < 0, "air", np.where(truth == 0, "A", "B"))
    rows = [f"{labels[k]},{k},{','.join(repr(float(v)) for v in q[k])}" for k in range(len(t))]
    (tmp_path / "lab.csv").write_text(
        "fixture,sample," + ",".join(f"q{i + 1}" for i in range(7)) + "\n" + "\n".join(rows)
    )
    argv[1] = str(tmp_path / "lab.csv")
    assert main(argv + ["--out", str(tmp_path / "b")]) == 0
    dataset = read_samples(tmp_path / "b/samples.csv", load_robot(PANDA))
    assert dataset.fixture_names == ("air", "A", "B") and dataset.t is None
    np.testing.assert_array_equal(dataset.for_fixture("B")[:5], q[truth == 1][:5])


def _refused(argv, folder, capsys) -> str:
    return refused(argv, folder, capsys).strip()


def test_ambiguous_drifting_or_incomplete_recordings_are_refused(recording, tmp_path, capsys) -> None:
    true = recording[0]
    t, q, _ = stream(true, [0.0, _offset(true, 0.010)], seconds=3.0)  # two sockets 10 mm apart
    bag = write_bag(tmp_path / "close", "sqlite3", t, q, NAMES)
    argv = ["import", str(bag), "--format", "bag", "--robot", str(PANDA), "--out", str(tmp_path / "out")]
    error = _refused(argv, tmp_path, capsys)
    assert "ambiguous" in error and "mm apart" in error
    t, q, _ = stream(true, [0.0], seconds=8.0, drift=np.array([0.008, 0.0, 0.0]))  # the socket slides 64 mm
    argv[1] = str(write_bag(tmp_path / "drift", "mcap", t, q, NAMES))
    assert "drifts" in _refused(argv, tmp_path, capsys)
    argv[1] = str(write_bag(tmp_path / "elbow.bag", "ros1", t[:50], q[:50], NAMES[:3] + ["elbow"] + NAMES[4:]))
    assert "field 'panda_joint4'" in _refused(argv, tmp_path, capsys)
    argv[1] = str(bag)
    assert "no topic '/joints'" in _refused(argv + ["--topic", "/joints"], tmp_path, capsys)
    (tmp_path / "junk.bag").write_text("not a bag\n")
    argv[1] = str(tmp_path / "junk.bag")
    assert "junk.bag: cannot read the bag" in _refused(argv, tmp_path, capsys)
    (tmp_path / "empty").mkdir()
    argv[1] = str(tmp_path / "empty")
    assert "empty: cannot read the bag" in _refused(argv, tmp_path, capsys)
    assert not (tmp_path / "out").exists()
    csv = tmp_path / "back.csv"
    csv.write_text(
        "t,"
        + ",".join(NAMES)
        + "\n"
        + "1.0"
        + ",0.1" * 3
        + ",-1"
        + ",0.1" * 3
        + "\n0.5"
        + ",0.1" * 3
        + ",-1"
        + ",0.1" * 3
        + "\n"
    )
    assert "back.csv: row 3, field 't': time goes back" in _refused(
        ["import", str(csv), "--format", "csv", "--robot", str(PANDA), "--out", str(tmp_path / "out")], tmp_path, capsys
    )



@pytest.mark.parametrize("column", ["time", "stamp"])
def test_time_going_back_names_the_time_column_as_named(column, tmp_path, capsys) -> None:
    # a review: the refusal said field 't' whatever the CSV's time column was called
    row = ",0.1" * 3 + ",-1" + ",0.1" * 3
    csv = tmp_path / "back.csv"
    csv.write_text(f"{column},{','.join(NAMES)}\n1.0{row}\n0.5{row}\n")
    err = refused(["import", csv, "--format", "csv", "--robot", PANDA, "--out", tmp_path / "out"], tmp_path, capsys,
                  f"back.csv: row 3, field '{column}': time goes back (0.500000 s after 1.000000 s)")
    assert "field 't'" not in err


@pytest.mark.parametrize("kind", ["sqlite3", "ros1"])
def test_a_bag_whose_clock_goes_back_is_refused_not_interleaved(recording, kind, tmp_path, capsys) -> None:
    # the stamps jump back 3 s after 8 s (a clock reset, two recordings in one bag): the reader sorted the
    # messages by stamp, interleaving the two streams; the import then said "no fixture found" here, and on a
    # three-socket stream exited 0 with one socket dropped and another cut by half
    true, t, q, _ = recording
    back = np.where(np.arange(len(t)) < 1600, t, t - 3.0)
    bag = write_bag(tmp_path / ("back.bag" if kind == "ros1" else "back"), kind, back, q, NAMES)
    argv = ["import", str(bag), "--format", "bag", "--robot", str(PANDA), "--out", str(tmp_path / "out")]
    error = _refused(argv, tmp_path, capsys)
    assert "field 'header.stamp': the joints move" in error and "faster than 10 rad/s" in error
    assert "messages of two streams interleaved by their stamps" in error
    bag = write_bag(tmp_path / ("ok.bag" if kind == "ros1" else "ok"), kind, t, q, NAMES)  # the same, in order
    assert main([*argv[:1], str(bag), *argv[2:]]) == 0


def _joint_states(path, messages) -> None:
    """A ROS 2 bag of ``sensor_msgs/JointState`` on /joint_states: ``messages`` of (stamp [s], names, positions) and
    optionally the bag's receive time [s] (default: the stamp)."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    state, header, time = (store.types[k] for k in ("sensor_msgs/msg/JointState", "std_msgs/msg/Header",
                                                    "builtin_interfaces/msg/Time"))
    with Writer(path, version=9) as writer:
        connection = writer.add_connection("/joint_states", state.__msgtype__, typestore=store)
        for stamp, names, position, *received in messages:
            sec = int(stamp)
            head = header(stamp=time(sec=sec, nanosec=int(round((stamp - sec) * 1e9))), frame_id="")
            data = state(header=head, name=list(names), position=np.asarray(position, float),
                         velocity=np.zeros(len(names)), effort=np.zeros(0))
            writer.write(connection, int((received[0] if received else stamp) * 1e9),
                         store.serialize_cdr(data, state.__msgtype__))


def test_where_the_clock_goes_back_counts_a_gripper_s_messages_between(recording, tmp_path, capsys) -> None:
    # the refusal said "at message {k + 2}" counting the arm's messages alone: with a gripper's message after each
    # of the arm's on the topic, the message it named was half the one where the stamps went back
    true, t, q, _ = recording
    back = np.where(np.arange(len(t)) < 1600, t, t - 3.0)
    gripper = ("panda_finger_joint1", "panda_finger_joint2")
    _joint_states(tmp_path / "back", [m for k in range(len(t)) for m in (
        (back[k], NAMES, q[k], t[k]), (back[k] + 1e-4, gripper, [0.04, 0.04], t[k] + 1e-4))])
    error = _refused(["import", str(tmp_path / "back"), "--format", "bag", "--robot", str(PANDA), "--out",
                      str(tmp_path / "out")], tmp_path, capsys)
    # the arm's message 1601 is the topic's 3201st: 1600 arm and 1600 gripper messages before it
    assert "its stamps go back " in error and " s at message 3201 (a clock reset" in error, error


def test_messages_without_positions_are_skipped_and_counted(recording, tmp_path, capsys) -> None:
    # every array of a JointState is optional: a driver publishing the arm's velocities alone between its position
    # messages made the whole bag a refusal ('message 2, field 'position': 0 positions for 7 names')
    true, t, q, truth = recording
    bag = tmp_path / "velocities"
    _joint_states(bag, [m for k in range(len(t)) for m in ((t[k], NAMES, q[k]), (t[k] + 1e-6, NAMES, []))])
    out = tmp_path / "out"
    assert main(["import", str(bag), "--format", "bag", "--robot", str(PANDA), "--out", str(out),
                 "--max-per-fixture", "100000"]) == 0
    assert f"skipped {len(t)} messages on /joint_states without positions" in capsys.readouterr().out
    _check_split(out, true, t, q, truth)
    only = tmp_path / "only_velocities"
    _joint_states(only, [(t[k], NAMES, []) for k in range(10)])
    error = _refused(["import", str(only), "--format", "bag", "--robot", str(PANDA), "--out", str(tmp_path / "o2")],
                     tmp_path, capsys)
    assert "field 'position': none of the 10 messages carries joint positions" in error


def test_an_arm_split_over_two_messages_is_refused_saying_so(recording, tmp_path, capsys) -> None:
    # joints 1-4 and 5-7 in messages of their own (two controllers): the refusal said 'joint panda_joint5 not in the
    # recording'; beside full messages, such a part stopped the import too
    true, t, q, truth = recording
    split = tmp_path / "split"
    _joint_states(split, [m for k in range(len(t)) for m in ((t[k], NAMES[:4], q[k, :4]),
                                                              (t[k] + 5e-4, NAMES[4:], q[k, 4:]))])
    argv = ["import", str(split), "--format", "bag", "--robot", str(PANDA), "--out", str(tmp_path / "a")]
    error = _refused(argv, tmp_path, capsys)
    assert "message 1, field 'name': no message names all of the arm's joints" in error
    assert "naming panda_joint5, panda_joint6, panda_joint7 (not panda_joint1" in error and "one instant" in error
    both = tmp_path / "both"
    _joint_states(both, [m for k in range(len(t)) for m in ((t[k], NAMES, q[k]), (t[k] + 5e-4, NAMES[4:], q[k, 4:]))])
    assert main([*argv[:1], str(both), *argv[2:-1], str(tmp_path / "b"), "--max-per-fixture", "100000"]) == 0
    assert f"skipped {len(t)} messages on /joint_states naming only some of the arm's joints" in capsys.readouterr().out
    _check_split(tmp_path / "b", true, t, q, truth)


def _held(out, q, truth) -> list[int]:
    """Samples per fixture of an import, each checked to be one recorded in its socket (by its joint angles)."""
    dataset = read_samples(out / "samples.csv", load_robot(PANDA))
    assert dataset.fixture_names == ("S1", "S2")
    counts = []
    for j, name in enumerate(dataset.fixture_names):
        socket = {row.tobytes() for row in q[truth == j]}
        assert all(row.tobytes() in socket for row in dataset.for_fixture(name))
        counts.append(len(dataset.for_fixture(name)))
    return counts


def test_csv_time_in_milliseconds_is_refused_unless_the_header_names_the_unit(recording, tmp_path, capsys) -> None:
    # stamps in milliseconds were read as seconds (samples 5 s apart) and the import said 'no fixture found';
    # microseconds above 1e15 were read as nanoseconds; a 'time_ns' column was not a time column at all
    true, t, q, truth = recording
    body = lambda scale: "\n".join(f"{float(t[k] - t[0]) * scale!r}," + ",".join(repr(float(v)) for v in q[k])  # noqa: E731
                                   for k in range(len(t))) + "\n"
    argv = ["import", "--format", "csv", "--robot", str(PANDA), "--max-per-fixture", "9999"]
    (tmp_path / "ms.csv").write_text("time," + ",".join(NAMES) + "\n" + body(1e3))
    error = _refused([*argv, str(tmp_path / "ms.csv"), "--out", str(tmp_path / "a")], tmp_path, capsys)
    assert "ms.csv: row 3, field 'time': samples 5 s apart (median)" in error and "(milliseconds?)" in error
    for name, scale in (("time_ms", 1e3), ("stamp [us]", 1e6), ("time_ns", 1e9)):
        (tmp_path / "unit.csv").write_text(f"{name}," + ",".join(NAMES) + "\n" + body(scale))
        out = tmp_path / name.replace(" ", "")
        assert main([*argv, str(tmp_path / "unit.csv"), "--out", str(out)]) == 0, name
        assert min(_held(out, q, truth)) > 0.8 * np.count_nonzero(truth == 0)


def test_rate_given_for_a_csv_with_a_time_column_is_ignored_with_one_warning(recording, tmp_path, capsys) -> None:
    # --rate was silently ignored when the CSV had a time column: the stamps decide, the user is told in one line
    _, t, q, truth = recording  # 200 Hz stamps
    rows = "\n".join(f"{float(t[k] - t[0])!r}," + ",".join(repr(float(v)) for v in q[k]) for k in range(len(t)))
    (tmp_path / "rec.csv").write_text("time," + ",".join(NAMES) + "\n" + rows + "\n")
    argv = ["import", str(tmp_path / "rec.csv"), "--format", "csv", "--robot", str(PANDA), "--max-per-fixture", "9999"]
    assert main([*argv, "--out", str(tmp_path / "plain")]) == 0
    assert capsys.readouterr().err == ""  # no --rate: nothing to say
    assert main([*argv, "--out", str(tmp_path / "fast"), "--rate", "1000"]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err == [f"spherecal import: warning: {tmp_path / 'rec.csv'}: --rate 1000 Hz ignored: the time column was "
                   "used (median 200 Hz, not the rate given); leave --rate out"], err
    plain, fast = (read_samples(tmp_path / name / "samples.csv", load_robot(PANDA)) for name in ("plain", "fast"))
    np.testing.assert_array_equal(fast.t, plain.t)  # the stamps, not 1 kHz
    np.testing.assert_array_equal(fast.q, plain.q)
    assert main([*argv, "--out", str(tmp_path / "same"), "--rate", "200"]) == 0  # agrees: still told, no dispute
    assert capsys.readouterr().err.splitlines()[0].endswith("--rate 200 Hz ignored: the time column was used "
                                                             "(median 200 Hz); leave --rate out")
    # without a time column the rate is the clock: no warning, the samples 1 / rate apart
    (tmp_path / "bare.csv").write_text(",".join(NAMES) + "\n" + "\n".join(r.split(",", 1)[1] for r in rows.split("\n"))
                                       + "\n")
    assert main([*argv[:1], str(tmp_path / "bare.csv"), *argv[2:], "--out", str(tmp_path / "bare"),
                 "--rate", "200"]) == 0
    assert capsys.readouterr().err == ""
    assert min(_held(tmp_path / "bare", q, truth)) > 0.8 * np.count_nonzero(truth == 0)


def test_a_plotjuggler_csv_of_joint_states_is_read_by_its_position_columns(recording, tmp_path, capsys) -> None:
    # PlotJuggler exports a topic as '__time,/joint_states/<joint>/position,/joint_states/<joint>/velocity,...':
    # refused, 'joint franka_panda_joint1 not in the recording'
    true, t, q, truth = recording
    columns = ",".join(f"/joint_states/{n}/position,/joint_states/{n}/velocity" for n in reversed(NAMES))
    rows = [f"{float(t[k] - t[0])!r}," + ",".join(f"{float(v)!r},0.0" for v in q[k, ::-1]) for k in range(len(t))]
    (tmp_path / "pj.csv").write_text("__time," + columns + "\n" + "\n".join(rows) + "\n")
    argv = ["import", str(tmp_path / "pj.csv"), "--format", "csv", "--robot", str(PANDA), "--max-per-fixture", "9999"]
    assert main(argv + ["--out", str(tmp_path / "a")]) == 0
    assert min(_held(tmp_path / "a", q, truth)) > 0.8 * np.count_nonzero(truth == 0)
    (tmp_path / "two.csv").write_text("__time," + columns + ",/cmd/panda_joint1/position\n"
                                      + "\n".join(row + ",0.0" for row in rows) + "\n")
    error = _refused([*argv[:1], str(tmp_path / "two.csv"), *argv[2:], "--out", str(tmp_path / "b")], tmp_path, capsys)
    assert "field 'panda_joint1': joint 'panda_joint1' is named twice" in error


def test_a_samples_csv_with_its_provenance_comments_imports_as_a_labelled_csv(recording, tmp_path, capsys) -> None:
    # read_joint_csv's docstring says samples.csv is such a file, but the '# command: ...' line spherecal writes
    # first was taken for the header: 'joint panda_joint1 not in the recording (has # command: ...)'
    from spherecal.correction.files.samples import Dataset
    from spherecal.correction.files.samples_csv import write_samples

    _, t, q, truth = recording
    held = truth >= 0
    dataset = Dataset(labels=np.where(truth[held] == 0, "A", "B"), q=q[held], t=t[held])
    write_samples(tmp_path / "samples.csv", dataset, "command: spherecal simulate --seed 3\nseed: 3")
    out = tmp_path / "out"
    assert main(["import", str(tmp_path / "samples.csv"), "--format", "csv", "--robot", str(PANDA), "--out", str(out),
                 "--max-per-fixture", "100000", "--dedup-deg", "0"]) == 0
    again = read_samples(out / "samples.csv", load_robot(PANDA))
    assert again.fixture_names == ("A", "B")
    np.testing.assert_array_equal(again.for_fixture("B"), q[truth == 1])
    # a recording handed to calibrate as samples: the refusal says what to do with it
    (tmp_path / "raw.csv").write_text("time," + ",".join(NAMES) + "\n0.0,0,0,0,-2,0,2,0\n")
    error = _refused(["calibrate", "--robot", str(PANDA), "--samples", str(tmp_path / "raw.csv"), "--out",
                      str(tmp_path / "c.yaml")], tmp_path, capsys)
    assert "first column must be 'fixture' (a recording without fixture labels? spherecal import" in error


def test_a_topic_typed_without_its_leading_slash_is_the_bags(recording, tmp_path, capsys) -> None:
    # --topic joint_states: "no topic 'joint_states' in the bag (has /joint_states)"
    true, t, q, truth = recording
    bag = write_bag(tmp_path / "rec", "sqlite3", t, q, NAMES)
    out = tmp_path / "out"
    assert main(["import", str(bag), "--format", "bag", "--robot", str(PANDA), "--out", str(out), "--topic",
                 "joint_states", "--max-per-fixture", "100000"]) == 0
    _check_split(out, true, t, q, truth)


def test_a_1khz_csv_stamped_in_milliseconds_is_refused(tmp_path, capsys) -> None:
    """Milliseconds at 1 kHz step by exactly 1: read as seconds (the step range's upper end was inclusive), the
    stillness segmentation failed on a '50.00-30314.00 s' stretch (a review)."""
    q = np.tile([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8], (50, 1))
    rows = "\n".join(f"{k}.0," + ",".join(repr(float(v)) for v in q[k]) for k in range(50))
    (tmp_path / "ms.csv").write_text("time," + ",".join(NAMES) + "\n" + rows + "\n")
    argv = ["import", str(tmp_path / "ms.csv"), "--format", "csv", "--robot", str(PANDA), "--out", str(tmp_path / "o")]
    error = _refused(argv, tmp_path, capsys)
    assert "field 'time': samples 1 s apart (median)" in error and "(milliseconds?)" in error


def test_a_joint_reading_that_jumps_is_refused_in_a_csv_as_in_a_bag(recording, tmp_path, capsys) -> None:
    """One row of joint 7 0.08 rad off (an encoder glitch): a bag refused it, a CSV passed it to the segmentation and
    wrote its fixtures (a review). Both refuse it now, naming the row and the glitch."""
    true, t, q, _ = recording
    glitch = q.copy()
    glitch[700, 6] += 0.08
    rows = "\n".join(f"{float(t[k])!r}," + ",".join(repr(float(v)) for v in glitch[k]) for k in range(len(t)))
    (tmp_path / "rec.csv").write_text("time," + ",".join(NAMES) + "\n" + rows + "\n")
    argv = ["import", str(tmp_path / "rec.csv"), "--format", "csv", "--robot", str(PANDA), "--out", str(tmp_path / "o")]
    error = _refused(argv, tmp_path, capsys)
    assert "rec.csv: row 702, field 'time': the joints move 0.08" in error
    assert "an encoder glitch: remove the row" in error
    bag = write_bag(tmp_path / "rec", "sqlite3", t, glitch, NAMES)
    error = _refused(["import", str(bag), "--format", "bag", *argv[4:]], tmp_path, capsys)
    assert "one joint reading that jumped (an encoder glitch)" in error


def _stream_csv(path, t, q) -> None:
    rows = "\n".join(f"{float(t[k])!r}," + ",".join(repr(float(v)) for v in q[k]) for k in range(len(t)))
    path.write_text("time," + ",".join(NAMES) + "\n" + rows + "\n")


@pytest.mark.parametrize("kind", ["csv", "bag"])
def test_a_repeated_stamp_is_dropped_when_its_joints_repeat_and_refused_when_they_differ(recording, kind, tmp_path,
                                                                                          capsys) -> None:
    """Two rows with one stamp passed silently (a review): the same joints (a logger writing a row twice) went to the
    deduplication unnamed; other joints (which came first cannot be told) were segmented in either order. A CSV and
    a bag now both drop the repeats, saying how many, and refuse the clash naming its row and the time field."""
    _, t, q, _ = recording

    def write(name, t, q):
        if kind == "bag":
            return write_bag(tmp_path / name, "sqlite3", t, q, NAMES)
        _stream_csv(tmp_path / f"{name}.csv", t, q)
        return tmp_path / f"{name}.csv"

    argv = ["import", "--format", kind, "--robot", str(PANDA), "--max-per-fixture", "100000"]
    assert main([*argv, str(write("clean", t, q)), "--out", str(tmp_path / "clean_out")]) == 0
    twice = np.sort(np.r_[np.arange(len(t)), np.arange(700, 710)])  # rows 700-709 written twice each
    capsys.readouterr()
    assert main([*argv, str(write("repeat", t[twice], q[twice])), "--out", str(tmp_path / "repeat_out")]) == 0
    noun = "rows" if kind == "csv" else "messages"
    lines = [line for line in capsys.readouterr().out.splitlines() if "repeating" in line]
    assert lines == [f"dropped 10 {noun} repeating the one before (the same time and joint angles: a logger's "
                     "repeat)"], lines
    clean, repeat = (read_samples(tmp_path / f"{name}_out/samples.csv", load_robot(PANDA)) for name in ("clean",
                                                                                                        "repeat"))
    np.testing.assert_array_equal(repeat.q, clean.q)
    np.testing.assert_array_equal(repeat.t, clean.t)
    clash = t.copy()
    clash[701] = clash[700]  # row 701 stamped as row 700, its joints 5 ms on
    source = write("clash", clash, q)
    error = _refused([*argv, str(source), "--out", str(tmp_path / "clash_out")], tmp_path, capsys)
    where = f"{source}: row 703, field 'time'" if kind == "csv" else f"{source}: /joint_states message 702, field " \
        "'header.stamp'"
    assert f"{where}: the same time as the one before" in error and "which came first cannot be told" in error


def _import_inputs(out) -> dict:
    """The options an import recorded in its provenance (fixtures.yaml, ``import: provenance: inputs``)."""
    return read_fixtures(out / "fixtures.yaml").extras["import"]["provenance"]["inputs"]


def test_the_provenance_records_the_clock_that_timed_the_samples(recording, tmp_path, capsys) -> None:
    """A CSV imported by its time column recorded 'rate: 1000.0', a rate nothing used (a review); a labelled CSV
    recorded a rate and segmentation thresholds though nothing was timed or segmented. The provenance now records the
    time field, or the rate where it timed the samples, and thresholds only where they split the recording."""
    _, t, q, truth = recording
    _stream_csv(tmp_path / "rec.csv", t, q)
    argv = ["import", "--robot", str(PANDA), "--max-per-fixture", "9999"]
    assert main([*argv, str(tmp_path / "rec.csv"), "--format", "csv", "--out", str(tmp_path / "a"), "--rate",
                 "1000"]) == 0
    used = _import_inputs(tmp_path / "a")
    assert used["time"] == "column 'time'" and "rate" not in used and used["still_radius"] == 0.003
    bare = tmp_path / "bare.csv"
    bare.write_text("\n".join(line.split(",", 1)[1] for line in (tmp_path / "rec.csv").read_text().splitlines())
                    + "\n")
    assert main([*argv, str(bare), "--format", "csv", "--out", str(tmp_path / "b"), "--rate", "200"]) == 0
    used = _import_inputs(tmp_path / "b")
    assert used["rate"] == 200.0 and "time" not in used
    labels = np.where(truth < 0, "air", np.where(truth == 0, "A", "B"))
    (tmp_path / "lab.csv").write_text("fixture," + ",".join(NAMES) + "\n" + "\n".join(
        f"{labels[k]}," + ",".join(repr(float(v)) for v in q[k]) for k in range(len(t))) + "\n")
    assert main([*argv, str(tmp_path / "lab.csv"), "--format", "csv", "--out", str(tmp_path / "c")]) == 0
    used = _import_inputs(tmp_path / "c")
    assert not {"rate", "time", "window", "still_radius", "min_separation"} & set(used), used
    bag = write_bag(tmp_path / "rec", "sqlite3", t, q, NAMES)
    assert main([*argv, str(bag), "--format", "bag", "--out", str(tmp_path / "d")]) == 0
    used = _import_inputs(tmp_path / "d")
    assert used["time"] == "header.stamp" and used["topic"] == "/joint_states" and "rate" not in used


def test_a_stream_with_one_socket_says_how_to_add_a_second(recording, tmp_path, capsys) -> None:
    """One still stretch segmented, one fixture: calibrate takes the scale from the nominal model; the import says so
    (a review: nothing was said until calibrate), naming a second socket in the recording and its distance."""
    true = recording[0]
    t, q, _ = stream(true, [0.0])
    _stream_csv(tmp_path / "one.csv", t, q)
    assert main(["import", str(tmp_path / "one.csv"), "--format", "csv", "--robot", str(PANDA), "--out",
                 str(tmp_path / "o")]) == 0
    lines = [line for line in capsys.readouterr().out.splitlines() if line.startswith("one fixture")]
    assert len(lines) == 1 and lines[0].startswith("one fixture (S1): "), lines
    assert "carry the ball to a second socket in the recording" in lines[0]
    assert "import it again with --known-distance S1 S2 METRES" in lines[0]


@pytest.fixture(scope="module")
def sources(recording, tmp_path_factory) -> dict:
    """A source of each format: a MUKCa placement, a bag and a CSV of the two-socket stream."""
    folder = tmp_path_factory.mktemp("sources")
    _, t, q, _ = recording
    _stream_csv(folder / "rec.csv", t, q)
    return {"mukca": DATA / "panda_2_clean" / "front_center", "csv": folder / "rec.csv",
            "bag": write_bag(folder / "rec", "sqlite3", t, q, NAMES)}


SEGMENTATION = [("--window", "0.5"), ("--still-radius", "3"), ("--min-duration", "2"), ("--min-configurations", "20"),
                ("--max-spread", "20"), ("--min-separation", "30")]


@pytest.mark.parametrize(("fmt", "option", "value", "applies"), [
    ("mukca", "--topic", "/joint_states", "bag"), ("csv", "--topic", "/arm/joint_states", "bag"),
    ("bag", "--distance", "0.05", "mukca"), ("csv", "--distance", "0.05", "mukca"),
    ("mukca", "--rate", "1000", "csv"), ("bag", "--rate", "500", "csv"),
    *[("mukca", option, value, "bag or csv") for option, value in SEGMENTATION],
])
def test_an_option_of_another_format_is_refused(sources, fmt, option, value, applies, tmp_path, capsys) -> None:
    """`import --topic` with --format mukca or csv was accepted and ignored (a review), as were --distance with a bag
    or a CSV and the segmentation thresholds with a MUKCa folder (labelled: nothing is segmented); --rate with MUKCa or
    a bag only warned. Each is refused in one line naming the option and the formats it applies to, even when typed
    at its default value."""
    argv = ["import", sources[fmt], "--format", fmt, "--robot", PANDA, "--out", tmp_path / "out", option, value]
    refused(argv, tmp_path, capsys, f"field '{option}': applies to --format {applies} only, not {fmt}")
    assert main([str(a) for a in argv[:-2]] + ["--max-per-fixture", "50"]) == 0  # the same import without it


@pytest.mark.parametrize("fmt", ["bag", "csv"])
def test_the_options_of_a_format_are_used(sources, fmt, tmp_path, capsys) -> None:
    """Refusing other formats' options keeps each format's own, defaults included: a still radius of 1 mm splits
    the same stream into fewer samples than the default 3 mm."""
    argv = ["import", str(sources[fmt]), "--format", fmt, "--robot", str(PANDA), "--max-per-fixture", "100000"]
    assert main([*argv, "--out", str(tmp_path / "default")]) == 0
    assert main([*argv, "--out", str(tmp_path / "tight"), "--still-radius", "1"]) == 0
    default, tight = (read_samples(tmp_path / name / "samples.csv", load_robot(PANDA)) for name in ("default", "tight"))
    assert 0 < tight.n_samples < default.n_samples
    assert _import_inputs(tmp_path / "tight")["still_radius"] == 0.001


def test_columns_numbered_past_the_arms_joints_are_named_in_a_note(tmp_path) -> None:
    """A review: a q1..q9 CSV read for a 7-joint arm dropped q8 and q9 without a word (a 9-joint file read wrong)."""
    from spherecal.correction import load_robot
    from spherecal.identification.ingest.importers import read_joint_csv

    q0 = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    rows = [",".join(f"q{i}" for i in range(1, 10))] + [",".join(f"{v:.6f}" for v in [*q0, 0.01, 0.02])] * 3
    (tmp_path / "q9.csv").write_text("\n".join(rows) + "\n")
    notes = read_joint_csv(tmp_path / "q9.csv", load_robot("panda")).notes
    assert any("columns q8, q9 go on after the arm's q1..q7 and are not read" in n for n in notes), notes
    (tmp_path / "q7.csv").write_text("\n".join(r.rsplit(",", 2)[0] for r in rows) + "\n")
    assert not read_joint_csv(tmp_path / "q7.csv", load_robot("panda")).notes


def _raw_joint_states(path, messages, edit=None, ros1=False, chunk=None) -> None:
    """A ROS 2 bag (a ROS 1 bag when ``ros1``: ``header.seq`` counting, ``chunk`` bytes a chunk) of
    ``sensor_msgs/JointState``: ``messages`` of (time [s], names, positions, frame_id, stamped[, received [s]
    [, connection]]), the time in ``header.stamp`` when ``stamped`` (else zero) and as the bag's receive time unless
    given, on /joint_states from ``connection`` (0 or 1: two publishers), each message's bytes passed through
    ``edit(k, data)`` when given (a corrupt message)."""
    from rosbags.typesys import Stores, get_typestore

    if ros1:
        from rosbags.rosbag1 import Writer

        writer = Writer(path)
        writer.chunk_threshold = chunk or writer.chunk_threshold
    else:
        from rosbags.rosbag2 import Writer

        writer = Writer(path, version=9)
    store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    state, header, time = (store.types[k] for k in ("sensor_msgs/msg/JointState", "std_msgs/msg/Header",
                                                    "builtin_interfaces/msg/Time"))
    serialize = store.serialize_ros1 if ros1 else store.serialize_cdr
    with writer:
        connections = [writer.add_connection("/joint_states", state.__msgtype__, typestore=store, **(
            {"callerid": f"/publisher{k}"} if ros1 else {"serialization_format": "cdr", "offered_qos_profiles": (
                [] if k == 0 else ["x"])})) for k in range(2)] if any(len(m) > 6 for m in messages) else (
            [writer.add_connection("/joint_states", state.__msgtype__, typestore=store)])
        for k, (stamp, names, position, frame, stamped, *more) in enumerate(messages):
            sec = int(stamp) if stamped else 0
            nanosec = int(round((stamp - sec) * 1e9)) if stamped else 0
            head = header(seq=k, stamp=time(sec=sec, nanosec=nanosec), frame_id=frame) if ros1 else (
                header(stamp=time(sec=sec, nanosec=nanosec), frame_id=frame))
            data = bytes(serialize(state(header=head, name=list(names), position=np.asarray(position, float),
                                         velocity=np.zeros(len(position)), effort=np.zeros(0)), state.__msgtype__))
            received, connection = (more + [stamp, 0][len(more):])[:2]
            writer.write(connections[connection], int(received * 1e9), edit(k, data) if edit else data)


def _mixed(t, q) -> list:
    """Messages of the arm (its joints reversed, the fingers after them or around them) with gripper messages and
    messages without positions between them, zero stamps and frame_ids of several lengths."""
    fingers = ["panda_finger_joint1", "panda_finger_joint2"]
    messages = []
    for k in range(0, len(t), 3):
        names, position = NAMES[::-1] + fingers, list(q[k, ::-1]) + [0.04, 0.04]
        if k % 2:  # a finger first: matched by name, not by place
            names, position = names[-1:] + names[:-1], position[-1:] + position[:-1]
        messages.append((t[k], names, position, "base" * (k % 3), k % 7 > 0))
        messages += [(t[k], fingers, [0.04, 0.04], "", True)] if k % 5 == 0 else []
        messages += [(t[k], NAMES, [], "", True)] if k % 11 == 0 else []
    return messages


def _same_reading(fast, slow) -> None:
    np.testing.assert_array_equal(fast.q, slow.q)
    np.testing.assert_array_equal(fast.t, slow.t)
    assert list(fast.rows) == list(slow.rows) and fast.notes == slow.notes


@pytest.mark.parametrize("ros1", [False, True])
def test_a_bag_read_at_its_messages_offsets_is_read_as_deserialised(recording, ros1, tmp_path, monkeypatch) -> None:
    # the reader deserialises one message of each layout and reads the others' stamps and positions at their offsets:
    # the same samples, rows and notes as deserialising every message, gripper messages, messages without
    # positions, zero stamps and frame_ids of several lengths interleaved (a ROS 1 bag in chunks of 2 kB: the
    # layouts read in arrays a chunk at a time)
    _, t, q, _ = recording
    messages = _mixed(t, q)
    bag = tmp_path / ("mixed.bag" if ros1 else "mixed")
    _raw_joint_states(bag, messages, ros1=ros1, chunk=2000)
    model = load_robot(PANDA)
    monkeypatch.setattr(bag_module, "_BLOCK", 5)  # messages read into arrays 5 at a time, between the others
    fast = read_bag(bag, model)
    assert len(fast.notes) == 2
    assert fast.rows[0] == f"{bag}: /joint_states message 1" and fast.rows[-1].endswith(f" {len(messages)}")
    nearest = np.abs(fast.t[:, None] - t[None, :]).argmin(axis=1)  # the sample each stamp is of (to 1 ns)
    np.testing.assert_array_equal(fast.q, q[nearest])  # the arm's joints, by name
    if ros1:  # rosbags' reader, message by message, the layouts matched one message at a time
        monkeypatch.setattr(bag_module, "_read_ros1", lambda path, model, topic: None)
        _same_reading(fast, read_bag(bag, model))
    monkeypatch.setattr(bag_module, "_layout_of", lambda raw, message, cdr: None)  # every message deserialised
    _same_reading(fast, read_bag(bag, model))


@pytest.mark.parametrize("ros1", [False, True])
def test_the_blocks_hold_the_arms_joints_only(recording, ros1, tmp_path, monkeypatch) -> None:
    # until joined, the blocks held every position of a message (a Panda's 9, the fingers too) and four int64 columns
    # (number, sec, nanosec, receive time): now the arm's 7 angles, by name, the number and one float stamp
    _, t, q, _ = recording
    bag = tmp_path / ("mixed.bag" if ros1 else "mixed")
    _raw_joint_states(bag, _mixed(t, q), ros1=ros1, chunk=2000)
    monkeypatch.setattr(bag_module, "_BLOCK", 5)
    columns, shapes = bag_module._Group.columns, []

    def recorded(group):
        shapes.extend((len(part), part[2].shape[1:], part[1].dtype) for part in group.parts())
        return columns(group)

    monkeypatch.setattr(bag_module._Group, "columns", recorded)
    read_bag(bag, load_robot(PANDA))
    assert len(shapes) > 5 and set(shapes) == {(3, (7,), np.dtype(float))}


def test_a_ros1_bag_is_read_in_rosbags_order_across_chunks_and_publishers(recording, tmp_path, monkeypatch) -> None:
    # the messages come in the order of their receive times (rosbags' reader: a tie by the connection, then by the
    # index), numbered so: two publishers on the topic, receive times that go back across chunks of 1 kB and ties
    _, t, q, _ = recording
    order = np.random.default_rng(0).permutation(len(t))[: len(t) // 2]
    messages = [(t[k], NAMES, list(q[k]), "", True, t[k] + 0.05 * (k % 4 == 0) - 0.004 * (k % 9 == 0), k % 3 == 0)
                for k in range(len(t))]
    for k in order[:50]:  # receive times alike, of both publishers
        messages[k] = (*messages[k][:5], t[order[0]], messages[k][6])
    bag = tmp_path / "two.bag"
    _raw_joint_states(bag, messages, ros1=True, chunk=1000)
    model = load_robot(PANDA)
    found = bag_module._read_ros1(bag, model, "/joint_states")
    assert found is not None and found[0].count == len(t)  # read a chunk at a time
    fast = read_bag(bag, model)
    monkeypatch.setattr(bag_module, "_read_ros1", lambda path, model, topic: None)
    _same_reading(fast, read_bag(bag, model))
    numbers, stamps, _ = found[0].arrays()
    assert list(numbers) == list(range(1, len(t) + 1))
    received = np.array([int(m[5] * 1e9) for m in messages])  # ties by the connection, then as written
    order = np.lexsort((np.arange(len(t)), [m[6] for m in messages], received))
    np.testing.assert_array_equal(stamps, np.array([m[0] for m in messages])[order])
    assert len(set(received[order[:-1]][np.diff(received[order]) == 0])) > 10


def test_a_ros1_bag_the_chunk_reader_leaves_is_read_by_rosbags(recording, tmp_path) -> None:
    # a message record whose header is not its connection's first one's (here: its fields in another order) is left
    # to rosbags' reader, message by message, with the same result
    _, t, q, _ = recording
    messages = [(t[k], NAMES, list(q[k]), "", True) for k in range(300)]
    bag = tmp_path / "odd.bag"
    _raw_joint_states(bag, messages, ros1=True, chunk=4000)
    model = load_robot(PANDA)
    before = read_bag(bag, model)
    data = bytearray(bag.read_bytes())
    op = b"\x04\x00\x00\x00op=\x02"
    at = data.index(op, data.index(op) + 1)  # the second message record's header: op, conn, time
    assert data[at + 8 : at + 21].startswith(b"\x09\x00\x00\x00conn=")
    data[at : at + 21] = data[at + 8 : at + 21] + data[at : at + 8]  # conn, op, time
    bag.write_bytes(bytes(data))
    assert bag_module._read_ros1(bag, model, "/joint_states") is None
    after = read_bag(bag, model)
    np.testing.assert_array_equal(after.q, before.q)
    assert list(after.rows) == list(before.rows)


@pytest.mark.parametrize("ros1", [False, True])
def test_a_bag_refuses_its_first_bad_message_first(recording, ros1, tmp_path) -> None:
    # the angles are checked once read, in arrays: a message whose angle is not finite is still refused before a
    # later message that cannot be read, and a message that cannot be read before a later angle that is not finite
    _, t, q, _ = recording
    model = load_robot(PANDA)
    messages = [(t[k], NAMES, list(q[k]), "", True) for k in range(200)]
    messages[40] = (t[40], NAMES, [np.nan] + list(q[40, 1:]), "", True)
    name = "{}.bag" if ros1 else "{}"
    _raw_joint_states(tmp_path / name.format("a"), messages, lambda k, data: data[:-9] if k == 77 else data, ros1)
    with pytest.raises(RecordingError, match=r"a(\.bag)?: /joint_states message 41, field 'position': not finite"):
        read_bag(tmp_path / name.format("a"), model)
    _raw_joint_states(tmp_path / name.format("b"), messages, lambda k, data: data[:-9] if k == 17 else data, ros1)
    with pytest.raises(RecordingError, match=r"b(\.bag)?: cannot read the bag: "):
        read_bag(tmp_path / name.format("b"), model)
    _raw_joint_states(tmp_path / name.format("c"), messages, lambda k, data: data + bytes(8) if k == 17 else data,
                      ros1)
    with pytest.raises(RecordingError, match=r"c(\.bag)?: cannot read the bag: (CDR|ROS1) message size mismatch"):
        read_bag(tmp_path / name.format("c"), model)
    p = list(messages[20])
    p[2] = p[2][:6]
    _raw_joint_states(tmp_path / name.format("d"), messages[:20] + [tuple(p)] + messages[21:], ros1=ros1)
    with pytest.raises(RecordingError, match=r"d(\.bag)?: /joint_states message 21, field 'position': 6 positions "):
        read_bag(tmp_path / name.format("d"), model)


def test_a_ros1_bag_whose_record_time_is_not_its_index_time_is_refused_in_one_line(recording, tmp_path) -> None:
    # a helper's note (stop 15): such a bag stopped inside rosbags on a bare assert, a traceback and no file named
    _, t, q, _ = recording
    messages = [(t[k], NAMES, list(q[k]), "", True) for k in range(300)]
    bag = tmp_path / "late.bag"
    _raw_joint_states(bag, messages, ros1=True, chunk=4000)
    data = bytearray(bag.read_bytes())
    op = b"\x04\x00\x00\x00op=\x02"
    at = data.index(op, data.index(op) + 1)  # the second message record's header: op, conn, time
    when = data.index(b"time=", at) + 5
    data[when : when + 4] = (int.from_bytes(data[when : when + 4], "little") + 1000).to_bytes(4, "little")
    bag.write_bytes(bytes(data))
    with pytest.raises(RecordingError, match=r"late\.bag: cannot read the bag: \w") as error:
        read_bag(bag, load_robot(PANDA))
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("text, said", [
    ("", "row 1, field 'rosbag2_bagfile_information': not a ROS 2 bag's metadata (an empty file)"),
    ("- a\n- b\n", "row 1, field 'rosbag2_bagfile_information': not a ROS 2 bag's metadata (a list)"),
    ("version: 9\n", "row 1, field 'rosbag2_bagfile_information': not a ROS 2 bag's metadata (keys 'version')"),
    ("rosbag2_bagfile_information: {version: 9\n", "row 2: invalid YAML"),
])
def test_a_metadata_yaml_not_a_bags_is_refused_naming_it(recording, tmp_path, capsys, text, said) -> None:
    """A bad-input sweep: an empty or list metadata.yaml said "Invalid bag metadata: 'NoneType' object is not
    subscriptable", naming the folder; invalid YAML, the YAML parser's lines with no row of ours."""
    true, t, q, _ = recording
    bag = write_bag(tmp_path / "bag", "sqlite3", t[:50], q[:50], [f"panda_joint{i + 1}" for i in range(7)])
    (bag / "metadata.yaml").write_text(text)
    refused(["import", bag, "--format", "bag", "--robot", PANDA, "--out", tmp_path / "out"], tmp_path, capsys,
            f"{bag / 'metadata.yaml'}: {said}")


def test_a_csv_given_as_a_bag_is_pointed_to_format_csv(recording, tmp_path, capsys) -> None:
    path = tmp_path / "rec.csv"
    path.write_text("time,q1\n0,0\n")
    refused(["import", path, "--format", "bag", "--robot", PANDA, "--out", tmp_path / "out"], tmp_path, capsys,
            f"{path}: field 'SOURCE': a CSV file, not a bag", "use --format csv")


#: MCAP files start and end with these 8 bytes (mcap.dev/spec), written out here rather than taken from the reader.
MAGIC = b"\x89MCAP0\r\n"


def _summary_past_the_end(data: bytes) -> bytes:
    """An MCAP file damaged inside, its two magics intact: its footer record (opcode 0x02, a uint64 length of 20,
    then the uint64 summary start: mcap.dev/spec) pointing past the end of the file."""
    footer = len(data) - len(MAGIC) - 29
    assert data[footer] == 0x02 and int.from_bytes(data[footer + 1 : footer + 9], "little") == 20
    return data[: footer + 9] + (len(data) + 100).to_bytes(8, "little") + data[footer + 17 :]


@pytest.mark.parametrize("damage, said", [
    (lambda data: data[: len(data) // 2], "a truncated MCAP file ({size} bytes, not ending with MCAP's closing magic"),
    (lambda data: data[:-1], "a truncated MCAP file ({size} bytes, not ending with MCAP's closing magic"),
    (lambda data: b"garbage\n" * 64, "not an MCAP file: it does not start with MCAP's magic bytes (starts b'garba"),
    (lambda data: b"", "an empty MCAP file (0 bytes)"),
    (lambda data: _summary_past_the_end(data), "a damaged storage file (Invalid MCAP summary offset"),
], ids=["half", "last-byte", "garbage", "empty", "summary-offset"])
@pytest.mark.parametrize("metadata", [True, False], ids=["folder", "no-metadata"])
def test_a_damaged_mcap_file_is_named_not_its_folder(recording, tmp_path, capsys, damage, said, metadata) -> None:
    # a review: a ROS 2 bag folder whose .mcap file was cut short said "rec: cannot read the bag: File end magic is
    # invalid.", naming the folder and not which file, nor that it was cut short
    _, t, q, _ = recording
    bag = write_bag(tmp_path / "rec", "mcap", t[:300], q[:300], NAMES)
    (storage,) = bag.glob("*.mcap")
    data = storage.read_bytes()
    assert data.startswith(MAGIC) and data.endswith(MAGIC)
    assert len(read_bag(bag, load_robot(PANDA)).q) == 300  # the bag before its damage reads whole
    storage.write_bytes(damage(data))
    if not metadata:  # a recording killed before ros2 bag record wrote metadata.yaml: its one file read alone
        (bag / "metadata.yaml").unlink()
    error = refused(["import", bag, "--format", "bag", "--robot", PANDA, "--out", tmp_path / "out"], tmp_path, capsys,
                    f"{storage}: cannot read the bag: {said.format(size=storage.stat().st_size)}")
    assert f"{bag}:" not in error and not (tmp_path / "out").exists()
