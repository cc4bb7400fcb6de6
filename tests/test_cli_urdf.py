"""--robot ARM.urdf with --tip-link/--base-link through the commands: calibrate a UR5e-like URDF
(Hayati beta on its parallel axes) from simulated samples, export into the same URDF, check in MuJoCo."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

from spherecal.cli import main
from spherecal.correction import load_robot, perturb, registered_errors, save_robot, tool_point
from spherecal.correction.files.fixtures import write_fixtures
from spherecal.correction.files.samples_csv import write_samples
from spherecal.correction.files.urdf_to_dh import NearlyParallelAxesWarning
from spherecal.identification.synthetic import make_dataset
from tests.correction.ur5e_urdf import ur5e_urdf
from tests.correction.urdf_helpers import MujocoUrdf
from tests.refusal import refused


@pytest.fixture
def ur5e_file(tmp_path):
    path = tmp_path / "ur5e.urdf"
    path.write_text(ur5e_urdf(skew=2e-5))
    return path


def test_calibrate_urdf_and_export_into_it(tmp_path, ur5e_file, capsys):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearlyParallelAxesWarning)
        nominal = load_robot(ur5e_file, tip_link="ball")
    assert nominal.hayati == (2, 3)
    true = perturb(nominal, np.random.default_rng(3))
    qc = nominal.random_configurations(3, np.random.default_rng(7)) * 0.5
    centres = {f"s{k}": tool_point(true, qc[k]) for k in range(3)}
    dataset, spec = make_dataset(true, centres, 200, np.random.default_rng(4))
    samples = write_samples(tmp_path / "samples.csv", dataset)
    fixtures = write_fixtures(tmp_path / "fixtures.yaml", spec)
    cal, out = tmp_path / "cal.yaml", tmp_path / "ur5e_calibrated.urdf"
    assert main(["calibrate", "--robot", str(ur5e_file), "--tip-link", "ball", "--samples", str(samples),
                 "--fixtures", str(fixtures), "--out", str(cal),
                 "--prior", "0"]) == 0  # noise-free: exact recovery (the default prior pulls by micrometres)
    said = capsys.readouterr().err  # the parametrisation, said once where it is chosen
    assert said.count("Hayati beta") == 1 and "joints elbow_joint, wrist_1_joint turn about axes" in said, said
    calibrated = load_robot(cal)
    assert calibrated.hayati == (2, 3) and calibrated.d[1] == 0.0 and calibrated.d[2] == 0.0
    assert calibrated.extras["urdf"]["parallel_joints"] == ["elbow_joint", "wrist_1_joint"]  # and recorded
    assert calibrated.extras["calibration"]["fixed"]["d2"].startswith("Hayati: held at zero")
    q = true.random_configurations(500, np.random.default_rng(5))
    assert registered_errors(tool_point(calibrated, q), tool_point(true, q)).max() < 1e-6
    assert main(["export", str(cal), "--format", "urdf", "--into", str(ur5e_file), "--out", str(out)]) == 0
    points, _ = MujocoUrdf(out.read_text()).body_pose("ball", calibrated.extras["joint_names"], q)
    assert np.abs(points - tool_point(calibrated, q)).max() < 1e-12
    assert "Hayati" not in capsys.readouterr().err  # the calibrated file's parametrisation: nothing to choose


def test_link_options_errors_are_one_line(tmp_path, ur5e_file, capsys):
    out = tmp_path / "x.yaml"
    assert main(["export", str(ur5e_file), "--tip-link", "wrist_3_link", "--format", "yaml", "--out", str(out)]) == 0
    assert load_robot(out).extras["urdf"]["tip_link"] == "wrist_3_link"
    warning = capsys.readouterr().err  # the UR's parallel axes: one line, as every message of the CLI
    assert warning.startswith("spherecal export: warning: ") and warning.count("\n") == 1 and "Hayati beta" in warning
    for args, message in (
        (["--tip-link", "gripper"], "field '--tip-link': no link 'gripper'"),
        (["--base-link", "ball"], "no revolute joint"),
    ):
        assert main(["export", str(ur5e_file), *args, "--format", "yaml", "--out", str(tmp_path / "y.yaml")]) == 1
        error = capsys.readouterr().err
        assert message in error and error.count("\n") == 1 and str(ur5e_file) in error
    assert main(["export", "panda", "--tip-link", "x", "--format", "yaml", "--out", str(tmp_path / "z.yaml")]) == 1
    assert "only for a URDF" in capsys.readouterr().err
    folder = tmp_path / "urdf"  # the folder of the URDF, not the file: named as a folder, not as a non-URDF
    folder.mkdir()
    z = str(tmp_path / "z.yaml")
    assert main(["export", str(folder), "--tip-link", "ball", "--format", "yaml", "--out", z]) == 1
    error = capsys.readouterr().err
    assert error.endswith(f"{folder}: cannot read: Is a directory (expected a robot file or a .urdf)\n")
    assert error.count("\n") == 1
    assert not (tmp_path / "y.yaml").exists() and not (tmp_path / "z.yaml").exists()


#: Every command that takes --tip-link and --base-link, with what else it needs to reach the robot (ROBOT: the URDF).
LINK_COMMANDS = [
    ["simulate", "--robot", "ROBOT", "--out", "out", "--seconds", "0.01", "--per-fixture", "5"],
    ["calibrate", "--robot", "ROBOT", "--samples", "s.csv", "--out", "cal.yaml"],
    ["import", "rec", "--format", "csv", "--robot", "ROBOT", "--out", "out"],
    ["validate", "--nominal", "ROBOT", "--calibrated", "panda", "--samples", "s.csv"],
    ["plan", "--robot", "ROBOT", "--grid", "0.3,0.5,2;-0.1,0.1,2;0.2,0.4,2"],
    ["export", "ROBOT", "--format", "yaml", "--out", "x.yaml"],
    ["tool", "panda", "--urdf", "ROBOT", "--out", "t.yaml"],
]


@pytest.fixture
def inputs(tmp_path, monkeypatch, ur5e_file):
    """The working folder of a refused command: the URDF, an empty samples.csv, an empty recording folder."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.csv").write_text("fixture,q1,q2,q3,q4,q5,q6\n")
    (tmp_path / "rec").mkdir()
    return tmp_path


