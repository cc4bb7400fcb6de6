"""One CLI idiom: units named in every --help and the same across commands; old spellings still
work with a warning; a value in the old unit is refused in one line, never reinterpreted."""

from __future__ import annotations

import argparse
import functools
import re
import socket

import pytest

from spherecal.cli import COMMANDS, build_parser, main

#: option -> its one unit on the command line (see spherecal.options).
UNITS = {
    "--noise": "mm",
    "--mocap-noise": "mm",
    "--length-std": "mm",
    "--tool-std": "mm",
    "--angle-std-deg": "deg",
    "--dedup-deg": "deg",
    "--seconds": "s",
    "--grid": "m",
    "--distance": "m",
    "--still-radius": "mm",
    "--max-spread": "mm",
    "--min-separation": "mm",
    "--window": "s",
    "--min-duration": "s",
    "--rate": "Hz",
    "--stiffness": "Nm/rad",
    "--min-gain": "mm",
    "--plate-grid": "m",
}
#: options that are counts, names, files or factors (no physical unit).
UNITLESS = {"--seed", "--per-fixture", "--max-per-fixture", "--configurations", "--sets", "--workers",
            "--fixture-count", "--max-change", "--method", "--loss", "--mode", "--solver", "--source",
            "--protocol", "--rows", "--motion", "--format", "--prefix", "--effort", "--velocity", "--topic",
            "--tip-link", "--base-link", "--convention", "--model", "--max-per-segment", "--min-configurations",
            "--prior", "--plate-orientations", "--per-socket"}


def _options() -> list[tuple[str, argparse.Action]]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    found = []
    for name, command in sub.choices.items():
        for action in command._actions:
            if action.help is argparse.SUPPRESS or not action.option_strings:
                continue
            found += [(name, action)]
    return found


def test_every_physical_option_states_its_unit_and_the_units_agree() -> None:
    seen = set()
    for command, action in _options():
        option = action.option_strings[-1]
        if option in UNITS:
            assert f"[{UNITS[option]}]" in action.help, f"spherecal {command} {option}: {action.help}"
            seen.add(option)
        elif isinstance(action.default, float) and option not in UNITLESS:
            pytest.fail(f"spherecal {command} {option} is a number with no unit registered here: {action.help}")
        # a bracketed unit, wherever it appears, is one of the command line's units
        for unit in re.findall(r"\[([a-zA-Z/]+)\]", action.help or ""):
            # (rad, rad/s and Nm: the units inside files, which stay SI; Nm/rad: --stiffness, its only unit)
            allowed = {"mm", "m", "deg", "s", "Hz", "rad", "rad/s", "Nm", "Nm/rad"}  # Nm/rad: joint stiffness
            assert unit in allowed, f"spherecal {command} {option}: [{unit}]"
    assert {"--noise", "--mocap-noise", "--seconds"} <= seen


def test_noise_is_millimetres_in_every_command() -> None:
    commands = {command for command, action in _options() if "--noise" in action.option_strings}
    assert {"simulate", "calibrate", "demo", "campaign", "plan"} <= commands


def test_samples_always_names_a_file() -> None:
    for command, action in _options():
        if "--samples" in action.option_strings:
            assert action.type is None and action.metavar in (None, "SAMPLES_CSV"), command
            assert "csv" in action.help.lower(), f"spherecal {command} --samples: {action.help}"


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["calibrate", "--robot", "panda", "--samples", "s.csv", "--out", "o.yaml", "--noise", "0.0003"],
         "0.0003 mm is below 0.01 mm: this option is in millimetres (it took metres before spherecal 0.2); "
         "for 0.3 mm write 0.3"),
        (["simulate", "--out", "o", "--noise", "0.0003"], "for 0.3 mm write 0.3"),
        (["simulate", "--out", "o", "--length-std", "0.001"], "for 1 mm write 1"),
        (["calibrate", "--robot", "panda", "--samples", "s.csv", "--out", "o.yaml", "--noise", "300"],
         "300 mm is not a plausible value"),
    ],
)
def test_a_value_in_the_old_unit_is_refused_in_one_line(tmp_path, capsys, monkeypatch, argv, message) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1, err
    assert list(tmp_path.iterdir()) == []


