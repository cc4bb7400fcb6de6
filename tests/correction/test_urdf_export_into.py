"""URDF out into the user's own file: MuJoCo compiles the written URDF and sees the calibration."""

from __future__ import annotations

import difflib
import hashlib
import re
import warnings
import xml.etree.ElementTree as ET
from dataclasses import replace

import numpy as np
import pytest

from spherecal.cli import main
from spherecal.correction import convert, perturb, save_robot, tool_point
from spherecal.correction.files.urdf_into import urdf_into
from spherecal.correction.files.urdf_read import parse_urdf
from spherecal.correction.files.urdf_to_dh import NearlyParallelAxesWarning, urdf_model
from spherecal.correction.files.urdf_write import ExportError, robot_to_urdf
from tests.correction.ur5e_urdf import ur5e_urdf
from tests.correction.urdf_helpers import DATA, MujocoUrdf

ROBOTS = {"panda": "ball_link", "iiwa14": None, "gen3lite": "ball_link", "ur5e": None}


def _text(robot: str) -> str:
    return ur5e_urdf(skew=2e-5) if robot == "ur5e" else (DATA / f"{robot}.urdf").read_text()


def _calibrated(robot: str, convention: str, rng):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearlyParallelAxesWarning)
        nominal = urdf_model(parse_urdf(_text(robot), robot), tip_link=ROBOTS[robot], convention=convention)
    return nominal, perturb(nominal, rng, 1e-3, np.deg2rad(0.2), 1e-3, base=True)


def _changed_joints(original: str, written: str) -> set[str]:
    before, after = ET.fromstring(original), ET.fromstring(written)
    changed = set()
    old, new = list(before.iter()), list(after.iter())
    assert [e.tag for e in old] == [e.tag for e in new]
    parents = {child: parent for parent in after.iter() for child in parent}
    for a, b in zip(old, new, strict=True):
        if a.attrib != b.attrib or (a.text or "").strip() != (b.text or "").strip():
            assert b.tag == "origin" and parents[b].tag == "joint", (a.tag, a.attrib, b.attrib)
            changed.add(parents[b].get("name"))
    return changed


@pytest.mark.parametrize("convention", ["modified", "standard"])
@pytest.mark.parametrize("robot", list(ROBOTS))
def test_written_urdf_is_the_calibrated_model_for_mujoco(robot, convention, rng):
    nominal, calibrated = _calibrated(robot, convention, rng)
    original = _text(robot)
    written = urdf_into(calibrated, original, robot)
    q = calibrated.random_configurations(250, rng)
    names, tip = calibrated.extras["joint_names"], calibrated.extras["urdf"]["tip_link"]
    points, _ = MujocoUrdf(written).body_pose(tip, names, q)
    error = np.linalg.norm(points - tool_point(calibrated, q), axis=1)
    assert error.max() < 1e-12, error.max()
    before, _ = MujocoUrdf(original).body_pose(tip, names, q)
    assert np.linalg.norm(before - tool_point(calibrated, q), axis=1).mean() > 1e-3  # it did change
    # Only the origins of the chain's revolute joints and of the fixed joint into the tip differ.
    path = parse_urdf(original).path(calibrated.extras["urdf"]["base_link"], tip)
    allowed = {j.name for j in path if j.type != "fixed"} | {path[-1].name}
    assert _changed_joints(original, written) <= allowed
    lines = difflib.ndiff(original.splitlines(), written.splitlines())
    for line in lines:
        if line.startswith(("- ", "+ ")) and "<origin" not in line:
            assert line.startswith("+ ") and ("spherecal" in line or "<!--" in line or "calibration" in line
                                              or "-->" in line or line.strip() in ("+",)), line


def test_everything_but_origins_is_kept_byte_for_byte(rng):
    _, calibrated = _calibrated("panda", "modified", rng)
    original = _text("panda")
    written = urdf_into(calibrated, original, "panda.urdf")
    assert "../meshes/panda/link0.dae" in written and "<safety_controller" in written
    assert '<!--origin rpy="0 0 0" xyz="0 0 0.1034"/-->' in _text("iiwa14")
    iiwa_nominal, iiwa = _calibrated("iiwa14", "modified", rng)
    kept = urdf_into(iiwa, _text("iiwa14"), "iiwa14.urdf")
    assert '<!--origin rpy="0 0 0" xyz="0 0 0.1034"/-->' in kept  # a commented-out origin is not an origin
    # Finger joints, limits, masses: identical elements.
    assert _changed_joints(original, written) == {f"panda_joint{i}" for i in range(1, 8)} | {"ball_joint"}


