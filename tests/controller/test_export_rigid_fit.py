"""`export --format urdf` of a model with joint compliance: the best rigid fit to the full model, read back by
MuJoCo's URDF compiler, is never farther from the full model than the URDF of the geometric part alone."""

from __future__ import annotations

import os
from dataclasses import replace

import mujoco
import numpy as np
import pytest

from spherecal.cli import main
from spherecal.controller.export import export_model, recorded_configurations
from spherecal.controller.rigid_fit import rigid_approximation
from spherecal.correction import Dataset, geometric_part, load_robot, perturb, save_robot, tool_point, write_samples
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
    made = {"provenance": {"inputs": {"samples": input_record(samples)}}}
    model = replace(model, extras={**model.extras, "calibration": made})
    cal = save_robot(model, tmp_path / "cal.yaml")
    out = tmp_path / "cal.urdf"
    assert main(["export", str(cal), "--format", "urdf", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "a URDF cannot carry c2, c3, c4, c5, c6:" in printed and "300 recorded configurations from" in printed
    plain = robot_to_urdf(geometric_part(model))  # the URDF export wrote before: the terms dropped
    nearby = np.clip(recorded[:200] + rng.normal(0.0, 0.2, (200, 7)), model.lower, model.upper)  # not fitted
    for q in (recorded, nearby):
        full = tool_point(model, q)
        fitted, dropped = _rms(_urdf_tool(out.read_text(), q), full), _rms(_urdf_tool(plain, q), full)
        assert dropped > 2e-4  # the compliance matters
        assert fitted <= 0.8 * dropped, (fitted, dropped)  # never worse, and here clearly better
    assert f"by {rigid_approximation(model, recorded).workspace_rms * 1e3:.3f} mm rms" in printed
    # exported from another folder: the samples file is found beside the calibrated file by its digest
    here = os.getcwd()
    try:
        os.chdir(tmp_path.parent)
        record = {"path": "samples.csv", "sha256": input_record(samples)["sha256"]}
        moved = replace(model, extras={**model.extras, "calibration": {"provenance": {"inputs": {"samples": record}}}})
        assert recorded_configurations(moved, folder=tmp_path)[0] is not None
        assert recorded_configurations(moved)[0] is None
    finally:
        os.chdir(here)


def test_rigid_model_is_exported_unchanged_and_other_formats_keep_every_term(panda, rng) -> None:
    model = perturb(panda, rng)
    exported = export_model(model, "urdf")
    assert exported.text == robot_to_urdf(model) and exported.notes == () and exported.fit.terms == ()
    elastic = with_compliance(model, COMPLIANCE)
    assert "compliance" in export_model(elastic, "yaml").text
    assert "flex2" in export_model(elastic, "mjcf").text  # the plant's flexible hinge behind the motor
    with pytest.raises(Exception, match="field '--samples': only the urdf format"):
        export_model(elastic, "yaml", samples="x.csv")


def test_real_panda_held_out_sockets_through_the_exported_urdf(tmp_path, capsys) -> None:
    """MUKCa's panda_2_clean (tests/data subset): elastic model trained on front_center, held-out sockets of the
    other placements read through each URDF by correction.load_urdf: the rigid fit keeps most of the full model's
    test MAE, the plain URDF loses it."""
    from pathlib import Path

    from spherecal.correction import load_urdf
    from spherecal.identification.ingest.importers import read_mukca

    data = Path(__file__).resolve().parents[1] / "data" / "mukca"
    robot = str(data / "panda_ball.yaml")
    train = tmp_path / "train"
    assert main(["import", str(data / "panda_2_clean" / "front_center"), "--format", "mukca", "--robot", robot,
                 "--out", str(train)]) == 0
    cal, out = tmp_path / "cal.yaml", tmp_path / "cal.urdf"
    assert main(["calibrate", "--robot", robot, "--samples", str(train / "samples.csv"), "--fixtures",
                 str(train / "fixtures.yaml"), "--model", "elastic", "--out", str(cal)]) == 0
    assert main(["export", str(cal), "--format", "urdf", "--out", str(out)]) == 0
    model = load_robot(cal)
    recording, _ = read_mukca(data / "panda_2_clean", model)
    held = ~np.char.startswith(recording.labels.astype(str), "front_center")

    def test_mae(m) -> float:
        points, labels = tool_point(m, recording.q[held]), recording.labels[held]
        return float(np.mean([np.linalg.norm(points[labels == s] - points[labels == s].mean(axis=0), axis=1).mean()
                              for s in np.unique(labels)]))

    full, fitted = test_mae(model), test_mae(load_urdf(out))
    plain = test_mae(geometric_part(model))
    assert fitted <= plain and fitted < full + 0.3 * (plain - full), (full, fitted, plain)
    # --into MUKCa's own panda.urdf: the same rigid fit, read by MuJoCo at the ball
    from tests.correction.urdf_helpers import DATA, MujocoUrdf

    into = tmp_path / "into.urdf"
    assert main(["export", str(cal), "--format", "urdf", "--into", str(DATA / "panda.urdf"), "--out", str(into)]) == 0
    recorded = read_mukca(data / "panda_2_clean" / "front_center", model)[0].q
    rigid = rigid_approximation(model, recorded).model
    q = recording.q[held][:50]
    ball, _ = MujocoUrdf(into.read_text()).body_pose("ball_link", model.extras["joint_names"], q)
    np.testing.assert_allclose(ball, tool_point(rigid, q), atol=1e-9)


def test_nearly_parallel_axes_without_a_hayati_beta_keep_a_physical_urdf(tmp_path) -> None:
    # A hand-written robot file with joint_3's axis antiparallel to joint_2's as a plain DH alpha = -pi (no Hayati
    # beta), calibrated with a joint-angle scale: alpha3 ends 2.2 mrad off -pi. The rigid fit traded d2 against d3
    # along their common normal and moved both by 17.7 m, and `export --into` MUKCa's gen3lite.urdf refused its own
    # output ('joint joint_2 <origin xyz>' not physical).
    from spherecal.correction.scale import with_scale
    from tests.correction.urdf_helpers import DATA

    nominal = load_robot(os.path.join(os.path.dirname(__file__), "..", "data", "mukca", "gen3lite_ball.yaml"))
    model = nominal.with_params(nominal.params + np.where(
        np.isin(nominal.param_names, ["alpha3"]), 2.2e-3, 0.0))
    model = with_scale(model, np.array([0.0, 0.0, 2e-3, -1.5e-3, 0.0, 0.0]))
    rng = np.random.default_rng(0)
    recorded = np.clip(rng.uniform(-0.5, 0.5, (40, 6)) + np.array([0.0, 0.6, 1.9, 0.0, 1.0, 0.0]),
                       model.lower, model.upper)
    fit = rigid_approximation(model, recorded)
    assert np.all(np.abs(fit.model.d - nominal.d) < 0.05), fit.model.d  # millimetres of calibration, not metres
    assert fit.fit_rms <= fit.dropped_fit_rms and fit.workspace_rms < fit.dropped_workspace_rms
    samples = write_samples(tmp_path / "samples.csv", Dataset(np.repeat(["a", "b"], 20), recorded))
    made = {"provenance": {"inputs": {"samples": input_record(samples)}}}
    cal = save_robot(replace(model, extras={**model.extras, "calibration": made}), tmp_path / "cal.yaml")
    out = tmp_path / "cal.urdf"
    assert main(["export", str(cal), "--format", "urdf", "--into", str(DATA / "gen3lite.urdf"),
                 "--out", str(out)]) == 0
    back = load_robot(out, tip_link="ball_link")
    assert _rms(tool_point(back, recorded), tool_point(fit.model, recorded)) < 1e-6


def test_the_urdf_header_records_the_seed_the_rigid_fit_drew_with(tmp_path, capsys, rng) -> None:
    # was: "seed 0" printed for the rigid fit, "seed: None" in the URDF's header
    model = with_compliance(perturb(load_robot("panda"), rng), COMPLIANCE)
    samples = write_samples(tmp_path / "samples.csv", Dataset(np.repeat(["a", "b", "c"], 20),
                                                               model.random_configurations(60, rng)))
    made = {"provenance": {"inputs": {"samples": input_record(samples)}}}
    cal = save_robot(replace(model, extras={**model.extras, "calibration": made}), tmp_path / "cal.yaml")
    rigid = save_robot(geometric_part(model), tmp_path / "rigid.yaml")
    # a rigid model draws nothing: --seed is refused there (test_a_seed_nothing_random_uses_is_refused), and its
    # header records no seed
    for source, seed, recorded in ((cal, ["--seed", "5"], "seed: 5"), (rigid, [], "seed: None")):
        out = tmp_path / f"{source.stem}.urdf"
        assert main(["export", str(source), "--format", "urdf", "--out", str(out), *seed]) == 0
        text = out.read_text()
        assert recorded in text.splitlines() and text.count("a double hyphen written '- -'") == 1
        # the rigid fit's recorded configurations are an input: named with their SHA-256 (found through the
        # calibration's provenance here); a rigid model draws nothing and reads none
        named = f"samples={samples} (sha256 {input_record(samples)['sha256']})"
        assert (named in text) == (source == cal)
    assert "; seed 5" in capsys.readouterr().out  # the rigid fit's summary: the same seed


def test_the_rigid_fit_says_how_far_it_turns_the_tool_frame(rng) -> None:
    """The fit matches tool points; a tool swapped on it follows the frame, turned by up to 0.34-0.44 deg on a real
    arm's elastic file, which no line said (a review). The largest turn is measured against scipy's rotation
    magnitude (an independent reading) and printed."""
    from scipy.spatial.transform import Rotation

    from spherecal.controller.rigid_fit import _largest_turn
    from spherecal.correction import tool_pose

    a = Rotation.random(50, random_state=1).as_matrix()
    b = Rotation.random(50, random_state=2).as_matrix()
    small = a @ Rotation.from_rotvec(rng.normal(0.0, 1e-7, (50, 3))).as_matrix()
    for x, y in ((a, b), (a, small)):
        expected = np.max((Rotation.from_matrix(x).inv() * Rotation.from_matrix(y)).magnitude())
        assert _largest_turn(x, y) == pytest.approx(expected, rel=1e-9, abs=1e-15)
    model = with_compliance(perturb(load_robot("panda"), rng), COMPLIANCE)
    fit = rigid_approximation(model, model.random_configurations(40, rng), workspace=300, seed=3)
    q = model.random_configurations(300, rng)
    some = _largest_turn(tool_pose(fit.model, q)[:, :3, :3], tool_pose(model, q)[:, :3, :3])
    assert 0.0 < fit.workspace_turn_max and 0.2 < some / fit.workspace_turn_max < 5.0  # the same size, another draw
    assert f"ones, where its tool frame turns by up to {np.rad2deg(fit.workspace_turn_max):.3g} deg (" in fit.summary()


def test_samples_no_rigid_fit_reads_are_said_to_be_unread(tmp_path, capsys) -> None:
    """A review: 'export panda --format urdf --samples nothere.csv' wrote the URDF, exit 0, without a word: a rigid
    model's URDF is exact and nothing reads the samples. Refusing it broke bench/mukca.py, which exports every model
    with its samples: whether a fit runs is the file's content, so one note says the samples were not read."""

    assert main(["export", "panda", "--format", "urdf", "--out", str(tmp_path / "a.urdf"), "--samples",
                 str(tmp_path / "s.csv")]) == 0  # a note, not a refusal: the file's terms decide (bench/mukca.py
    assert f"--samples {tmp_path / 's.csv'} not read: " in capsys.readouterr().out  # exports every model so)
    model = with_compliance(load_robot("panda"), COMPLIANCE)  # an elastic model's rigid fit reads them
    samples = write_samples(tmp_path / "s.csv", Dataset(np.repeat(["a", "b", "c"], 20),
                                                        model.random_configurations(60, np.random.default_rng(0))))
    cal = save_robot(model, tmp_path / "elastic.yaml")
    assert main(["export", str(cal), "--format", "urdf", "--out", str(tmp_path / "a.urdf"), "--samples",
                 str(samples)]) == 0
    assert f"60 recorded configurations from {samples}" in capsys.readouterr().out


def test_a_seed_nothing_random_uses_is_refused(tmp_path, capsys, rng) -> None:
    """A review: 'export --seed' was accepted for a YAML export and for a model with nothing to fit, the value
    unused. The evidence: those documents are the same whatever the seed, while an elastic arm's URDF (a rigid fit
    drawn with it) is not; the seed is refused where it changes nothing, in one line naming it."""
    from tests.refusal import refused

    elastic = with_compliance(perturb(load_robot("panda"), rng), COMPLIANCE)  # an MJCF carries its springs
    rigid = geometric_part(elastic)
    for model, output_format in ((rigid, "urdf"), (rigid, "mjcf"), (elastic, "yaml"), (elastic, "mjcf")):
        assert export_model(model, output_format, "", seed=0).data == export_model(model, output_format, "",
                                                                                   seed=5).data, output_format
    assert export_model(elastic, "urdf", "", seed=0).data != export_model(elastic, "urdf", "", seed=5).data
    cal, plain = save_robot(elastic, tmp_path / "cal.yaml"), save_robot(rigid, tmp_path / "rigid.yaml")
    refused(["export", cal, "--format", "yaml", "--out", tmp_path / "a.yaml", "--seed", "5"], tmp_path, capsys,
            "error: field '--seed': ", "draws nothing random")  # the format itself: a mistake in the command
    for source, output_format, out in ((cal, "mjcf", "a.xml"), (plain, "urdf", "r.urdf"), (plain, "mjcf", "r.xml")):
        # the calibrated file's terms decide: a script exporting every model with one seed stays valid, told
        assert main(["export", str(source), "--format", output_format, "--out", str(tmp_path / out), "--seed",
                     "5"]) == 0
        assert "--seed 5 not used: " in capsys.readouterr().out
    assert main(["export", str(cal), "--format", "urdf", "--out", str(tmp_path / "c.urdf"), "--seed", "5"]) == 0


@pytest.mark.parametrize("given", [False, True])
def test_export_hashes_the_samples_once(given, tmp_path, monkeypatch, capsys) -> None:
    """A review: an export with a rigid fit hashed the calibration's samples file 7 times (each of the two look-ups
    tried the same file under three names, then the provenance hashed it again). Once now, found by the calibration's
    record or given with --samples, and the header records the same digest as before."""
    import spherecal.correction.files.provenance as provenance

    rng = np.random.default_rng(0)
    model = with_compliance(perturb(load_robot("panda"), rng), COMPLIANCE)
    recorded = model.random_configurations(90, rng)
    samples = write_samples(tmp_path / "samples.csv", Dataset(np.repeat(["a", "b", "c"], 30), recorded))
    record = {"path": "samples.csv", "sha256": input_record(samples)["sha256"]}  # relative: found beside cal.yaml
    model = replace(model, extras={**model.extras, "calibration": {"provenance": {"inputs": {"samples": record}}}})
    save_robot(model, tmp_path / "cal.yaml")
    hashed: list[str] = []
    real = provenance.file_digest
    monkeypatch.setattr(provenance, "file_digest", lambda path: hashed.append(os.path.basename(path)) or real(path))
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "cal.urdf"
    assert main(["export", "cal.yaml", "--format", "urdf", "--out", str(out),
                 *(["--samples", "samples.csv"] if given else [])]) == 0
    assert sorted(hashed) == ["cal.yaml", "samples.csv"]
    assert f"samples=samples.csv (sha256 {record['sha256']})" in out.read_text()
    assert "90 recorded configurations from samples.csv" in capsys.readouterr().out