def test_old_spellings_still_work_with_a_warning(capsys) -> None:
    parser = build_parser()
    args = parser.parse_args(["plan", "--grid", "0.5,0.5,1;0,0,1;0.4,0.4,1", "--samples", "120", "--fixtures", "2"])
    assert args.per_fixture == 120 and args.fixture_count == 2 and args.fixtures is None
    err = capsys.readouterr().err
    assert "--samples is deprecated, use --per-fixture" in err and "use --fixture-count" in err
    args = parser.parse_args(["calibrate", "--robot", "panda", "--samples", "s.csv", "--out", "o.yaml",
                              "--max-samples", "50", "--dedup-tol", "0.001"])
    assert args.max_per_fixture == 50 and args.dedup_deg == pytest.approx(0.057295779513)
    args = parser.parse_args(["validate", "--nominal", "n", "--calibrated", "c", "--noise", "0.5"])
    assert args.mocap_noise == 0.5
    err = capsys.readouterr().err
    assert "--max-samples is deprecated" in err and "--dedup-tol is deprecated" in err
    assert "--noise is deprecated, use --mocap-noise" in err


def test_every_subcommand_is_registered_once() -> None:
    assert len(COMMANDS) == len(set(COMMANDS.values()))
    assert all(module.startswith("spherecal.commands.") for module in COMMANDS.values())


@pytest.mark.parametrize("argv, field", [
    (["calibrate", "--robot", "panda", "--samples", "a.csv", "--samples", "b.csv", "--out", "c.yaml"], "--samples"),
    (["calibrate", "--robot", "panda", "--samples=a.csv", "--sam", "b.csv", "--out", "c.yaml"], "--samples"),
    (["import", "x", "--format", "mukca", "--robot", "panda", "--distance", "0.05", "--distance", "0.08", "--out",
      "o"], "--distance"),
    (["validate", "--nominal", "panda", "--calibrated", "c.yaml", "--samples", "a.csv", "--fixtures", "a.yaml",
      "--fixtures", "b.yaml"], "--fixtures"),
])
def test_an_option_of_one_value_given_twice_is_refused(argv, field, capsys) -> None:
    # argparse kept the last silently: 'calibrate --samples a.csv --samples b.csv' calibrated on b.csv alone,
    # the user believing both placements were used
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"error: field '{field}': given twice (" in err
    assert "the second would silently replace the first" in err


def test_a_repeatable_option_may_still_be_repeated() -> None:
    args = build_parser().parse_args(["calibrate", "--robot", "panda", "--samples", "a.csv", "--exclude-fixture",
                                      "A", "--exclude-fixture", "B", "--out", "c.yaml"])
    assert args.exclude_fixture == ["A", "B"] and not hasattr(args, "_given_once")


@pytest.mark.parametrize("option", ["--still-radius", "--max-spread", "--min-separation"])
def test_segmentation_lengths_typed_in_metres_or_zero_are_refused(option, tmp_path, capsys) -> None:
    """'--min-separation 0.03' (30 mm typed in metres) was read as 0.03 mm and turned the check off; 0 passed to the
    segmentation, which then blamed the data (a review). Below 0.1 mm, or 0, the option is refused in one line."""
    out = tmp_path / "out"
    for value, said in (("0.03", "for 30 mm write 30"), ("0", "expected a number > 0 [mm]")):
        assert main(["import", str(tmp_path / "rec.csv"), "--format", "csv", "--robot", "panda", option, value,
                     "--out", str(out)]) == 1
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and option in err and said in err and not out.exists()


#: validate's models (the files need not exist: an option the run would ignore is refused before any is read)
_MODELS = ["--nominal", "panda", "--calibrated", "c.yaml"]
_GRID = ["--grid", "0.5,0.5,1;0,0,1;0.4,0.4,1"]


