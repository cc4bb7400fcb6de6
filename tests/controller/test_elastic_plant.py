"""The elastic MuJoCo plant: links sag by -c tau under gravity while the motors (the readings) hold."""

from dataclasses import replace

import mujoco
import numpy as np
import pytest

from spherecal.controller.export import export_model
from spherecal.controller.plant import build_plant
from spherecal.correction import SpherecalError, load_robot, tool_point
from spherecal.correction.elastic import link_angles, with_compliance
from spherecal.correction.gravity import gravity_torques
from tests.controller.settle import settle

COMPLIANCE = np.array([0.0, 1 / 3e4, 1 / 3e4, 1 / 3e4, 0.0, 0.0, 0.0])


def test_sag_settles_where_the_elastic_model_puts_it():
    model = with_compliance(load_robot("panda"), COMPLIANCE)
    plant = build_plant(model)
    assert plant.elastic and plant.flex_joints.tolist() == [1, 2, 3]
    q0 = np.array([0.3, -0.5, 0.4, -2.0, 0.2, 1.8, 0.5])
    plant.set_state(q0)
    d = plant.mj_data
    d.qpos[plant.flex_qpos] = 0.0  # start rigid: MuJoCo's dynamics must find the sag
    settle(plant, 3000)
    assert np.abs(plant.q - q0).max() < 1e-6  # the motors (readings) held
    sag = d.qpos[plant.flex_qpos]
    expected = (link_angles(model, plant.q) - plant.q)[[1, 2, 3]]
    assert np.abs(sag).max() > 3e-4  # a real deflection
    np.testing.assert_allclose(sag, expected, atol=1e-5)  # second order: tau at the measured angles
    rigid_gap = np.linalg.norm(plant.tool_position() - tool_point(load_robot("panda"), plant.q))
    elastic_gap = np.linalg.norm(plant.tool_position() - tool_point(model, plant.q))
    assert rigid_gap > 3e-4 and elastic_gap < 1e-5


def test_rigid_plant_unchanged_and_kinematics_batch_uses_the_sag():
    panda = load_robot("panda")
    rigid = build_plant(panda)
    assert not rigid.elastic and "flex" not in rigid.mjcf and rigid.mj_model.nq == 7
    model = with_compliance(panda, COMPLIANCE)
    q = panda.random_configurations(4, np.random.default_rng(0))
    np.testing.assert_allclose(build_plant(model).tool_points(q), tool_point(model, q), atol=1e-12)


def test_compliance_without_inertials_is_refused():
    panda = load_robot("panda")
    extras = {k: v for k, v in panda.extras.items() if k not in ("inertials", "payload")}
    with pytest.raises(SpherecalError, match="'inertials'"):
        build_plant(with_compliance(replace(panda, extras=extras), COMPLIANCE))


