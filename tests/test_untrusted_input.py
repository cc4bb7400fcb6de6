"""Untrusted text and numbers: YAML bombs, duplicate keys, broken CSV, non-physical values: one line each."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
import pytest
import yaml

from spherecal.cli import main
from spherecal.correction import RobotFileError, dump_robot, load_robot, save_robot, tool_point
from spherecal.correction.files.fixtures import read_fixtures
from spherecal.correction.files.samples import Dataset, DatasetError
from spherecal.correction.files.samples_csv import format_samples, read_samples, write_samples
from spherecal.correction.files.yaml_safe import MAX_BYTES
from spherecal.identification.ingest.importers import RecordingError, read_joint_csv
from spherecal.validation.mocap import MocapError, MocapMeasurement, read_mocap_csv, write_mocap_csv
from spherecal.validation.planning.candidates import CandidateError, read_candidates
from tests.refusal import refused

BOMB = "\n".join(
    ["a: &a [x, x, x, x, x, x, x, x, x, x]"]
    + [f"{chr(98 + k)}: &{chr(98 + k)} [*{chr(97 + k)}, *{chr(97 + k)}, *{chr(97 + k)}, *{chr(97 + k)}, "
       f"*{chr(97 + k)}, *{chr(97 + k)}, *{chr(97 + k)}, *{chr(97 + k)}, *{chr(97 + k)}, *{chr(97 + k)}]"
       for k in range(8)]
) + "\n"  # 10**9 values once expanded, 500 bytes of text
DEEP = "x: " + "[" * 20000 + "]" * 20000 + "\n"
HUGE = "x: [" + ", ".join(["0.0"] * (MAX_BYTES // 5 + 10)) + "]\n"


def _readers(tmp_path, panda):
    return {
        "robot": (lambda p: load_robot(p), RobotFileError),
        "fixtures": (lambda p: read_fixtures(p), DatasetError),
        "candidates": (lambda p: read_candidates(p, panda.n_joints), CandidateError),
    }


@pytest.mark.parametrize("reader", ["robot", "fixtures", "candidates"])
@pytest.mark.parametrize(("text", "message"), [(BOMB, "expands to more than"), (DEEP, "nested more than"),
                                               (HUGE, "a YAML file here is at most")])
def test_yaml_bombs_deep_and_huge_documents_are_refused_at_once(tmp_path, panda, reader, text, message) -> None:
    path = tmp_path / "input.yaml"
    path.write_text(text)
    read, error = _readers(tmp_path, panda)[reader]
    start = time.process_time()  # CPU time: the machine may be shared
    with pytest.raises(error, match=message) as refused_:
        read(path)
    assert time.process_time() - start < 1.0  # refused before anything expands or recurses
    assert "\n" not in str(refused_.value) and str(path) in str(refused_.value)


@pytest.mark.parametrize("reader", ["robot", "fixtures", "candidates"])
def test_a_duplicated_key_is_an_error_naming_it_and_its_row(tmp_path, panda, reader) -> None:
    texts = {
        "robot": dump_robot(panda).replace("name: franka_panda", "name: franka_panda\nname: other"),
        "fixtures": "fixtures:\n  P1: {}\n  P2: {}\n  P1: {position: [0, 0, 0]}\n",
        "candidates": "candidates:\n  C1: {position: [0.5, 0, 0.3]}\n  C1: {position: [0.4, 0, 0.3]}\n",
    }
    path = tmp_path / "input.yaml"
    path.write_text(texts[reader])
    row = next(k + 1 for k, line in enumerate(texts[reader].splitlines())
               if line.strip().startswith(("name: other", "P1: {position", "C1: {position: [0.4")))
    read, error = _readers(tmp_path, panda)[reader]
    with pytest.raises(error, match=rf"row {row}, field '(name|P1|C1)': duplicate key"):
        read(path)


def test_a_yaml_alias_within_the_budget_still_reads(tmp_path) -> None:
    path = tmp_path / "fixtures.yaml"
    path.write_text("centre: &c [0.5, 0.0, 0.3]\nfixtures:\n  P1: {position: *c}\n  P2: {}\n")
    assert read_fixtures(path).positions["P1"].tolist() == [0.5, 0.0, 0.3]


# ----------------------------------------------------------------------------------------- CSV
def _samples(panda, rows: int = 12) -> Dataset:
    q = panda.random_configurations(rows, np.random.default_rng(1))
    return Dataset(labels=np.repeat(["P1", "P2"], rows // 2), q=q, t=np.arange(rows) * 1e-3)


def _edit_line(path, row: int, edit) -> None:
    lines = path.read_text().splitlines(keepends=True)
    lines[row - 1] = edit(lines[row - 1])
    path.write_text("".join(lines))


def _cell(line: str, column: int, text: str) -> str:
    fields = line.rstrip("\n").split(",")
    fields[column] = text
    return ",".join(fields) + "\n"


@pytest.mark.parametrize("text", ["\u0661", "\uff11", "1_0", "0.\u0665"])
def test_a_digit_of_another_script_or_an_underscore_is_not_a_number(tmp_path, panda, text) -> None:
    # Python's float() reads '\u0661' (Arabic-Indic one) as 1.0, full-width '\uff11' as 1.0 and '1_0' as 10.0:
    # a corrupted or foreign-locale cell was used as an angle (a refusal came, if at all, from the fit)
    path = write_samples(tmp_path / "samples.csv", _samples(panda))
    _edit_line(path, 5, lambda line: _cell(line, 4, text))  # fixture, t, q1, q2, q3
    with pytest.raises(DatasetError, match=rf"row 5, field 'q3': expected a number, got '{text}'"):
        read_samples(path, panda)
    joint = tmp_path / "joint.csv"
    joint.write_text("t,q1,q2,q3,q4,q5,q6,q7\n0," + ",".join(["0.1"] * 2 + [text] + ["-1", "0.1", "1", "0.1"]) + "\n")
    with pytest.raises(RecordingError, match=rf"row 2, field 'q3': expected a number, got '{text}'"):
        read_joint_csv(joint, panda)
    mocap = write_mocap_csv(tmp_path / "mocap.csv", MocapMeasurement(q=_samples(panda).q[:5],
                                                                     tool=np.zeros((5, 3))))
    _edit_line(mocap, 3, lambda line: _cell(line, 2, text))
    with pytest.raises(MocapError, match=rf"row 3: field q3: bad value '{text}'"):
        read_mocap_csv(mocap, panda.n_joints)


def test_two_files_concatenated_name_the_second_header(tmp_path, panda) -> None:
    # `cat a.csv b.csv > all.csv`: the second header was "expected a number, got 'q1'" (samples) or
    # "got 'panda_joint1'" (joint CSV), not what had happened
    one = format_samples(_samples(panda))
    path = tmp_path / "samples.csv"
    path.write_text(one + one)
    row = len(one.splitlines()) + 1  # the first line of the second copy
    with pytest.raises(DatasetError, match=rf"samples.csv: row {row}, field 'fixture': the header again \(two files "
                                           r"concatenated\?"):
        read_samples(path, panda)
    joint = tmp_path / "joint.csv"
    text = "t,q1,q2,q3,q4,q5,q6,q7\n0," + ",".join(["0.1"] * 3 + ["-1", "0.1", "1", "0.1"]) + "\n"
    joint.write_text(text + text)
    with pytest.raises(RecordingError, match=r"joint.csv: row 3, field 't': the header again \(two files concatenated"):
        read_joint_csv(joint, panda)


CSV_CASES = [
    (lambda line: line.replace(",", ',"', 1), 3, "unterminated quote"),
    (lambda line: line.replace(",", "," + "7" * 200_000, 1), 4, "a field longer than the CSV limit"),
]


@pytest.mark.parametrize(("edit", "row", "message"), CSV_CASES)
def test_samples_csv_broken_quotes_and_huge_fields_name_their_row(tmp_path, panda, edit, row, message) -> None:
    path = write_samples(tmp_path / "samples.csv", _samples(panda))
    _edit_line(path, row, edit)
    with pytest.raises(DatasetError, match=rf"row {row}: {message}") as error:
        read_samples(path, panda)
    assert "\n" not in str(error.value)


@pytest.mark.parametrize(("edit", "row", "message"), CSV_CASES)
def test_mocap_and_joint_csv_broken_quotes_and_huge_fields_name_their_row(tmp_path, panda, edit, row,
                                                                          message) -> None:
    q = panda.random_configurations(12, np.random.default_rng(2))
    mocap = write_mocap_csv(tmp_path / "mocap.csv", MocapMeasurement(q=q, tool=tool_point(panda, q)))
    joints = write_samples(tmp_path / "joints.csv", _samples(panda))
    for path, read, error in ((mocap, lambda p: read_mocap_csv(p, 7), MocapError),
                              (joints, lambda p: read_joint_csv(p, panda), RecordingError)):
        _edit_line(path, row, edit)
        with pytest.raises(error, match=rf"row {row}: {message}"):
            read(path)


def test_the_fast_and_the_careful_samples_readers_agree(tmp_path, panda) -> None:
    # a comment or a quoted name sends a block through the csv module line by line; same result
    data = _samples(panda, 40)
    plain = write_samples(tmp_path / "plain.csv", data)
    careful = tmp_path / "careful.csv"
    text = format_samples(data).replace("\nP2,", '\n"P2",', 1)
    careful.write_text("# comment\n" + text + "\n   \n")
    a, b = read_samples(plain, panda), read_samples(careful, panda)
    np.testing.assert_array_equal(a.q, data.q)  # every bit (repr of floats)
    np.testing.assert_array_equal(a.t, data.t)
    for name in ("q", "t", "labels"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert a.fixture_names == b.fixture_names == ("P1", "P2")
    np.testing.assert_array_equal(b.lines, a.lines + 1)  # the comment shifts every row by one line


@pytest.mark.parametrize(("edit", "field"), [
    (lambda line: line.replace(line.split(",")[3], "nan"), "q2"),
    (lambda line: line.rsplit(",", 1)[0] + "\n", "q7"),
    (lambda line: line.rstrip("\n") + ",0.1\n", "column 10"),
    (lambda line: "," + line.split(",", 1)[1], "fixture"),
])
def test_samples_csv_bad_row_named_in_a_large_block(tmp_path, panda, edit, field) -> None:
    data = _samples(panda, 3000)
    path = write_samples(tmp_path / "samples.csv", data)
    _edit_line(path, 2500, edit)
    with pytest.raises(DatasetError, match=rf"row 2500, field '{field}'"):
        read_samples(path, panda)


def test_a_file_name_with_a_newline_is_one_line(tmp_path, panda, capsys) -> None:
    folder = tmp_path / "in"
    folder.mkdir()
    save_robot(panda, folder / "robot.yaml")
    path = folder / "bad\nname.csv"
    path.write_text("fixture,q1\nP1,0\n")
    refused(["calibrate", "--robot", folder / "robot.yaml", "--samples", path, "--out", tmp_path / "cal.yaml"],
            tmp_path, capsys, "bad\\nname.csv")


# -------------------------------------------------------------------------------------- numbers
@pytest.mark.parametrize(("edit", "field"), [
    (lambda d: d["joints"][3].update(a=1e308), r"row \d+, field 'joints\[3\].a': 1e\+308 m is not physical"),
    (lambda d: d["joints"][0].update(d=-12.0), r"row \d+, field 'joints\[0\].d': -12.0 m is not physical"),
    (lambda d: d.update(tool=[0.0, 0.0, 20.0]), r"row \d+, field 'tool\[2\]': 20.0 m is not physical"),
    (lambda d: d.update(base={"xyz": [0, 11, 0], "rpy": [0, 0, 0]}), r"base.xyz\[1\]"),
    (lambda d: d["joints"][2].update(alpha=100.0), r"row \d+, field 'joints\[2\].alpha': 100.0 rad is not physical"),
    (lambda d: d["joints"][1].update(lower=-1e6), r"joints\[1\].lower"),
    (lambda d: d["joints"][1].update(lower=1.0, upper=1.0), r"row \d+, field 'joints\[1\].lower': must be below upper"),
])
def test_robot_file_refuses_non_physical_numbers(tmp_path, panda, edit, field) -> None:
    data = yaml.safe_load(dump_robot(panda))
    edit(data)
    path = tmp_path / "robot.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(RobotFileError, match=field):
        load_robot(path)


@pytest.mark.parametrize(("argv", "message"), [
    (["simulate", "--out", "o", "--seconds", "1e9"], "at most 3600 s"),
    (["demo", "--seconds", "7200"], "at most 3600 s"),
    (["campaign", "--seconds", "inf"], "finite"),
    (["plan", "--grid", "0,1,2;0,1,2;0,1,2", "--seconds", "1e308"], "at most 3600 s"),
    (["demo", "--configurations", str(10**9)], "an integer in 3..200000"),
    (["validate", "--nominal", "panda", "--calibrated", "panda", "--configurations", str(10**9)], "3..200000"),
    (["campaign", "--per-fixture", str(10**9)], "an integer in 1..100000"),
    # a row twice: the table said 'sets 2' for one seeded set counted twice (std 0.000), exit 0
    (["campaign", "--sets", "1", "--rows", "P1,P2,P1", "--out", "c"], "field '--rows': P1 is given twice"),
    (["calibrate", "--robot", "panda", "--samples", "s.csv", "--out", "c.yaml", "--noise", "1e308"], "plausible"),
])
def test_out_of_range_options_are_one_line(tmp_path, capsys, monkeypatch, argv, message) -> None:
    monkeypatch.chdir(tmp_path)
    refused(argv, tmp_path, capsys, message)


def _mocap_case(tmp_path, panda, kind: str):
    q = panda.random_configurations(40, np.random.default_rng(4))
    tool = tool_point(panda, q)
    if kind == "millimetres":
        tool = tool * 1e3
    elif kind == "identical rows":
        q, tool = np.repeat(q[:1], 40, axis=0), np.repeat(tool[:1], 40, axis=0)
    elif kind == "outside limits":
        q[7, 3] = 1.0
    elif kind == "on one line":
        tool[:, :2] = tool[0, :2]  # x and y columns constant: only z varies
    write_mocap_csv(tmp_path / "mocap.csv", MocapMeasurement(q=q, tool=tool))


@pytest.mark.parametrize(("kind", "message"), [
    ("millimetres", "m from the recording's centre, but franka_panda reaches at most"),
    ("identical rows", "rows 2-41, field q1: 1 distinct configurations in 40 rows, need at least 10"),
    ("outside limits", "row 9: field q4: 1 rad outside the joint limits"),
    ("on one line", "rows 2-41: field x: the tool points lie on one line (0.00 mm RMS off it, at least 1 mm needed)"),
])
def test_validate_refuses_mocap_that_cannot_be_of_this_arm(tmp_path, panda, capsys, kind, message) -> None:
    # millimetres in a metres file gave a 573 m "error", identical rows 0.000 mm for both models, exit 0; tool
    # points on one line (x, y constant) registered about that line by noise alone: 470 mm "errors", exit 0
    _mocap_case(tmp_path, panda, kind)
    save_robot(panda, tmp_path / "cal.yaml")
    refused(["validate", "--nominal", "panda", "--calibrated", tmp_path / "cal.yaml", "--mocap",
             tmp_path / "mocap.csv", "--out", tmp_path / "report.json"], tmp_path, capsys, message)


@pytest.mark.parametrize(("edit", "message"), [
    (lambda m: replace(m, upper=m.upper - np.r_[0, 0, 0, 0, 0, 0, 0.5]), "field joints[6].upper"),
    (lambda m: replace(m, tool=m.tool + np.array([0.0, 0.2, 0.0])), "tool point up to 200 mm from the nominal"),
])
def test_validate_refuses_a_calibrated_file_of_another_arm(tmp_path, panda, capsys, edit, message) -> None:
    _mocap_case(tmp_path, panda, "fine")
    save_robot(edit(panda), tmp_path / "cal.yaml")
    refused(["validate", "--nominal", "panda", "--calibrated", tmp_path / "cal.yaml", "--mocap",
             tmp_path / "mocap.csv", "--out", tmp_path / "report.json"], tmp_path, capsys, message)


def test_validate_takes_a_calibration_whose_file_rounds_the_joint_limits(tmp_path, panda, capsys) -> None:
    # the embedded iiwa14's calibration validated against MUKCa's iiwa14.urdf (limits rounded to 4 decimals, 3e-4 rad
    # apart) was refused as another arm's: "field joints[0].lower: np.float64(-2.96705972839), expected
    # np.float64(-2.9668)"
    _mocap_case(tmp_path, panda, "fine")
    save_robot(replace(panda, lower=np.round(panda.lower, 3) - 2e-4, upper=np.round(panda.upper, 3)),
               tmp_path / "cal.yaml")
    argv = ["validate", "--nominal", "panda", "--calibrated", str(tmp_path / "cal.yaml"), "--mocap",
            str(tmp_path / "mocap.csv")]
    assert main(argv) == 0, capsys.readouterr().err
    save_robot(replace(panda, lower=panda.lower - np.r_[0.01, 0, 0, 0, 0, 0, 0]), tmp_path / "cal.yaml")
    refused(argv, tmp_path, capsys, "field joints[0].lower: -2.9073 rad, expected -2.8973 rad as in the nominal")


@pytest.mark.parametrize(("text", "message"), [
    ("fixtures:\n  P1: {position: [500.0, 0, 300.0]}\n",
     r"row 2, field 'fixtures.P1.position': \[500.0, 0, 300.0\] m"),
    ("fixtures:\n  P1: {}\n  P2: {}\ndistances:\n  - [P1, P2, 50.0]\n",
     r"row 5, field 'distances\[0\]': 50.0 m is not physical"),
])
def test_fixtures_refuse_millimetres_in_a_metres_file(tmp_path, text, message) -> None:
    path = tmp_path / "fixtures.yaml"
    path.write_text(text)
    with pytest.raises(DatasetError, match=message):
        read_fixtures(path)


@pytest.mark.parametrize(("key", "message"), [
    ("distancse", r"row 5, field 'distancse': unknown key 'distancse' \(did you mean 'distances'\?"),
    ("Distances", r"row 5, field 'Distances': unknown key 'Distances' \(did you mean 'distances'\?"),
    ("fixture", r"row 5, field 'fixture': unknown key 'fixture' \(did you mean 'fixtures'\?"),
])
def test_fixtures_refuse_a_misspelt_top_level_key(tmp_path, key, message) -> None:
    # `distancse:` was kept as an unread extra: the known distance silently played no part in the calibration
    path = tmp_path / "fixtures.yaml"
    path.write_text(f"fixtures:\n  P1: {{}}\n  P2: {{}}\n{key}:\n  - [P1, P2, 0.05]\n")
    with pytest.raises(DatasetError, match=message):
        read_fixtures(path)
    path.write_text("fixtures:\n  P1: {}\n  P2: {}\nnotes: plate screwed to the table\nimport: {format: csv}\n")
    assert read_fixtures(path).extras == {"notes": "plate screwed to the table", "import": {"format": "csv"}}


def test_fixtures_refuse_centres_beside_the_fixtures_and_suggest_a_name(tmp_path) -> None:
    # a user trial: 'positions:' beside 'fixtures:' was kept unread (the calibration ran without the known centres),
    # and a distance naming 'P3' among P1, P2 said only that it is not listed
    path = tmp_path / "fixtures.yaml"
    path.write_text("fixtures:\n  P1: {}\n  P2: {}\npositions:\n  P1: [0.5, 0.0, 0.3]\n")
    with pytest.raises(DatasetError, match=r"row 5, field 'positions': unknown key 'positions': a fixture's known "
                                           r"centre is given under its name, 'fixtures: \{P1: \{position: \[x, y, z\]"):
        read_fixtures(path)
    path.write_text("fixtures:\n  front_h0: {}\n  front_h1: {}\ndistances:\n  - [front_h0, front_hl, 0.05]\n")
    with pytest.raises(DatasetError, match=r"'front_hl' is not listed under 'fixtures' \(did you mean 'front_h1'\?\)"):
        read_fixtures(path)
    path.write_text("fixtures:\n  P1: {}\n  P2: {}\ndistances:\n  - [P1, left, 0.05]\n")
    with pytest.raises(DatasetError, match=r"'left' is not listed under 'fixtures' \(listed: P1, P2\)"):
        read_fixtures(path)


@pytest.mark.parametrize(("argv", "message"), [
    (["import", "x", "--format", "mukca", "--robot", "panda", "--out", "o", "--distance", "50"],
     "at most 10 m, got '50' (millimetres? it is in metres)"),
    (["calibrate", "--robot", "panda", "--samples", "s.csv", "--out", "c.yaml", "--dedup-deg", "1e300"], "10 deg"),
    (["simulate", "--out", "o", "--angle-std-deg", "90"], "at most 10 deg"),
    (["plan", "--grid", "0,1e300,2;0,1,2;0,1,2"], "|max| <= 10 m"),
])
def test_more_out_of_range_options(tmp_path, capsys, monkeypatch, argv, message) -> None:
    monkeypatch.chdir(tmp_path)
    refused(argv, tmp_path, capsys, message)


def test_joint_csv_fast_and_careful_readers_agree(tmp_path, panda) -> None:
    # joints in another order between other columns, nanosecond stamps; a comment sends a block line by line
    q = panda.random_configurations(30, np.random.default_rng(5))
    order = [3, 0, 6, 1, 5, 2, 4]
    head = ["stamp", "finger", "fixture"] + [f"panda_joint{j + 1}" for j in order]
    body = [",".join([str(10**18 + k * 10**6), "0.04", "P1" if k < 15 else "P2"]
                     + [repr(float(q[k, j])) for j in order]) for k in range(30)]
    plain = tmp_path / "plain.csv"
    plain.write_text("\n".join([",".join(head)] + body) + "\n")
    careful = tmp_path / "careful.csv"
    careful.write_text("\n".join([",".join(head)] + body[:10] + ["# a comment", '"' + body[10].replace(",", '",', 1)]
                                 + body[11:]) + "\n")
    a, b = read_joint_csv(plain, panda), read_joint_csv(careful, panda)
    np.testing.assert_array_equal(a.q, q)
    np.testing.assert_array_equal(a.t, (10**18 + np.arange(30) * 10**6) * 1e-9)
    for name in ("q", "t", "labels"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert a.rows[12] == f"{plain}: row 14" and b.rows[12] == f"{careful}: row 15"


# ------------------------------------------------------------------------------ endless inputs
@pytest.mark.parametrize(("option", "device", "message"), [
    ("--samples", "/dev/zero", "/dev/zero: row 1: a line longer than"),
    ("--fixtures", "/dev/zero", "/dev/zero: cannot read: larger than"),
    ("--calibrated", "/dev/zero", "/dev/zero: cannot read: larger than"),
    ("--nominal", "/dev/urandom", "/dev/urandom: cannot read: larger than"),
    ("--mocap", "/dev/zero", "/dev/zero: row 1: a line longer than"),
])
def test_an_endless_input_is_refused_not_read_forever(tmp_path, panda, option, device, message) -> None:
    # `--fixtures /dev/zero` grew until the kernel killed the process (a minute, no message); `--samples
    # /dev/zero` and a robot file from /dev/urandom hung: every reader read the whole input first
    import subprocess
    import sys

    save_robot(panda, tmp_path / "robot.yaml")
    path = write_samples(tmp_path / "samples.csv", Dataset(labels=np.array(["P1"] * 3),
                                                           q=panda.random_configurations(3, np.random.default_rng(0))))
    inputs = {"--nominal": tmp_path / "robot.yaml", "--calibrated": tmp_path / "robot.yaml"}
    if option != "--mocap":  # (--samples with --mocap is refused as unused: the measurement is compared alone)
        inputs |= {"--samples": path, option: device}
    argv = [a for pair in inputs.items() for a in pair] + (["--mocap", device] if option == "--mocap" else [])
    run = subprocess.run([sys.executable, "-c", "import sys; from spherecal.cli import main; sys.exit(main())",
                          "validate", *map(str, argv)], capture_output=True, text=True, timeout=60)
    assert run.returncode == 1 and len(run.stderr.strip().splitlines()) == 1, run.stderr[-500:]
    assert message in run.stderr, run.stderr


@pytest.mark.parametrize(("position", "expected"), [
    ("[1.5, 0, 0.3]", "fixture A at [1.5, 0.0, 0.3] m is out of reach"),
    ("[0.0, 0, 0.1]", "fixture A at [0.0, 0.0, 0.1] m is inside the robot"),
])
def test_simulate_names_the_file_and_field_of_a_fixture_it_cannot_use(tmp_path, capsys, position, expected) -> None:
    # the refusal named neither the fixtures file nor the field ('fixture A at [...] m is out of reach (...)')
    (tmp_path / "fixtures.yaml").write_text(f"fixtures:\n  A: {{position: {position}}}\n")
    refused(["simulate", "--out", tmp_path / "sim", "--fixtures", tmp_path / "fixtures.yaml", "--seconds", "0.01",
             "--per-fixture", "5"], tmp_path, capsys, f"fixtures.yaml: field 'fixtures.A.position': {expected}")


def test_an_elastic_model_of_an_arm_without_masses_names_the_file_and_the_way_to_give_them(tmp_path, capsys) -> None:
    # a URDF without <inertial> of an arm no embedded one matches: the refusals named the robot ('ur5e: field
    # inertials') and not its file, nor --inertials
    from spherecal.correction import load_robot
    from tests.correction.ur5e_urdf import ur5e_urdf

    (tmp_path / "ur5e.urdf").write_text(ur5e_urdf())
    q = load_robot(tmp_path / "ur5e.urdf").random_configurations(40, np.random.default_rng(0))
    rows = [("A" if k < 20 else "B") + "," + ",".join(repr(float(v)) for v in row) for k, row in enumerate(q)]
    (tmp_path / "samples.csv").write_text("fixture," + ",".join(f"q{i + 1}" for i in range(6)) + "\n"
                                          + "\n".join(rows) + "\n")
    refused(["calibrate", "--robot", tmp_path / "ur5e.urdf", "--samples", tmp_path / "samples.csv", "--model",
             "elastic", "--out", tmp_path / "cal.yaml"], tmp_path, capsys,
            "ur5e.urdf: field 'inertials': --model elastic needs the link masses", "--inertials FILE")
    refused(["simulate", "--robot", tmp_path / "ur5e.urdf", "--stiffness", "1e4", "--out", tmp_path / "sim",
             "--seconds", "0.01", "--per-fixture", "5"], tmp_path, capsys,
            "ur5e.urdf: field 'inertials': expected a list of 6 {mass, com} entries, got none", "--inertials FILE")