@pytest.mark.parametrize(("argv", "field", "said"), [
    (["validate", *_MODELS, "--samples", "s.csv", "--configurations", "300"], "--configurations",
     "only with --truth and no --mocap"),
    (["validate", *_MODELS, "--truth", "t.yaml", "--mocap", "m.csv", "--mocap-noise", "0.5"], "--mocap-noise",
     "only with --truth and no --mocap"),
    (["validate", *_MODELS, "--mocap", "m.csv", "--seed", "3"], "--seed", "only with --truth and no --mocap"),
    (["validate", *_MODELS, "--mocap", "m.csv", "--samples", "s.csv"], "--samples", "not with --mocap"),
    (["plan", *_GRID, "--out", "plan.json"], "--out", "only with --samples, not in a plan from scratch"),
    (["plan", "--samples", "s.csv", "--plate-orientations", "4"], "--plate-orientations", "only with --plate-grid"),
    (["plan", *_GRID, "--seconds", "5"], "--seconds", "only with --motion controller"),
    (["plan", "--predict", "s.csv", "--fixture-count", "2"], "--fixture-count", "not with --predict"),
    (["plan", *_GRID, "--min-gain", "0.1"], "--min-gain", "only with --samples"),
    (["plan", "--predict", "s.csv", "--samples", "r.csv"], "--samples", "not with --predict"),
    (["plan", "--analysis", "a.md", "--robot", "fr3"], "--robot", "not with --analysis"),
    (["plan", "--predict", "s.csv", "--rrd", "p.rrd"], "--rrd", "not with --predict"),
    (["plan", "--samples", "s.csv", "--workers", "1"], "--workers", "not with --samples"),
    (["plan", *_GRID, "--fixtures", "f.yaml"], "--fixtures", "not in a plan from scratch"),
    (["plan", "--analysis", "a.md", "--scheduler", "local"], "--scheduler", "not with --analysis"),
])
def test_an_option_the_run_would_ignore_is_refused(argv, field, said, tmp_path, capsys, monkeypatch) -> None:
    """A review: 'validate --configurations' without --truth and 'plan --out' without --samples were accepted and
    silently unused; every such combination is refused in one line naming the option, before any file is read."""
    from tests.refusal import refused

    monkeypatch.chdir(tmp_path)
    refused(argv, tmp_path, capsys, f"field '{field}': ", said)


