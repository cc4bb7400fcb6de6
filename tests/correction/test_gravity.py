"""Gravity torques against MuJoCo's own dynamics (qfrc_bias at rest) and the Panda's URDF frames."""

from dataclasses import replace

import mujoco
import numpy as np
import pytest

from spherecal.correction import RobotModel, link_frames, load_robot, rpy_matrix
from spherecal.correction.gravity import _PREPARED, InertialsError, gravity_torques, inertials_of


def _quat(rotation):
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(rotation).ravel())
    return quat


def _mjcf(model: RobotModel) -> str:
    """Inline MJCF: body i placed by link_frames at q = 0, inertial at the COM of inertials_of."""
    masses, coms = inertials_of(model)
    frames = link_frames(model, np.zeros(model.n_joints))
    v = lambda a: " ".join(format(float(x), ".17g") for x in np.ravel(a))  # noqa: E731
    base = frames[0]
    xml = [f'<mujoco><option gravity="0 0 -9.81"/><worldbody><body pos="{v(base[:3, 3])}" '
           f'quat="{v(_quat(base[:3, :3]))}">']
    for i in range(model.n_joints):
        parent, child = frames[i], frames[i + 1]
        rot = parent[:3, :3].T @ child[:3, :3]
        pos = parent[:3, :3].T @ (child[:3, 3] - parent[:3, 3])
        if model.convention == "modified":
            jpos, axis = np.zeros(3), np.array([0, 0, 1.0])
        else:
            jpos, axis = -rot.T @ pos, rot.T @ np.array([0, 0, 1.0])
        xml.append(f'<body pos="{v(pos)}" quat="{v(_quat(rot))}">'
                   f'<inertial pos="{v(coms[i])}" mass="{float(masses[i])!r}" diaginertia="0.01 0.01 0.01"/>'
                   f'<joint type="hinge" pos="{v(jpos)}" axis="{v(axis)}"/>')
    xml.append(f'<body><inertial pos="{v(coms[-1])}" mass="{float(masses[-1])!r}" diaginertia="0.001 0.001 0.001"/>'
               "</body>")
    xml.append("</body>" * (model.n_joints + 1) + "</worldbody></mujoco>")
    return "".join(xml)


def _mujoco_bias(model: RobotModel, q: np.ndarray) -> np.ndarray:
    mj = mujoco.MjModel.from_xml_string(_mjcf(model))
    data = mujoco.MjData(mj)
    out = np.empty_like(q)
    for k, qk in enumerate(q):
        data.qpos[:] = qk
        data.qvel[:] = 0.0
        mujoco.mj_forward(mj, data)
        out[k] = data.qfrc_bias
    return out


def _random_inertials(model: RobotModel, rng) -> RobotModel:
    extras = {
        "inertials": [{"mass": float(rng.uniform(0.5, 4)), "com": rng.normal(0, 0.08, 3).tolist()}
                      for _ in range(model.n_joints)],
        "payload": {"mass": 0.8, "com": rng.normal(0, 0.05, 3).tolist()},
    }
    return replace(model, extras=extras)


def test_panda_matches_mujoco_qfrc_bias():
    panda = load_robot("panda")
    q = panda.random_configurations(20, np.random.default_rng(1))
    ours, theirs = gravity_torques(panda, q), _mujoco_bias(panda, q)
    assert np.abs(theirs).max() > 10.0  # real loads, not a trivially zero comparison
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-9 * np.abs(theirs).max())


def test_standard_dh_tilted_base_matches_mujoco():
    rng = np.random.default_rng(2)
    arm = RobotModel(
        name="arm6", convention="standard", a=rng.uniform(-0.3, 0.3, 6), alpha=rng.uniform(-2, 2, 6),
        d=rng.uniform(-0.3, 0.3, 6), theta=rng.uniform(-1, 1, 6), lower=-np.full(6, 3.0), upper=np.full(6, 3.0),
        tool=[0.0, 0.05, 0.1], base_xyz=[0.1, -0.2, 0.3], base_rpy=[0.3, -0.2, 0.5],
    )
    arm = _random_inertials(arm, rng)
    q = arm.random_configurations(15, rng)
    ours, theirs = gravity_torques(arm, q), _mujoco_bias(arm, q)
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-9 * np.abs(theirs).max())
    # one configuration gives the batch row, and a sideways gravity changes the answer
    np.testing.assert_allclose(gravity_torques(arm, q[3]), ours[3], atol=1e-12)
    assert np.abs(gravity_torques(arm, q, g=[9.81, 0, 0]) - ours).max() > 1.0


