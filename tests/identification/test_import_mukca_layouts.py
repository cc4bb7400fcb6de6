"""MUKCa folders as users bring them: placements nested deeper, hole files with a header or a gripper's fingers.

Each is read back against the plain import of the same real recording (tests/data/mukca, MIT).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from spherecal.cli import main
from spherecal.correction import load_robot
from spherecal.correction.files.fixtures import read_fixtures
from spherecal.identification.ingest.importers import RecordingError, read_mukca
from tests.refusal import refused

DATA = Path(__file__).parents[1] / "data" / "mukca"
PANDA = DATA / "panda_ball.yaml"
FRONT = DATA / "panda_2_clean" / "front_center"


@pytest.fixture(scope="module")
def panda():
    return load_robot(PANDA)


def _rows(path: Path) -> list[str]:
    return path.read_text().splitlines()


def test_a_placement_nested_one_level_deeper_is_read_not_dropped(tmp_path, capsys) -> None:
    # robot/day1/front/hole_*.csv beside robot/left/hole_*.csv: import wrote 'left' alone with exit 0, the
    # nested placement dropped without a word
    robot = tmp_path / "panda"
    shutil.copytree(FRONT, robot / "day1" / "front")
    shutil.copytree(DATA / "panda_2_clean" / "mid_right", robot / "left")
    out = tmp_path / "out"
    assert main(["import", str(robot), "--format", "mukca", "--robot", str(PANDA), "--out", str(out)]) == 0
    spec = read_fixtures(out / "fixtures.yaml")
    assert spec.names == ("day1/front_h0", "day1/front_h1", "left_h0", "left_h1")
    assert [d[:2] for d in spec.distances] == [("day1/front_h0", "day1/front_h1"), ("left_h0", "left_h1")]
    # one placement recorded twice under one name (re-placed plate): two placements, not one socket of both
    shutil.copytree(DATA / "panda_2_clean" / "back_left", robot / "day2" / "front")
    with pytest.warns(UserWarning, match=r"placements in 2 folders below it \(day1: 1, day2: 1 placements\), imported "
                                         "as one arm's recordings; if they are several arms', import each"):
        recording, spec = read_mukca(robot, load_robot(PANDA))
    assert {"day1/front_h0", "day2/front_h0"} <= set(spec.names)
    # a placement holding another placement deeper down: which one is meant cannot be told
    shutil.copytree(FRONT, robot / "left" / "again" / "x")
    error = refused(["import", str(robot), "--format", "mukca", "--robot", str(PANDA), "--out",
                     str(tmp_path / "out2")], tmp_path, capsys)
    assert "panda/left: field 'SOURCE': holds hole_<k>.csv files and placement folders (again/x)" in error


def test_hole_files_with_a_header_or_finger_columns_read_the_joints(tmp_path, panda) -> None:
    # a header row ('expected a number, got q1') and a gripper's two fingers appended ('9 joint angles, panda has
    # 7') were refused, although the joint angles are all there
    plain, _ = read_mukca(FRONT, panda)
    names = [f"franka_panda_joint{i}" for i in range(1, 8)]
    order = [6, 0, 1, 2, 3, 4, 5]  # columns in another order, a finger column between them
    for variant in ("header", "fingers"):
        folder = tmp_path / variant / "front_center"
        folder.mkdir(parents=True)
        for hole in ("hole_0.csv", "hole_1.csv"):
            rows = [line.split(",") for line in _rows(FRONT / hole)]
            if variant == "header":
                text = [",".join([names[k] for k in order] + ["panda_finger_joint1"])]
                text += [",".join([row[k] for k in order] + ["0.04"]) for row in rows]
            else:
                text = [",".join(row + ["0.0399", "0.0401"]) for row in rows]
            (folder / hole).write_text("\r\n".join(text) + "\r\n")
        recording, spec = read_mukca(folder, panda)
        np.testing.assert_array_equal(recording.q, plain.q)
        assert list(recording.labels) == list(plain.labels) and spec.names == ("front_center_h0", "front_center_h1")
        assert len(recording.notes) == 2
    # more values than fingers could be: another arm's file
    folder = tmp_path / "bad" / "front"
    folder.mkdir(parents=True)
    shutil.copy(FRONT / "hole_1.csv", folder / "hole_1.csv")
    (folder / "hole_0.csv").write_text("".join(f"{line},0.04,2.5\n" for line in _rows(FRONT / "hole_0.csv")))
    with pytest.raises(RecordingError, match=r"hole_0.csv: row 1, field 'q9': 9 values per row, franka_panda has 7 "
                                             r"joints, and 2.5 is no gripper finger's"):
        read_mukca(folder, panda)
    # a header naming no joint of the arm is named for it
    (folder / "hole_0.csv").write_text("x,y,z,qx,qy,qz,qw\n" + "0.3,0,0.5,0,0,0,1\n")
    with pytest.raises(RecordingError, match=r"hole_0.csv: row 1, field '.*joint1': joint .* not in the recording"):
        read_mukca(folder, panda)


def test_hole_files_as_other_tools_write_them(tmp_path, panda) -> None:
    # a separator ending every row was 'field q8: expected a number', upper-case names (a Windows copy) 'no
    # hole_<k>.csv here', and space-separated values (numpy's savetxt default) "joint 'q1' ... not in the recording"
    plain, _ = read_mukca(FRONT, panda)
    folder = tmp_path / "front_center"
    folder.mkdir()
    for hole, name in (("hole_0.csv", "HOLE_0.CSV"), ("hole_1.csv", "Hole_1.csv")):
        (folder / name).write_text("".join(f"{line},\n" for line in _rows(FRONT / hole)))
    recording, spec = read_mukca(folder, panda)
    np.testing.assert_array_equal(recording.q, plain.q)
    assert spec.names == ("front_center_h0", "front_center_h1")
    shutil.copy(FRONT / "hole_1.csv", folder / "hole_01.csv")  # two files of one hole: which is the socket's?
    with pytest.raises(RecordingError, match=r"hole_01.csv: row 1, field 'q1': a second file of hole 1 beside"):
        read_mukca(folder, panda)
    (folder / "hole_01.csv").unlink()
    (folder / "HOLE_0.CSV").write_text("".join(line.replace(",", " ") + "\n" for line in _rows(FRONT / "hole_0.csv")))
    with pytest.raises(RecordingError, match=r"HOLE_0.CSV: row 1, field 'q1': the values are separated by spaces"):
        read_mukca(folder, panda)


def test_only_hole_0_and_hole_1_are_the_plates_known_distance_apart(tmp_path, panda) -> None:
    # hole_0.csv beside hole_2.csv (hole_1 deleted, or a third socket): the two were declared --distance apart
    folder = tmp_path / "front"
    folder.mkdir()
    shutil.copy(FRONT / "hole_0.csv", folder / "hole_0.csv")
    shutil.copy(FRONT / "hole_1.csv", folder / "hole_2.csv")
    recording, spec = read_mukca(folder, panda)
    assert spec.names == ("front_h0", "front_h2") and spec.distances == []
    assert any("no hole_0.csv and hole_1.csv pair: no known distance" in note for note in recording.notes)
    shutil.copy(DATA / "panda_2_clean" / "mid_right" / "hole_1.csv", folder / "hole_1.csv")  # a third socket
    recording, spec = read_mukca(folder, panda)
    assert spec.names == ("front_h0", "front_h1", "front_h2") and spec.distances == [("front_h0", "front_h1", 0.05)]
