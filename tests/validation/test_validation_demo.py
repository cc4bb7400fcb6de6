"""`spherecal demo` end to end on a short configuration; its recording read back."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from spherecal.cli import main

ROOT = Path(__file__).parents[2]
SECONDS, SAMPLES, CONFIGURATIONS = 1.0, 60, 200


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    args = ["demo", "--out", str(out), "--seconds", str(SECONDS), "--per-fixture", str(SAMPLES)]
    args += ["--configurations", str(CONFIGURATIONS), "--seed", "3", "--noise", "0"]
    return out, args


def test_short_demo_writes_everything_and_its_recording_holds_the_documented_entities(demo, capsys) -> None:
    from spherecal.validation.viewer.recording import read_entity_rows, read_view_names

    out, args = demo
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "mocap floor" in text and f"recording: {out / 'demo.rrd'}" in text
    headline = re.search(r"nominal ([\d.]+) mm -> calibrated ([\d.]+) mm against the exact", text)
    assert float(headline[2]) < float(headline[1])
    # the RMS deviation counts what the calibration determines: held parameters out, d7 + tool_z as one
    report = json.loads((out / "demo.json").read_text())["validation"]["parameter_deviations"]
    assert "d7 + tool_z" in report["names"] and not {"d7", "tool_z", "a1", "theta1", "base_x"} & set(report["names"])
    lengths = re.search(r"(\d+) lengths [\d.]+ -> [\d.]+ mm; (\d+) angles", text)
    assert int(lengths[1]) + int(lengths[2]) == len(report["names"])
    assert {"a1", "d7", "theta7", "base_yaw"} <= set(report["held_at_nominal"])
    names = sorted(p.name for p in out.iterdir())
    expected = ["calibrated.yaml", "demo.json", "demo.rrd", "fixtures.yaml", "mocap.csv", "samples.csv", "truth.yaml"]
    assert names == expected
    report = json.loads((out / "demo.json").read_text())
    assert report["provenance"]["seed"] == 3 and report["provenance"]["inputs"]["samples_per_fixture"] == SAMPLES
    assert report["provenance"]["inputs"]["control_rate_hz"] == 250.0  # the controller's rate over 1 kHz physics
    for name in ("samples.csv", "fixtures.yaml", "truth.yaml", "calibrated.yaml", "mocap.csv"):
        assert "mujoco 4" in (out / name).read_text(), name  # versions recorded in every result file

    rows = read_entity_rows(out / "demo.rrd")
    steps = 3 * round(SECONDS / 0.01)  # the controller's decimated trajectory: every 10 ms, three fixtures
    expected_rows = {
        "world/fixtures": 1,
        "world/base_frame": 1,
        "world/samples": 1,
        "world/robot/arm": steps + 1,  # one row per step, and the static radii and colours
        "world/robot/tool": steps + 1,
        **{f"errors/{m}/{p}": 1 for m in ("nominal", "calibrated")
           for p in ("points", "colour_scale", "heading", "histogram")},
        "residuals/before": 1,
        "residuals/after": 1,
        **{f"parameters/{g}/{p}": 1 for g in ("lengths", "angles") for p in ("bars", "names", "std", "zero", "scale")},
        **{f"parameters/{g}/truth": 1 for g in ("lengths", "angles")},
        **{f"coverage/P{i}": 1 for i in (1, 2, 3)},
        "tables/validation": 1,
        "tables/calibration": 1,
        "tables/deviations": 1,
        "tables/provenance": 1,
    }
    assert rows == expected_rows
    # the recording records its provenance as every other output does (a review: the .rrd recorded none)
    from spherecal.validation.viewer.recording import read_provenance

    assert read_provenance(out / "demo.rrd") == json.loads((out / "demo.json").read_text())["provenance"]
    from spherecal.validation.experiments.demo import DemoConfig, demo_outputs

    demo_outputs(DemoConfig(out=out))  # a demo run again into its folder replaces its own files
    views = read_view_names(out / "demo.rrd")
    assert any(v.startswith("True robot (simulated) and fixtures") for v in views)
    for start in ("Nominal: mean", "Calibrated: mean", "Nominal: error histogram [mm]",
                  "Residuals before calibration [mm]", "Residuals after calibration [mm]",
                  "Lengths [mm]: change, +-1 std, white dot = true change", "Angles [deg]: change, +-1 std",
                  "P1: joint coverage", "Calibration table (mm, deg)"):
        assert any(v.startswith(start) for v in views), start
    guide = (ROOT / "docs" / "guide.md").read_text()
    section = guide.split("## Validation", 1)[1].split("\n## ", 1)[0]
    for path in expected_rows:
        documented = re.sub(r"^errors/(nominal|calibrated)/", "errors/<model>/", path)
        documented = re.sub(r"^residuals/(before|after)$", "residuals/<before|after>", documented)
        kinds = "parameters/<lengths|angles|compliances>/*"
        documented = re.sub(r"^parameters/(lengths|angles)/.*$", kinds, documented)
        documented = re.sub(r"^(coverage)/P\d$", r"\1/<fixture>", documented)
        documented = re.sub(r"^tables/.*$", "tables/<name>", documented)
        assert f"`{documented}`" in section, documented


def test_demo_keeps_a_recording_in_its_out_folder(tmp_path, capsys) -> None:
    # `demo --out DIR` into a folder holding an imported recording replaced its samples.csv and fixtures.yaml
    from tests.refusal import refused

    (tmp_path / "samples.csv").write_text("# command: spherecal import --format mukca\nfixture,q1\n")
    (tmp_path / "fixtures.yaml").write_text("fixtures:\n  front_h0: {}\n")
    refused(["demo", "--out", tmp_path, "--seconds", "1", "--per-fixture", "60"], tmp_path, capsys,
            "samples.csv: field '--out': exists and was not written by an earlier `spherecal demo`")
    (tmp_path / "samples.csv").unlink()
    refused(["demo", "--out", tmp_path, "--seconds", "1", "--per-fixture", "60"], tmp_path, capsys,
            "fixtures.yaml: field '--out'")


def test_demo_refuses_bad_options_and_writes_nothing(tmp_path, capsys) -> None:
    assert main(["demo", "--out", str(tmp_path / "x"), "--per-fixture", "5"]) == 1
    err = capsys.readouterr().err
    assert err == "spherecal demo: error: field '--per-fixture': expected at least 10 samples per fixture, got 5\n"
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize(
    ("command", "option", "value"),
    [
        ("demo", "--noise", "nan"),
        ("demo", "--mocap-noise", "nan"),
        ("demo", "--seconds", "inf"),
        ("validate", "--mocap-noise", "nan"),
        ("campaign", "--noise", "inf"),
        ("campaign", "--seconds", "-1"),
        ("calibrate", "--noise", "inf"),
        ("calibrate", "--dedup-deg", "nan"),
        ("plan", "--noise", "nan"),
        ("plan", "--seconds", "-1"),
    ],
)
def test_non_finite_or_negative_amounts_are_usage_errors(tmp_path, capsys, command, option, value) -> None:
    # NaN passed the "< 0" checks (validate died in the mocap fit, demo in the sample projection); calibrate
    # --noise inf said "the fixture centres are not determined"; campaign/plan --seconds -1 were tracebacks
    assert main([command, option, value, "--out", str(tmp_path / "x")]) == 1
    err = capsys.readouterr().err
    assert f"field '{option}': expected a " in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x").exists()


@pytest.mark.parametrize("command", ["demo", "campaign"])
def test_out_that_is_a_file_is_refused_before_the_run(tmp_path, capsys, command) -> None:
    # used to fail with "cannot write: File exists" only after the whole run (minutes to hours)
    taken = tmp_path / "taken"
    taken.write_text("keep me\n")
    args = [command, "--out", str(taken), "--per-fixture", "10", "--configurations", "3", "--source", "synthetic"]
    extra = ["--sets", "1", "--rows", "P1", "--workers", "1"] if command == "campaign" else ["--no-rrd"]
    assert main(args + extra) == 1
    out, err = capsys.readouterr()
    assert f"{taken}: field '--out': exists and is not a folder" in err and len(err.strip().splitlines()) == 1
    assert out == "" and taken.read_text() == "keep me\n"


def test_campaign_refuses_more_samples_than_readings(tmp_path, capsys) -> None:
    # more samples than 1 kHz readings ran on silently (as the demo refuses)
    args = ["campaign", "--source", "mujoco", "--seconds", "0.01", "--per-fixture", "100", "--out", str(tmp_path / "c")]
    assert main(args) == 1
    err = capsys.readouterr().err
    assert "field '--per-fixture': 100 samples per fixture are more than 0.01 s of 1000 Hz readings hold (10)" in err
    assert not (tmp_path / "c").exists()


@pytest.mark.slow
def test_default_demo_meets_its_accuracy_figures(tmp_path) -> None:
    """The default demo (seed 0, 0.3 mm fixture noise, 0.3 mm mocap): calibrated <= 0.1 mm against the
    exact tool point where nominal is >= 2 mm, and against the mocap at its noise floor."""
    from spherecal.validation.experiments.demo import DemoConfig, run_demo
    from spherecal.validation.pipeline import RANDOM_SET

    result = run_demo(DemoConfig(out=tmp_path, rrd=False), say=lambda line: None)
    random = result.report.comparison(RANDOM_SET)
    assert random.vs_exact["nominal"].mean >= 2e-3
    assert random.vs_exact["calibrated"].mean <= 0.1e-3
    floor = random.floor.mean
    assert 0.25e-3 < floor < 0.4e-3
    assert floor <= random.vs_mocap["calibrated"].mean <= floor + 0.05e-3
