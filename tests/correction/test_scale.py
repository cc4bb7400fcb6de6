"""The joint angle scale kind: layout, file round trip, Jacobians against central differences."""

from dataclasses import replace

import numpy as np
import pytest

from spherecal.correction import joint_jacobian, load_robot, param_jacobian, save_robot, tool_point
from spherecal.correction.elastic import with_compliance
from spherecal.correction.gravity import gravity_torques
from spherecal.correction.layout import SCALE
from spherecal.correction.scale import ScaleError, recorded_angles, scale_of, with_scale

S = np.array([1e-3, -2e-3, 5e-4, 1.5e-3, -1e-3, 2e-3, -5e-4])
C = np.array([0.0, 2e-5, 3e-5, 4e-5, 1e-5, 5e-6, 0.0])


def _scaled(elastic: bool):
    panda = load_robot("panda")
    return with_scale(with_compliance(panda, C) if elastic else panda, S)


def _central(model, q, k, h):
    x = model.params
    e = np.zeros_like(x)
    e[k] = h
    return (tool_point(model.with_params(x + e), q) - tool_point(model.with_params(x - e), q)) / (2 * h)


def test_layout_file_and_order_with_compliance(tmp_path):
    model = _scaled(elastic=True)
    lay = model.layout
    assert lay.scaled and lay.elastic and model.n_params == 37 + 14
    assert lay.names[lay.scale] == tuple(f"s{i}" for i in range(1, 8)) and lay.scale.start == lay.compliance.stop
    assert all(k is SCALE for k in lay.kinds[lay.scale]) and lay.spread()[lay.scale].tolist() == [1e-3] * 7
    values = model.params.copy()
    values[lay.scale] *= 3
    assert model.with_params(values).extras["scale"] == pytest.approx(list(3 * S))
    save_robot(model, tmp_path / "r.yaml")
    back = load_robot(tmp_path / "r.yaml")
    assert back.extras["scale"] == pytest.approx(list(S)) and back.layout.scaled
    # scale first, then the compliance at the scaled angles (correction.kinematics' stated order)
    q = model.random_configurations(6, np.random.default_rng(0))
    q_joint = (1 + S) * q
    q_link = q_joint - C * gravity_torques(model, q_joint)
    np.testing.assert_allclose(tool_point(model, q), tool_point(load_robot("panda"), q_link), atol=1e-15)
    np.testing.assert_allclose(tool_point(back, q), tool_point(model, q), atol=1e-15)
    np.testing.assert_allclose(recorded_angles(model, q_joint), q, atol=1e-15)


@pytest.mark.parametrize("elastic", [False, True])
def test_scale_columns_match_central_differences(elastic):
    model = _scaled(elastic)
    q = model.random_configurations(8, np.random.default_rng(1))
    jac = param_jacobian(model, q)
    lay = model.layout
    for k in range(lay.scale.start, lay.scale.stop):
        fd = _central(model, q, k, 1e-6)
        if elastic:  # the torque's dependence on the angle neglected: c |dtau/dq| ~ 1e-3 of the column
            assert np.abs(jac[:, :, k] - fd).max() <= 3e-3 * max(1.0, np.abs(fd).max())
        else:
            np.testing.assert_allclose(jac[:, :, k], fd, atol=1e-9)
    assert np.abs(jac[:, :, lay.index("s2")]).max() > 0.1  # m per unit scale: a lever arm times an angle
    if elastic:  # the compliance columns stay exact with a scale in front of them
        for k in range(lay.compliance.start, lay.compliance.stop):
            fd = _central(model, q, k, 1e-6)
            np.testing.assert_allclose(jac[:, :, k], fd, atol=1e-9 * max(1.0, np.abs(fd).max()))


def test_joint_jacobian_includes_the_scale():
    model = _scaled(elastic=True)
    q = model.random_configurations(5, np.random.default_rng(2))
    jac, h = joint_jacobian(model, q), 1e-6
    for k in range(7):
        e = np.zeros(7)
        e[k] = h
        fd = (tool_point(model, q + e) - tool_point(model, q - e)) / (2 * h)
        np.testing.assert_allclose(jac[:, :, k], fd, atol=1e-9)


def test_malformed_scale_is_refused():
    panda = load_robot("panda")
    for bad in ([0.0] * 6, [0.0] * 6 + [float("nan")], "x"):
        with pytest.raises(ScaleError, match="field 'scale'"):
            scale_of(replace(panda, extras={"scale": bad}))