def test_refuses_another_chain(rng):
    _, panda = _calibrated("panda", "modified", rng)
    _, ur5e = _calibrated("ur5e", "modified", rng)
    with pytest.raises(ExportError, match="7 revolute joints, the calibrated model 6"):
        urdf_into(replace(ur5e, extras={}), _text("panda"), "panda.urdf")
    renamed = _text("panda").replace('"panda_joint3"', '"arm_joint3"')
    with pytest.raises(ExportError, match="joint names"):
        urdf_into(panda, renamed, "renamed.urdf")
    bigger = ur5e_urdf().replace("-0.425 0 0", "-0.725 0 0")
    with pytest.raises(ExportError, match="not the calibrated robot"):
        urdf_into(ur5e, bigger, "bigger.urdf")


def test_bare_panda_urdf_uses_franka_names_and_flange(panda, rng):
    q = panda.random_configurations(100, rng)
    ours, _ = MujocoUrdf(robot_to_urdf(panda)).body_pose("panda_link8", [f"panda_joint{i}" for i in range(1, 8)], q)
    franka, _ = MujocoUrdf(_text("panda")).body_pose("panda_link8", [f"panda_joint{i}" for i in range(1, 8)], q)
    assert np.abs(ours - franka).max() < 1e-12


def test_export_cli_into(tmp_path, rng, capsys):
    _, calibrated = _calibrated("gen3lite", "standard", rng)
    cal, into, out = tmp_path / "cal.yaml", tmp_path / "kinova.urdf", tmp_path / "calibrated.urdf"
    save_robot(calibrated, cal)
    into.write_text(_text("gen3lite"))
    args = ["export", str(cal), "--format", "urdf", "--into", str(into), "--out", str(out)]
    assert main(args) == 0
    q = calibrated.random_configurations(200, rng)
    points, _ = MujocoUrdf(out.read_text()).body_pose("ball_link", calibrated.extras["joint_names"], q)
    assert np.abs(points - tool_point(calibrated, q)).max() < 1e-12
    assert into.read_text() == _text("gen3lite")
    # the header names the URDF written into with its SHA-256, as it names the calibrated file (a review: only the
    # calibrated file was recorded)
    digest = hashlib.sha256(into.read_bytes()).hexdigest()
    assert f"into={into} (sha256 {digest})" in out.read_text()
    # --out naming the --into file (also through a symbolic link) is refused, nothing written.
    link = tmp_path / "link.urdf"
    link.symlink_to(into)
    for target in (into, link):
        assert main(["export", str(cal), "--format", "urdf", "--into", str(into), "--out", str(target)]) == 1
        assert "is the --into file" in capsys.readouterr().err
    assert into.read_text() == _text("gen3lite")
    # Another arm: one line, nothing written.
    other = tmp_path / "other.urdf"
    assert main(["export", str(cal), "--format", "urdf", "--into", str(DATA / "panda.urdf"), "--out", str(other)]) == 1
    error = capsys.readouterr().err
    assert error.count("\n") == 1 and "spherecal export: error:" in error and not other.exists()


def test_export_into_says_the_other_tool_links_keep_their_nominal_offsets(tmp_path, rng, capsys):
    # a review: the TCP of `spherecal tool --urdf ... --tip-link tool0` and tool0 of the `export --into` URDF were
    # 0.75 mm apart on an iiwa14 (1.6 mm on a Gen3 lite), neither output saying so: tool carries the calibration's
    # tool correction to the new tool, --into writes it on the ball's joint alone
    nominal, calibrated = _calibrated("gen3lite", "standard", rng)
    block = {"nominal_tool": nominal.tool.tolist()}
    cal, into, out = tmp_path / "cal.yaml", tmp_path / "kinova.urdf", tmp_path / "calibrated.urdf"
    save_robot(replace(calibrated, extras={**calibrated.extras, "calibration": block}), cal)
    into.write_text(_text("gen3lite"))
    assert main(["export", str(cal), "--format", "urdf", "--into", str(into), "--out", str(out)]) == 0
    shift = ", ".join(f"{v * 1e3:+.3f}" for v in calibrated.tool - nominal.tool)
    printed = " ".join(capsys.readouterr().out.split())
    assert f"the calibrated tool point moved ({shift}) mm in the last frame" in printed, printed
    assert "keep their nominal offsets" in printed
    save_robot(calibrated, cal)  # no record of the tool it started from: nothing to say
    assert main(["export", str(cal), "--format", "urdf", "--into", str(into), "--out", str(tmp_path / "b.urdf")]) == 0
    assert "tool point moved" not in capsys.readouterr().out