def test_simulate_stiffness_writes_the_compliance_and_refuses_bad_values(tmp_path, capsys):
    from spherecal.cli import main

    out = tmp_path / "out"
    args = ["simulate", "--out", str(out), "--seconds", "0.3", "--samples", "20", "--seed", "2", "--noise", "0"]
    assert main([*args, "--stiffness", "0,3e4,3e4,3e4,0,0,0"]) == 0
    truth = load_robot(out / "truth.yaml")
    np.testing.assert_allclose(truth.extras["compliance"], COMPLIANCE, rtol=1e-15)
    bad = tmp_path / "bad"
    assert main(["simulate", "--out", str(bad), "--stiffness", "3e4,1"]) == 1
    assert main(["simulate", "--out", str(bad), "--stiffness", "-5"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("spherecal simulate: error: field '--stiffness': '-5'") and not bad.exists()


def test_export_urdf_says_it_drops_the_compliance_mjcf_keeps_it(tmp_path, capsys):
    from spherecal.cli import main
    from spherecal.correction import save_robot

    save_robot(with_compliance(load_robot("panda"), COMPLIANCE), tmp_path / "el.yaml")
    assert main(["export", str(tmp_path / "el.yaml"), "--format", "urdf", "--out", str(tmp_path / "el.urdf")]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[-2].startswith("spherecal export: a URDF cannot carry c2, c3, c4: wrote the best rigid fit")
    assert main(["export", str(tmp_path / "el.yaml"), "--format", "mjcf", "--out", str(tmp_path / "el.xml")]) == 0
    assert 'name="flex3"' in (tmp_path / "el.xml").read_text()
    assert "cannot carry" not in capsys.readouterr().out


def test_ik_on_the_elastic_model_puts_the_sagging_plant_on_target():
    from spherecal.controller.ik import ik

    model = with_compliance(load_robot("panda"), COMPLIANCE)
    target = np.array([0.5, -0.1, 0.35])
    result = ik(model, target, np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8]))
    assert result.converged
    landed = build_plant(model).tool_points(result.q[None])[0]  # MuJoCo's sagged links, not our formula
    assert np.linalg.norm(landed - target) < 1e-6
    assert np.linalg.norm(tool_point(load_robot("panda"), result.q) - target) > 1e-4  # rigid IK would miss


def test_a_compliance_the_data_left_at_float_noise_is_a_rigid_hinge_and_the_plant_stays_still():
    """A calibration leaves a compliance the data does not see at float noise or a few 1e-9 rad/Nm (MUKCa panda_6:
    c1 1.16e-24, c7 1.5e-9 rad/Nm); as springs of 8.6e23 and 6.8e8 Nm/rad MuJoCo diverged within 3 steps (a review).
    Such joints are rigid hinges; the real compliances stay springs; a negative one at float noise keeps the MJCF
    whole (it sent an elastic model to the rigid fit)."""
    from spherecal.controller.export import mjcf_lost_terms
    from spherecal.controller.stiffness import MAX_FLEX_STIFFNESS

    compliance = np.array([1.16e-24, 1 / 3e4, 1 / 3e4, 1 / 3e4, 2e-8, 1 / 2e5, 1.5e-9])
    plant = build_plant(with_compliance(load_robot("panda"), compliance))
    assert plant.flex_joints.tolist() == [1, 2, 3, 5]  # springs softer than MAX_FLEX_STIFFNESS only
    assert 1.0 / compliance[4] > MAX_FLEX_STIFFNESS > 1.0 / compliance[5]
    plant.set_state(np.array([0.3, -0.5, 0.4, -2.0, 0.2, 1.8, 0.5]))
    d = plant.mj_data
    settle(plant, 1000)
    assert np.all(np.isfinite(d.qacc)) and d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number == 0
    assert np.abs(d.qvel).max() < 1e-3
    noise = with_compliance(load_robot("panda"), np.array([-4.1e-26, 1 / 3e4, 1 / 3e4, 1 / 3e4, 0.0, 0.0, 0.0]))
    assert mjcf_lost_terms(noise) == ()
    assert mjcf_lost_terms(with_compliance(load_robot("panda"), -compliance)) == ("c2", "c3", "c4", "c6")


@pytest.mark.parametrize("convention", ["modified", "standard"])
def test_the_plant_sags_as_the_elastic_model_with_every_joint_compliant(convention):
    """The rotors (motor-side bodies) take their mass from their links, on the hinge axis: the plant's gravity
    torques are the model's, and its tool point settles where the elastic model puts it (31-33 um apart when the
    rotors' 0.05 kg were added to the arm; a review measured 17 um on an exported MJCF)."""
    from spherecal.correction import to_standard

    panda = load_robot("panda")
    model = with_compliance(panda if convention == "modified" else to_standard(panda),
                            np.array([0.0, *[1 / 3e4] * 6]))
    plant = build_plant(model)
    plant.set_state(np.array([0.4, -0.3, 0.5, -2.2, 0.6, 2.1, -0.4]))
    settle(plant, 3000)
    m = plant.mj_model
    assert np.linalg.norm(plant.tool_position() - tool_point(model, plant.q)) < 3e-6
    total = m.body_subtreemass[m.body("link0").id]
    assert total == pytest.approx(sum(e["mass"] for e in model.extras["inertials"]) + model.extras["payload"]["mass"]
                                  + m.body_mass[m.body("link0").id])


def test_the_exported_mjcf_alone_sags_as_the_elastic_model_in_plain_mujoco():
    """An elastic model's MJCF loaded by a user (``from_xml_string``, ``mj_step``, the motors held by their velocity
    actuators at 0) settles where the elastic model puts its tool: gravity acts on the ``flex`` springs, its
    compensation on the motors only. Every body's ``gravcomp`` held the springs too and our plant put gravity back in
    Python, so the file alone was the rigid chain: 0.35-1.59 mm from the model here (a review, on an iiwa14
    calibration: 0.40 mm mean). The micrometres left are the model's (``tau`` at the motor angles): MuJoCo's rest is
    the exact static equilibrium."""
    compliance = np.array([0.0, *[1 / 3e4] * 6])
    model = with_compliance(load_robot("panda"), compliance)
    mj = mujoco.MjModel.from_xml_string(export_model(model, "mjcf").text)
    data = mujoco.MjData(mj)
    motors = [mj.joint(f"joint{i + 1}").qposadr[0] for i in range(model.n_joints)]
    springs = [mj.joint(f"flex{i + 1}").qposadr[0] for i in range(1, model.n_joints)]
    for q in model.random_configurations(3, np.random.default_rng(1)):
        mujoco.mj_resetData(mj, data)  # the links start rigid on the motors: MuJoCo must find the sag
        data.qpos[motors] = q
        for _ in range(3000):
            mujoco.mj_step(mj, data)
        held = data.qpos[motors]
        assert np.abs(held - q).max() < 1e-6 and np.abs(data.qvel).max() < 1e-9  # the motors held, at rest
        tool = data.site("tool").xpos
        assert np.linalg.norm(tool - tool_point(load_robot("panda"), held)) > 2e-4  # a real sag
        assert np.linalg.norm(tool - tool_point(model, held)) < 3e-6  # the model's, to its second order
        links = held + np.r_[0.0, data.qpos[springs]]  # exact statics: the spring holds gravity at the link angles
        np.testing.assert_allclose(links + compliance * gravity_torques(model, links), held, atol=1e-12)
