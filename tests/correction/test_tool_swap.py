"""Tool swap: the calibrated chain with another tool point, against a hand-written chain and MuJoCo's URDF
compiler; the README's controller example on a real (MUKCa) calibration; the `tool` command."""

from __future__ import annotations

import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import spherecal.correction
from spherecal.cli import main
from spherecal.controller.compensation import ModelMismatchError, compensate, corrected_ik
from spherecal.correction import load_robot, load_urdf, perturb, tool_point
from spherecal.correction.elastic import link_angles, with_compliance
from spherecal.correction.files.tools import put_tool
from spherecal.correction.tool import CarriedTipWarning, ToolError, with_tool
from tests.correction.urdf_helpers import DATA, MujocoUrdf

MUKCA = Path(__file__).resolve().parents[1] / "data" / "mukca"


def _hand_chain(model, q: np.ndarray, tool: np.ndarray) -> np.ndarray:
    """(3,) tool point of a modified-DH chain, written out with 4x4 matrices (no spherecal kinematics)."""
    def rx(a):
        c, s = np.cos(a), np.sin(a)
        return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])

    def rz(a):
        c, s = np.cos(a), np.sin(a)
        return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])

    def move(x, y, z):
        m = np.eye(4)
        m[:3, 3] = x, y, z
        return m

    r, p, y = model.base_rpy
    ry = np.array([[np.cos(p), 0, np.sin(p), 0], [0, 1, 0, 0], [-np.sin(p), 0, np.cos(p), 0], [0, 0, 0, 1.0]])
    pose = move(*model.base_xyz) @ rz(y) @ ry @ rx(r)
    for i in range(model.n_joints):
        pose = pose @ rx(model.alpha[i]) @ move(model.a[i], 0, 0) @ rz(model.theta[i] + q[i]) @ move(0, 0, model.d[i])
    return (pose @ np.append(tool, 1.0))[:3]


def test_swapped_tool_point_is_the_hand_written_chains(panda, rng) -> None:
    calibrated = with_compliance(perturb(panda, rng), [0.0, 5e-5, 3e-5, 3e-5, 1e-4, 0.0, 0.0])
    new = np.array([0.01, -0.02, 0.21])
    swap = with_tool(calibrated, new)
    assert swap.model.extras["compliance"] == calibrated.extras["compliance"]  # every identified term kept
    q = calibrated.random_configurations(20, rng)
    q_link = link_angles(calibrated, q)  # the sag: the same arm and payload, so the same link angles
    expected = np.array([_hand_chain(calibrated, qk, new) for qk in q_link])
    np.testing.assert_allclose(tool_point(swap.model, q), expected, atol=1e-12)
    assert np.linalg.norm(tool_point(swap.model, q) - tool_point(calibrated, q), axis=1).min() > 0.05
    assert swap.distance == pytest.approx(np.linalg.norm(new - calibrated.tool))
    assert swap.unidentified == pytest.approx(np.sin(np.deg2rad(0.2)) * swap.distance)
    with pytest.raises(ToolError, match="3 finite"):
        with_tool(calibrated, [0.0, np.nan, 0.1])


def test_urdf_tool_lands_where_mujoco_puts_the_tcp(rng) -> None:
    ball = load_urdf(DATA / "panda.urdf", tip_link="ball_link")  # calibrated with the ball ...
    swap, _ = put_tool(ball, urdf=DATA / "panda.urdf", tip_link="panda_hand_tcp")  # ... working with the TCP
    assert swap.distance == pytest.approx(0.0301, abs=1e-3)
    q = ball.random_configurations(50, rng)
    points, _ = MujocoUrdf((DATA / "panda.urdf").read_text()).body_pose("panda_hand_tcp",
                                                                        ball.extras["joint_names"], q)
    np.testing.assert_allclose(tool_point(swap.model, q), points, atol=1e-12)
    with pytest.raises(ToolError, match="last frame"):
        put_tool(ball, urdf=DATA / "iiwa14.urdf", tip_link="ball_link")


