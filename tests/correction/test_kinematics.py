"""Forward kinematics and Jacobians against independent references."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from spherecal.correction import (
    JointAngleError,
    RobotModel,
    SpherecalError,
    joint_jacobian,
    link_angle_jacobian,
    link_frames,
    param_jacobian,
    pose_jacobian,
    to_modified,
    to_standard,
    tool_point,
    tool_pose,
)
from spherecal.correction.elastic import with_compliance
from spherecal.correction.gravity import gravity_torques
from spherecal.correction.kinematics import ANGLE_MARGIN, _link_angles
from spherecal.correction.scale import joint_angles, with_scale
from tests.conftest import perturbed
from tests.correction.hand_transforms import rot, shift

# MuJoCo Menagerie's franka_emika_panda/panda_nohand.xml: body pos and quat (w x y z) in
# their parents, each joint a hinge about its body's z, a flange site 0.107 m along z7.
MENAGERIE_PANDA = """
<mujoco>
  <compiler boundmass="0.001" boundinertia="0.000001"/>
  <worldbody>
    <body name="link0">
      <body name="link1" pos="0 0 0.333">
        <joint name="joint1" axis="0 0 1"/>
        <body name="link2" quat="0.7071068 -0.7071068 0 0">
          <joint name="joint2" axis="0 0 1"/>
          <body name="link3" pos="0 -0.316 0" quat="0.7071068 0.7071068 0 0">
            <joint name="joint3" axis="0 0 1"/>
            <body name="link4" pos="0.0825 0 0" quat="0.7071068 0.7071068 0 0">
              <joint name="joint4" axis="0 0 1"/>
              <body name="link5" pos="-0.0825 0.384 0" quat="0.7071068 -0.7071068 0 0">
                <joint name="joint5" axis="0 0 1"/>
                <body name="link6" quat="0.7071068 0.7071068 0 0">
                  <joint name="joint6" axis="0 0 1"/>
                  <body name="link7" pos="0.088 0 0" quat="0.7071068 0.7071068 0 0">
                    <joint name="joint7" axis="0 0 1"/>
                    <site name="flange" pos="0 0 0.107"/>
                  </body>
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def test_nominal_panda_matches_menagerie_tree(panda: RobotModel, rng) -> None:
    mujoco = pytest.importorskip("mujoco")
    model = mujoco.MjModel.from_xml_string(MENAGERIE_PANDA)
    data = mujoco.MjData(model)
    q = panda.random_configurations(1000, rng)
    site = model.site("flange").id
    reference = np.empty((len(q), 3))
    for k, qk in enumerate(q):
        data.qpos[:] = qk
        mujoco.mj_kinematics(model, data)
        reference[k] = data.site_xpos[site]
    # Menagerie rounds its quaternions to 7 digits (0.7071068): normalised, that is an
    # exact quarter turn to ~1e-15, so the trees agree to far below 1e-9 m.
    np.testing.assert_allclose(tool_point(panda, q), reference, rtol=0, atol=1e-9)


def test_panda_zero_pose_is_the_published_one(panda: RobotModel) -> None:
    # At q = 0 the flange is 0.088 m forward and 0.333 + 0.316 + 0.384 - 0.107 m up.
    np.testing.assert_allclose(tool_point(panda, np.zeros(7)), [0.088, 0, 0.926], atol=1e-15)


def _central_difference(function, x: np.ndarray, step: float) -> np.ndarray:
    columns = []
    for k in range(x.size):
        dx = np.zeros_like(x)
        dx[k] = step
        columns.append((function(x + dx) - function(x - dx)) / (2 * step))
    return np.stack(columns, axis=-1)


def _generic(panda: RobotModel, convention: str, rng) -> RobotModel:
    model = perturbed(panda, rng, scale=20.0)  # 2 cm, 4 deg: nothing special left
    model = to_standard(model) if convention == "standard" else model
    # a non-trivial base and tool so every column is exercised
    params = model.params.copy()
    params[-9:] += rng.normal(0, 0.3, 9)
    return model.with_params(params)


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_parameter_jacobian_equals_central_differences(panda, convention, rng) -> None:
    for _ in range(3):
        model = _generic(panda, convention, rng)
        q = model.random_configurations(20, rng)
        analytic = param_jacobian(model, q)
        numeric = _central_difference(
            lambda x, m=model, q=q: tool_point(m.with_params(x), q), model.params, 1e-6
        )
        assert analytic.shape == (20, 3, model.n_params)
        scale = np.abs(numeric).max()
        assert np.abs(analytic - numeric).max() / scale < 1e-6


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_joint_jacobian_equals_central_differences(panda, convention, rng) -> None:
    model = _generic(panda, convention, rng)
    q = model.random_configurations(50, rng)
    analytic = joint_jacobian(model, q)
    numeric = np.stack(
        [
            (tool_point(model, q + 1e-6 * e) - tool_point(model, q - 1e-6 * e)) / 2e-6
            for e in np.eye(model.n_joints)
        ],
        axis=-1,
    )
    assert analytic.shape == (50, 3, 7)
    assert np.abs(analytic - numeric).max() / np.abs(numeric).max() < 1e-6


