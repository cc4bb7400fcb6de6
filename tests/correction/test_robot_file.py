"""Robot files: exact round trip, and one clear line for every bad field."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from spherecal.correction import RobotFileError, load_robot, save_robot, to_standard
from tests.conftest import perturbed

PANDA_TEXT = (Path(__file__).parents[2] / "correction" / "data" / "panda.yaml").read_text()


def test_embedded_panda_is_the_published_one(panda) -> None:
    assert panda.convention == "modified" and panda.n_joints == 7
    np.testing.assert_array_equal(panda.a, [0, 0, 0, 0.0825, -0.0825, 0, 0.088])
    np.testing.assert_array_equal(panda.d, [0.333, 0, 0.316, 0, 0.384, 0, 0])
    np.testing.assert_allclose(panda.alpha, np.pi / 2 * np.array([0, -1, 1, 1, -1, 1, 1]))
    np.testing.assert_array_equal(panda.tool, [0, 0, 0.107])
    np.testing.assert_array_equal(panda.upper[3], -0.0698)
    assert panda.param_names[:4] == ("a1", "alpha1", "d1", "theta1")
    assert panda.param_names[28:31] == ("tool_x", "tool_y", "tool_z")
    assert panda.param_index("alpha4") == 13


def test_round_trip_is_exact(panda, rng, tmp_path) -> None:
    for model in (perturbed(panda, rng), to_standard(perturbed(panda, rng, 50.0))):
        path = save_robot(model, tmp_path / "robot.yaml")
        again = load_robot(path)
        assert again.convention == model.convention and again.name == model.name
        np.testing.assert_array_equal(again.params, model.params)
        np.testing.assert_array_equal(again.lower, model.lower)
        np.testing.assert_array_equal(again.upper, model.upper)
    assert not list(tmp_path.glob(".*tmp"))  # no temporary left behind


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(min_value=-4.0, max_value=4.0), min_size=37, max_size=37))
def test_round_trip_any_float(tmp_path_factory, values) -> None:
    """Every float a robot file accepts (|length| <= 10 m, |angle| <= 4 pi) comes back bit for bit."""
    panda = load_robot("panda")
    model = panda.with_params(np.array(values))
    path = save_robot(model, tmp_path_factory.mktemp("rt") / "r.yaml")
    np.testing.assert_array_equal(load_robot(path).params, model.params)


def test_other_keys_are_kept(tmp_path) -> None:
    data = yaml.safe_load(PANDA_TEXT)
    data["calibration"] = {"method": "lm", "residual_rms_mm": 0.01}
    path = tmp_path / "cal.yaml"
    path.write_text(yaml.safe_dump(data))
    model = load_robot(path)
    assert model.extras["calibration"]["method"] == "lm"
    save_robot(model, tmp_path / "again.yaml")
    assert yaml.safe_load((tmp_path / "again.yaml").read_text())["calibration"]["method"] == "lm"


def _edit(edit) -> dict:
    data = yaml.safe_load(PANDA_TEXT)
    edit(data)
    return data


BAD_FILES = [
    ("missing key", lambda d: d.pop("tool"), r"field 'tool': missing key 'tool'"),
    ("missing joint key", lambda d: d["joints"][2].pop("alpha"), r"field 'joints\[2\]\.alpha': missing key 'alpha'"),
    ("wrong type", lambda d: d["joints"][1].update(d="abc"), r"field 'joints\[1\]\.d': expected a number"),
    ("bool", lambda d: d["joints"][1].update(a=True), r"field 'joints\[1\]\.a': expected a number"),
    ("nan", lambda d: d["joints"][4].update(theta=float("nan")), r"field 'joints\[4\]\.theta': must be finite"),
    ("inf", lambda d: d["tool"].__setitem__(2, float("inf")), r"field 'tool\[2\]': must be finite"),
    ("lower > upper", lambda d: d["joints"][0].update(lower=1.0, upper=-1.0),
     r"field 'joints\[0\]\.lower': must be below upper"),
    ("convention", lambda d: d.update(convention="craig"), r"field 'convention': unknown convention 'craig'"),
    ("tool length", lambda d: d.update(tool=[0, 0]), r"field 'tool': expected a list of 3 numbers"),
    ("base", lambda d: d.update(base={"xyz": [0, 0], "rpy": [0, 0, 0]}), r"field 'base\.xyz': expected a list of 3"),
    ("joints empty", lambda d: d.update(joints=[]), r"field 'joints': expected a non-empty list"),
    # a misspelt key used to be dropped silently: the base placement or a joint offset read as zero
    ("base typo", lambda d: d.update(base={"xyz": [0, 0, 0], "RPY": [0, 0, 1.5]}),
     r"field 'base\.RPY': unknown key 'RPY'"),
    ("joint typo", lambda d: d["joints"][3].update(offset=0.1), r"field 'joints\[3\]\.offset': unknown key 'offset'"),
    # a hand-edited optional block was read only where it was used: a `compliance` or `scale` of the wrong
    # length was a ValueError traceback in calibrate, a NaN compliance calibrated, and a wrong `joint_names` or
    # `inertials` block was kept (inertials of 6 links on a 7-joint arm: the elastic candidates silently dropped)
    ("compliance length", lambda d: d.update(compliance=[0.0, 0.0]),
     r"field 'compliance': expected a list of 7 finite numbers \[rad/Nm\], got \[0.0, 0.0\]"),
    ("compliance nan", lambda d: d.update(compliance=[float("nan")] + [0.0] * 6), r"field 'compliance': expected"),
    ("compliance text", lambda d: d.update(compliance="0"), r"field 'compliance': expected a list of 7"),
    ("scale length", lambda d: d.update(scale=[0.0] * 8), r"field 'scale': expected a list of 7 finite numbers"),
    ("joint_names length", lambda d: d.update(joint_names=[f"j{k}" for k in range(6)]),
     r"field 'joint_names': expected a list of 7 joint names"),
    ("joint_names twice", lambda d: d.update(joint_names=[f"j{k}" for k in range(6)] + ["j2"]),
     r"field 'joint_names\[6\]': 'j2' is named twice"),
    ("inertials count", lambda d: d["inertials"].pop(), r"field 'inertials': expected a list of 7 \{mass, com\} "
     r"entries, got 6 entries"),
    ("inertials mass", lambda d: d["inertials"][2].update(mass=-1.0), r"field 'inertials\[2\].mass': expected a "
     r"finite mass >= 0"),
    ("inertials millimetres", lambda d: d["inertials"][6].update(com=[10.5, -4.2, 61.6]),
     r"field 'inertials\[6\].com': .* not physical \(at most 10 m; the file is in metres\)"),
    ("payload", lambda d: d.update(payload={"mass": "lots"}), r"field 'payload.mass': expected a finite mass"),
]


@pytest.mark.parametrize("label,edit,message", BAD_FILES, ids=[b[0] for b in BAD_FILES])
def test_bad_field_names_file_and_field(tmp_path, label, edit, message) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(_edit(edit)))
    with pytest.raises(RobotFileError, match=message) as error:
        load_robot(path)
    text = str(error.value)
    assert text.startswith(f"{path}: row ") and ", field '" in text and "\n" not in text


def test_unreadable_and_invalid_yaml(tmp_path) -> None:
    with pytest.raises(RobotFileError, match="cannot read"):
        load_robot(tmp_path / "absent.yaml")
    path = tmp_path / "broken.yaml"
    path.write_text("name: [unclosed\n")
    with pytest.raises(RobotFileError, match="invalid YAML"):
        load_robot(path)
    path.write_text("- just a list\n")
    with pytest.raises(RobotFileError, match="mapping at the top level"):
        load_robot(path)
    path.write_bytes(b"name: caf\xe9\n")  # Latin-1, not UTF-8: was a UnicodeDecodeError traceback
    with pytest.raises(RobotFileError, match="broken.yaml: cannot read: not UTF-8 text"):
        load_robot(path)


def test_atomic_files_follow_the_umask(panda, tmp_path) -> None:
    import os

    old = os.umask(0o022)
    try:
        path = save_robot(panda, tmp_path / "robot.yaml")
    finally:
        os.umask(old)
    assert path.stat().st_mode & 0o777 == 0o644


@pytest.mark.parametrize(("name", "text", "expected"), [
    # each was 'expected a mapping at the top level, got str' (or 'invalid YAML' for a commented MJCF); a URDF not
    # named .urdf was then refused ('name it arm.urdf'): it is read as the URDF it is, here one without a joint
    ("robot_description.xml", '<?xml version="1.0"?>\n<!-- xacro -->\n<robot name="arm"><link name="a"/></robot>\n',
     "robot_description.xml: no revolute joint between 'a' and 'a'"),
    ("arm", '\ufeff<robot name="arm"><link name="a"/></robot>', "arm: no revolute joint between 'a' and 'a'"),
    ("cal.xml", '<!-- spherecal export\n-->\n<mujoco model="arm"><worldbody/></mujoco>\n', "an MJCF model (<mujoco>)"),
    ("launch.xml", "<launch><node/></launch>", "an XML document (<launch>), not a robot file"),
])
def test_an_xml_file_read_as_a_robot_file_says_what_it_holds(tmp_path, name, text, expected) -> None:
    (tmp_path / name).write_text(text, encoding="utf-8")
    with pytest.raises(RobotFileError, match=re.escape(expected)) as error:
        load_robot(tmp_path / name)
    assert "\n" not in str(error.value)


@pytest.mark.parametrize("block", ["deleted", ["a2"], 3])
def test_a_calibration_block_that_is_not_a_mapping_is_named(tmp_path, panda, block) -> None:
    # it was kept unread: validate then took the training sockets for held-out ones (no record of them)
    data = yaml.safe_load(Path(save_robot(panda, tmp_path / "cal.yaml")).read_text())
    data["calibration"] = block
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(data))
    with pytest.raises(RobotFileError, match=r"bad.yaml: row \d+, field 'calibration': expected the mapping "):
        load_robot(tmp_path / "bad.yaml")


@pytest.mark.parametrize("key, terms", [("compliance", ["c2", "c3"]), ("scale", ["s1"])])
def test_a_calibrated_file_whose_identified_terms_were_removed_is_refused(tmp_path, panda, key, terms) -> None:
    # a review: an iiwa14 elastic calibration with its 'compliance:' list deleted by hand loaded as the rigid
    # geometry (0.363 against 0.315 mm held out), its calibration block still listing c1..c6 as identified
    data = yaml.safe_load(Path(save_robot(panda, tmp_path / "cal.yaml")).read_text())
    data["calibration"] = {"identified": ["a2", "theta2", *terms, "tool_z"]}
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(data))
    with pytest.raises(RobotFileError, match=rf"bad.yaml: row \d+, field '{key}': missing, while calibration"
                                             rf"\.identified lists {', '.join(terms)}: "):
        load_robot(tmp_path / "bad.yaml")
    data[key] = [0.0] * 7  # with its list, or without such terms, it loads
    (tmp_path / "good.yaml").write_text(yaml.safe_dump(data))
    assert load_robot(tmp_path / "good.yaml").extras[key] == [0.0] * 7
    data.pop(key)
    data["calibration"]["identified"] = ["a2", "theta2", "tool_z"]
    (tmp_path / "dh.yaml").write_text(yaml.safe_dump(data))
    assert key not in load_robot(tmp_path / "dh.yaml").extras


#: A hand-written two-joint robot file: comments, a flow joint and a block joint (the line numbers are the point).
HAND_WRITTEN = """\
# two joints, written by hand
name: two
convention: modified
joints:
  - {a: 0.0, alpha: 0.0, d: 0.333, theta: 0.0, lower: -2.9, upper: 2.9}
  - a: 0.0
    alpha: -1.5707963267948966
    d: 0.0
    theta: 0.0
    lower: -1.76
    upper: 1.76
