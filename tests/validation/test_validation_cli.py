"""`spherecal validate`: a simulated run, a recorded run, and bad inputs refused in one line."""

from __future__ import annotations

import dataclasses
import json
import re

import numpy as np
import pytest

from spherecal.cli import main
from spherecal.correction import (
    dump_robot,
    load_robot,
    perturb,
    robot_from_dict,
    robot_to_dict,
    save_robot,
    to_standard,
    tool_point,
)
from spherecal.validation.mocap import MocapMeasurement, write_mocap_csv


@pytest.fixture
def files(tmp_path, panda):
    rng = np.random.default_rng(3)
    truth = perturb(panda, rng)
    calibrated = truth.with_params(truth.params + rng.normal(0.0, 1e-6, truth.n_params))
    paths = {"truth": tmp_path / "truth.yaml", "nominal": tmp_path / "nominal.yaml", "calibrated": tmp_path / "c.yaml"}
    save_robot(truth, paths["truth"])
    save_robot(panda, paths["nominal"])
    save_robot(calibrated, paths["calibrated"])
    q = panda.random_configurations(50, rng)
    paths["mocap"] = write_mocap_csv(tmp_path / "mocap.csv", MocapMeasurement(q=q, tool=tool_point(truth, q) + 1.0))
    return paths


def _args(files, *extra):
    return ["validate", "--nominal", str(files["nominal"]), "--calibrated", str(files["calibrated"]), *extra]


def test_simulated_validation_prints_both_columns_and_writes_report(files, tmp_path, capsys) -> None:
    out = tmp_path / "out" / "report.json"
    code = main(_args(files, "--truth", str(files["truth"]), "--configurations", "300", "--out", str(out)))
    assert code == 0
    text = capsys.readouterr().out
    assert "mocap floor" in text and "vs exact tool point" in text and "alpha3" in text
    report = json.loads(out.read_text())
    random = report["validation"]["sets"]["random workspace"]
    assert random["vs_exact"]["calibrated"]["mean"] < 1e-5 < 1e-3 < random["vs_exact"]["nominal"]["mean"]
    assert report["provenance"]["seed"] == 0 and "numpy" in report["provenance"]["versions"]
    assert len(report["provenance"]["inputs"]["truth"]["sha256"]) == 64


def test_recorded_mocap_validation(files, capsys, tmp_path) -> None:
    assert main(_args(files, "--mocap", str(files["mocap"]), "--rrd", str(tmp_path / "v.rrd"))) == 0
    text = capsys.readouterr().out
    assert "recorded (50)" in text
    # the Errors views' heading: what the error is a distance to, then the count once (h6's review: 'the mocap
    # (recorded (5000)), 5000 points')
    from tests.validation.test_validation import _scene

    heading = _scene(tmp_path / "v.rrd", "errors/calibrated/heading")["errors/calibrated/heading"]["labels"][0]
    assert heading.replace("\n", " ") == "calibrated: distance [mm] to the mocap (recorded), 50 points"
    # the mocap points are the truth's, shifted by 1 m: the calibrated model is micrometres off
    calibrated = next(line for line in text.splitlines() if "calibrated" in line)
    assert float(calibrated.split("|")[1].split()[0]) < 0.01


def _bad_joint_count(files, tmp_path):
    data = robot_to_dict(load_robot(files["calibrated"]))
    data["joints"] = data["joints"][:6]
    for key in ("inertials", "compliance", "scale", "joint_names"):  # per-joint blocks: one per joint left
        if key in data:
            data[key] = data[key][:6]
    path = tmp_path / "six.yaml"
    path.write_text(dump_robot(robot_from_dict(data)))
    return ["--truth", str(files["truth"])], {"calibrated": path}, "field joints: 6 joints"


def _other_convention(files, tmp_path):
    path = tmp_path / "truth_standard.yaml"
    save_robot(to_standard(load_robot(files["truth"])), path)
    return ["--truth", str(path)], {}, "field convention: 'standard'"


def _missing_mocap_value(files, tmp_path):
    lines = files["mocap"].read_text().splitlines()
    lines[7] = ",".join(lines[7].split(",")[:4] + [""] + lines[7].split(",")[5:])
    path = tmp_path / "missing.csv"
    path.write_text("\n".join(lines) + "\n")
    return ["--mocap", str(path)], {}, "row 8: field q5: missing value"


def _tool_swapped(files, tmp_path):
    # a calibrated file given another tool 120 mm on (spherecal tool) validated on the ball's data: the refusal
    # asked 'a model of another arm?'
    path = tmp_path / "tcp.yaml"
    assert main(["tool", str(files["calibrated"]), "--offset", "0", "0", "0.227", "--out", str(path)]) == 0
    return ["--mocap", str(files["mocap"])], {"calibrated": path}, "its tool was replaced by `spherecal tool`"