@pytest.mark.parametrize(("argv", "field", "said"), [
    (["validate", *_MODELS, "--samples", "s.csv", "--noise", "0.5"], "--noise", "only with --truth and no --mocap"),
    (["plan", "--predict", "s.csv", "--samples", "120"], "--samples", "not with --predict"),  # the old count
])
def test_an_old_spelling_the_run_would_ignore_is_refused(argv, field, said, tmp_path, capsys, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 1
    warning, refusal = capsys.readouterr().err.splitlines()  # the deprecation's warning, then the refusal
    assert "is deprecated" in warning and f"error: field '{field}': " in refusal and said in refusal
    assert list(tmp_path.iterdir()) == []


def test_the_options_a_run_uses_are_not_refused() -> None:
    """The record of given options behind those refusals: what was typed, by destination (abbreviations and old
    spellings under the option's own destination), and nothing argparse filled in by default."""
    from spherecal.options import given

    args = build_parser().parse_args(["plan", "--sam", "120", "--see", "4", "--motion", "controller"])
    assert given(args) == {"per_fixture": "--samples", "seed": "--seed", "motion": "--motion"}
    args = build_parser().parse_args(["validate", *_MODELS, "--noise", "0.5"])
    assert given(args) == {"nominal": "--nominal", "calibrated": "--calibrated", "mocap_noise": "--noise"}


@pytest.mark.parametrize(("argv", "field"), [
    (["export", "panda", "--format", "urdf", "--out", "a.urdf", "--prefix", "a b"], "--prefix"),
    (["export", "panda", "--format", "yaml", "--out", "a.yaml", "--prefix", "arm_"], "--prefix"),
    (["export", "panda", "--format", "mjcf", "--out", "a.xml", "--velocity", "1,1,1,1,1,1,1"], "--velocity"),
    (["export", "iiwa14", "--format", "urdf", "--out", "a.urdf", "--effort", "1,2"], "--effort"),  # (its own: 300 Nm)
    (["export", "panda", "--format", "yaml", "--out", "a.yaml", "--tip-link", "x"], "--tip-link"),
    (["tool", "panda", "--offset", "0", "0", "0.2", "--base-link", "x", "--out", "t.yaml"], "--base-link"),
    (["calibrate", "--robot", "panda", "--samples", "s.csv", "--method", "pso", "--loss", "huber", "--out",
      "c.yaml"], "--loss"),
    (["validate", "--nominal", "panda", "--calibrated", "panda", "--base-link", "x", "--samples", "s.csv"],
     "--base-link"),
])
def test_a_refused_option_is_named_as_field(argv, field, tmp_path, capsys, monkeypatch) -> None:
    """A review: refusals said 'prefix: ...', '--prefix: only the urdf format takes it', '--tip-link and --base-link:
    only with --urdf', '--loss huber: ...'; each names its option as every other refusal does, field '--name'."""
    from tests.refusal import refused

    monkeypatch.chdir(tmp_path)
    refused(argv, tmp_path, capsys, f"field '{field}': ")


def test_an_overlong_line_names_its_row_not_an_empty_field(tmp_path, capsys) -> None:
    from tests.refusal import refused

    (tmp_path / "s.csv").write_text("x" * 1_000_001 + "\n")
    err = refused(["validate", "--nominal", "panda", "--calibrated", "panda", "--samples", tmp_path / "s.csv"],
                  tmp_path, capsys, "s.csv: row 1: a line longer than")
    assert "field ''" not in err


@pytest.mark.parametrize(("argv", "field", "said"), [
    (["demo", "--per-fixture", "5", "--out", "d"], "--per-fixture", "expected at least 10 samples per fixture, got 5"),
    (["campaign", "--per-fixture", "5", "--out", "c"], "--per-fixture", "at least 10"),
    (["campaign", "--source", "mujoco", "--seconds", "0.01", "--per-fixture", "100", "--out", "c"], "--per-fixture",
     "100 samples per fixture are more than 0.01 s of 1000 Hz readings hold (10)"),
    (["demo", "--seconds", "0.01", "--per-fixture", "100", "--out", "d"], "--per-fixture", "more than 0.01 s"),
    (["simulate", "--out", "s", "--seconds", "0.1"], "--per-fixture", "500 samples per fixture are more than 0.1 s"),
    (["simulate", "--out", "s", "--seconds", "0.0001"], "--seconds", "expected at least 0.001 s"),
    (["campaign", "--rows", "P9", "--out", "c"], "--rows", "unknown ['P9']"),
    (["campaign", "--rows", "P1,P1", "--out", "c"], "--rows", "P1 is given twice"),
    (["campaign", "--stiffness", "x", "--out", "c"], "--stiffness", "'x': expected numbers [Nm/rad]"),
    (["simulate", "--out", "s", "--stiffness", "1,2"], "--stiffness", "expected 1 or 7 finite values"),
    (["simulate", "--out", "s", "--solver", "nope"], "--solver", "'nope' is not installed"),
    (["plan", "--grid", "x"], "--grid", "'x': expected 'xmin,xmax,nx;ymin,ymax,ny;zmin,zmax,nz'"),
    (["plan", "--grid", "0,1,2;0,1,x;0,1,2"], "--grid", "y: expected 'min,max,count'"),
    (["plan", *_GRID, "--fixture-count", "9"], "--fixture-count", "expected an integer in 1..4, got 9"),
    (["plan"], "--candidates", "give --candidates C.yaml or --grid"),
])
def test_every_command_names_a_refused_option_as_field(argv, field, said, tmp_path, capsys, monkeypatch) -> None:
    """A review: demo, campaign and simulate said '--per-fixture must be >= 10', '--rows: ...', '--seconds must be';
    plan '--grid 'x': ...' (and '--grid' for a bad --plate-grid), '--fixture-count must be', 'give --candidates';
    '--stiffness '-5': ...', '--solver 'nope' ...'. Each names its option, as typed, as field '--name'."""
    from tests.refusal import refused

    monkeypatch.chdir(tmp_path)
    refused(argv, tmp_path, capsys, f"error: field '{field}': ", said)


def test_a_bad_plate_grid_is_named_as_plate_grid() -> None:
    """The grid's refusals named '--grid' for a bad --plate-grid too."""
    import numpy as np

    from spherecal.validation.planning.candidates import CandidateError
    from spherecal.validation.planning.placements import plate_placements

    with pytest.raises(CandidateError, match=r"^field '--plate-grid': '0,1,2;0,1,x;0,1,2': y: expected"):
        plate_placements({"h0": np.zeros(3)}, "0,1,2;0,1,x;0,1,2")


@pytest.mark.parametrize(("argv", "field", "said"), [
    (["demo", "--noise", "nan", "--out", "d"], "--noise", "expected a finite number, got 'nan'"),
    (["campaign", "--per-fixture", "0", "--out", "c"], "--per-fixture", "expected an integer in 1..100000"),
    (["calibrate", "--robot", "panda", "--samples", "s.csv", "--out", "c.yaml", "--method", "x"], "--method",
     "invalid choice: 'x'"),
    (["tool", "panda", "--offset", "0", "0", "--out", "t.yaml"], "--offset", "expected 3 arguments"),
    (["plan", "--grid", "0,1,1;0,1,1;0,1,1", "--samples", "0"], "--samples", "expected an integer in 1..100000"),
])
def test_a_value_argparse_refuses_names_its_option_as_field(argv, field, said, tmp_path, capsys, monkeypatch) -> None:
    """argparse's own refusals said 'argument --noise: expected a finite number', unlike every other refusal."""
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 1
    err = capsys.readouterr().err.splitlines()[-1]  # plan's old --samples count warns first
    assert err.startswith(f"spherecal {argv[0]}: error: field '{field}': {said}"), err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("argv", "said"), [
    (["calibrate", "--samples", "s.csv"], "field '--robot': required (also missing: --out)"),
    (["simulate"], "field '--out': required"),
    (["tool", "panda", "--out", "t.yaml"], "field '--offset': give --offset or --urdf (one of them is required)"),
    # a positional argument kept argparse's words: 'the following arguments are required: CAL.yaml, --format, --out'
    (["export"], "field 'CAL.yaml': required (also missing: --format, --out) (see spherecal export --help)"),
    (["tool", "--out", "t.yaml"], "field 'CAL.yaml': required (see spherecal tool --help)"),
    # a missing option of a few values names them (a user trial: 'export' said only 'required')
    (["export", "c.yaml", "--out", "c.urdf"], "field '--format': required (one of urdf, mjcf, yaml) (see spherecal "
                                              "export --help)"),
    (["import"], "field 'SOURCE': required (also missing: --format, --robot, --out)"),
])
def test_a_missing_option_is_named_as_field(argv, said, tmp_path, capsys, monkeypatch) -> None:
    """argparse said 'the following arguments are required: --robot, --out' and 'one of the arguments --offset --urdf
    is required'; the line names the (first) missing option as every other refusal does."""
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"spherecal {argv[0]}: error: {said}") and err.count("\n") == 1, err


