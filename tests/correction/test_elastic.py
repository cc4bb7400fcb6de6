"""The elastic-joint model: layout, Jacobians against central differences, motor/link angles."""

import numpy as np

from spherecal.correction import joint_jacobian, load_robot, param_jacobian, tool_point
from spherecal.correction.elastic import link_angles, motor_angles, with_compliance, with_stiffness
from spherecal.correction.gravity import gravity_torques
from spherecal.correction.layout import COMPLIANCE

C = np.array([0.0, 2e-5, 3e-5, 4e-5, 1e-5, 5e-6, 0.0])


def _panda():
    return with_compliance(load_robot("panda"), C)


def test_layout_and_round_trip():
    panda = load_robot("panda")
    model = _panda()
    assert panda.n_params == 37 and not panda.layout.elastic
    lay = model.layout
    assert model.n_params == 44 and lay.names[lay.compliance] == tuple(f"c{i}" for i in range(1, 8))
    assert all(k is COMPLIANCE for k in lay.kinds[lay.compliance]) and lay.format("c3", 3e-5) == "30 urad/Nm"
    np.testing.assert_array_equal(model.params[lay.compliance], C)
    values = model.params.copy()
    values[lay.compliance] *= 2
    assert model.with_params(values).extras["compliance"] == list(2 * C)
    assert lay.spread()[lay.compliance].tolist() == [3e-5] * 7 and model.layout.elastic and not panda.layout.elastic


def test_tool_point_is_the_rigid_one_at_the_link_angles():
    model = _panda()
    q = model.random_configurations(10, np.random.default_rng(0))
    q_link = q - C * gravity_torques(model, q)
    np.testing.assert_allclose(link_angles(model, q), q_link, atol=1e-15)
    rigid = load_robot("panda")
    np.testing.assert_allclose(tool_point(model, q), tool_point(rigid, q_link), atol=1e-15)
    assert np.abs(tool_point(model, q) - tool_point(rigid, q)).max() > 2e-4  # sub-mm, but there
    np.testing.assert_allclose(link_angles(model, motor_angles(model, q_link)), q_link, atol=1e-14)


def test_compliance_columns_match_central_differences():
    model = _panda()
    q = model.random_configurations(8, np.random.default_rng(1))
    jac = param_jacobian(model, q)
    lay, x, h = model.layout, model.params, 1e-6
    for k in range(lay.compliance.start, lay.compliance.stop):
        e = np.zeros_like(x)
        e[k] = h
        fd = (tool_point(model.with_params(x + e), q) - tool_point(model.with_params(x - e), q)) / (2 * h)
        np.testing.assert_allclose(jac[:, :, k], fd, atol=1e-9 * max(1.0, np.abs(fd).max()))
    assert np.abs(jac[:, :, lay.index("c3")]).max() > 1.0  # m per rad/Nm: tens of Nm on joint 3


def test_geometric_columns_neglect_only_the_torque_dependence():
    """At c = 0 exact; at 3e-5 rad/Nm within the stated c |dtau/dparam| (~1e-3 of a column)."""
    model = _panda()
    q = model.random_configurations(8, np.random.default_rng(2))
    jac = param_jacobian(model, q)
    x, h = model.params, 1e-7
    for k in range(model.layout.compliance.start):
        e = np.zeros_like(x)
        e[k] = h
        fd = (tool_point(model.with_params(x + e), q) - tool_point(model.with_params(x - e), q)) / (2 * h)
        assert np.abs(jac[:, :, k] - fd).max() <= 3e-3 * max(1.0, np.abs(fd).max())


def test_joint_jacobian_is_exact_through_the_torque():
    model = _panda()
    q = model.random_configurations(8, np.random.default_rng(3))
    jac, h = joint_jacobian(model, q), 1e-6
    rigid_part = joint_jacobian(load_robot("panda"), link_angles(model, q))
    for k in range(7):
        e = np.zeros(7)
        e[k] = h
        fd = (tool_point(model, q + e) - tool_point(model, q - e)) / (2 * h)
        np.testing.assert_allclose(jac[:, :, k], fd, atol=1e-8)
    assert np.abs(jac - rigid_part).max() > 1e-5  # the torque term is not negligible at this tolerance


def test_with_stiffness_is_the_inverse_compliance():
    panda = with_compliance(load_robot("panda"), C)
    k = [0.0, 3e4, 0.0, 5e4, 0.0, 0.0, 1e3]  # 0: a rigid joint
    np.testing.assert_array_equal(with_stiffness(panda, k).extras["compliance"],
                                  [0.0, 1 / 3e4, 0.0, 1 / 5e4, 0.0, 0.0, 1 / 1e3])
    assert "compliance" not in with_stiffness(panda, [0.0] * 7).extras  # every joint rigid: the file's is removed