tool: [0.0, 0.0, 0.107]
base:
  xyz: [0.0, 0.0, 0.0]
  rpy: [0.0, 0.0, 0.0]
"""


@pytest.mark.parametrize(("old", "new", "row", "field"), [
    ("alpha: -1.5707963267948966", "alpha: -90deg", 7, "joints[1].alpha"),
    ("d: 0.333", "d: .nan", 5, "joints[0].d"),
    ("[0.0, 0.0, 0.107]", "[0.0, 0.0, 107]", 12, "tool[2]"),
    ("  rpy: [0.0, 0.0, 0.0]", "  RPY: [0.0, 0.0, 0.0]", 15, "base.RPY"),
    ("    upper: 1.76\n", "", 6, "joints[1].upper"),  # a missing key: the row of its joint
    ("convention: modified", "convention: craig", 3, "convention"),
])
def test_a_refusal_names_the_row_of_the_field(tmp_path, old, new, row, field) -> None:
    assert HAND_WRITTEN.count(old) == 1
    path = tmp_path / "robot.yaml"
    path.write_text(HAND_WRITTEN.replace(old, new))
    with pytest.raises(RobotFileError) as error:
        load_robot(path)
    assert str(error.value).startswith(f"{path}: row {row}, field '{field}': ")
    assert load_robot(_written(tmp_path, HAND_WRITTEN)).n_joints == 2  # the file unedited is read


def _written(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "good.yaml"
    path.write_text(text)
    return path


def test_is_urdf_reads_the_root_not_the_ending(tmp_path, panda) -> None:
    # validate gave --tip-link to the model named .urdf only: a calibrated URDF saved as arm.xml (ROS's ending), which
    # load_robot reads as a URDF, was refused as 'only for a URDF robot description'
    from spherecal.correction.files.robots import is_urdf
    from spherecal.correction.files.urdf_write import robot_to_urdf

    (tmp_path / "arm.xml").write_text(robot_to_urdf(panda))
    (tmp_path / "arm.URDF").write_text("")
    assert is_urdf(tmp_path / "arm.xml") and is_urdf(tmp_path / "arm.URDF")
    assert not is_urdf(save_robot(panda, tmp_path / "cal.yaml")) and not is_urdf("panda")
    assert not is_urdf(tmp_path / "missing.xml")