def test_readme_controller_example_on_a_real_calibration(tmp_path) -> None:
    robot = str(MUKCA / "panda_ball.yaml")  # MUKCa's ball on the embedded Panda
    train = tmp_path / "train"
    assert main(["import", str(MUKCA / "panda_2_clean" / "front_center"), "--format", "mukca", "--robot", robot,
                 "--out", str(train)]) == 0
    cal = tmp_path / "cal.yaml"
    assert main(["calibrate", "--robot", robot, "--samples", str(train / "samples.csv"), "--fixtures",
                 str(train / "fixtures.yaml"), "--model", "dh", "--out", str(cal)]) == 0
    nominal, calibrated = load_robot("panda"), load_robot(cal)  # the README's two lines
    q_now = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    target = tool_point(nominal, q_now) + [0.03, 0.02, -0.02]
    with pytest.raises(ModelMismatchError, match="mm at the seed .*put the controller's tool on it") as error:
        compensate(target, nominal, calibrated, q_now)  # the ball
    out = tmp_path / "cal_flange.yaml"
    assert main(["tool", str(cal), "--offset", *map(str, nominal.tool), "--out", str(out)]) == 0
    flange = load_robot(out)  # the same calibrated arm, its tool at the nominal model's (the flange)
    # the message's two remedies put the same tool on: its Python call, run as printed, is the command's
    call = str(error.value).split("first: ", 1)[1].split(" or `spherecal tool")[0]
    assert "nominal_tool=" in call
    swapped = eval(call, {"correction": spherecal.correction, "calibrated": calibrated})  # noqa: S307 - our message
    np.testing.assert_allclose(swapped.tool, flange.tool, atol=1e-12)
    result = compensate(target, nominal, flange, q_now)
    assert np.linalg.norm(tool_point(flange, result.q) - target) < 1e-9 and result.gain > 1e-4
    q = corrected_ik(flange, target, q_now, nominal=nominal)
    assert np.linalg.norm(tool_point(flange, q) - target) < 1e-9


