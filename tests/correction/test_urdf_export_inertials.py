"""The standalone URDF export carries the model's link inertials, checked with MuJoCo's URDF compiler.

MuJoCo compiles the exported text as is (no ``<mujoco>`` extension); its gravity torques (``qfrc_bias`` at
rest) equal :func:`correction.gravity.gravity_torques` of the exported (calibrated) model, the tool link's body
sits at :func:`correction.tool_point`, and the inertia tensors give the mass matrix of the original URDF (the
Gen3 lite's own ``<inertial>`` elements, lumped per DH link and turned into the exported frames).
"""

from __future__ import annotations

import warnings
import xml.etree.ElementTree as ET
from dataclasses import replace

import numpy as np
import pytest

from spherecal.correction import convert, load_urdf, tool_point
from spherecal.correction.files.urdf_write import dynamics_note, robot_to_urdf
from spherecal.correction.gravity import gravity_torques
from spherecal.correction.inertia import lumped
from spherecal.correction.inertials import link_inertias
from tests.conftest import perturbed
from tests.correction.urdf_helpers import DATA, mujoco_ready

mujoco = pytest.importorskip("mujoco")

CONFIGURATIONS = 20


def _gen3lite(convention: str = "modified"):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its nearly parallel joints 2-3 (Hayati beta), tested elsewhere
        return load_urdf(DATA / "gen3lite.urdf", tip_link="ball_link", convention=convention)


def _urdf(model) -> str:
    limits = {} if model.n_joints == 7 else {"effort": [10.0] * model.n_joints, "velocity": [1.0] * model.n_joints}
    return robot_to_urdf(model, prefix="arm_", **limits)


def _joints(mj, names):
    ids = [mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_JOINT, name) for name in names]
    assert min(ids) >= 0, names
    return [mj.jnt_qposadr[j] for j in ids], [mj.jnt_dofadr[j] for j in ids]


def _mass_matrices(mj, names, q):
    """(N, n, n) joint-space inertia of the named joints at angles ``q`` (other joints at 0)."""
    data = mujoco.MjData(mj)
    qpos, dof = _joints(mj, names)
    out = []
    for qk in q:
        data.qpos[:] = 0.0
        data.qpos[qpos] = qk
        mujoco.mj_forward(mj, data)
        full = np.zeros((mj.nv, mj.nv))
        mujoco.mj_fullM(mj, data, full)
        out.append(full[np.ix_(dof, dof)])
    return np.array(out)


@pytest.mark.parametrize("arm", ["panda", "gen3lite"])
@pytest.mark.parametrize("convention", ["modified", "standard"])
def test_exported_urdf_gives_mujocos_gravity_and_tool_point(arm, convention, panda, rng) -> None:
    nominal = panda if arm == "panda" else _gen3lite()
    model = perturbed(convert(nominal, convention) if convention != "modified" else nominal, rng)  # "calibrated"
    assert link_inertias(model).tensors.any() and not link_inertias(model).estimated.any()
    text = _urdf(model)
    assert dynamics_note(model) is None
    mj = mujoco.MjModel.from_xml_string(text)  # as written: no <mujoco> extension, no bound on masses
    assert mj.nv == model.n_joints
    names = [f"arm_joint{i + 1}" for i in range(model.n_joints)]
    qpos, dof = _joints(mj, names)
    data = mujoco.MjData(mj)
    q = model.random_configurations(CONFIGURATIONS, rng)
    reference = []
    for qk in q:
        data.qpos[qpos], data.qvel[:] = qk, 0.0
        mujoco.mj_forward(mj, data)
        reference.append(data.qfrc_bias[dof].copy())  # at rest: the torques that hold the arm up
    reference = np.array(reference)
    ours = gravity_torques(model, q)
    assert np.abs(reference).max() > 1.0
    assert np.abs(ours - reference).max() <= 1e-6 * np.abs(reference).max()
    # the tool link is a body when MuJoCo keeps fixed links (its URDF default fuses them into the flange)
    spec = mujoco.MjSpec.from_string(text)
    spec.compiler.fusestatic = False
    kept = spec.compile()
    body = mujoco.mj_name2id(kept, mujoco.mjtObj.mjOBJ_BODY, f"arm_link{model.n_joints + 1}")
    kept_data = mujoco.MjData(kept)
    qpos, _ = _joints(kept, names)
    points = []
    for qk in q:
        kept_data.qpos[qpos] = qk
        mujoco.mj_kinematics(kept, kept_data)
        points.append(kept_data.xpos[body].copy())
    np.testing.assert_allclose(np.array(points), tool_point(model, q), rtol=0.0, atol=1e-9)


