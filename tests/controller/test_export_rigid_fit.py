"""`export --format urdf` of a model with joint compliance: the best rigid fit to the full model, read back by
MuJoCo's URDF compiler, is never farther from the full model than the URDF of the geometric part alone."""

from __future__ import annotations

from dataclasses import replace

import mujoco
import numpy as np
import pytest

from spherecal.cli import main
from spherecal.controller.export import export_model
from spherecal.controller.rigid_fit import geometric_part, rigid_approximation
from spherecal.correction import Dataset, load_robot, perturb, save_robot, tool_point, write_samples
from spherecal.correction.elastic import with_compliance
from spherecal.correction.files.provenance import input_record
from spherecal.correction.files.urdf_write import robot_to_urdf
from tests.correction.urdf_helpers import mujoco_ready

COMPLIANCE = np.array([0.0, 1 / 2e4, 1 / 3e4, 1 / 3e4, 1 / 1e4, 1 / 1e4, 0.0])


def _urdf_tool(text: str, q: np.ndarray) -> np.ndarray:
    """(N, 3) flange (panda_link8) positions of a URDF compiled by MuJoCo [m]."""
    mj = mujoco.MjModel.from_xml_string(mujoco_ready(text))
    data = mujoco.MjData(mj)
    body = mujoco.mj_name2id(mj, mujoco.mjtObj.mjOBJ_BODY, "panda_link8")
    out = np.empty((len(q), 3))
    for k, qk in enumerate(q):
        data.qpos[:] = qk
        mujoco.mj_kinematics(mj, data)
        out[k] = data.xpos[body]
    return out


def _rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((a - b) ** 2, axis=1))))


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_rigid_fit_urdf_is_never_worse_than_the_plain_dh_urdf(tmp_path, capsys, seed) -> None:
    rng = np.random.default_rng(seed)
    model = with_compliance(perturb(load_robot("panda"), rng), COMPLIANCE * rng.uniform(0.5, 1.5, 7))
    # the recording: three sockets' worth of configurations, in a corner of the workspace
    centre = rng.uniform(model.lower + 0.5, model.upper - 0.5)
    recorded = np.clip(centre + rng.normal(0.0, 0.3, (300, 7)), model.lower, model.upper)
    samples = write_samples(tmp_path / "samples.csv", Dataset(np.repeat(["a", "b", "c"], 100), recorded))
    model = replace(model, extras={**model.extras, "calibration": {"inputs": {"samples": input_record(samples)}}})
    cal = save_robot(model, tmp_path / "cal.yaml")
    out = tmp_path / "cal.urdf"
    assert main(["export", str(cal), "--format", "urdf", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "a URDF cannot carry c1" in printed and "300 recorded configurations from" in printed
    plain = robot_to_urdf(geometric_part(model))  # the URDF export wrote before: the terms dropped
    workspace = model.random_configurations(1000, rng)
    for q in (recorded, workspace):
        full = tool_point(model, q)
        fitted, dropped = _rms(_urdf_tool(out.read_text(), q), full), _rms(_urdf_tool(plain, q), full)
        assert dropped > 2e-4  # the compliance matters
        assert fitted <= 0.8 * dropped, (fitted, dropped)  # never worse, and here clearly better
    assert f"{rigid_approximation(model, recorded).workspace_rms * 1e3:.3f} mm rms" in printed


def test_rigid_model_is_exported_unchanged_and_other_formats_keep_every_term(panda, rng) -> None:
    model = perturb(panda, rng)
    exported = export_model(model, "urdf")
    assert exported.text == robot_to_urdf(model) and exported.notes == () and exported.fit.terms == ()
    elastic = with_compliance(model, COMPLIANCE)
    assert "compliance" in export_model(elastic, "yaml").text
    assert "flex2" in export_model(elastic, "mjcf").text  # the plant's flexible hinge behind the motor
    with pytest.raises(Exception, match="--samples: only the urdf format"):
        export_model(elastic, "yaml", samples="x.csv")
