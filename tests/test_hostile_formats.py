"""Files from a user's own stack: fixtures.yaml, inertials and samples.csv as other tools write them.

Each case once gave a silent wrong result or a misleading refusal; each is now read as written or refused in
one line naming the file, row and field.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import yaml

from spherecal.cli import main
from spherecal.correction import RobotFileError, dump_robot, load_robot
from spherecal.correction.files.fixtures import read_fixtures
from spherecal.correction.files.inertials_file import with_inertials_file
from spherecal.correction.files.samples import DatasetError
from spherecal.correction.files.samples_csv import read_samples
from spherecal.correction.gravity import InertialsError, inertials_of
from spherecal.identification.ingest.importers import RecordingError, read_joint_csv
from tests.refusal import refused


# ------------------------------------------------------------------------------------ fixtures.yaml
@pytest.mark.parametrize(("names", "expected"), [
    (["1", "01"], ["1", "01"]),  # YAML 1.1: both the integer 1, one fixture silently dropped
    (["0x1", "1"], ["0x1", "1"]),
    (["yes", "no"], ["yes", "no"]),  # True / False
    (["on", "null"], ["on", "null"]),  # True / None
    (["010", "1:30"], ["010", "1:30"]),  # octal 8, sexagesimal 90
])
def test_fixture_names_are_read_as_the_file_writes_them(tmp_path, names, expected) -> None:
    path = tmp_path / "fixtures.yaml"
    path.write_text("fixtures:\n" + "".join(f"  {name}: {{}}\n" for name in names)
                    + f"distances:\n  - [{names[0]}, {names[1]}, 0.3]\n")
    spec = read_fixtures(path)
    assert list(spec.names) == expected
    assert spec.distances == [(expected[0], expected[1], 0.3)]


@pytest.mark.parametrize(("key", "problem"), [
    ('"P\\x001"', "control character"), ('"P\\n1"', "control character"), ("'#P1'", "starts with '#'"),
    ("' P1'", "spaces around it"),
])
def test_a_fixture_name_no_samples_label_can_match_is_refused_on_one_line(tmp_path, key, problem) -> None:
    path = tmp_path / "fixtures.yaml"
    path.write_text(f"fixtures:\n  P0: {{}}\n  {key}: {{}}\n")
    with pytest.raises(DatasetError, match=f"row 3, field 'fixtures.*{problem}") as error:
        read_fixtures(path)
    assert "\n" not in str(error.value) and str(path) in str(error.value)


def test_numbers_in_exponent_notation_are_numbers(tmp_path) -> None:
    """YAML 1.2 (ruamel.yaml, yaml-cpp) reads 1e-1 as a float; PyYAML's 1.1 rules made it the string '1e-1'."""
    path = tmp_path / "fixtures.yaml"
    path.write_text("fixtures:\n  P1: {position: [5e-1, 0, 3E-1]}\n  P2: {}\ndistances:\n  - [P1, P2, 1e-1]\n")
    spec = read_fixtures(path)
    assert spec.positions["P1"].tolist() == [0.5, 0.0, 0.3] and spec.distances == [("P1", "P2", 0.1)]


# ----------------------------------------------------------------------------------------- inertials
def _inertials_text(masses, coms, payload: str = "") -> str:
    rows = "".join(f"  - {{mass: {float(m)!r}, com: {[float(v) for v in c]}}}\n"
                   for m, c in zip(masses, coms, strict=True))
    return "inertials:\n" + rows + payload