def _calibrated_with_another_tool(files, tmp_path):
    # a review: an iiwa14 calibrated with its ball (40 mm beyond the flange; here 30 mm) validated against the
    # embedded arm (the flange): 'nominal test MAE 17.341 mm' against the 0.804 mm of the ball's robot file, no word
    model = load_robot(files["calibrated"])
    block = {**model.extras.get("calibration", {}), "nominal_tool": (model.tool + [0.0, 0.0, 0.03]).tolist()}
    path = tmp_path / "ball.yaml"
    save_robot(dataclasses.replace(model, tool=model.tool + [0.0, 0.0, 0.03],
                                   extras={**model.extras, "calibration": block}), path)
    return ["--mocap", str(files["mocap"])], {"calibrated": path}, (
        "field 'calibration.nominal_tool': its tool point calibrates the tool at ")


@pytest.mark.parametrize("case", [_bad_joint_count, _other_convention, _missing_mocap_value, _tool_swapped,
                                  _calibrated_with_another_tool])
def test_bad_inputs_exit_nonzero_with_one_line_and_write_nothing(files, tmp_path, capsys, case) -> None:
    extra, replace, message = case(files, tmp_path)
    files = {**files, **replace}
    capsys.readouterr()
    out, rrd = tmp_path / "out" / "report.json", tmp_path / "out" / "v.rrd"
    before = sorted(p.name for p in tmp_path.rglob("*"))
    code = main(_args(files, *extra, "--out", str(out), "--rrd", str(rrd)))
    captured = capsys.readouterr()
    assert code == 1
    assert captured.err.count("\n") == 1 and message in captured.err, captured.err
    assert captured.err.startswith("spherecal validate: error: ")
    assert sorted(p.name for p in tmp_path.rglob("*")) == before


@pytest.mark.parametrize("option", ["--out", "--rrd"])
def test_output_under_a_file_is_refused_before_anything_is_written(files, tmp_path, capsys, option) -> None:
    # --rrd under a file used to die with a FileExistsError traceback after --out's JSON was written
    blocker = tmp_path / "blocker"
    blocker.write_text("x\n")
    outputs = {"--out": str(tmp_path / "report.json"), "--rrd": str(tmp_path / "v.rrd")}
    outputs[option] = str(blocker / "x")
    args = _args(files, "--truth", str(files["truth"]))
    args += ["--configurations", "20"] + [v for k, path in outputs.items() for v in (k, path)]
    assert main(args) == 1
    err = capsys.readouterr().err
    assert f"field '{option}': {blocker} is not a folder" in err and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir() if p.suffix in (".json", ".rrd")) == []


@pytest.mark.parametrize("command", ["calibrate", "validate", "plan", "demo", "campaign"])
def test_negative_seed_is_a_usage_error(command, capsys) -> None:
    # numpy refuses negative seeds: every one of these died with "ValueError: expected non-negative integer"
    assert main([command, "--seed", "-1"]) == 1
    assert "field '--seed': expected an integer >= 0, got '-1'" in capsys.readouterr().err



def test_validation_of_a_calibrated_file_compares_identifiable_sums_and_records_the_layout(
    files, tmp_path, capsys, panda
) -> None:
    from dataclasses import replace

    from spherecal.validation.viewer.recording import read_entity_rows, read_view_names

    truth = load_robot(files["truth"])
    names = truth.param_names
    # a calibration that got d7 + tool_z right but put it all into tool_z, and held a1 at nominal
    params = truth.params.copy()
    params[names.index("a1")] = panda.params[names.index("a1")]
    params[names.index("tool_z")] += truth.params[names.index("d7")] - panda.params[names.index("d7")]
    params[names.index("d7")] = panda.params[names.index("d7")]
    fixed = {"a1": "gauge: moves every tool point rigidly", "d7": "redundant with tool_z"}
    identified = [n for n in names if n not in fixed and not n.startswith("base")]
    block = {"fixed": fixed, "identified": identified, "std": {n: 1e-5 for n in identified},
             "fixture_centres": {"P1": [0.5, -0.25, 0.5], "P2": [0.5, 0.0, 0.4]}}
    path = save_robot(replace(truth.with_params(params), extras={"calibration": block}), tmp_path / "cal.yaml")
    rrd = tmp_path / "v.rrd"
    args = _args({**files, "calibrated": path}, "--truth", str(files["truth"]), "--configurations", "200")
    assert main([*args, "--rrd", str(rrd)]) == 0
    text = capsys.readouterr().out
    row = next(line for line in text.splitlines() if line.startswith("d7 + tool_z"))
    assert abs(float(row.split()[-1])) < 1e-9  # the sum is exact; tool_z alone would be off by d7's error
    assert not re.findall(r"^(tool_z|d7|a1) +mm", text, flags=re.M)  # neither alone, nor the one held
    assert "held at nominal (not determined by the data, not compared): a1, d7" in text
    rows = read_entity_rows(rrd)
    assert rows["world/fixtures"] == 1 and rows["world/robot/arm"] == 201  # 200 configurations + static style
    assert rows["errors/calibrated/points"] == rows["parameters/lengths/bars"] == rows["tables/validation"] == 1
    views = read_view_names(rrd)
    assert any(v.startswith("True robot and fixtures") for v in views)
    assert "Lengths [mm]: change, +-1 std, white dot = true change" in views
