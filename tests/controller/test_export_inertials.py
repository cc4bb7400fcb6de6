"""`export`: the MJCF carries the same link inertials as the standalone URDF, and the command says when a
model has none (MuJoCo compiles both files; its bodies, not our numbers, are compared)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from spherecal.cli import main
from spherecal.controller.export import export_model
from spherecal.correction import load_robot, save_robot
from spherecal.correction.elastic import with_compliance
from spherecal.correction.files.urdf_write import robot_to_urdf
from spherecal.correction.gravity import gravity_torques
from tests.conftest import perturbed

mujoco = pytest.importorskip("mujoco")


def _bodies(mj, names, q, joints):
    """World mass, centre of mass and inertia tensor of the named bodies at angles ``q`` of ``joints``."""
    data = mujoco.MjData(mj)
    qpos = [mj.jnt_qposadr[mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_JOINT, j)] for j in joints]
    ids = [mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_BODY, name) for name in names]
    assert min(ids) >= 0, names
    out = []
    for qk in q:
        data.qpos[:] = 0.0
        data.qpos[qpos] = qk
        mujoco.mj_kinematics(mj, data)
        for b in ids:
            rotation = data.ximat[b].reshape(3, 3)
            out.append((mj.body_mass[b], data.xipos[b].copy(), rotation @ np.diag(mj.body_inertia[b]) @ rotation.T))
    return out


def _kept(text: str):
    """MuJoCo's model of a URDF with its fixed links kept as bodies (the file itself unchanged)."""
    spec = mujoco.MjSpec.from_string(text)
    spec.compiler.fusestatic = False
    return spec.compile()


@pytest.mark.parametrize("elastic", [False, True])
def test_mjcf_and_urdf_carry_the_same_bodies(panda, rng, elastic) -> None:
    model = perturbed(panda, rng)
    if elastic:  # rotor bodies and flex hinges in the MJCF; the link bodies are the same
        model = with_compliance(model, np.full(7, 2e-5))
    mjcf = mujoco.MjModel.from_xml_string(export_model(model, "mjcf").text)
    urdf = _kept(robot_to_urdf(model, prefix="arm_"))
    q = model.random_configurations(5, rng)
    ours = _bodies(mjcf, [f"link{i}" for i in range(1, 8)] + ["payload"], q, [f"joint{i}" for i in range(1, 8)])
    theirs = _bodies(urdf, [f"arm_link{i}" for i in range(1, 9)], q, [f"arm_joint{i}" for i in range(1, 8)])
    if elastic:  # each rotor's mass is its link's, on the hinge axis: the link and its rotor carry the URDF link's
        rotors = _bodies(mjcf, [f"rotor{i}" for i in range(1, 8)], q, [f"joint{i}" for i in range(1, 8)])
        rotors = [r for k in range(len(q)) for r in [*rotors[7 * k: 7 * k + 7], (0.0, np.zeros(3), None)]]  # payload
        ours = [(m1 + mr, (m1 * c1 + mr * cr) / (m1 + mr), i1) for (m1, c1, i1), (mr, cr, _)
                in zip(ours, rotors, strict=True)]
    for (m1, c1, i1), (m2, c2, i2) in zip(ours, theirs, strict=True):
        assert m1 == pytest.approx(m2, rel=1e-12) and m1 > 0.0
        np.testing.assert_allclose(c1, c2, rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(i1, i2, rtol=0.0, atol=1e-12)
    if not elastic:  # the MJCF's gravity torques are the model's (its gravcomp acts in qfrc_passive, not here)
        data = mujoco.MjData(mjcf)
        reference = []
        for qk in q:
            data.qpos[:7], data.qvel[:] = qk, 0.0
            mujoco.mj_forward(mjcf, data)
            reference.append(data.qfrc_bias[:7].copy())
        np.testing.assert_allclose(gravity_torques(model, q), reference, rtol=0.0,
                                   atol=1e-6 * np.abs(reference).max())


def test_export_says_when_the_model_has_no_inertials(tmp_path, panda, rng, capsys) -> None:
    # 5 cm and 10 deg off the Panda: no embedded arm's axes match, so no inertials are taken over
    path = save_robot(replace(perturbed(panda, rng, scale=50.0), extras={}), tmp_path / "other.yaml")
    assert "inertials" not in load_robot(path).extras
    for fmt, suffix in (("urdf", "urdf"), ("mjcf", "xml")):
        assert main(["export", str(path), "--format", fmt, "--out", str(tmp_path / f"out.{suffix}")]) == 0
        out = capsys.readouterr().out
        assert "no link inertials" in out and "--inertials FILE" in out
    assert main(["export", "panda", "--format", "urdf", "--out", str(tmp_path / "panda.urdf")]) == 0
    assert "inertials" not in capsys.readouterr().out
    mujoco.MjModel.from_xml_path(str(tmp_path / "panda.urdf"))  # compiles as written