def test_model_in_other_convention_of_same_arm(rng):
    nominal, calibrated = _calibrated("ur5e", "modified", rng)
    standard = convert(calibrated, "standard")
    written = urdf_into(standard, _text("ur5e"), "ur5e")
    q = calibrated.random_configurations(50, rng)
    points, _ = MujocoUrdf(written).body_pose("ball", calibrated.extras["joint_names"], q)
    assert np.abs(points - tool_point(calibrated, q)).max() < 1e-12


def test_a_model_without_its_tip_link_goes_to_the_chain_end_at_its_tool_point(rng):
    """A robot file (no URDF links recorded) into a URDF whose chain ends in fingers, a tool frame and the
    ball: the end whose tool point is the model's is written (before: the longest chain, a finger, refused)."""
    nominal, calibrated = _calibrated("gen3lite", "modified", rng)
    bare = replace(calibrated, extras={"joint_names": calibrated.extras["joint_names"]})
    original = _text("gen3lite")
    written = urdf_into(bare, original, "gen3lite.urdf")
    q = calibrated.random_configurations(250, rng)
    points, _ = MujocoUrdf(written).body_pose("ball_link", calibrated.extras["joint_names"], q)
    assert np.linalg.norm(points - tool_point(calibrated, q), axis=1).max() < 1e-12
    assert "ball_joint" in _changed_joints(original, written)
    # the tool point 120 mm past the ball matches no end within 50 mm: the refusal lists them
    from spherecal.correction import RobotFileError

    far = replace(bare, tool=bare.tool + np.array([0.0, 0.0, 0.12]))
    with pytest.raises(RobotFileError, match="4 links at different points") as error:
        urdf_into(far, original, "gen3lite.urdf")
    assert "ball_link (180 mm from end_effector_link)" in str(error.value)


def test_export_into_a_latin1_urdf_writes_latin1(tmp_path, rng):
    """--into a URDF declaring ISO-8859-1 (a comment with accents) was refused as 'not UTF-8 text'; it is read in
    its encoding and the calibrated copy is written in it too: the declaration still tells the truth."""
    _, calibrated = _calibrated("gen3lite", "standard", rng)
    cal, into, out = tmp_path / "cal.yaml", tmp_path / "kinova.urdf", tmp_path / "calibrated.urdf"
    save_robot(calibrated, cal)
    original = _text("gen3lite").replace('<?xml version="1.0" ?>', '<?xml version="1.0" encoding="ISO-8859-1"?>\n'
                                         "<!-- bras étalonné: épaule, coude -->", 1)
    assert "ISO-8859-1" in original
    into.write_bytes(original.encode("latin-1"))
    assert main(["export", str(cal), "--format", "urdf", "--into", str(into), "--out", str(out)]) == 0
    data = out.read_bytes()
    assert b"\xe9talonn\xe9" in data  # Latin-1 bytes, as declared
    written = data.decode("latin-1")
    assert written.startswith('<?xml version="1.0" encoding="ISO-8859-1"?>')
    q = calibrated.random_configurations(200, rng)
    points, _ = MujocoUrdf(written).body_pose("ball_link", calibrated.extras["joint_names"], q)
    assert np.abs(points - tool_point(calibrated, q)).max() < 1e-12