@pytest.mark.parametrize("command", LINK_COMMANDS, ids=lambda c: c[0])
@pytest.mark.parametrize(("option", "link", "said"), [
    ("--tip-link", "wrist_3", "(did you mean 'wrist_3_link'"),
    ("--base-link", "bse_link", "(did you mean 'base_link'"),
    ("--tip-link", "gripper", "(its ends: ball)"),
])
def test_an_unknown_link_is_refused_naming_its_option(inputs, ur5e_file, capsys, command, option, link, said):
    # a review: every command named the link ('tip link 'x' is not a link of robot ...') but not the option
    argv = [str(ur5e_file) if a == "ROBOT" else a for a in command]
    error = refused([*argv, option, link], inputs, capsys,
                    f"ur5e.urdf: field '{option}': no link '{link}' in robot ", said)
    assert error.rstrip("\n").endswith(")")  # the whole hint, on this one line


#: Every command's options that name a robot (a file or an embedded arm), with what else the command needs.
ROBOT_COMMANDS = [
    (["simulate", "--out", "out", "--seconds", "0.01", "--per-fixture", "5", "--robot"], "--robot"),
    (["calibrate", "--samples", "s.csv", "--out", "cal.yaml", "--robot"], "--robot"),
    (["import", "rec", "--format", "csv", "--out", "out", "--robot"], "--robot"),
    (["plan", "--grid", "0.3,0.5,2;-0.1,0.1,2;0.2,0.4,2", "--robot"], "--robot"),
    (["validate", "--calibrated", "panda", "--samples", "s.csv", "--nominal"], "--nominal"),
    (["validate", "--nominal", "panda", "--samples", "s.csv", "--calibrated"], "--calibrated"),
    (["validate", "--nominal", "panda", "--calibrated", "panda", "--samples", "s.csv", "--truth"], "--truth"),
    (["export", "--format", "yaml", "--out", "x.yaml"], "CAL.yaml"),
    (["tool", "--offset", "0", "0", "0.1", "--out", "t.yaml"], "CAL.yaml"),
]


