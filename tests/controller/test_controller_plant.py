"""The MuJoCo plant: generated MJCF against correction's kinematics, fixtures engage/release."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from spherecal.controller.plant import build_plant
from spherecal.correction import link_frames, to_standard, tool_point
from tests.conftest import perturbed


@pytest.mark.parametrize("convention", ["modified", "standard"])
@pytest.mark.parametrize("kind", ["nominal", "perturbed"])
def test_sites_equal_forward_kinematics(panda, rng, convention, kind):
    model = panda if convention == "modified" else to_standard(panda)
    if kind == "perturbed":
        model = perturbed(model, rng, scale=5.0)  # base moved too
    markers = np.array([[0.05, 0.0, 0.1], [-0.03, 0.04, 0.08], [0.0, -0.06, 0.12]])
    plant = build_plant(model, {"P1": [0.5, 0.0, 0.4]}, markers=markers)
    q = model.random_configurations(1000, rng)
    sites = np.append(plant.marker_sites, plant.tool_site)
    got = plant.site_positions(q, sites)
    frames = link_frames(model, q)[:, -1]
    expected_markers = np.einsum("nij,mj->nmi", frames[:, :3, :3], markers) + frames[:, None, :3, 3]
    assert np.abs(got[:, -1] - tool_point(model, q)).max() < 1e-9
    assert np.abs(got[:, :-1] - expected_markers).max() < 1e-9
    # every body frame is the model's link frame
    data = mujoco.MjData(plant.mj_model)
    for qk, fk in zip(q[:20], link_frames(model, q[:20]), strict=True):
        data.qpos[:] = qk
        mujoco.mj_kinematics(plant.mj_model, data)
        assert np.abs(data.xpos[1:] - fk[:, :3, 3]).max() < 1e-9
        assert np.abs(data.xmat[1:].reshape(-1, 3, 3) - fk[:, :3, :3]).max() < 1e-9


def test_plant_settings_and_fixtures(panda):
    plant = build_plant(panda, {"A": [0.5, 0.0, 0.4], "B": [0.4, 0.2, 0.3]})
    m = plant.mj_model
    assert m.opt.timestep == pytest.approx(1e-3)
    assert m.neq == 2 and m.nu == panda.n_joints
    assert np.allclose(m.eq_solref[:, 0], 0.002)
    assert np.allclose(m.jnt_range, np.stack([panda.lower, panda.upper], axis=1))
    assert not plant.mj_data.eq_active.any()
    plant.engage("B")
    assert plant.mj_data.eq_active.tolist() == [0, 1]
    plant.release()
    assert not plant.mj_data.eq_active.any()
    with pytest.raises(KeyError):
        plant.engage("C")


def test_engaged_fixture_holds_tool_point(panda, rng):
    from spherecal.controller.self_motion import reach_fixture

    centre = np.array([0.5, 0.0, 0.4])
    plant = build_plant(panda, {"A": centre})
    plant.set_state(reach_fixture(panda, "A", centre, rng))
    plant.engage("A")
    plant.mj_data.qvel[:] = rng.normal(0.0, 0.2, panda.n_joints)  # push it around, no control
    for _ in range(300):
        mujoco.mj_step(plant.mj_model, plant.mj_data)
    mujoco.mj_forward(plant.mj_model, plant.mj_data)
    assert np.linalg.norm(plant.tool_position() - centre) < 2e-4
    plant.release()  # released: it falls away (gravity compensation is on, velocity stays)


def test_names_with_xml_characters_compile(panda):
    from dataclasses import replace

    from spherecal.controller.plant import build_mjcf

    text = build_mjcf(replace(panda, name='arm "x" & <y>'), fixtures={"a--b": np.zeros(3), 'c"': np.ones(3)})
    import xml.etree.ElementTree as ET

    root = ET.fromstring(text)
    assert root.get("model") == 'arm "x" & <y>'
    assert [s.get("name") for s in root.iter("site") if s.get("name", "").startswith("fixture")] == [
        "fixture0", "fixture1"]
    mujoco.MjModel.from_xml_string(text)
def test_a_mujoco_warning_writes_no_log_file_into_the_working_directory(tmp_path) -> None:
    # MuJoCo's default warning handler appends to MUJOCO_LOG.TXT in the cwd (the user's folder)
    import os
    import subprocess
    import sys
    from pathlib import Path

    code = (
        "import numpy as np, mujoco; from spherecal.correction import load_robot;"
        "from spherecal.controller.plant import build_plant;"
        "p = build_plant(load_robot('panda')); p.mj_data.qvel[:] = np.nan; mujoco.mj_step(p.mj_model, p.mj_data);"
        "print('warned', p.mj_data.warning[mujoco.mjtWarning.mjWARN_BADQVEL].number)"
    )
    root = str(Path(__file__).parents[2])
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=60,
                         env={**os.environ, "PYTHONPATH": root})
    assert out.returncode == 0, out.stderr
    assert "warned 1" in out.stdout and "Nan, Inf or huge value in QVEL" in out.stdout + out.stderr
    assert list(tmp_path.iterdir()) == []


def test_a_fixture_no_posture_reaches_is_refused_in_one_line(panda):
    """A controls review: build_plant took a fixture centre in millimetres ([500, 0, 300]) silently and built a plant
    whose fixture no posture reaches. It is refused, naming the fixture and the unit, with a bound from the model's
    own lengths: every tool point the arm reaches passes, an arm twice as long takes what the Panda is refused."""
    from dataclasses import replace

    from spherecal.controller.reach import UnreachableFixtureError
    from spherecal.correction import perturb

    # the position's unit after it, as the other fixture refusals print it (was '... 300.0] is out of reach')
    with pytest.raises(UnreachableFixtureError, match=r"^fixture P2 at \[500.0, 0.0, 300.0\] m is out of reach: "
                                                      r"583.1 m from the base of 'franka_panda'.*unit of fixture "
                                                      r"positions is metres") as raised:
        build_plant(panda, {"P1": [0.5, 0.0, 0.4], "P2": [500.0, 0.0, 300.0]})
    assert raised.value.fixture == "P2" and "\n" not in str(raised.value)
    with pytest.raises(UnreachableFixtureError, match=r"fixture P1 at \[nan, 0.0, 0.4\] m is out of reach"):
        build_plant(panda, {"P1": [np.nan, 0.0, 0.4]})
    # no posture is refused: the farthest tool points of 20000 random configurations of a perturbed arm, and the
    # arm stretched straight up, build
    true = perturb(panda, np.random.default_rng(1))
    points = tool_point(true, true.random_configurations(20000, np.random.default_rng(2)))
    far = points[np.argsort(np.linalg.norm(points, axis=1))[-3:]]
    stretched = tool_point(true, np.zeros(7))
    plant = build_plant(true, {f"F{k}": p for k, p in enumerate([*far, stretched])})
    assert plant.fixture_centres.shape == (4, 3)
    # the bound is the model's: twice the Panda's lengths reach a fixture the Panda cannot
    big = replace(panda, a=2 * panda.a, d=2 * panda.d, tool=2 * panda.tool)
    outside = np.array([1.9, 0.0, 0.6])  # 1.99 m from the base: beyond 1.1 x the Panda's 1.39 m
    with pytest.raises(UnreachableFixtureError, match="fixture A"):
        build_plant(panda, {"A": outside})
    assert build_plant(big, {"A": outside}).fixture_names == ("A",)


@pytest.mark.parametrize("centre, shape", [([0.5, 0.0], r"\(2,\)"), ([[0.5, 0.0, 0.4]], r"\(1, 3\)"),
                                           ([0.5, 0.0, 0.4, 1.0], r"\(4,\)"), ("far", "'far'")])
def test_a_fixture_of_the_wrong_shape_is_refused_naming_it(panda, centre, shape):
    """A review: build_plant({'P1': [0.5, 0.0]}) raised numpy's 'cannot reshape array of size 2 into shape (3,)',
    naming neither the fixture nor what was expected. Our ShapeError (a ValueError too), one line, naming both; a
    (1, 3) row, which reshape took silently, is refused too."""
    from spherecal.correction.errors import ShapeError

    with pytest.raises(ShapeError, match=rf"^fixture P1: expected a position \(3,\) \[m\], got (shape )?{shape}$"):
        build_plant(panda, {"A": [0.5, 0.0, 0.4], "P1": centre})
    assert issubclass(ShapeError, ValueError)


def test_move_fixture_checks_the_centre_as_build_plant_does(panda):
    """A review: Plant.move_fixture put a site anywhere (millimetres, two numbers) without the check build_plant
    runs. It refuses a centre out of reach or of the wrong shape, naming the fixture, and leaves the site where it
    was; a centre in reach moves it."""
    from spherecal.controller.reach import UnreachableFixtureError
    from spherecal.correction.errors import ShapeError

    plant = build_plant(panda, {"A": [0.5, 0.0, 0.4], "B": [0.4, 0.2, 0.3]})
    site = plant.fixture_sites[1]
    with pytest.raises(UnreachableFixtureError, match=r"^fixture B at \[400.0, 200.0, 300.0\] m is out of reach") \
            as raised:
        plant.move_fixture("B", [400.0, 200.0, 300.0])
    assert raised.value.fixture == "B"
    with pytest.raises(ShapeError, match=r"^fixture B: expected a position \(3,\) \[m\], got shape \(2,\)$"):
        plant.move_fixture("B", [0.4, 0.2])
    assert np.array_equal(plant.mj_model.site_pos[site], [0.4, 0.2, 0.3])
    plant.move_fixture("B", np.array([0.45, 0.1, 0.35]))
    assert np.array_equal(plant.mj_model.site_pos[site], [0.45, 0.1, 0.35])