@pytest.mark.parametrize(("argv", "work"), [
    (["demo", "--spawn", "--out", "d"], "spherecal.validation.experiments.demo.run_demo"),
    (["validate", *_MODELS, "--truth", "panda", "--spawn"], "spherecal.validation.validate_files.validate_files"),
])
def test_spawn_without_a_viewer_is_refused_before_any_work(argv, work, tmp_path, capsys, monkeypatch) -> None:
    """A review: 'demo --spawn' with no Rerun viewer on PATH ran the whole demo (9 s) and only then refused
    ('field '--spawn': cannot start a Rerun viewer'). rerun's own spawn (the 'rerun' executable on PATH) now runs
    first: with an empty PATH the command is refused in one line before its work starts, writing nothing."""
    import rerun

    from tests.refusal import refused

    def no_work(*args, **kwargs):
        raise AssertionError("the work started before --spawn was checked")

    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))  # no 'rerun' anywhere on it
    monkeypatch.delenv("_RERUN_TEST_FORCE_SAVE", raising=False)  # rerun skips spawning under it
    # rerun's spawn starts nothing when a viewer already listens on its port (one a developer has open took the
    # default port and this test failed once): spawn on a port nothing listens on
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        free = probe.getsockname()[1]
    monkeypatch.setattr(rerun.RecordingStream, "spawn", functools.partialmethod(rerun.RecordingStream.spawn, port=free))
    monkeypatch.setattr(work, no_work)
    refused(argv, tmp_path, capsys, "error: field '--spawn': cannot start a Rerun viewer: Failed to find Rerun Viewer")
