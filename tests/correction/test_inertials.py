"""Inertials where the description has none: an embedded arm's published masses, moved into the chain's own
DH frames, give MuJoCo's gravity torques of a model built from the published description; an inertials file
replaces them; a chain of another arm gets none."""

from __future__ import annotations

import re
from dataclasses import replace
from importlib import resources

import numpy as np
import pytest
import yaml

from spherecal.cli import main
from spherecal.correction import load_robot
from spherecal.correction.gravity import InertialsError, gravity_torques, has_inertials
from tests.correction.urdf_helpers import DATA, mujoco_ready
from tests.refusal import refused


def _qfrc_bias(urdf_text: str, joint_names: list[str], q: np.ndarray) -> np.ndarray:
    """(N, n) MuJoCo's bias forces at rest (the torques that hold the arm up) of a URDF, by joint name."""
    mujoco = pytest.importorskip("mujoco")
    mj = mujoco.MjModel.from_xml_string(mujoco_ready(urdf_text, boundmass="1e-9", boundinertia="1e-12"))
    data = mujoco.MjData(mj)
    joints = [mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_JOINT, name) for name in joint_names]
    qpos, dof = [mj.jnt_qposadr[j] for j in joints], [mj.jnt_dofadr[j] for j in joints]
    out = []
    for qk in q:
        data.qpos[:], data.qvel[:] = 0.0, 0.0
        data.qpos[qpos] = qk
        mujoco.mj_forward(mj, data)
        out.append(data.qfrc_bias[dof].copy())
    return np.array(out)


def test_iiwa_chain_without_masses_gets_drakes_and_mujocos_torques(tmp_path, rng, capsys) -> None:
    # MUKCa's iiwa14.urdf (ROS-Industrial frames, joint 4 about -y), with the 0.44 mm joint offsets of
    # that file removed so that its axes are exactly those of the published (Drake) description
    text = (DATA / "iiwa14.urdf").read_text().replace('xyz="-0.00043624 0 0.36"', 'xyz="0 0 0.36"')
    text = text.replace('xyz="0.00043624 0 0.42"', 'xyz="0 0 0.42"')
    assert "<inertial" not in text
    path = tmp_path / "iiwa14.urdf"
    path.write_text(text)
    lines: list[str] = []
    model = load_robot(path, tip_link="ball_link", report=lines.append)
    assert has_inertials(model) and len(lines) == 1 and "kuka_iiwa14" in lines[0]
    assert "embedded kuka_iiwa14" in model.extras["inertials_source"]
    q = model.random_configurations(30, rng)
    published = resources.files("spherecal.correction").joinpath("data", "iiwa14.urdf").read_text()
    names = [f"iiwa_joint_{k}" for k in range(1, 8)]
    reference = _qfrc_bias(published, names, q)
    assert np.abs(reference).max() > 20.0
    np.testing.assert_allclose(gravity_torques(model, q), reference, atol=1e-6)


def test_panda_urdf_without_masses_gets_the_published_panda_torques(tmp_path, rng) -> None:
    text = (DATA / "panda.urdf").read_text()  # MUKCa's: no <inertial> at all
    assert "<inertial" not in text
    panda = yaml.safe_load(resources.files("spherecal.correction").joinpath("data", "panda.yaml").read_text())
    # the reference: the same URDF with the published masses put on panda_link<i> (= DH frame i, as published)
    # and the hand as a body fixed on panda_link7, compiled by MuJoCo
    for i, entry in enumerate(panda["inertials"], start=1):
        inertial = (f'<inertial><origin xyz="{" ".join(map(str, entry["com"]))}" rpy="0 0 0"/>'
                    f'<mass value="{entry["mass"]}"/><inertia ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" '
                    f'izz="1e-6"/></inertial>')
        text, count = re.subn(rf'(<link name="panda_link{i}">)', rf"\1{inertial}", text)
        assert count == 1
    hand = panda["payload"]
    text = text.replace("</robot>", (
        f'<link name="hand_mass"><inertial><origin xyz="{" ".join(map(str, hand["com"]))}" rpy="0 0 0"/>'
        f'<mass value="{hand["mass"]}"/><inertia ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"/>'
        '</inertial></link><joint name="hand_mass_joint" type="fixed"><parent link="panda_link7"/>'
        '<child link="hand_mass"/><origin xyz="0 0 0" rpy="0 0 0"/></joint></robot>'))
    model = load_robot(DATA / "panda.urdf", tip_link="ball_link")
    assert "franka_panda" in model.extras["inertials_source"]  # not the FR3: its limits are the Panda's
    q = model.random_configurations(30, rng)
    reference = _qfrc_bias(text, model.extras["joint_names"], q)
    assert np.abs(reference).max() > 10.0
    np.testing.assert_allclose(gravity_torques(model, q), reference, atol=1e-6)


