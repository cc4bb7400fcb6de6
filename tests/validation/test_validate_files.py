"""validation.validate_files: `spherecal validate` as one library call (read, check, compare, write)."""

import json

import numpy as np
import pytest

from spherecal.correction import perturb, save_robot, tool_point
from spherecal.correction.files.outputs import OutputSet
from spherecal.correction.files.samples import Dataset
from spherecal.correction.files.samples_csv import write_samples
from spherecal.validation.inputs import ValidationInputError
from spherecal.validation.mocap import MocapError, MocapMeasurement, read_mocap_csv, write_mocap_csv
from spherecal.validation.pipeline import validate_models
from spherecal.validation.sockets import FixtureSpread, SocketReport
from spherecal.validation.validate_files import ValidateConfig, validate_files


@pytest.fixture
def files(tmp_path, panda):
    rng = np.random.default_rng(8)
    truth = perturb(panda, rng)
    paths = {"nominal": tmp_path / "nominal.yaml", "calibrated": tmp_path / "c.yaml"}
    save_robot(panda, paths["nominal"])
    save_robot(truth, paths["calibrated"])
    q = panda.random_configurations(40, rng)
    tool = tool_point(truth, q) + 0.5
    paths["mocap"] = write_mocap_csv(tmp_path / "mocap.csv", MocapMeasurement(q=q, tool=tool))
    paths["mocap_mm"] = write_mocap_csv(tmp_path / "mocap_mm.csv", MocapMeasurement(q=q, tool=tool * 1e3))
    # two sockets: 20 configurations each within ~0.3 deg of a centre configuration (tool points millimetres apart)
    centres = panda.random_configurations(2, rng)
    held = np.repeat(centres, 20, axis=0) + rng.normal(0.0, 0.005, (40, 7))
    paths["samples"] = write_samples(tmp_path / "samples.csv", Dataset(np.repeat(["a", "b"], 20), held))
    return {name: str(path) for name, path in paths.items()}, truth, held


def test_mocap_validation_writes_the_pipeline_report_after_showing_it(files, tmp_path, panda):
    paths, truth, _ = files
    out = tmp_path / "report.json"
    shown = []
    config = ValidateConfig(nominal=paths["nominal"], calibrated=paths["calibrated"], mocap=paths["mocap"], seed=3,
                            out=str(out), options={"mocap": paths["mocap"]})
    report = validate_files(config, OutputSet({"--out": str(out)}),
                            show=lambda r: shown.append(out.exists()) or None)
    assert shown == [False]  # the tables come before the file appears
    # the explicit pipeline call on the same file gives the same comparison
    expected = validate_models(panda, truth, np.random.default_rng(3),
                               measurement=read_mocap_csv(paths["mocap"], 7))
    assert report.to_dict() == expected.to_dict()
    written = json.loads(out.read_text())
    assert written["validation"] == json.loads(json.dumps(expected.to_dict()))
    assert written["provenance"]["seed"] == 3 and written["provenance"]["inputs"]["mocap"] == paths["mocap"]


def test_mocap_in_millimetres_is_refused_before_anything_is_shown_or_written(files, tmp_path):
    paths, _, _ = files
    out = tmp_path / "report.json"
    shown, before = [], sorted(tmp_path.iterdir())
    config = ValidateConfig(nominal=paths["nominal"], calibrated=paths["calibrated"], mocap=paths["mocap_mm"],
                            out=str(out))
    with pytest.raises(MocapError, match="millimetres"):
        validate_files(config, OutputSet({"--out": str(out)}), show=shown.append)
    assert shown == [] and sorted(tmp_path.iterdir()) == before  # no report, no staged file left


def test_socket_only_spreads_are_those_of_the_tool_points(files, tmp_path):
    paths, truth, held = files
    out = tmp_path / "sockets.json"
    config = ValidateConfig(nominal=paths["nominal"], calibrated=paths["calibrated"], samples=paths["samples"],
                            out=str(out))
    with pytest.warns(UserWarning, match="no 'calibration' block"):
        report = validate_files(config, OutputSet({"--out": str(out)}))
    for fixture, rows in zip(report.fixtures, (held[:20], held[20:]), strict=True):
        points = tool_point(truth, rows)
        spread = np.linalg.norm(points - points.mean(axis=0), axis=1)
        assert fixture.mean["calibrated"] == pytest.approx(spread.mean(), rel=1e-9)
        assert fixture.max["calibrated"] == pytest.approx(spread.max(), rel=1e-9)
    assert json.loads(out.read_text())["sockets"] == json.loads(json.dumps(report.to_dict()))


@pytest.mark.parametrize("given, message", [
    ({}, "^field '--truth': give --truth"),
    ({"mocap": "m.csv", "fixtures": "f.yaml"}, "^field '--fixtures': goes with --samples alone"),
    ({"truth": "t.yaml", "samples": "s.csv", "fixtures": "f.yaml"}, "^field '--fixtures': goes with --samples alone"),
    ({"truth": "t.yaml", "mocap": "m.csv", "samples": "s.csv"}, "^field '--samples': not with --mocap"),
])
def test_a_config_without_a_reference_is_refused(given, message):
    with pytest.raises(ValidationInputError, match=message):
        ValidateConfig(nominal="panda", calibrated="c.yaml", **given)


def test_report_says_when_held_out_sockets_beat_the_prediction_and_counts_one_fixture() -> None:
    """The printed band '0.5x-2x of it is as expected': a held-out spread below it is said (better than predicted),
    inside it nothing is added; one held-out socket is '1 fixture'."""

    def report(measured: float) -> str:
        spread = FixtureSpread("front_h0", 20, True, {"nominal": 6e-3, "calibrated": measured},
                               {"nominal": 9e-3, "calibrated": 2 * measured}, {}, distinct=20, predicted=4e-3)
        return SocketReport(("nominal", "calibrated"), [spread], [], "test").format()

    low, inside = report(1.5e-3), report(2.5e-3)
    assert "held-out (1 fixture) calibrated" in low and "fixtures)" not in low
    assert "distance error" not in low  # no known distance held out: nothing said (it printed '... | -  mm')
    assert "measured 1.500 mm is 0.38x of it, below the band: better than the calibration predicted" in low
    assert "below the band" not in inside