@pytest.mark.parametrize(("scale", "payload", "field"), [
    (1000.0, "", "row 2, field 'inertials[0].mass'"),  # the Panda's masses in grams
    (1.0, "payload: {mass: 1e6, com: [0, 0, 0.1]}\n", "row 9, field 'payload.mass'"),  # was the string '1e6'
    (1.0, "payload: {mass: 1.0e+6, com: [0, 0, 0.1]}\n", "row 9, field 'payload.mass'"),  # was read
])
def test_masses_no_arm_of_its_size_carries_are_refused(tmp_path, panda, scale, payload, field) -> None:
    masses, coms = inertials_of(panda)
    path = tmp_path / "inertials.yaml"
    path.write_text(_inertials_text(masses[:7] * scale, coms[:7], payload))
    with pytest.raises(InertialsError, match=rf"{re.escape(str(path))}: {re.escape(field)}: .* kg in all for an arm"
                                             r" of 1.29 m of links, not physical .*kilograms"):
        with_inertials_file(panda, path)
    path.write_text(_inertials_text(masses[:7], coms[:7], "payload: {mass: 3e0, com: [0, 0, 1e-1]}\n"))
    assert inertials_of(with_inertials_file(panda, path))[0][-1] == 3.0  # a real payload, exponent notation


def test_elastic_calibration_with_masses_of_zero_is_refused(tmp_path, panda, capsys) -> None:
    assert main(["simulate", "--out", str(tmp_path / "sim"), "--seconds", "3", "--per-fixture", "30",
                 "--stiffness", "20000", "--seed", "1"]) == 0
    _, coms = inertials_of(panda)
    (tmp_path / "zero.yaml").write_text(_inertials_text([0.0] * 7, coms[:7]))
    sim = tmp_path / "sim"
    refused(["calibrate", "--robot", "panda", "--samples", sim / "samples.csv", "--fixtures", sim / "fixtures.yaml",
             "--model", "elastic", "--inertials", tmp_path / "zero.yaml", "--out", tmp_path / "out.yaml"],
            tmp_path, capsys, "zero.yaml: field 'inertials': every link mass and the payload are 0 kg")


# ---------------------------------------------------------------------------------------- samples.csv
@pytest.mark.parametrize(("header", "message"), [
    ("fixture;q1;q2;q3;q4;q5;q6;q7", "row 1, field 'fixture': the columns are separated by ';', not commas"),
    ("fixture\tq1\tq2\tq3\tq4\tq5\tq6\tq7", "row 1, field 'fixture': the columns are separated by '\\t'"),
    ("fixture,q1,q2,q3,q4,q5,q6,q7,", "row 1, field 'column 9': a column without a name"),
    ("fixture,Q1,Q2,Q3,Q4,Q5,Q6,Q7", "row 1, field 'Q1': joint columns are named in lower case, q1..q7"),
])
def test_a_header_from_another_tool_is_named_for_what_it_is(tmp_path, panda, header, message) -> None:
    path = tmp_path / "samples.csv"
    path.write_text(header + "\n" + header.replace("fixture", "P1").replace("q", "0.").replace("Q", "0.") + "\n")
    with pytest.raises(DatasetError, match=message.replace("(", r"\(").replace("'\\t'", "'\\\\t'")):
        read_samples(path, panda)


def test_a_fixture_label_with_a_nul_byte_is_refused_naming_its_row(tmp_path, panda) -> None:
    q = panda.random_configurations(3, np.random.default_rng(0))
    rows = ["fixture,q1,q2,q3,q4,q5,q6,q7"] + [",".join([label] + [repr(float(v)) for v in r])
                                               for label, r in zip(["P1", "P\x001", "P1"], q, strict=True)]
    path = tmp_path / "samples.csv"
    path.write_text("\n".join(rows) + "\n")
    with pytest.raises(DatasetError, match=r"row 3, field 'fixture': the fixture name 'P\\x001' holds a control"):
        read_samples(path, panda)


# ---------------------------------------------------------------------------------------------- URDF
PANDA_URDF = Path(__file__).parent / "data" / "urdf" / "panda.urdf"
XACRO = 'xmlns:xacro="http://www.ros.org/wiki/xacro"'