def _stencil(f, q: np.ndarray, h: float) -> np.ndarray:
    """(N, m, n) five-point central differences of ``f`` (N, n) -> (N, m) at ``q`` (N, n): error ~h^4."""
    out = []
    for k in range(q.shape[1]):
        e = h * np.eye(q.shape[1])[k]
        out.append((-f(q + 2 * e) + 8 * f(q + e) - 8 * f(q - e) + f(q - 2 * e)) / (12 * h))
    return np.stack(out, axis=-1)


@pytest.mark.parametrize("extras", ["scale", "compliance", "both"])
def test_link_angle_jacobian_is_within_1e_12_of_the_exact_derivative(panda, extras, rng) -> None:
    """h2's review: the Jacobian differenced the whole map q -> q_link with a 1e-6 step, so the angles' own rounding
    (~3 rad x 1e-16 / 2e-6) left a 2e-10 floor under a docstring promising 1e-12. References: (a) the formula
    (I - diag(c) d tau / d q_joint) diag(1 + s), d tau by a five-point stencil of the torque alone with a 1e-3 step
    (truncation ~1e-12 of tau's fifth derivative, times c; rounding ~1e-16 |tau| / 1e-3: ~1e-15 in all); (b) a
    five-point stencil of the whole map, step 1e-3 (its own rounding ~5e-13), which shares no formula with it."""
    c = np.array([0.0, 2e-5, 3e-5, 4e-5, 1e-5, 5e-6, 1e-5]) if extras != "scale" else np.zeros(7)
    s = np.array([1e-3, -2e-3, 0.0, 5e-4, 0.0, 1e-3, -1e-3]) if extras != "compliance" else np.zeros(7)
    model = with_scale(with_compliance(panda, c if extras != "scale" else None), s if extras != "compliance" else None)
    q = model.random_configurations(20, rng)
    jac = link_angle_jacobian(model, q)
    slope = _stencil(lambda x: c * gravity_torques(model, x), joint_angles(model, q), 1e-3)
    np.testing.assert_allclose(jac, (np.eye(7) - slope) * (1 + s), rtol=0, atol=1e-12)
    whole = _stencil(lambda x: _link_angles(model, x), q, 1e-3)
    np.testing.assert_allclose(jac, whole, rtol=0, atol=2e-12)
    old = _stencil(lambda x: _link_angles(model, x), q, 1e-6)  # (the old way, a 1e-6 step on the whole map, fails)
    assert np.abs(old - whole).max() > 2e-11
    np.testing.assert_array_equal(link_angle_jacobian(model, q[3]), jac[3])
    assert link_angle_jacobian(with_scale(panda, np.zeros(7)), q) is None


@pytest.mark.parametrize("convention", ["standard", "modified"])
def test_frames_pose_and_point_agree(panda, convention, rng) -> None:
    model = _generic(panda, convention, rng)
    q = model.random_configurations(30, rng)
    frames = link_frames(model, q)
    assert frames.shape == (30, 8, 4, 4)
    # every frame is a rigid transform
    rotations = frames[..., :3, :3]
    np.testing.assert_allclose(
        rotations @ np.swapaxes(rotations, -1, -2), np.broadcast_to(np.eye(3), rotations.shape),
        atol=1e-12,
    )
    pose = tool_pose(model, q)
    np.testing.assert_allclose(pose[:, :3, :3], frames[:, -1, :3, :3], atol=1e-15)
    expected = frames[:, -1, :3, :3] @ model.tool + frames[:, -1, :3, 3]
    np.testing.assert_allclose(pose[:, :3, 3], expected, atol=1e-12)
    np.testing.assert_allclose(tool_point(model, q), expected, atol=1e-12)
    # one configuration drops the batch axis
    np.testing.assert_allclose(tool_point(model, q[0]), expected[0], atol=1e-12)
    assert param_jacobian(model, q[0]).shape == (3, model.n_params)




def test_frames_follow_the_convention_definition(panda, rng) -> None:
    """Each link transform is the product the convention defines, built here by hand."""
    trans = shift

    for convention in ("standard", "modified"):
        model = _generic(panda, convention, rng)
        q = model.random_configurations(1, rng)[0]
        pose = model.base_transform
        for i in range(7):
            a, al, d, th = model.a[i], model.alpha[i], model.d[i], model.theta[i]
            if convention == "standard":
                link = rot(2, th + q[i]) @ trans(2, d) @ trans(0, a) @ rot(0, al)
            else:
                link = rot(0, al) @ trans(0, a) @ rot(2, th + q[i]) @ trans(2, d)
            pose = pose @ link
        np.testing.assert_allclose(link_frames(model, q)[-1], pose, atol=1e-12)