def test_tool_command_errors_are_one_line_and_write_nothing(tmp_path, capsys) -> None:
    out = tmp_path / "new.yaml"
    assert main(["tool", "panda", "--offset", "0", "0", "0.2", "--urdf", str(DATA / "panda.urdf"),
                 "--out", str(out)]) == 1
    assert main(["tool", "panda", "--urdf", str(DATA / "panda.urdf"), "--tip-link", "nope", "--out", str(out)]) == 1
    assert main(["tool", "panda", "--offset", "0", "0", "0.2", "--tip-link", "x", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 3 and "nope" in err and not out.exists()
    assert main(["tool", "panda", "--offset", "0", "0", "0.2", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "93.0 mm from the calibrated tool point" in printed and "0.32 mm" in printed
    assert load_robot(out).tool.tolist() == [0.0, 0.0, 0.2]
    out.unlink()
    # 100 typed in millimetres for metres: a tool point 100 m off the flange is refused, nothing written
    assert main(["tool", "panda", "--offset", "0", "0", "100", "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "100 m from the last frame, more than the arm itself" in err and not out.exists()


def test_tool_swap_carries_the_flange_error_the_tool_point_absorbed(panda, rng) -> None:
    """A true arm whose flange is off along and about the last axis (d7, theta7: held at nominal in a
    calibration, redundant with the tool point) carries a ball and then a gripper from the same flange.
    Calibrated on the ball (noise-free, kinematic samples), the swapped gripper lands where the true one
    is (after the rigid registration the gauge allows) only when the ball's correction is carried over;
    putting the gripper at its nominal point as given misses by the flange error."""
    from spherecal.correction import registered_errors
    from spherecal.identification.calibrate import calibrate
    from spherecal.identification.synthetic import make_dataset

    ball, grip = np.array([0.0, 0.0, 0.107 + 0.05]), np.array([0.0, 0.0, 0.107 + 0.1034])
    nominal = replace(panda, tool=ball)
    true = perturb(nominal, rng)
    true = replace(true, tool=true.tool + [0.0, 0.0, 0.0015])  # 1.5 mm more along the flange axis
    dataset, spec = make_dataset(true, per_fixture=300, rng=rng)
    cal = calibrate(nominal, dataset, spec).model
    q = panda.random_configurations(500, rng)
    truth = tool_point(with_tool(true, grip, nominal_tool=ball).model, q)  # the gripper on the true flange
    carried = with_tool(cal, grip, nominal_tool=ball)
    assert registered_errors(tool_point(carried.model, q), truth).max() < 1e-6
    assert "carried to the new tool" in carried.note
    # the note bounds what one ball cannot split (a review: the TCP 1.6 mm off where 0.11 mm was printed)
    assert f"may be off by up to {np.linalg.norm(cal.tool - ball) * 1e3:.2f} mm more" in carried.note
    as_given = with_tool(cal, grip).model
    assert registered_errors(tool_point(as_given, q), truth).mean() > 1e-3


def test_a_second_tool_swap_starts_from_the_calibrated_tool(panda, tmp_path) -> None:
    # `tool` on the output of `tool` carried the calibration's correction from the first new tool: the second
    # tool point landed 90 mm off (0.111 m instead of 0.2017 m along the last axis), exit 0
    from dataclasses import replace

    from spherecal.correction import save_robot

    ball = panda.tool + [0.0, 0.0, 0.135]
    cal = replace(panda, tool=ball + [2e-4, -2e-4, 1.6e-3],  # a calibrated ball: its correction is 1.6 mm
                  extras={**panda.extras, "calibration": {"nominal_tool": ball.tolist()}})
    direct, _ = put_tool(cal, offset=panda.tool + [0.0, 0.0, 0.09])
    first, _ = put_tool(cal, offset=panda.tool + [0.0, 0.0, 0.04])
    save_robot(first.model, tmp_path / "first.yaml")
    again, _ = put_tool(load_robot(tmp_path / "first.yaml"), offset=panda.tool + [0.0, 0.0, 0.09])
    np.testing.assert_allclose(again.model.tool, direct.model.tool, atol=1e-12)
    np.testing.assert_allclose(direct.model.tool, panda.tool + [2e-4, -2e-4, 0.09 + 1.6e-3], atol=1e-12)
    assert again.distance == pytest.approx(direct.distance) and again.note == direct.note


def test_a_ball_calibration_within_the_seed_check_is_refused_by_its_recorded_tool(panda, rng) -> None:
    # a review: an iiwa14 calibrated with its ball 40 mm beyond the flange passed corrected_ik and compensate against
    # the flange (the tool points within the 50 mm check at the seed) and missed every target by 40 mm
    ball = panda.tool + [0.0, 0.0, 0.04]
    cal = perturb(replace(panda, tool=ball), rng)
    cal = replace(cal, extras={**cal.extras, "calibration": {"nominal_tool": ball.tolist()}})
    q_now = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    target = tool_point(panda, q_now) + [0.02, 0.0, -0.01]
    assert np.linalg.norm(tool_point(cal, q_now) - tool_point(panda, q_now)) < 0.05  # the old check let it through
    calls = (lambda: corrected_ik(cal, target, q_now, nominal=panda), lambda: compensate(target, panda, cal, q_now))
    for call in calls:
        with pytest.raises(ModelMismatchError, match=r"calibrates the tool at .* 40\.0 mm from the controller"):
            call()
    flange = with_tool(cal, panda.tool, nominal_tool=ball).model  # the remedy: the flange on the calibrated arm
    q = corrected_ik(flange, target, q_now, nominal=panda)
    np.testing.assert_allclose(_hand_chain(cal, q, cal.tool - [0.0, 0.0, 0.04]), target, atol=1e-9)
    moved = replace(panda, tool=panda.tool + [0.0, 0.0, 5e-5])  # the same tool, saved again with rounding
    assert corrected_ik(replace(cal, extras={**cal.extras, "calibration": {"nominal_tool": moved.tool.tolist()}}),
                        tool_point(cal, q_now), q_now, nominal=panda) is not None


def test_the_remedy_for_a_swapped_file_puts_the_new_tool_on_the_calibrated_one(panda, rng) -> None:
    # a review: a file swapped to the hand TCP, refused against the flange, printed a Python remedy that carried the
    # correction a second time from the TCP (30.13 mm off), and corrected_ik took the result
    ball = panda.tool + [0.0, 0.0, 0.05]
    cal = perturb(replace(panda, tool=ball), rng)
    cal = replace(cal, extras={**cal.extras, "calibration": {"nominal_tool": ball.tolist()}})
    tcp = with_tool(cal, panda.tool + [0.0, 0.0, 0.1034], nominal_tool=ball).model
    q_now = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    target = tool_point(panda, q_now) + [0.02, 0.0, -0.01]
    with pytest.raises(ModelMismatchError) as error:
        corrected_ik(tcp, target, q_now, nominal=panda)
    call = str(error.value).split("first: ", 1)[1].split(" or `spherecal tool")[0]
    flange = eval(call, {"correction": spherecal.correction, "calibrated": tcp})  # noqa: S307 - our message (.model)
    direct = with_tool(cal, panda.tool, nominal_tool=ball).model
    np.testing.assert_allclose(flange.tool, direct.tool, atol=1e-15)
    q = corrected_ik(flange, target, q_now, nominal=panda)
    carried = cal.tool - ball  # the flange's own error that the ball's point absorbed, on the flange
    np.testing.assert_allclose(_hand_chain(cal, q, panda.tool + carried), target, atol=1e-9)


def test_two_urdfs_to_different_tip_links_are_refused_as_different_tools(rng) -> None:
    # a review: an iiwa14 calibration exported --into its URDF and loaded to ball_link (no calibration record left)
    # passed corrected_ik against the URDF loaded to tool0, 40 mm off: the 50 mm seed check only
    ball = load_urdf(DATA / "panda.urdf", tip_link="ball_link")
    cal = replace(perturb(ball, rng), extras=ball.extras)  # as a calibrated URDF loads: the urdf block, no record
    tcp = load_urdf(DATA / "panda.urdf", tip_link="panda_hand_tcp")
    q_now = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    points, _ = MujocoUrdf((DATA / "panda.urdf").read_text()).body_pose("panda_hand_tcp", ball.extras["joint_names"],
                                                                        q_now[None])
    target = points[0] + [0.02, 0.0, -0.01]  # MuJoCo's TCP, moved
    assert np.linalg.norm(tool_point(cal, q_now) - points[0]) < 0.05  # within the seed check
    with pytest.raises(ModelMismatchError, match=r"its tool is URDF link 'ball_link', the controller model's "
                                                 r"'panda_hand_tcp', 3\d\.\d mm apart"):
        corrected_ik(cal, target, q_now, nominal=tcp)
    q = corrected_ik(cal, tool_point(ball, q_now), q_now, nominal=ball)  # the same link: taken
    assert np.linalg.norm(tool_point(cal, q) - tool_point(ball, q_now)) < 1e-9


def test_a_correction_beyond_a_calibrations_is_carried_with_a_warning(panda) -> None:
    # a review: a calibration whose --tip-link named the flange (the ball 40 mm further) gave the "flange" the ball's
    # point through `spherecal tool --tip-link tool0`, exit 0 and no word
    cal = replace(panda, tool=panda.tool + [0.0, 0.0, 0.0406],
                  extras={**panda.extras, "calibration": {"nominal_tool": panda.tool.tolist()}})
    with pytest.warns(CarriedTipWarning, match="40.6 mm from the robot file's tool"):
        with_tool(cal, panda.tool, nominal_tool=panda.tool)
    near = replace(cal, tool=panda.tool + [0.0, 0.0, 0.002])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with_tool(near, panda.tool, nominal_tool=panda.tool)  # a calibration's 2 mm: no word


def test_tool_command_says_where_the_nominal_tool_is_and_prints_both_points(panda, tmp_path, capsys) -> None:
    # was: --help said "the new tool's nominal point" only; the old tool's was to be dug out of the YAML
    from dataclasses import replace

    from spherecal.correction import save_robot

    assert main(["tool", "--help"]) == 0
    assert "calibration.nominal_tool in CAL.yaml" in " ".join(capsys.readouterr().out.split())
    ball = panda.tool + [0.0, 0.0, 0.135]
    cal = save_robot(replace(panda, tool=ball + [2e-4, -2e-4, 1.6e-3],
                             extras={**panda.extras, "calibration": {"nominal_tool": ball.tolist()}}),
                     tmp_path / "cal.yaml")
    assert main(["tool", str(cal), "--offset", *map(str, ball + [0.0, 0.0, 0.1]), "--out",
                 str(tmp_path / "new.yaml")]) == 0
    printed = capsys.readouterr().out
    assert (f"nominal tool points [m] in the last frame: the calibration's {ball.round(6).tolist()} "
            f"(calibration.nominal_tool), the new tool's {(ball + [0.0, 0.0, 0.1]).round(6).tolist()}") in printed


def test_the_guides_tool_swap_snippet_prints_a_few_short_lines(panda, tmp_path, capsys, monkeypatch) -> None:
    # was: `swap.model, ...` as the snippet's last line: a RobotModel repr of tens of thousands of characters
    import re
    from dataclasses import replace

    from spherecal.correction import save_robot

    guide = (Path(__file__).resolve().parents[2] / "docs" / "guide.md").read_text()
    snippet = next(b for b in re.findall(r"```python\n(.*?)```", guide, re.S) if "with_tool(cal" in b)
    save_robot(replace(panda, extras={**panda.extras, "calibration": {"nominal_tool": panda.tool.tolist()}}),
               tmp_path / "cal.yaml")
    monkeypatch.chdir(tmp_path)
    exec(snippet, {})  # noqa: S102 - our own documentation
    printed = capsys.readouterr().out
    assert "0.2104" in printed and "from the calibrated tool point" in printed and len(printed) < 1000


def test_an_offset_typed_in_millimetres_is_refused_naming_the_option(tmp_path, capsys) -> None:
    """A review: '--offset 0 0 103.4' (a 103.4 mm tool typed in millimetres) was refused without naming the option
    or saying why the value looks wrong. The bound is the arm's own length (a tool beyond it is no real tool, and
    stricter than a fixed few metres on a small arm); within it a tool is put as given."""
    from tests.refusal import refused

    cal = spherecal.correction.save_robot(load_robot("panda"), tmp_path / "cal.yaml")
    length = load_robot("panda").chain_length
    refused(["tool", cal, "--offset", "0", "0", "103.4", "--out", tmp_path / "new.yaml"], tmp_path, capsys,
            "field '--offset': ", "103.4 m from the last frame", "(millimetres? the offset is in m)")
    refused(["tool", cal, "--offset", 0, length * 0.8, length * 0.8, "--out", tmp_path / "new.yaml"], tmp_path,
            capsys, "field '--offset': ", f"{np.hypot(length * 0.8, length * 0.8):.4g} m from the last frame")
    assert main(["tool", str(cal), "--offset", "0", "0", str(length * 0.99), "--out", str(tmp_path / "new.yaml")]) == 0
    with pytest.raises(ToolError, match=r"^field 'tool': .* more than the arm itself"):
        with_tool(load_robot("panda"), [0.0, 0.0, 103.4])


@pytest.mark.parametrize("recorded", ["abc", [0.0, 0.0], [0.0, 0.0, float("nan")]])
def test_a_calibrated_file_with_a_bad_nominal_tool_names_the_file_and_field(recorded, tmp_path, capsys) -> None:
    # a hand-edited 'nominal_tool: abc' was a ValueError traceback; '[0, 0]' said 'nominal_tool: expected ...'
    from dataclasses import replace

    from tests.refusal import refused

    panda = load_robot("panda")
    cal = spherecal.correction.save_robot(
        replace(panda, extras={**panda.extras, "calibration": {"nominal_tool": recorded}}), tmp_path / "cal.yaml")
    refused(["tool", cal, "--offset", "0", "0", "0.2", "--out", tmp_path / "new.yaml"], tmp_path, capsys,
            f"{cal}: field 'calibration.nominal_tool': expected 3 finite coordinates [m]")


def test_the_refusal_of_another_tool_prints_both_tools_without_float_noise(panda, rng) -> None:
    # the message printed the tools rounded to 6 digits (a -0.0 from a component of -1e-13) beside a remedy at 9
    noisy = panda.tool + [-1e-13, 0.0, 0.0]
    ball = noisy + [0.0, 0.0, 0.04]
    cal = perturb(replace(panda, tool=ball), rng)
    cal = replace(cal, extras={**cal.extras, "calibration": {"nominal_tool": ball.tolist()}})
    q_now = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    with pytest.raises(ModelMismatchError) as error:
        corrected_ik(cal, tool_point(panda, q_now), q_now, nominal=replace(panda, tool=noisy))
    text = str(error.value)
    assert "-0.0" not in text and "e-1" not in text
    assert f"calibrates the tool at {(np.round(ball, 9) + 0.0).tolist()} m" in text
    assert f"the controller model's {(np.round(noisy, 9) + 0.0).tolist()} m" in text


@pytest.mark.parametrize(("urdf", "tip", "link", "joint"), [
    ("panda.urdf", "ball_link", "panda_link7", "panda_joint7"),
    ("iiwa14.urdf", "ball_link", "link_7", "joint_a7"),
])
def test_tool_names_the_link_its_last_frame_is_fixed_to(urdf, tip, link, joint, tmp_path, capsys, rng) -> None:
    """A review: --offset is a point in the last DH frame, and neither --help nor the output said which link of a URDF
    arm that frame is. The output names it; MuJoCo's pose of that link, compiled from the URDF itself, stays at one
    pose in the last DH frame over random postures (the frame is fixed to it), and no other link of the chain does."""
    from spherecal.commands.tool import last_frame
    from spherecal.correction import save_robot
    from spherecal.correction.chain import link_frames

    model = load_urdf(DATA / urdf, tip_link=tip)
    cal = save_robot(model, tmp_path / "cal.yaml")
    assert main(["tool", str(cal), "--offset", "0", "0", "0.2", "--out", str(tmp_path / "new.yaml")]) == 0
    said = f"the last DH frame (frame {model.n_joints}), fixed to link {link}, the child of the last revolute joint "
    assert f"spherecal tool: the last frame: {said}{joint}:" in capsys.readouterr().out
    q = model.random_configurations(20, rng)
    frames = link_frames(model, q)[:, -1]
    mujoco = MujocoUrdf((DATA / urdf).read_text())
    for name in model.extras["urdf"]["links"]:
        points, rotations = mujoco.body_pose(name, model.extras["joint_names"], q)
        relative = np.einsum("kji,kj->ki", frames[:, :3, :3], points - frames[:, :3, 3])  # the link's origin in it
        fixed = np.ptp(relative, axis=0).max() < 1e-9 and np.ptp(
            np.einsum("kji,kjl->kil", frames[:, :3, :3], rotations), axis=0).max() < 1e-9
        assert fixed == (name == link), name
    assert main(["tool", "--help"]) == 0
    assert "fixed to the child link of the last revolute joint" in " ".join(capsys.readouterr().out.split())
    assert last_frame(load_robot("panda")) == "the last DH frame (frame 7 of the robot file; it records no URDF link)"
