"""`spherecal export`: formats, provenance, prefix, atomic output and one-line errors."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

from spherecal.cli import main
from spherecal.correction import load_robot, save_robot, tool_point
from tests.conftest import perturbed


@pytest.fixture
def calibrated_file(tmp_path, panda, rng):
    from dataclasses import replace

    model = replace(perturbed(panda, rng), extras={"calibration": {"samples": 420, "rms_mm": 0.031}})
    return save_robot(model, tmp_path / "cal.yaml"), model


def test_yaml_export_round_trips_exactly(tmp_path, calibrated_file):
    path, model = calibrated_file
    out = tmp_path / "out" / "robot.yaml"
    assert main(["export", str(path), "--format", "yaml", "--out", str(out)]) == 0
    text = out.read_text()
    assert f"robot={path} (sha256 " in text and "numpy" in text
    back = load_robot(out)
    assert back.same_as(model) and back.extras["calibration"]["rms_mm"] == 0.031


def test_urdf_export_has_prefix_provenance_and_versions(tmp_path, calibrated_file):
    path, model = calibrated_file
    out = tmp_path / "robot.urdf"
    assert main(["export", str(path), "--format", "urdf", "--out", str(out), "--prefix", "arm_"]) == 0
    text = out.read_text()
    root = ET.fromstring(text)
    assert {j.get("name") for j in root.iter("joint") if j.get("type") == "revolute"} == {
        f"arm_joint{i}" for i in range(1, 8)
    }
    assert "rms_mm: 0.031" in text and "mujoco" in text and str(path) in text


def test_errors_are_one_line_and_write_nothing(tmp_path, calibrated_file, capsys):
    path, _ = calibrated_file
    out = tmp_path / "robot.urdf"
    assert main(["export", str(path), "--format", "urdf", "--out", str(out), "--prefix", "bad prefix"]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("spherecal export: error: field '--prefix'") and "\n" not in err
    assert main(["export", str(tmp_path / "missing.yaml"), "--format", "urdf", "--out", str(out)]) == 1
    assert "missing.yaml" in capsys.readouterr().err
    assert not out.exists() and list(tmp_path.iterdir()) == [path]


def test_mjcf_export_compiles_to_the_same_tool_point(tmp_path, calibrated_file, rng):
    mujoco = pytest.importorskip("mujoco")
    pytest.importorskip("controller.plant")
    path, model = calibrated_file
    bad = tmp_path / "bad.xml"
    assert main(["export", str(path), "--format", "mjcf", "--out", str(bad), "--prefix", "x_"]) == 1
    assert not bad.exists()
    out = tmp_path / "robot.xml"
    assert main(["export", str(path), "--format", "mjcf", "--out", str(out)]) == 0
    mj = mujoco.MjModel.from_xml_path(str(out))
    data = mujoco.MjData(mj)
    q = model.random_configurations(50, rng)
    site = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_SITE, "tool")
    points = []
    for qk in q:
        data.qpos[: model.n_joints] = qk
        mujoco.mj_kinematics(mj, data)
        points.append(data.site_xpos[site].copy())
    assert np.abs(np.array(points) - tool_point(model, q)).max() < 1e-9
    assert "rms_mm: 0.031" in out.read_text()


@pytest.mark.parametrize("where", ["directory", "missing_parent_is_file"])
def test_unwritable_out_is_one_line_error(tmp_path, calibrated_file, capsys, where):
    path, _ = calibrated_file
    if where == "directory":
        out = tmp_path / "adir"
        out.mkdir()
    else:
        (tmp_path / "plain").write_text("x")
        out = tmp_path / "plain" / "robot.urdf"
    assert main(["export", str(path), "--format", "urdf", "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("spherecal export: error:") and "\n" not in err and str(out) in err
    assert not [p for p in tmp_path.rglob(".*.tmp")]


def test_urdf_export_of_a_six_joint_arm_takes_effort_and_velocity(tmp_path, capsys):
    from tests.controller.test_generic_arm import UR5

    robot = save_robot(UR5, tmp_path / "ur5.yaml")
    out = tmp_path / "ur5.urdf"
    assert main(["export", str(robot), "--format", "urdf", "--out", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert "--effort" in err and "\n" not in err and not out.exists()
    assert main(["export", str(robot), "--format", "urdf", "--out", str(out), "--effort", "150,150,150,28,28,28",
                 "--velocity", "3.14,3.14,3.14,3.14,3.14,3.14"]) == 0
    limits = [j.find("limit") for j in ET.fromstring(out.read_text()).iter("joint") if j.get("type") == "revolute"]
    assert [float(lim.get("effort")) for lim in limits] == [150, 150, 150, 28, 28, 28]
    assert main(["export", str(robot), "--format", "yaml", "--out", str(tmp_path / "x.yaml"),
                 "--effort", "1,1,1,1,1,1"]) == 1
    assert main(["export", str(robot), "--format", "urdf", "--out", str(out), "--effort", "1,x"]) == 1
    assert len(capsys.readouterr().err.strip().splitlines()) == 2


def test_mjcf_export_of_a_name_with_xml_characters_is_well_formed(tmp_path, panda):
    from dataclasses import replace

    robot = save_robot(replace(panda, name='panda & "gripper" <v2>'), tmp_path / "odd.yaml")
    out = tmp_path / "odd.xml"
    assert main(["export", str(robot), "--format", "mjcf", "--out", str(out)]) == 0
    assert ET.fromstring(out.read_text()).get("model") == 'panda & "gripper" <v2>'