@pytest.mark.parametrize(("old", "new", "message"), [
    ('rpy="-1.5707963267948966 0 0"', 'rpy="${-pi/2} 0 0"',  # was 'expected 3 numbers'
     "field 'joint panda_joint2 <origin rpy>': '${-pi/2} 0 0' holds an unexpanded xacro expression"),
    ('<robot name="panda">', f'<robot name="panda" {XACRO}><xacro:include filename="$(find pkg)/hand.xacro"/>',
     # was read without the hand it includes
     "field '<xacro:include>': <xacro:include> element: a .xacro file, not yet a URDF"),
    ('xyz="0 0 0.333"', 'xyz="0 0 333"',  # millimetres: was 'joints[1].a: 5.4e+18 m' after a warning
     "field 'joint panda_joint1 <origin xyz>': '0 0 333' is not physical (at most 10 m in magnitude; a URDF is in "
     "metres)"),
    ('lower="-2.8973" upper="2.8973"', 'lower="-166" upper="166"',  # degrees: was 'joints[0].lower: -166.0 rad'
     "field 'joint panda_joint1 <limit lower>': -166 rad is not physical"),
])
def test_a_urdf_not_ready_for_use_is_refused_naming_the_joint(tmp_path, capsys, old, new, message) -> None:
    text = PANDA_URDF.read_text()
    assert old in text
    path = tmp_path / "robot.urdf"
    path.write_text(text.replace(old, new, 1))
    row = text[:text.index(old)].count("\n") + 1  # the line of the element the edit is in
    refused(["calibrate", "--robot", path, "--samples", tmp_path / "samples.csv", "--out", tmp_path / "out.yaml"],
            tmp_path, capsys, f"{path}: row {row}, {message}")


# ------------------------------------------------------------------------------- robot files of other tools
@pytest.mark.parametrize(("rename", "message"), [
    (("payload", "payloads"), "field 'payloads': unknown key (did you mean 'payload'?"),  # 0.76 kg silently dropped
    (("inertials", "inertial"), "field 'inertial': unknown key (did you mean 'inertials'?"),
])
def test_a_misspelt_block_of_a_robot_file_is_refused(tmp_path, panda, rename, message) -> None:
    path = tmp_path / "robot.yaml"
    text = dump_robot(panda).replace(f"\n{rename[0]}:", f"\n{rename[1]}:")
    path.write_text(text)
    row = text.splitlines().index(f"{rename[1]}:") + 1  # the misspelt key's line
    with pytest.raises(RobotFileError, match=re.escape(f"{path}: row {row}, {message}")):
        load_robot(path)


@pytest.mark.parametrize(("text", "message"), [
    ("robot:\n  dh:\n    - [0, 0, 0.333, 0]\n", "field 'robot': not a spherecal robot file (keys 'robot'"),  # 'name'
    (None, "field 'joints': 210 joints, at most 64 (not a serial arm)"),  # was read, refused only for its inertials
])
def test_a_robot_file_of_another_tool_or_no_arm_is_named(tmp_path, panda, text, message) -> None:
    path = tmp_path / "robot.yaml"
    if text is None:
        data = yaml.safe_load(dump_robot(panda))
        data["joints"] *= 30
        del data["inertials"], data["payload"]
        text = yaml.safe_dump(data)
    path.write_text(text)
    row = text.splitlines().index(message.split("'")[1] + ":") + 1  # the line of the key named
    with pytest.raises(RobotFileError, match=re.escape(f"{path}: row {row}, {message}")):
        load_robot(path)


def test_a_joint_csv_separated_by_semicolons_is_named_so(tmp_path, panda) -> None:
    """import --format csv: was 'joint franka_panda_joint1 of franka_panda not in the recording'."""
    header = ["time"] + [f"panda_joint{k}" for k in range(1, 8)]
    q = panda.random_configurations(3, np.random.default_rng(0))
    path = tmp_path / "joints.csv"
    path.write_text(";".join(header) + "\n" + "".join(
        ";".join([f"{k * 0.001:.3f}"] + [f"{v:.5f}" for v in r]).replace(".", ",") + "\n" for k, r in enumerate(q)))
    with pytest.raises(RecordingError, match=re.escape(f"{path}: row 1, field 'time': the columns are separated by "
                                                       "';', not commas")):
        read_joint_csv(path, panda)