@pytest.mark.parametrize("convention", ["modified", "standard"])
def test_exported_tensors_give_the_original_urdfs_mass_matrix(convention, rng) -> None:
    model = _gen3lite(convention)  # the nominal chain: its joints are the URDF's joints exactly
    # MuJoCo bounds the original's massless bodies (the difference scales with the bound: 2e-9 at 1e-9 kg)
    original = mujoco.MjModel.from_xml_string(
        mujoco_ready((DATA / "gen3lite.urdf").read_text(), boundmass="1e-12", boundinertia="1e-14"))
    exported = mujoco.MjModel.from_xml_string(_urdf(model))
    q = model.random_configurations(5, rng)
    reference = _mass_matrices(original, model.extras["joint_names"], q)
    ours = _mass_matrices(exported, [f"arm_joint{i + 1}" for i in range(model.n_joints)], q)
    assert np.abs(reference).max() > 0.1
    np.testing.assert_allclose(ours, reference, rtol=0.0, atol=1e-10 * np.abs(reference).max())


def test_panda_tensors_agree_in_both_conventions(panda, rng) -> None:
    """The standard chain's links are other frames (inertials moved by the conversion, then by each joint's
    trailing transform); MuJoCo's mass matrix of the two exports is the same arm's."""
    model = perturbed(panda, rng)
    q = model.random_configurations(5, rng)
    names = [f"arm_joint{i + 1}" for i in range(7)]
    modified = _mass_matrices(mujoco.MjModel.from_xml_string(_urdf(model)), names, q)
    standard = _mass_matrices(mujoco.MjModel.from_xml_string(_urdf(convert(model, "standard"))), names, q)
    assert np.abs(modified).max() > 0.5
    np.testing.assert_allclose(standard, modified, rtol=0.0, atol=1e-9 * np.abs(modified).max())


def test_without_inertials_the_file_is_kinematics_only_and_says_so(panda) -> None:
    bare = replace(panda, extras={})
    text = _urdf(bare)
    assert not list(ET.fromstring(text).iter("inertial")) and "kinematics only" in text
    note = dynamics_note(bare)
    assert note is not None and "--inertials FILE" in note and "--into" in note
    with pytest.raises(ValueError, match="mass"):  # what the note is about: MuJoCo refuses massless links
        mujoco.MjModel.from_xml_string(text)
    assert len(list(ET.fromstring(_urdf(panda)).iter("inertial"))) == 8  # 7 links and the hand


def test_a_missing_tensor_is_a_sphere_and_named(panda, rng) -> None:
    entries = [dict(e) for e in panda.extras["inertials"]]
    entries[2].pop("inertia")
    model = replace(panda, extras={**panda.extras, "inertials": entries})
    note = dynamics_note(model)
    assert note is not None and "link 3" in note and "link 2" not in note and "payload" not in note
    mj = mujoco.MjModel.from_xml_string(_urdf(model))
    body = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_BODY, "arm_link3")
    np.testing.assert_allclose(mj.body_inertia[body], 0.4 * entries[2]["mass"] * 0.05**2 * np.ones(3), rtol=1e-12)


def test_lumped_matches_point_masses_and_the_parallel_axis_theorem() -> None:
    r, m = 0.3, 2.0  # two point masses at +-r on x: I = diag(0, 2 m r^2, 2 m r^2) about the middle
    mass, com, tensor = lumped([m, m], [[r, 0, 0], [-r, 0, 0]], np.zeros((2, 3, 3)))
    assert mass == 2 * m
    np.testing.assert_allclose(com, 0.0, atol=1e-15)
    np.testing.assert_allclose(tensor, np.diag([0.0, 2 * m * r**2, 2 * m * r**2]), atol=1e-15)
    rod = np.diag([0.0, 1.0, 1.0]) * m * (2 * r) ** 2 / 12  # a thin rod about its centre, and shifted by r
    _, com, tensor = lumped([m, 0.0], [[r, 0, 0], [0, 0, 0]], np.array([rod, np.zeros((3, 3))]))
    np.testing.assert_allclose(com, [r, 0, 0])
    np.testing.assert_allclose(tensor, rod, atol=1e-15)


@pytest.mark.parametrize("bad", ["[0.1, 0, 0, 0.1, 0]", "[-0.1, 0, 0, 0.1, 0, 0.1]", "[1e9, 0, 0, 1, 0, 1]"])
def test_a_malformed_tensor_is_refused_in_one_line(tmp_path, panda, bad) -> None:
    from spherecal.correction.files.inertials_file import with_inertials_file
    from spherecal.correction.gravity import InertialsError

    lines = [f"  - {{mass: 1.0, com: [0.0, 0.0, 0.0]{', inertia: ' + bad if k == 2 else ''}}}" for k in range(7)]
    path = tmp_path / "masses.yaml"
    path.write_text("inertials:\n" + "\n".join(lines) + "\n")
    with pytest.raises(InertialsError) as error:
        with_inertials_file(panda, path)
    message = str(error.value)
    assert "\n" not in message and str(path) in message and "row 4" in message and "inertials[2].inertia" in message
