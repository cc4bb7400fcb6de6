"""URDF in: MuJoCo's URDF compiler is the independent evaluator of our DH conversion."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

from spherecal.correction import load_robot, to_modified, to_standard, tool_point
from spherecal.correction.files.urdf_read import parse_urdf
from spherecal.correction.files.urdf_to_dh import NearlyParallelAxesWarning, load_urdf, urdf_model
from tests.correction.ur5e_urdf import NAMES, ur5e_urdf
from tests.correction.urdf_helpers import DATA, MujocoUrdf

ROBOTS = {  # file or inline text, tip link
    "panda": ("panda.urdf", "ball_link"),
    "panda_flange": ("panda.urdf", "panda_link8"),
    "iiwa14": ("iiwa14.urdf", None),
    "gen3lite": ("gen3lite.urdf", "ball_link"),
    "ur5e": (None, None),
    "ur5e_skewed": (None, None),
    # 3 mrad: beyond PARALLEL_TOL, but the common normal is ~100 m away (a calibrated arm exported to URDF)
    "ur5e_skewed_3mrad": (None, None),
}
SKEW = {"ur5e_skewed": 2e-5, "ur5e_skewed_3mrad": 3e-3}


def _text(robot: str) -> str:
    file, _ = ROBOTS[robot]
    if file is None:
        return ur5e_urdf(skew=SKEW.get(robot, 0.0))
    return (DATA / file).read_text()


def _model(robot: str, convention: str):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NearlyParallelAxesWarning)
        return urdf_model(parse_urdf(_text(robot), robot), tip_link=ROBOTS[robot][1], convention=convention)


@pytest.mark.parametrize("convention", ["modified", "standard"])
@pytest.mark.parametrize("robot", list(ROBOTS))
def test_tool_point_equals_mujoco_urdf_compiler(robot, convention, rng):
    model = _model(robot, convention)
    assert model.convention == convention
    q = model.random_configurations(250, rng)
    points, _ = MujocoUrdf(_text(robot)).body_pose(model.extras["urdf"]["tip_link"], model.extras["joint_names"], q)
    error = np.linalg.norm(points - tool_point(model, q), axis=1)
    assert error.max() < 1e-12, error.max()
    assert np.ptp(points, axis=0).min() > 0.1  # the arm really moved


@pytest.mark.parametrize("robot", list(ROBOTS))
def test_standard_modified_round_trip(robot, rng):
    modified, standard = _model(robot, "modified"), _model(robot, "standard")
    q = modified.random_configurations(200, rng)
    assert np.abs(tool_point(to_standard(modified), q) - tool_point(modified, q)).max() < 1e-12
    assert np.abs(tool_point(to_modified(standard), q) - tool_point(modified, q)).max() < 1e-12
    back = to_modified(to_standard(modified))
    np.testing.assert_allclose(back.params[3 * 0 + 4 :], modified.params[4:], atol=1e-12)


def test_franka_urdf_gives_franka_dh():
    model = load_urdf(DATA / "panda.urdf", tip_link="panda_link8")
    panda = load_robot("panda")
    for name in ("a", "alpha", "d", "theta", "beta", "lower", "upper", "tool", "base_xyz", "base_rpy"):
        np.testing.assert_allclose(getattr(model, name), getattr(panda, name), atol=1e-15, err_msg=name)
    assert model.extras["joint_names"] == [f"panda_joint{i}" for i in range(1, 8)]
    assert model.extras["urdf"]["links"] == [f"panda_link{i}" for i in range(1, 8)]


def test_parallel_axes_get_beta_only_when_skewed():
    exact, skewed = _model("ur5e", "modified"), _model("ur5e_skewed", "modified")
    assert exact.extras["urdf"]["parallel_joints"] == list(NAMES[2:4])
    assert skewed.extras["urdf"]["parallel_joints"] == list(NAMES[2:4])
    assert np.abs(exact.beta).max() < 1e-15
    # The elbow tilt is about the link's x (into alpha), the wrist-1 tilt about y (Hayati's beta).
    assert abs(skewed.beta[2]) < 1e-15 and abs(np.sin(skewed.alpha[2])) == pytest.approx(2e-5, rel=1e-6)
    assert abs(skewed.beta[3]) == pytest.approx(2e-5, rel=1e-6)
    # d of the joint before each parallel pair is held at zero, and no d blows up.
    assert skewed.d[1] == 0.0 and skewed.d[2] == 0.0
    assert np.abs(skewed.d).max() < 0.2 and np.abs(skewed.a).max() < 0.5
    with pytest.warns(NearlyParallelAxesWarning, match="elbow_joint"):
        urdf_model(parse_urdf(_text("ur5e_skewed"), "ur5e"))
    gen3 = _model("gen3lite", "modified")
    assert gen3.extras["urdf"]["parallel_joints"] == ["joint_3"]
    assert 1e-6 < abs(gen3.beta[2]) < 1e-4 and np.abs(gen3.d).max() < 0.3  # 1.5708 and 3.1416 in the file


def test_axes_whose_common_normal_is_far_get_beta():
    """3 mrad between axes 0.4 m apart: plain DH would put wrist 1's common normal ~130 m away (a d no
    robot file accepts); the far normal counts as parallel, so the joint gets a Hayati beta and stays short
    (the elbow's tilt about the offset's own direction leaves its normal at the foot: plain DH, exact)."""
    model = _model("ur5e_skewed_3mrad", "modified")
    assert model.extras["urdf"]["parallel_joints"] == [NAMES[3]]
    assert abs(model.beta[3]) == pytest.approx(3e-3, rel=1e-6)
    assert np.abs(model.d).max() < 0.2 and np.abs(model.a).max() < 0.5


def test_inertials_lumped_per_joint_match_mujoco_centre_of_mass(rng):
    import mujoco

    model = _model("gen3lite", "modified")
    inertials, payload = model.extras["inertials"], model.extras["payload"]
    assert len(inertials) == model.n_joints
    tree = parse_urdf(_text("gen3lite"), "gen3lite")
    below = {link for link in tree.links if link not in ("world", "kinova_base_link")}
    total = sum(tree.inertials[k].mass for k in below if k in tree.inertials)
    assert sum(i["mass"] for i in inertials) + payload["mass"] == pytest.approx(total, abs=1e-12)
    assert payload["mass"] > 0.1  # the gripper
    # World centre of mass of everything moving, from our DH frames, against MuJoCo's subtree_com.
    from spherecal.correction import link_frames

    mj = MujocoUrdf(_text("gen3lite"), boundmass="0", boundinertia="0")  # MuJoCo's masses as written
    shoulder = mujoco.mj_name2id(mj.model, mujoco.mjtObj.mjOBJ_BODY, "shoulder_link")
    assert mj.model.body_mass[shoulder:].sum() == pytest.approx(total, abs=1e-12)
    for q in model.random_configurations(20, rng):
        frames = link_frames(model, q)[1:]
        moments = [i["mass"] * (f[:3, :3] @ i["com"] + f[:3, 3]) for i, f in zip(inertials, frames, strict=True)]
        moments.append(payload["mass"] * (frames[-1][:3, :3] @ payload["com"] + frames[-1][:3, 3]))
        mj.body_pose("shoulder_link", model.extras["joint_names"], q[None])
        mujoco.mj_comPos(mj.model, mj.data)
        # Each joint's lumped centre of mass against MuJoCo's per-body centres of mass.
        for i, name in enumerate(model.extras["urdf"]["links"][:-1]):
            body = mujoco.mj_name2id(mj.model, mujoco.mjtObj.mjOBJ_BODY, name)
            theirs = mj.data.xipos[body] * mj.model.body_mass[body]
            assert np.linalg.norm(moments[i] - theirs) < 1e-12, name
        assert np.linalg.norm(sum(moments) / total - mj.data.subtree_com[shoulder]) < 1e-12


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda t: t.replace('revolute"><parent link="upper_arm_link"', 'prismatic"><parent link="upper_arm_link"'),
         r"row \d+, field 'joint elbow_joint': a prismatic joint"),
        (lambda t: t.replace('<child link="flange"/>', '<child link="wrist_2_link"/>'),
         "link 'wrist_2_link' has two parents"),
        (lambda t: t.replace('<parent link="forearm_link"/>', '<parent link="forarm_link"/>'),
         "parent link 'forarm_link' is not defined"),
        (lambda t: t.replace('type="revolute"', 'type="sliding"', 1), "unknown type 'sliding'"),
        (lambda t: t.replace("<robot", "<robo").replace("</robot>", "</robo>"), "expected a <robot>"),
        (lambda t: t.replace("</robot>", ""), "invalid XML"),
        # a <limit> with effort and velocity only: URDF's lower = upper = 0 was 'joints[0].lower: must be below upper'
        (lambda t: re.sub(r'<limit lower="[^"]*" upper="[^"]*"', "<limit", t, count=1),
         r"row \d+, field 'joint shoulder_pan_joint <limit>': <limit> lower and upper are both 0 .missing from it."),
    ],
)
def test_bad_urdf_one_line_error(edit, match, tmp_path):
    from spherecal.correction import RobotFileError

    path = tmp_path / "arm.urdf"
    path.write_text(edit(ur5e_urdf()))
    with pytest.raises(RobotFileError, match=match) as error:
        load_urdf(path)
    assert str(path) in str(error.value) and "\n" not in str(error.value)


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"tip_link": "gripper"}, r"field '--tip-link': no link 'gripper' in robot '\w+' \(its ends: ball\)$"),
        ({"tip_link": "wrist_3"}, r"no link 'wrist_3' .* \(did you mean 'wrist_3_link'.*\? its ends: ball\)$"),
        ({"base_link": "bse"}, r"field '--base-link': no link 'bse' in robot '\w+' \(did you mean 'base_link'"),
        ({"base_link": "wrist_1_link", "tip_link": "shoulder_link"}, "'shoulder_link' is not below base link"),
        ({"base_link": "ball"}, "no revolute joint"),
    ],
)
def test_bad_links_one_line_error(options, match, tmp_path):
    from spherecal.correction import RobotFileError

    path = tmp_path / "arm.urdf"
    path.write_text(ur5e_urdf())
    with pytest.raises(RobotFileError, match=match):
        load_urdf(path, **options)


def test_base_link_and_default_tip(tmp_path):
    path = tmp_path / "arm.urdf"
    path.write_text(ur5e_urdf())
    full, sub = load_urdf(path), load_urdf(path, base_link="upper_arm_link")
    assert full.extras["urdf"]["tip_link"] == "ball" and full.n_joints == 6
    assert sub.n_joints == 4 and sub.extras["joint_names"] == list(NAMES[2:])


def _with_ends(text: str, *ends: tuple[str, str, str, str]) -> str:
    """``text`` with more links: (name, parent, joint type, xyz) each, fixed or prismatic."""
    extra = "".join(
        f'  <link name="{name}"/>\n  <joint name="{name}_joint" type="{kind}"><parent link="{parent}"/>'
        f'<child link="{name}"/><origin xyz="{xyz}" rpy="0 0 0"/><axis xyz="0 1 0"/>'
        '<limit lower="0" upper="0.04" effort="20" velocity="0.2"/></joint>\n'
        for name, parent, kind, xyz in ends)
    return text.replace("</robot>", extra + "</robot>")


def test_default_tip_is_the_one_end_of_the_chain_and_a_branching_tool_is_the_users_choice(tmp_path):
    from spherecal.correction import RobotFileError

    path = tmp_path / "arm.urdf"
    # a prismatic finger cannot be on the chain, a frame at the ball's centre is the same tool point
    path.write_text(_with_ends(ur5e_urdf(), ("finger", "tool0", "prismatic", "0 0.02 0.03"),
                               ("ball_frame", "tool0", "fixed", "0.001 -0.002 0.05")))
    assert load_urdf(path).extras["urdf"]["tip_link"] == "ball"
    # fingers on fixed joints beside the ball, deeper than it (the longest chain was a finger, 65 mm off the ball)
    path.write_text(_with_ends(ur5e_urdf(), ("finger_base", "tool0", "fixed", "0 0.03 0.02"),
                               ("finger_tip", "finger_base", "fixed", "0 0 0.03")))
    with pytest.raises(RobotFileError) as error:
        load_urdf(path)
    message = str(error.value)
    assert "\n" not in message and str(path) in message and "--tip-link" in message
    assert "ball (50 mm from wrist_3_link)" in message and "finger_tip (58 mm from wrist_3_link)" in message
    assert load_urdf(path, tip_link="ball").extras["urdf"]["tip_link"] == "ball"


def test_gen3lite_default_tip_lists_its_ball_fingers_and_tool_frame(tmp_path, capsys):
    from spherecal.correction import RobotFileError
    from tests.refusal import refused

    with pytest.raises(RobotFileError, match=r"4 links at different points: tool_frame \(130 mm.*ball_link \(180 mm"):
        load_urdf(DATA / "gen3lite.urdf")
    with pytest.raises(RobotFileError, match=r"for tool, the new tool's point"):  # not only the ball (a UR trial)
        load_urdf(DATA / "gen3lite.urdf")
    source = tmp_path / "left"
    source.mkdir()
    (source / "hole_0.csv").write_text("0.1,0.2,0.3,0.4,0.5,0.6\n")
    (source / "hole_1.csv").write_text("0.1,0.2,0.3,0.4,0.5,0.7\n")
    refused(["import", source, "--format", "mukca", "--robot", DATA / "gen3lite.urdf", "--out", tmp_path / "out"],
            tmp_path, capsys, "right_finger_dist_link (116 mm", "ball_link (180 mm", "--tip-link")


def _declared(text: str, encoding: str) -> str:
    """``text`` with an XML declaration naming ``encoding`` and a comment holding non-ASCII characters."""
    assert text.startswith('<?xml version="1.0"?>')
    return text.replace('<?xml version="1.0"?>', f'<?xml version="1.0" encoding="{encoding}"?>\n'
                        "<!-- épaule, coude, poignet: modèle cinématique -->", 1)


def test_a_urdf_is_read_in_the_encoding_it_declares(tmp_path):
    """A Latin-1 URDF declaring ISO-8859-1 was refused as 'not UTF-8 text': the XML standard reads it in the
    encoding its declaration names; only bytes that are not text in that encoding are refused."""
    from spherecal.correction import RobotFileError

    plain = tmp_path / "utf8.urdf"
    plain.write_text(ur5e_urdf(), encoding="utf-8")
    latin = tmp_path / "latin1.urdf"
    latin.write_bytes(_declared(ur5e_urdf(), "ISO-8859-1").encode("latin-1"))
    assert b"\xe9paule" in latin.read_bytes()  # one byte per character: not UTF-8
    reference, model = load_urdf(plain), load_urdf(latin)
    np.testing.assert_array_equal(model.params, reference.params)
    assert model.extras["joint_names"] == reference.extras["joint_names"]
    utf8 = tmp_path / "declared_utf8.urdf"  # the same characters in UTF-8, declared: the same arm
    utf8.write_bytes(_declared(ur5e_urdf(), "UTF-8").encode("utf-8"))
    np.testing.assert_array_equal(load_urdf(utf8).params, reference.params)
    for encoding, data, match in (
        ("US-ASCII", _declared(ur5e_urdf(), "US-ASCII").encode("latin-1"),
         r"not US-ASCII text \(byte \d+\), the encoding its XML declaration names"),
        ("UTF-8", _declared(ur5e_urdf(), "UTF-8").encode("latin-1"), r"not UTF-8 text \(byte \d+\)"),
        ("none", _declared(ur5e_urdf(), "UTF-8").replace(' encoding="UTF-8"', "").encode("latin-1"),
         r"not UTF-8 text \(byte \d+\)$"),
        ("unknown", _declared(ur5e_urdf(), "x-klingon").encode("latin-1"), "names an unknown encoding 'x-klingon'"),
    ):
        bad = tmp_path / f"{encoding}.urdf"
        bad.write_bytes(data)
        with pytest.raises(RobotFileError, match=match) as error:
            load_urdf(bad)
        assert str(bad) in str(error.value) and "\n" not in str(error.value)


#: A hand-written two-joint URDF: a comment, an element over two lines (the line numbers are the point).
HAND_WRITTEN = """\
<?xml version="1.0"?>
<!-- two joints, written by hand -->
<robot name="two">
  <link name="base"/>
  <link name="l1"/>
  <link name="l2"/>
  <joint name="j1" type="revolute">
    <parent link="base"/>
    <child link="l1"/>
    <origin xyz="0 0 0.333" rpy="0 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-2.9" upper="2.9" effort="87" velocity="2.1"/>
  </joint>
  <joint name="j2"
         type="revolute">
    <parent link="l1"/>
    <child link="l2"/>
    <origin xyz="0 0 0"
            rpy="-1.5707963267948966 0 0"/>
    <axis xyz="0 0 1"/>
    <limit lower="-1.76" upper="1.76" effort="87" velocity="2.1"/>
  </joint>