def test_fr3_limits_pick_the_fr3_and_another_arm_gets_nothing(panda) -> None:
    from spherecal.correction.files.robots import embedded_inertials

    fr3 = load_robot("fr3")
    bare = replace(fr3, extras={})
    moved, line = embedded_inertials(bare)
    assert "franka_fr3" in line
    coms = [entry["com"] for entry in moved.extras["inertials"]]
    np.testing.assert_allclose(coms, [entry["com"] for entry in fr3.extras["inertials"]], atol=1e-15)
    moved, line = embedded_inertials(replace(panda, extras={}))
    assert "franka_panda" in line
    d = panda.d.copy()
    d[2] += 0.005  # the elbow 5 mm further out: another arm, no borrowed masses
    assert embedded_inertials(replace(panda, d=d, extras={})) is None


def test_inertials_file_replaces_and_a_bad_one_is_one_line(tmp_path, capsys) -> None:
    good = tmp_path / "masses.yaml"
    good.write_text("inertials:\n" + "".join("  - {mass: 1.0, com: [0.0, 0.0, 0.01]}\n" for _ in range(7))
                    + "payload: {mass: 0.5, com: [0, 0, 0.1]}\n")
    model = load_robot("panda", inertials=good)
    assert model.extras["inertials"][3] == {"mass": 1.0, "com": [0.0, 0.0, 0.01]}
    assert model.extras["inertials_source"] == str(good)
    bad = tmp_path / "bad.yaml"
    bad.write_text("inertials:\n  - {mass: 1.0, com: [0, 0]}\n")
    with pytest.raises(InertialsError, match="bad.yaml: row 1, field 'inertials': expected a list of 7"):
        load_robot("panda", inertials=bad)
    out = tmp_path / "out.yaml"
    assert main(["export", "panda", "--format", "yaml", "--out", str(out), "--inertials", str(bad)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "bad.yaml" in err and not out.exists()
    assert main(["export", "panda", "--format", "yaml", "--out", str(out), "--inertials", str(good)]) == 0
    assert load_robot(out).extras["inertials"][0]["mass"] == 1.0
    # a robot file given for an inertials file (h5's audit: 'unknown key 'name'', no row, no field)
    robot = tmp_path / "robot.yaml"
    assert main(["export", "panda", "--format", "yaml", "--out", str(robot)]) == 0
    row = 1 + next(k for k, line in enumerate(robot.read_text().splitlines()) if line.startswith("name:"))
    with pytest.raises(InertialsError, match=rf"robot.yaml: row {row}, field 'name': unknown key \(an inertials file "
                                             r"holds inertials, payload; a robot file .* is not an inertials file\)"):
        load_robot("panda", inertials=robot)



@pytest.mark.parametrize("text, expected", [
    ("inertial:\n  - {mass: 1.0, com: [0, 0, 0.01]}\n",  # a misspelt block: named, not 'expected a mapping'
     r"m.yaml: row 1, field 'inertial': unknown key \(did you mean 'inertials'\? an inertials file holds"),
    ("payload: {mass: 0.5, com: [0, 0, 0.1]}\n", r"m.yaml: row 1, field 'inertials': missing"),
    ("- {mass: 1.0, com: [0, 0, 0.01]}\n", r"m.yaml: row 1, field 'inertials': expected a mapping .*, got list"),
    ("", r"m.yaml: row 1, field 'inertials': expected a mapping .*, got an empty file"),
])
def test_an_inertials_file_without_its_list_names_the_row_and_field(tmp_path, capsys, text, expected) -> None:
    """A bad-input sweep: 'inertial:' for 'inertials:' said only 'expected a mapping with an inertials list'."""
    path = tmp_path / "m.yaml"
    path.write_text(text)
    with pytest.raises(InertialsError, match=expected):
        load_robot("panda", inertials=path)
    err = refused(["export", "panda", "--format", "yaml", "--out", tmp_path / "out.yaml", "--inertials", path],
                  tmp_path, capsys)
    assert re.search(expected, err), err


def test_converting_the_convention_keeps_gravity_torques(panda, rng) -> None:
    from spherecal.correction import convert

    q = panda.random_configurations(20, rng)
    standard = convert(panda, "standard")
    assert standard.convention == "standard" and np.abs(gravity_torques(panda, q)).max() > 10.0
    np.testing.assert_allclose(gravity_torques(standard, q), gravity_torques(panda, q), atol=1e-9)
    back = convert(standard, "modified")
    for mine, theirs in zip(back.extras["inertials"], panda.extras["inertials"], strict=True):
        np.testing.assert_allclose(mine["com"], theirs["com"], atol=1e-12)


def test_gen3_lite_urdf_without_masses_gets_kinovas(tmp_path, rng) -> None:
    import warnings

    text = (DATA / "gen3lite.urdf").read_text()  # MUKCa's, with Kinova's masses (checked against MuJoCo elsewhere)
    bare = tmp_path / "gen3lite.urdf"
    bare.write_text(re.sub(r"<inertial>.*?</inertial>", "", text, flags=re.S))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # joints 2-3 nearly parallel: a Hayati beta, tested elsewhere
        model = load_robot(bare, tip_link="ball_link")
        reference = load_robot(DATA / "gen3lite.urdf", tip_link="ball_link")
    assert "kinova_gen3_lite" in model.extras["inertials_source"]
    q = model.random_configurations(20, rng)
    np.testing.assert_allclose(gravity_torques(model, q), gravity_torques(reference, q), atol=1e-9)


def test_inertials_read_once_per_block_stay_those_of_each_model() -> None:
    """inertials_of remembers a block it checked (a fit reads it at every step): a model with another block, a
    payload added, another joint count or grams for kilograms still gets its own answer, and the arrays it
    returns are the caller's to change."""
    from spherecal.correction.gravity import inertials_of

    panda = load_robot("panda")
    masses, coms = inertials_of(panda)
    masses[:] = 0.0  # the caller's copy
    again, _ = inertials_of(panda.with_params(panda.params + 1e-4))  # another geometry, the same block
    assert again[0] > 0 and np.array_equal(again, inertials_of(panda)[0])
    heavier = [dict(e) for e in panda.extras["inertials"]]
    heavier[2] = {**heavier[2], "mass": heavier[2]["mass"] + 1.0}
    other = replace(panda, extras={**panda.extras, "inertials": heavier})
    assert inertials_of(other)[0][2] == pytest.approx(inertials_of(panda)[0][2] + 1.0)
    own = inertials_of(panda)[0][-1]  # the embedded Panda's hand
    loaded = replace(panda, extras={**panda.extras, "payload": {"mass": own + 2.0, "com": [0.0, 0.0, 0.05]}})
    assert inertials_of(loaded)[0][-1] == own + 2.0 and inertials_of(panda)[0][-1] == own
    grams = replace(panda, extras={**panda.extras, "inertials": [{**e, "mass": e["mass"] * 1e3}
                                                                 for e in panda.extras["inertials"]]})
    for _ in range(2):  # refused every time, not remembered
        with pytest.raises(InertialsError, match="not physical"):
            inertials_of(grams)
    short = replace(panda, a=panda.a[:6], alpha=panda.alpha[:6], d=panda.d[:6], theta=panda.theta[:6],
                    lower=panda.lower[:6], upper=panda.upper[:6])
    with pytest.raises(InertialsError, match="expected a list of 6"):
        inertials_of(short)
