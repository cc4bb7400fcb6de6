"""Gravity torques from a URDF's own <inertial> elements (lumped per DH link by the importer, the
hand and fingers as payload) against MuJoCo's qfrc_bias on the same URDF."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from spherecal.correction import load_urdf
from spherecal.correction.gravity import gravity_torques, has_inertials
from tests.correction.urdf_helpers import DATA, mujoco_ready


def test_urdf_inertials_give_mujocos_gravity_torques(rng) -> None:
    mujoco = pytest.importorskip("mujoco")
    path = DATA / "gen3lite.urdf"  # the MUKCa Kinova: 12 inertials, fingers on prismatic joints
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its nearly parallel joints 2-3 (Hayati beta), tested elsewhere
        model = load_urdf(path, tip_link="ball_link")
    assert has_inertials(model)
    # MuJoCo bounds the mass of massless moving bodies; 1e-9 kg keeps that far below the tolerance
    mj = mujoco.MjModel.from_xml_string(mujoco_ready(path.read_text(), boundmass="1e-9", boundinertia="1e-12"))
    data = mujoco.MjData(mj)
    joints = [mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_JOINT, name) for name in model.extras["joint_names"]]
    qpos, dof = [mj.jnt_qposadr[j] for j in joints], [mj.jnt_dofadr[j] for j in joints]
    q = model.random_configurations(40, rng)
    reference = []
    for qk in q:
        data.qpos[:], data.qvel[:] = 0.0, 0.0
        data.qpos[qpos] = qk
        mujoco.mj_forward(mj, data)
        reference.append(data.qfrc_bias[dof].copy())  # at rest: the torques that hold the arm up
    reference = np.array(reference)
    assert np.abs(reference).max() > 1.0  # the check has something to compare
    np.testing.assert_allclose(gravity_torques(model, q), reference, atol=1e-6)
