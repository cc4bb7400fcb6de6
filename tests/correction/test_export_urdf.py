"""URDF export: an independent reader (MuJoCo's URDF compiler, xml.etree) sees our chain."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import replace

import mujoco
import numpy as np
import pytest

from spherecal.correction import load_robot, to_standard, tool_point, tool_pose
from spherecal.correction.files.urdf_write import ExportError, robot_to_urdf
from tests.conftest import perturbed


def _calibrated(panda, rng, convention):
    """A perturbed ('calibrated') model of the given convention with a far-from-trivial base."""
    model = perturbed(panda if convention == "modified" else to_standard(panda), rng)
    base = np.array([0.12, -0.34, 0.56, 0.3, -0.2, 1.1])
    return model.with_params(np.concatenate([model.params[:-6], base]))


def _mujoco_tool(text, q, prefix="panda_"):
    """(N, 3) positions and (N, 3, 3) orientations of the tool body in MuJoCo."""
    mj = mujoco.MjModel.from_xml_string(text)
    data = mujoco.MjData(mj)
    body = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_BODY, f"{prefix}link8")  # Franka's flange
    assert body >= 0
    points, rotations = np.empty((len(q), 3)), np.empty((len(q), 3, 3))
    for k, qk in enumerate(q):
        data.qpos[:] = qk
        mujoco.mj_kinematics(mj, data)
        points[k], rotations[k] = data.xpos[body], data.xmat[body].reshape(3, 3)
    return mj, points, rotations


@pytest.mark.parametrize("convention", ["modified", "standard"])
def test_mujoco_reads_the_same_tool_point(panda, rng, convention):
    model = _calibrated(panda, rng, convention)
    assert model.convention == convention
    q = model.random_configurations(1000, rng)
    mj, points, rotations = _mujoco_tool(robot_to_urdf(model, mujoco=True), q)
    assert mj.njnt == model.n_joints
    np.testing.assert_array_equal(mj.jnt_range, np.stack([model.lower, model.upper], axis=1))
    error = np.linalg.norm(points - tool_point(model, q), axis=1)
    assert error.max() < 1e-9, error.max()
    np.testing.assert_allclose(rotations, tool_pose(model, q)[:, :3, :3], atol=1e-12)
    # Not trivially true: the nominal model is millimetres away.
    nominal = panda if convention == "modified" else to_standard(panda)
    assert np.linalg.norm(points - tool_point(nominal, q), axis=1).mean() > 1e-3


def test_floats_are_written_exactly_and_names_carry_the_prefix(panda, rng):
    model = _calibrated(panda, rng, "modified")
    root = ET.fromstring(robot_to_urdf(model, prefix="left_"))
    joints = {j.get("name"): j for j in root.iter("joint")}
    links = {link.get("name") for link in root.iter("link")}
    assert {f"left_link{i}" for i in range(9)} | {"left_base"} == links
    revolute = [joints[f"left_joint{i + 1}"] for i in range(7)]
    assert all(j.get("type") == "revolute" and j.find("axis").get("xyz") == "0 0 1" for j in revolute)
    limits = np.array([[float(j.find("limit").get(k)) for k in ("lower", "upper")] for j in revolute])
    np.testing.assert_array_equal(limits, np.stack([model.lower, model.upper], axis=1))  # bit for bit
    base = joints["left_base_joint"].find("origin")
    np.testing.assert_array_equal([float(v) for v in base.get("xyz").split()], model.base_xyz)
    np.testing.assert_array_equal([float(v) for v in base.get("rpy").split()], model.base_rpy)
    tool = joints["left_joint8"].find("origin")  # modified DH: the tool point in link 7 as written
    np.testing.assert_array_equal([float(v) for v in tool.get("xyz").split()], model.tool)


def test_provenance_comment_survives_awkward_text(panda):
    from dataclasses import replace

    model = replace(panda, extras={"calibration": {"method": "self-motion -- test", "rms_mm": 0.05}})
    text = robot_to_urdf(model)
    ET.fromstring(text)  # still well-formed XML although the block contained "--"
    assert "provenance" in text and "rms_mm: 0.05" in text and "self-motion - - test" in text
    assert "calibration: none" in robot_to_urdf(panda)


def test_bad_options_raise_named_errors(panda):
    with pytest.raises(ExportError, match="prefix"):
        robot_to_urdf(panda, prefix='a"b')
    with pytest.raises(ExportError, match="effort"):
        robot_to_urdf(panda, effort=[1.0, 2.0])


def test_another_arm_keeps_its_joint_names_and_must_give_its_limits(tmp_path, capsys) -> None:
    # a review exported a calibrated KUKA iiwa14 standalone: panda_joint1..7 and Franka's 87 / 12 N m, silently
    from spherecal.cli import main
    from spherecal.correction import save_robot
    from spherecal.correction.files.urdf_write import is_franka

    described = load_robot("iiwa14")  # its URDF's <limit effort velocity> are the defaults (test below)
    assert 'effort="300.0" velocity="10.0"' in robot_to_urdf(described)
    block = {k: v for k, v in described.extras["urdf"].items() if k not in ("effort", "velocity")}
    iiwa = replace(described, extras={**described.extras, "urdf": block})
    assert not is_franka(iiwa) and is_franka(load_robot("panda")) and is_franka(load_robot("fr3"))
    with pytest.raises(ExportError, match=r"field '--effort': no default for 'kuka_iiwa14'"):
        robot_to_urdf(iiwa)
    cal = save_robot(iiwa, tmp_path / "iiwa.yaml")
    out = tmp_path / "iiwa.urdf"
    assert main(["export", str(cal), "--format", "urdf", "--out", str(out)]) == 1 and not out.exists()
    assert "field '--effort': no default" in capsys.readouterr().err
    effort, velocity = "320,320,176,176,110,40,40", "1.48,1.48,1.75,1.31,2.27,2.36,2.36"
    assert main(["export", str(cal), "--format", "urdf", "--out", str(out), "--effort", effort,
                 "--velocity", velocity]) == 0
    text = out.read_text()
    assert all(f'<joint name="iiwa_joint_{i}" type="revolute">' in text for i in range(1, 8))
    assert 'effort="320.0" velocity="1.48"' in text and "panda_" not in text
    back = load_robot(out)
    q = iiwa.random_configurations(20, np.random.default_rng(0))
    np.testing.assert_allclose(tool_point(back, q), tool_point(iiwa, q), atol=1e-9)


@pytest.mark.parametrize(("option", "values", "said"), [
    ("--effort", "0,87,87,87,12,12,12", "joint 1: 0 Nm"),
    ("--effort", "-5,87,87,87,12,12,12", "joint 1: -5 Nm"),  # a negative number reaches the check
    ("--effort", "-5", "expected 7 limits [Nm]"),
    ("--effort", "87,87,87,87,12,12,1e9", "joint 7: 1e+09 Nm is beyond any real arm"),
    ("--velocity", "2.175,2.175,2.175,2.175,2.61,2.61,1e6", "joint 7: 1e+06 rad/s is beyond any real arm"),
    ("--velocity", "125,125,125,125,150,150,150", "(deg/s? the limit is in rad/s)"),  # Franka's in deg/s
    ("--velocity", "2.175,x", "expected comma-separated numbers [rad/s]"),
])
def test_implausible_joint_limits_are_refused_naming_the_option_and_its_unit(option, values, said, tmp_path,
                                                                                capsys) -> None:
    # a review: --effort 0 and --effort 1e9 were written into the URDF; '--effort -5,87,...' was 'expected one argument'
    from tests.refusal import refused

    refused(["export", "panda", "--format", "urdf", "--out", tmp_path / "a.urdf", option, values], tmp_path, capsys,
            f"field '{option}': ", said)


def test_joint_limit_bounds_leave_real_arms_their_limits(panda) -> None:
    from spherecal.correction.files.urdf_write import MAX_EFFORT, MAX_VELOCITY, PANDA_EFFORT, PANDA_VELOCITY

    assert 'effort="87.0" velocity="2.175"' in robot_to_urdf(panda, effort=PANDA_EFFORT, velocity=PANDA_VELOCITY)
    # a heavy industrial arm's shoulder (tens of kN m) and a fast SCARA's wrist (about 60 rad/s) stay under the bounds
    text = robot_to_urdf(panda, effort=[MAX_EFFORT] + [85e3] * 6, velocity=[MAX_VELOCITY] + [63.0] * 6)
    assert f'effort="{MAX_EFFORT!r}" velocity="{MAX_VELOCITY!r}"' in text
    with pytest.raises(ExportError, match=r"field '--velocity': joint 2: .* beyond any real arm"):
        robot_to_urdf(panda, velocity=[1.0, MAX_VELOCITY * 1.01, 1, 1, 1, 1, 1])


#: A 4-joint arm that is not a Franka one, its joints' <limit> naming effort [N m] and velocity [rad/s]; the last
#: one continuous.
_LIMITED = """<robot name="ur_like">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/><link name="l4"/><link name="ball"/>
  <joint name="pan" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.16"/>
    <axis xyz="0 0 1"/><limit lower="-6.28" upper="6.28" effort="150" velocity="3.14"/></joint>
  <joint name="lift" type="revolute"><parent link="l1"/><child link="l2"/><origin rpy="1.5708 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="150" velocity="3.14"/></joint>
  <joint name="elbow" type="revolute"><parent link="l2"/><child link="l3"/><origin xyz="-0.425 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="150" velocity="3.14"/></joint>
  <joint name="wrist" type="continuous"><parent link="l3"/><child link="l4"/><origin xyz="-0.39 0 0.13"/>
    <axis xyz="0 1 0"/><limit effort="28" velocity="6.28"/></joint>
  <joint name="tip" type="fixed"><parent link="l4"/><child link="ball"/><origin xyz="0 -0.1 0.05"/></joint>