def _urdf_chain(q: np.ndarray) -> list[np.ndarray]:
    """franka_description's panda_link1..7 in the world: joint origins (xyz, rpy) then Rz(q)."""
    h = np.pi / 2
    origins = [((0, 0, 0.333), (0, 0, 0)), ((0, 0, 0), (-h, 0, 0)), ((0, -0.316, 0), (h, 0, 0)),
               ((0.0825, 0, 0), (h, 0, 0)), ((-0.0825, 0.384, 0), (-h, 0, 0)), ((0, 0, 0), (h, 0, 0)),
               ((0.088, 0, 0), (h, 0, 0))]
    pose, out = np.eye(4), []
    for (xyz, rpy), angle in zip(origins, q, strict=True):
        joint = np.eye(4)
        joint[:3, :3], joint[:3, 3] = rpy_matrix(np.array(rpy, float)), xyz
        turn = np.eye(4)
        turn[:3, :3] = rpy_matrix(np.array([0, 0, angle]))
        pose = pose @ joint @ turn
        out.append(pose)
    return out


def test_panda_dh_frames_are_the_urdf_link_frames():
    """The published COMs are in URDF link frames: those must be our DH frames for the numbers to apply."""
    panda = load_robot("panda")
    for q in panda.random_configurations(5, np.random.default_rng(3)):
        ours = link_frames(panda, q)[1:]
        for mine, theirs in zip(ours, _urdf_chain(q), strict=True):
            np.testing.assert_allclose(mine, theirs, atol=1e-12)


def test_bad_inertials_name_the_field():
    panda = load_robot("panda")
    with pytest.raises(InertialsError, match="'inertials': expected a list of 7"):
        inertials_of(replace(panda, extras={}))
    bad = [dict(e) for e in panda.extras["inertials"]]
    bad[2] = {"mass": -1.0, "com": [0, 0, 0]}
    with pytest.raises(InertialsError, match=r"'inertials\[2\].mass'"):
        inertials_of(replace(panda, extras={"inertials": bad}))
    with pytest.raises(InertialsError, match="'payload.com'"):
        inertials_of(replace(panda, extras={**panda.extras, "payload": {"mass": 1.0, "com": [0, 0]}}))


def test_kept_loads_follow_the_model_and_its_blocks(rng):
    """gravity_torques keeps each model's chain and loads (_PREPARED, one named record per model): a model with other
    loads, explicit masses, and the first model again each get their own torques, which equal those computed from
    explicit masses and centres (the path that keeps nothing), one configuration (Python floats) and a batch alike."""
    panda = load_robot("panda")
    heavier = replace(panda, extras={**panda.extras, "payload": {"mass": 2.5, "com": [0.0, 0.0, 0.2]}})
    q = panda.random_configurations(6, rng)
    for model in (panda, heavier, panda):
        masses, coms = inertials_of(model)
        for angles in (q, q[0]):
            np.testing.assert_array_equal(gravity_torques(model, angles), gravity_torques(model, angles, masses, coms))
        kept = _PREPARED[id(model)]
        assert kept.model is model and kept.block is model.extras["inertials"]
        assert kept.payload is model.extras.get("payload") and kept.rows == kept.bodies.tolist()
    assert np.abs(gravity_torques(heavier, q) - gravity_torques(panda, q)).max() > 1.0  # 1.74 kg more at the flange
    held = _PREPARED[id(panda)].bodies
    lighter = gravity_torques(panda, q, *inertials_of(replace(panda, extras={"inertials": panda.extras["inertials"]})))
    assert np.abs(lighter - gravity_torques(panda, q)).max() > 0.1  # explicit loads: not the kept ones ...
    assert _PREPARED[id(panda)].bodies is held  # ... nor kept in their place