@pytest.mark.parametrize(("command", "option"), ROBOT_COMMANDS, ids=lambda c: c if isinstance(c, str) else c[0])
def test_an_unknown_robot_name_is_refused_naming_its_option(inputs, capsys, command, option):
    argv = [*command, "iiwa"] if option != "CAL.yaml" else [command[0], "iiwa", *command[1:]]
    refused(argv, inputs, capsys, f"iiwa: field '{option}': no such file, nor an embedded robot (did you mean "
            "'iiwa14'? embedded: panda, ")


def test_validate_a_calibration_of_a_urdf_arm_against_that_urdf(tmp_path, ur5e_file, capsys):
    """--tip-link names a link of the URDF among the models; the calibrated file is a robot file."""
    cal = tmp_path / "cal.yaml"
    assert main(["export", str(ur5e_file), "--tip-link", "wrist_3_link", "--format", "yaml", "--out", str(cal)]) == 0
    out = tmp_path / "report.json"
    args = ["validate", "--nominal", str(ur5e_file), "--tip-link", "wrist_3_link", "--calibrated", str(cal),
            "--truth", str(cal), "--configurations", "50", "--out", str(out)]
    capsys.readouterr()
    assert main(args) == 0
    said = capsys.readouterr().err  # a review: every command that read the Gen3 lite's URDF repeated the Hayati beta
    assert "Hayati" not in said, said
    assert out.exists()
    assert main(["simulate", "--robot", str(ur5e_file), "--tip-link", "wrist_3_link", "--seconds", "1",
                 "--per-fixture", "10", "--out", str(tmp_path / "sim")]) == 0
    assert "Hayati" not in capsys.readouterr().err


def test_a_urdf_named_xml_is_read_back_as_a_urdf(tmp_path, panda, capsys):
    """A review: 'export --format urdf --out arm.xml' (the ending ROS tools use) was accepted, but spherecal refused
    to read what it wrote ('arm.xml: row 1: a URDF (<robot>) not named .urdf'). A file whose XML root is <robot> is
    read as a URDF whatever its ending, its link options with it; a robot file still refuses them. (export now
    writes a URDF only as .urdf, .xml being the MJCF export's ending: tests/test_outputs.py; one renamed is read.)"""
    cal = save_robot(perturb(panda, np.random.default_rng(2)), tmp_path / "cal.yaml")
    xml = tmp_path / "arm.xml"
    assert main(["export", str(cal), "--format", "urdf", "--out", str(tmp_path / "arm.urdf")]) == 0
    (tmp_path / "arm.urdf").rename(xml)
    tip = re.findall(r'<link name="([^"]+)"', xml.read_text())[-1]  # the exported chain's end
    back = load_robot(xml, tip_link=tip)
    q = panda.random_configurations(200, np.random.default_rng(5))
    assert np.abs(tool_point(back, q) - tool_point(load_robot(cal), q)).max() < 1e-12
    assert back.extras["urdf"]["tip_link"] == tip
    for argv, said in ((["export", str(xml), "--tip-link", "nope"], "field '--tip-link': no link 'nope'"),
                       (["export", str(cal), "--tip-link", tip], "only for a URDF")):
        assert main([*argv, "--format", "yaml", "--out", str(tmp_path / "x.yaml")]) == 1
        error = capsys.readouterr().err
        assert said in error and error.count("\n") == 1, error
    assert main(["export", str(xml), "--tip-link", tip, "--format", "yaml", "--out", str(tmp_path / "x.yaml")]) == 0
    assert load_robot(tmp_path / "x.yaml").extras["urdf"]["tip_link"] == tip
