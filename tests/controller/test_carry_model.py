"""The whole calibrated model carried to the controller: Jacobians, IK and compensation use every identified
term (here joint compliance), checked against finite differences and an elastic MuJoCo plant."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from spherecal.controller.compensation import compensate
from spherecal.controller.ik import _rotvec, ik
from spherecal.controller.plant import build_plant
from spherecal.correction import (
    convert,
    load_robot,
    perturb,
    pose_jacobian,
    rpy_matrix,
    save_robot,
    tool_point,
    tool_pose,
)
from spherecal.correction.elastic import with_compliance
from tests.controller.settle import settle

COMPLIANCE = np.array([0.0, 1 / 2e4, 1 / 3e4, 1 / 3e4, 1 / 1e4, 0.0, 0.0])
HOME = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])


def _elastic():
    return with_compliance(load_robot("panda"), COMPLIANCE)


@pytest.mark.parametrize("convention", ["modified", "standard"])
def test_pose_jacobian_matches_central_differences_of_the_elastic_pose(rng, convention) -> None:
    model = convert(_elastic(), convention)
    q = model.random_configurations(5, rng)
    jac = pose_jacobian(model, q)
    h = 1e-6
    for k in range(model.n_joints):
        step = np.zeros(model.n_joints)
        step[k] = h
        for i in range(len(q)):
            plus, minus = tool_pose(model, q[i] + step), tool_pose(model, q[i] - step)
            np.testing.assert_allclose(jac[i, :3, k], (plus[:3, 3] - minus[:3, 3]) / (2 * h), atol=1e-8)
            turn = _rotvec(plus[:3, :3] @ minus[:3, :3].T) / (2 * h)  # world angular velocity per unit rate
            np.testing.assert_allclose(jac[i, 3:, k], turn, atol=1e-8)
    rigid = pose_jacobian(convert(load_robot("panda"), convention), q)
    assert np.abs(rigid[:, 3:] - jac[:, 3:]).max() > 1e-4  # the elastic terms are in the angular rows too
    np.testing.assert_allclose(pose_jacobian(model, q[0]), jac[0])


def test_ik_with_orientation_lands_the_elastic_plant_on_the_target() -> None:
    model = _elastic()
    target, rotation = np.array([0.55, 0.1, 0.35]), rpy_matrix([np.pi, 0.1, 0.3])
    result = ik(model, target, HOME, orientation=rotation)
    rigid = ik(load_robot("panda"), target, HOME, orientation=rotation)
    assert result.converged and rigid.converged
    plant = build_plant(model)  # MuJoCo: flexible joints behind the motors, gravity bends them
    landing = {}
    for name, q in (("elastic", result.q), ("rigid", rigid.q)):
        plant.set_state(q)
        settle(plant)
        landing[name] = np.linalg.norm(plant.tool_position() - target)
    assert landing["rigid"] > 3e-4  # the rigid model's answer sags off the target
    assert landing["elastic"] < 2e-5  # the full model's lands (second order in the sag)


def test_compensation_uses_the_full_model_and_reports_its_gain(rng) -> None:
    nominal = load_robot("panda")
    calibrated = with_compliance(perturb(nominal, rng), COMPLIANCE)
    target = tool_point(nominal, HOME) + [0.02, -0.03, 0.01]
    result = compensate(target, nominal, calibrated, HOME)
    assert np.linalg.norm(tool_point(calibrated, result.q) - target) < 1e-9  # the elastic arm lands
    geometric = replace(calibrated, extras={k: v for k, v in calibrated.extras.items() if k != "compliance"})
    assert np.linalg.norm(tool_point(geometric, result.q) - target) > 3e-4  # compliance was compensated too
    assert result.uncompensated_error > 1e-3 and np.isclose(result.gain, result.uncompensated_error
                                                              - result.position_residual)


def test_the_calibrated_file_keeps_every_term(tmp_path, rng) -> None:
    model = with_compliance(perturb(load_robot("panda"), rng), COMPLIANCE)
    model = replace(model, extras={**model.extras, "custom_term": [1.0, 2.0]})
    path = save_robot(model, tmp_path / "cal.yaml")
    back = load_robot(path)
    assert back.layout.names == model.layout.names and np.array_equal(back.params, model.params)
    assert back.extras == model.extras
    q = model.random_configurations(20, rng)
    np.testing.assert_array_equal(tool_point(back, q), tool_point(model, q))