def test_a_new_tool_goes_to_its_own_link_not_to_the_ball(rng):
    """`tool --urdf TOOL.urdf --tip-link panda_hand_tcp` then `export --into`: the calibrated file kept the ball as
    its tip link, and export wrote the new tool point into ball_joint (the ball link moved 30 mm to the TCP, the
    TCP link left at nominal, exit 0); a tool put by --offset (no link there) was 'not the calibrated robot'."""
    from spherecal.correction.files.tools import put_tool

    nominal, calibrated = _calibrated("panda", "modified", rng)
    swap, _ = put_tool(calibrated, urdf=DATA / "panda.urdf", tip_link="panda_hand_tcp")
    original = _text("panda")
    written = urdf_into(swap.model, original, "panda.urdf")
    changed = _changed_joints(original, written)
    assert "panda_hand_tcp_joint" in changed and "ball_joint" not in changed
    q = calibrated.random_configurations(100, rng)
    points, _ = MujocoUrdf(written).body_pose("panda_hand_tcp", calibrated.extras["joint_names"], q)
    assert np.linalg.norm(points - tool_point(swap.model, q), axis=1).max() < 1e-12
    offset, _ = put_tool(calibrated, offset=calibrated.tool + [0.0, 0.0, -0.09])
    with pytest.raises(ExportError, match="field 'tip_link': the calibrated file carries a new tool .* no link of "
                                          "this URDF is at it .*spherecal tool --urdf"):
        urdf_into(offset.model, original, "panda.urdf")


def _cut_after_flange(text: str) -> str:
    """panda.urdf without the hand, its TCP, the ball and the fingers: a URDF that ends at the flange."""
    import re

    for name in ("panda_hand_joint", "panda_hand_tcp_joint", "ball_joint", "panda_finger_joint1",
                 "panda_finger_joint2"):
        text = re.sub(rf'<joint name="{name}".*?</joint>', "", text, flags=re.S)
    for name in ("panda_hand", "panda_hand_tcp", "ball_link", "panda_leftfinger", "panda_rightfinger"):
        text = re.sub(rf'<link name="{name}"\s*/>', "", text)
        text = re.sub(rf'<link name="{name}">.*?</link>', "", text, flags=re.S)
    return text


def test_a_calibration_whose_ball_lies_beyond_its_tip_link_is_written_at_the_ball(rng):
    """Calibrated with a URDF that ends at the flange (the ball 137 mm further out, found by the samples:
    identification.tool_fit), then `export --into` that URDF or the whole panda.urdf: both were refused 'not the
    calibrated robot: tool points 157 mm apart', the same arm compared with two tools."""
    from spherecal.correction.tool import with_tool_of

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearlyParallelAxesWarning)
        flange = urdf_model(parse_urdf(_text("panda"), "panda"), tip_link="panda_link8")
        ball = urdf_model(parse_urdf(_text("panda"), "panda"), tip_link="ball_link")
    calibrated = perturb(flange, rng, 1e-3, np.deg2rad(0.2), 1e-3)
    params = calibrated.params.copy()
    params[calibrated.layout.tool] = ball.tool + [0.004, -0.003, 0.006]  # where the samples put the ball
    calibrated = calibrated.with_params(params)
    record = {"nominal_tool": flange.tool.tolist()}  # what calibrate writes: the robot file's tool
    calibrated = replace(calibrated, extras={**calibrated.extras, "calibration": record})
    names, q = calibrated.extras["joint_names"], calibrated.random_configurations(100, rng)
    with pytest.warns(UserWarning, match="the calibration's tool point is 1.. mm from 'panda_link8', the tip link "
                                         "it was calibrated with, and at 'ball_link' of this URDF: written at "
                                         "'ball_link'"):
        written = urdf_into(calibrated, _text("panda"), "panda.urdf")
    points, _ = MujocoUrdf(written).body_pose("ball_link", names, q)
    assert np.abs(points - tool_point(calibrated, q)).max() < 1e-12
    points, _ = MujocoUrdf(written).body_pose("panda_link8", names, q)  # the flange where the URDF has it
    assert np.abs(points - tool_point(with_tool_of(calibrated, flange), q)).max() < 1e-12
    with pytest.warns(UserWarning, match="'panda_link8' written at the calibrated tool point, 1.. mm from its place "
                                         "in this URDF .*'panda_link8' of the written file is the ball"):
        written = urdf_into(calibrated, _cut_after_flange(_text("panda")), "flange.urdf")
    points, _ = MujocoUrdf(written).body_pose("panda_link8", names, q)
    assert np.abs(points - tool_point(calibrated, q)).max() < 1e-12
    stranger = replace(calibrated, extras={k: v for k, v in calibrated.extras.items() if k != "calibration"})
    with pytest.raises(ExportError, match="not the calibrated robot"):  # no record of the tip: another robot
        urdf_into(stranger, _cut_after_flange(_text("panda")), "flange.urdf")