</robot>"""


def test_a_urdf_arm_exports_standalone_with_its_own_limits(tmp_path) -> None:
    # a UR5e-like arm read from its own URDF (limits effort="150" ...) was refused a standalone export: "no default
    # for 'ur5e_like' (Franka's are for a Franka arm ...)": its description's limits now are the defaults, through
    # the calibrated robot file as well
    from spherecal.correction import save_robot

    source = tmp_path / "ur_like.urdf"
    source.write_text(_LIMITED)
    model = load_robot(source)
    assert model.extras["urdf"]["effort"] == [150.0, 150.0, 150.0, 28.0]
    assert model.extras["urdf"]["velocity"] == [3.14, 3.14, 3.14, 6.28]
    back = load_robot(save_robot(model, tmp_path / "cal.yaml"))
    for text in (robot_to_urdf(model), robot_to_urdf(back)):
        limits = [(float(e.get("effort")), float(e.get("velocity"))) for e in ET.fromstring(text).iter("limit")]
        assert limits == [(150.0, 3.14)] * 3 + [(28.0, 6.28)]
    written = robot_to_urdf(back, effort=[1, 2, 3, 4], velocity=[5, 6, 7, 8])  # given ones still win
    assert [float(e.get("effort")) for e in ET.fromstring(written).iter("limit")] == [1.0, 2.0, 3.0, 4.0]
    # a joint without them leaves none for the arm: refused as before
    source.write_text(_LIMITED.replace(' effort="28" velocity="6.28"', ""))
    partial = load_robot(source)
    assert "effort" not in partial.extras["urdf"] and "velocity" not in partial.extras["urdf"]
    with pytest.raises(ExportError, match=r"field '--effort': no default for 'ur_like'"):
        robot_to_urdf(partial)


def test_a_revolute_joint_of_one_turn_keeps_its_limits(tmp_path) -> None:
    # a UR trial: the elbow, revolute within [-pi, pi], was written back as 'continuous' (its limit dropped) because
    # a continuous joint is read as [-pi, pi] too; a URDF's model now names its continuous joints
    from spherecal.correction import save_robot

    source = tmp_path / "ur_like.urdf"
    source.write_text(_LIMITED.replace('lower="-3" upper="3"', f'lower="{-np.pi!r}" upper="{np.pi!r}"'))
    model = load_robot(source)
    assert model.upper[1] - model.lower[1] == pytest.approx(2 * np.pi)  # a span of one turn, like the wrist's
    assert model.full_turn.tolist() == [False, False, False, True]
    back = load_robot(save_robot(model, tmp_path / "cal.yaml"))
    assert back.full_turn.tolist() == [False, False, False, True]
    joints = {e.get("name"): e for e in ET.fromstring(robot_to_urdf(back)).iter("joint")}
    kinds = [(e.get("type"), e.find("limit").get("lower")) for e in joints.values() if e.get("type") != "fixed"]
    assert kinds == [("revolute", "-6.28"), ("revolute", repr(-np.pi)), ("revolute", repr(-np.pi)),
                     ("continuous", None)], kinds
    # a model that does not name them (a DH file, a file written before) counts every span of one turn
    unnamed = replace(model, extras={**model.extras, "urdf": {
        k: v for k, v in model.extras["urdf"].items() if k != "continuous_joints"}})
    assert unnamed.full_turn.tolist() == [False, True, True, True]


def test_the_provenance_comment_leaves_the_machine_records_in_the_robot_file(panda):
    """A ROS user's trial: a URDF of 8 kB exported with 56 kB of comment, most of it the parameters' covariance that
    validate reads from the calibrated robot file. The comment keeps what a reader reviews and says what it left."""
    block = {"method": "lm", "residual_mm": {"after": {"rms": 0.42}}, "trained_on": {"P1": {"digest": "ab" * 32}},
             "self_check": {"verdict": "consistent", "prediction": {"covariance": [[1.0, 0.5], [0.5, 1.0]]}}}
    model = replace(panda, extras={"calibration": block})
    text = robot_to_urdf(model)
    ET.fromstring(text)
    assert "verdict: consistent" in text and "rms: 0.42" in text
    assert "covariance" not in text and "digest" not in text
    assert "(left out here, in the robot file: self_check.prediction, trained_on)" in text
    assert block["self_check"]["prediction"] and block["trained_on"]  # the model's own block is left as it was