def test_conversion_keeps_every_tool_point(panda, rng) -> None:
    for _ in range(5):
        modified = _generic(panda, "modified", rng)
        q = modified.random_configurations(200, rng)
        standard = to_standard(modified)
        assert standard.convention == "standard"
        np.testing.assert_allclose(tool_point(standard, q), tool_point(modified, q), atol=1e-12)
        back = to_modified(standard)
        np.testing.assert_allclose(tool_point(back, q), tool_point(modified, q), atol=1e-12)
        # a standard arm of its own (non-zero a7, alpha7) converts by adjusting the tool
        other = _generic(panda, "standard", rng)
        np.testing.assert_allclose(
            tool_point(to_modified(other), q), tool_point(other, q), atol=1e-12
        )


def test_panda_standard_has_identity_base_and_adjusted_tool(panda) -> None:
    standard = to_standard(panda)
    np.testing.assert_allclose(standard.base_transform, np.eye(4), atol=1e-15)
    np.testing.assert_allclose(standard.a, [0, 0, 0.0825, -0.0825, 0, 0.088, 0])


def test_bad_shapes_are_refused(panda) -> None:
    with pytest.raises(ValueError, match=r"q must have shape"):
        tool_point(panda, np.zeros((4, 6)))
    with pytest.raises(ValueError, match=r"params must have shape"):
        panda.with_params(np.zeros(3))


@pytest.mark.parametrize("entry", [tool_point, tool_pose, joint_jacobian, param_jacobian, link_angle_jacobian,
                                   pose_jacobian])
def test_joint_angles_in_degrees_are_refused_at_every_public_entry(panda, entry) -> None:
    """A reviewer: tool_point(model, q) with q in degrees returned a tool point metres away without a word. An angle
    more than a full turn beyond its joint's limits is refused with the package's own exception, naming the sample,
    the joint and the limits; an angle a turn past them less a hair (a wrapped encoder, an arm beyond its file's
    limits) is still computed."""
    q = panda.random_configurations(50, np.random.default_rng(3))
    with pytest.raises(JointAngleError, match=r"^q\[\d+, \d\] \(joint \d\): .* rad is more than a full turn .* "
                       r"beyond the joint limits \[.*\] of franka_panda: no angle of this joint \(degrees\?"):
        entry(panda, np.degrees(q))
    with pytest.raises(SpherecalError, match=r"^q\[3\] \(joint 4\): -20 rad"):
        entry(panda, np.where(np.arange(7) == 3, -20.0, q[0]))
    edge = np.tile(q[0], (2, 1))
    edge[0, 5], edge[1, 0] = panda.upper[5] + ANGLE_MARGIN - 1e-9, panda.lower[0] - ANGLE_MARGIN + 1e-9
    out = entry(panda, edge)  # link_angle_jacobian: None for a rigid arm
    assert out is None or np.all(np.isfinite(out))


def test_a_joint_that_turns_freely_takes_any_number_of_turns(panda) -> None:
    """A URDF 'continuous' joint is read as [-pi, pi] and counts its turns (a wrist turned five times reads 31 rad):
    no angle of it is refused; a revolute joint limited to [-pi, pi] (a UR elbow, named so by its URDF) is."""
    free = replace(panda, lower=np.full(7, -np.pi), upper=np.full(7, np.pi))
    assert free.full_turn.all()
    q = np.full(7, 10 * np.pi + 0.3)
    assert np.allclose(tool_point(free, q), tool_point(free, q - 10 * np.pi))
    names = [f"j{i + 1}" for i in range(7)]
    limited = replace(free, extras={"joint_names": names, "urdf": {"continuous_joints": names[1:]}})
    with pytest.raises(JointAngleError, match=r"^q\[0\] \(joint 1\): 31.7159 rad"):
        tool_point(limited, q)


@pytest.mark.parametrize("entry", [tool_point, tool_pose, joint_jacobian, param_jacobian, link_angle_jacobian])
def test_angles_of_another_arm_raise_our_shape_error_naming_the_shape_given(panda, entry) -> None:
    """h7's API review: a wrong shape raised numpy's ValueError family only, and gravity_torques named the shape it
    had made of it ('got (1, 6)' for (6,)); ShapeError is ours (the command line's one line) and a ValueError."""
    from spherecal.correction import ShapeError, gravity_torques

    for function in (entry, gravity_torques):
        with pytest.raises(ShapeError, match=r"q must have shape \(N, 7\) or \(7,\), got \(6,\)") as raised:
            function(panda, np.zeros(6))
        assert isinstance(raised.value, ValueError)