def test_a_calibration_of_another_description_of_the_arm_goes_to_the_chain_end_at_its_tool(rng):
    """A calibration of the embedded iiwa14 (links 'base' -> 'iiwa_link_ee_kuka', joints iiwa_joint_*) exported into
    MUKCa's iiwa14.urdf (joint_a*, ending at ball_link) was refused "tip link 'iiwa_link_ee_kuka' is not a link of
    robot 'iiwa14'"; the joints are matched by geometry, the tool goes to the one chain end at it."""
    nominal, calibrated = _calibrated("panda", "modified", rng)
    names = [f"arm_joint{i}" for i in range(1, 8)]
    other = replace(calibrated, extras={**calibrated.extras, "joint_names": names,
                                        "urdf": {"base_link": "world", "tip_link": "tool_ee"}})
    with pytest.warns(UserWarning, match="the calibrated file's chain 'world' -> 'tool_ee' is another description's "
                                         r"\(not in this URDF\): written into its chain to 'ball_link'"):
        written = urdf_into(other, _text("panda"), "panda.urdf")
    q = calibrated.random_configurations(100, rng)
    points, _ = MujocoUrdf(written).body_pose("ball_link", calibrated.extras["joint_names"], q)
    assert np.abs(points - tool_point(calibrated, q)).max() < 1e-12
    with pytest.raises(ExportError, match="field 'tip_link': the calibrated file's chain 'world' -> 'tool_ee' is not "
                                          "in this URDF .* none of its chain's ends is at the calibrated tool point"):
        urdf_into(other, _cut_after_flange(_text("panda")), "flange.urdf")


def test_a_joint_zero_moved_by_degrees_is_still_this_arm(rng):
    """A calibration moves a joint's zero by degrees (real Gen3 lites: 1-3 deg; dinova_2's -3 deg put its tool points
    51 mm from the URDF's, past the 50 mm that tells another robot, and export --into refused its own arm): the arms
    are compared with the URDF's zeros, the written URDF carries the calibrated zero, and another robot (a link 0.3 m
    longer) is still refused."""
    nominal, calibrated = _calibrated("gen3lite", "modified", rng)
    params = calibrated.params.copy()
    params[calibrated.param_index("theta2")] += np.deg2rad(6.0)
    moved = calibrated.with_params(params)
    written = urdf_into(moved, _text("gen3lite"), "gen3lite.urdf")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearlyParallelAxesWarning)
        back = urdf_model(parse_urdf(written, "written"), tip_link="ball_link", convention="modified")
    q = moved.random_configurations(50, rng)
    assert np.abs(tool_point(back, q) - tool_point(moved, q)).max() < 1e-6
    bigger = ur5e_urdf().replace("-0.425 0 0", "-0.725 0 0")
    _, ur5e = _calibrated("ur5e", "modified", rng)
    params = ur5e.params.copy()
    params[ur5e.param_index("theta2")] += np.deg2rad(6.0)
    with pytest.raises(ExportError, match="not the calibrated robot"):
        urdf_into(ur5e.with_params(params), bigger, "bigger.urdf")


@pytest.mark.parametrize("extra", ["compliance", "scale"])
def test_a_joint_zero_degrees_off_is_written_into_its_urdf_whatever_terms_the_file_carries(extra, rng):
    """A real Gen3 lite's theta2 sits 3-4 deg from its URDF's; the arms are compared with the URDF's zeros, so
    it is written into its URDF. A file carrying a compliance or scale block (all 0: nothing identified) was compared
    without them and refused, 52 mm apart, where the same geometry as a dh file was written (a review)."""
    nominal, calibrated = _calibrated("gen3lite", "modified", rng)
    params = calibrated.params.copy()
    params[calibrated.param_index("theta2")] += np.deg2rad(-4.0)  # compared without the zeros: past SAME_ROBOT_TOL
    calibrated = calibrated.with_params(params)
    original = _text("gen3lite")
    plain = urdf_into(calibrated, original, "gen3lite")
    zeros = [0.0] * calibrated.n_joints
    carrying = replace(calibrated, extras={**calibrated.extras, extra: zeros})
    assert carrying.n_params == calibrated.n_params + calibrated.n_joints  # c1..cn or s1..sn beside the geometry
    assert urdf_into(carrying, original, "gen3lite") == plain