</robot>
"""


@pytest.mark.parametrize(("old", "new", "row", "field"), [
    ('rpy="-1.5707963267948966 0 0"', 'rpy="-90 deg 0"', 18, "joint j2 <origin rpy>"),  # the element's first line
    ('<parent link="l1"/>', '<parent link="l0"/>', 16, "joint j2 <parent>"),
    ('lower="-2.9"', 'lower="-166"', 12, "joint j1 <limit lower>"),
    ('type="revolute">\n    <parent link="l1"/>', 'type="sliding">\n    <parent link="l1"/>', 14, "joint j2"),
    ('<axis xyz="0 0 1"/>\n    <limit lower="-1.76"', '<axis xyz="0 0 0"/>\n    <limit lower="-1.76"', 20,
     "joint j2 <axis xyz>"),
    ('  <link name="l2"/>\n', '  <link name="l2"/>\n  <link name="l1"/>\n', 7, "link l1"),  # defined twice
    ("</robot>\n", "", 23, ""),  # invalid XML: the end of the file, where the parser stopped
])
def test_a_urdf_refusal_names_the_row_of_the_element(tmp_path, old, new, row, field) -> None:
    from spherecal.correction import RobotFileError

    assert HAND_WRITTEN.count(old) == 1
    path = tmp_path / "arm.urdf"
    path.write_text(HAND_WRITTEN.replace(old, new))
    with pytest.raises(RobotFileError) as error:
        load_urdf(path)
    assert str(error.value).startswith(f"{path}: row {row}, field '{field}': " if field else f"{path}: row {row}: ")
    assert parse_urdf(HAND_WRITTEN).joints["l2"].row == 14  # the file unedited is read, each joint at its line


def test_an_entity_bomb_in_a_urdf_is_refused_at_once(tmp_path) -> None:
    # the parser that records rows is expat as ElementTree uses it: its amplification limit still applies
    entities = '<!ENTITY a0 "lol">' + "".join(f'<!ENTITY a{k} "{f"&a{k - 1};" * 10}">' for k in range(1, 10))
    text = f'<?xml version="1.0"?><!DOCTYPE robot [{entities}]><robot name="&a9;"><link name="b"/></robot>'
    path = tmp_path / "bomb.urdf"
    path.write_text(text)
    from spherecal.correction import RobotFileError

    with pytest.raises(RobotFileError, match=r"bomb.urdf: row 1: invalid XML: "):
        load_urdf(path)