@pytest.mark.parametrize("block", [None, {"method": "lm", "self_check": {"note": "x" * 20000}}])
def test_exporting_into_an_exported_urdf_does_not_grow_it(block, tmp_path, rng, capsys):
    """A review: each `export --into` of the last result added its two comments again (the calibration's provenance
    block, tens of kB): an iiwa14 URDF of 5 kB became 55, 104, 153 kB. An export into a file an export wrote replaces
    the earlier comments (and says so); the user's own comments stay."""
    nominal, calibrated = _calibrated("iiwa14", "modified", rng)
    held = [calibrated.param_names.index(name) for name in ("d7", "theta7")]  # as a calibration holds them (they
    params = calibrated.params.copy()  # are redundant with the tool point); else each export moves link 7 further
    params[held] = nominal.params[held]
    calibrated = calibrated.with_params(params)
    if block is not None:
        calibrated = replace(calibrated, extras={**calibrated.extras, "calibration": block})
    cal = tmp_path / "cal.yaml"
    save_robot(calibrated, cal)
    files = [tmp_path / "user.urdf", tmp_path / "a.urdf", tmp_path / "b.urdf", tmp_path / "c.urdf"]
    files[0].write_text(_text("iiwa14"))
    for into, out in zip(files, files[1:], strict=False):
        assert main(["export", str(cal), "--format", "urdf", "--into", str(into), "--out", str(out)]) == 0
    capsys.readouterr()
    first, *again = [f.read_text() for f in files[1:]]
    for text in again:
        assert text.count("written by spherecal") == 1 and text.count("<!--") == first.count("<!--")
        assert "the comments of the earlier spherecal export" in text
        assert abs(len(text) - len(first)) < 200  # the file names and that line, not another block
        assert text.startswith(_text("iiwa14")[:_text("iiwa14").find("-->")])  # the user's comment, first and kept
    origins = [[line for line in text.splitlines() if "<origin" in line] for text in (first, again[-1])]
    for before, after in zip(*origins, strict=True):  # the same origins, to rounding
        numbers = [np.array(re.findall(r"-?[0-9.]+(?:e[-+]?[0-9]+)?", line), dtype=float) for line in (before, after)]
        np.testing.assert_allclose(*numbers, atol=1e-12)
    assert "the comments of the earlier" not in first  # a user's file: nothing replaced
    assert first.count("<!--") == _text("iiwa14").count("<!--") + 2


def test_a_tip_link_millimetres_from_the_end_where_the_ball_sat_is_named_in_a_warning(rng):
    """A review: tip links less than 10 mm apart were accepted without a word. Calibrated with --tip-link ball_link
    while the ball sat on a probe link 6 mm from it, the export moved ball_link 6 mm onto the probe silently (the
    same mistake 10 mm further away is found and written at the probe: test above). Now the probe is named, the
    export written as before; a calibration whose ball was at its tip link gets no warning."""
    probe = ('  <joint name="probe_joint" type="fixed">\n    <parent link="link_7"/>\n    <child link="probe"/>\n'
             '    <origin xyz="0 0.006 0.166" rpy="0 0 0"/>\n  </joint>\n  <link name="probe"/>\n</robot>')
    text = _text("iiwa14").replace("</robot>", probe)
    nominal, calibrated = _calibrated("iiwa14", "modified", rng)
    record = {"calibration": {"nominal_tool": nominal.tool.tolist()}}
    correction = np.array([0.3, -0.2, 0.4]) * 1e-3  # what a calibration moves a tool point by
    at_probe = replace(calibrated, tool=nominal.tool + [0.0, 0.006, 0.0] + correction,
                       extras={**calibrated.extras, **record})
    moved, gap = np.linalg.norm([0.0, 0.006, 0.0] + correction), np.linalg.norm(correction)  # 5.8 mm, 0.5 mm
    expected = (rf"the calibration's tool point is {moved * 1e3:.1f} mm from 'ball_link', the tip link it was "
                rf"calibrated with, and {gap * 1e3:.1f} mm from 'probe', another end of this URDF: written at "
                r"'ball_link' .* calibrate again with --tip-link probe")
    with pytest.warns(UserWarning, match=expected):
        written = urdf_into(at_probe, text, "iiwa14.urdf")
    assert _changed_joints(text, written) >= {"ball_joint"} and "probe_joint" not in _changed_joints(text, written)
    at_ball = replace(at_probe, tool=nominal.tool + correction)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        urdf_into(at_ball, text, "iiwa14.urdf")
