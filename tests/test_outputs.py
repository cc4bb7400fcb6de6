"""Files: no output over an input (links resolved), several outputs appear together or not at all."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from spherecal.correction import save_robot, tool_point
from spherecal.correction.files.atomic import OutputError
from spherecal.correction.files.fixtures import FixtureSpec, write_fixtures
from spherecal.correction.files.outputs import OutputSet
from spherecal.correction.files.samples import Dataset
from spherecal.correction.files.samples_csv import write_samples
from spherecal.validation.mocap import MocapMeasurement, write_mocap_csv
from tests.refusal import refused, snapshot


# ------------------------------------------------------------------------------- OutputSet
def test_output_set_writes_all_files_together(tmp_path) -> None:
    out = tmp_path / "new" / "deeper"
    files = [out / "a.txt", out / "b.txt"]
    outputs = OutputSet({"--out": files})
    assert not out.exists()  # checking creates nothing
    with outputs:
        outputs.write_text(files[0], "one")
        save_robot_path = outputs.stage(files[1])
        save_robot_path.write_text("two")
        assert not files[0].exists() and not files[1].exists()  # staged, not in place yet
    assert files[0].read_text() == "one" and files[1].read_text() == "two"
    assert sorted(p.name for p in out.iterdir()) == ["a.txt", "b.txt"]  # nothing staged left behind


def test_output_set_failure_leaves_nothing(tmp_path) -> None:
    (tmp_path / "keep.txt").write_text("old")
    before = snapshot(tmp_path)
    files = [tmp_path / "new" / "a.txt", tmp_path / "keep.txt"]
    with pytest.raises(RuntimeError, match="boom"), OutputSet({"--out": files}) as outputs:
        outputs.write_text(files[0], "one")
        outputs.write_text(files[1], "new")
        raise RuntimeError("boom")
    assert snapshot(tmp_path) == before  # the old file kept, the created folder removed, no staged file


def test_output_set_refuses_a_file_never_written(tmp_path) -> None:
    files = [tmp_path / "a.txt", tmp_path / "b.txt"]
    with pytest.raises(RuntimeError, match="never written"), OutputSet({"--out": files}) as outputs:
        outputs.write_text(files[0], "one")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("link", ["same", "relative", "symlink", "hardlink", "symlinked folder"])
def test_output_set_refuses_an_input_however_named(tmp_path, monkeypatch, link) -> None:
    source = tmp_path / "in.yaml"
    source.write_text("x")
    monkeypatch.chdir(tmp_path)
    if link == "same":
        output = source
    elif link == "relative":
        (tmp_path / "sub").mkdir()
        output = Path("sub/../in.yaml")
    elif link == "symlink":
        output = tmp_path / "alias.yaml"
        output.symlink_to(source)
    elif link == "hardlink":
        output = tmp_path / "hard.yaml"
        os.link(source, output)
    else:
        (tmp_path / "view").symlink_to(tmp_path, target_is_directory=True)
        output = tmp_path / "view" / "in.yaml"
    with pytest.raises(OutputError, match=r"field '--out': is the --robot file"):
        OutputSet({"--out": output}, {"--robot": str(source)})
    assert source.read_text() == "x"


@pytest.mark.parametrize("command", [
    ["simulate", "--seconds", "0.1", "--per-fixture", "5"],
    ["calibrate", "--robot", "panda", "--samples", "SAMPLES"],
    ["plan", "--samples", "SAMPLES", "--rrd"],  # (--predict writes nothing: its --rrd is refused as unused)
])
def test_a_folder_given_for_fixtures_is_named_as_such(tmp_path, capsys, command) -> None:
    """--fixtures naming a folder that the output lies in was refused as 'the output is inside the --fixtures
    folder': the mistake is the folder given for a file."""
    folder = tmp_path / "fixtures"
    folder.mkdir()
    samples = tmp_path / "samples.csv"
    write_samples(samples, Dataset(labels=np.array(["A"] * 3), q=np.zeros((3, 7))))
    out = str(folder / ("out.rrd" if command[0] == "plan" else "out"))
    argv = [str(samples) if word == "SAMPLES" else word for word in command]
    argv += [out] if argv[-1] == "--rrd" else ["--out", out]
    error = refused([*argv, "--fixtures", str(folder)], tmp_path, capsys)
    assert error == f"spherecal {command[0]}: error: {folder}: field '--fixtures': is a folder, not a file; give the " \
                    "file itself\n", error
    with pytest.raises(OutputError, match="is inside the SOURCE folder"):  # a folder where one is expected: as before
        OutputSet({"--out": folder / "x"}, {"SOURCE": str(folder)}, file_inputs=["--fixtures"])


def test_output_set_refuses_one_file_planned_twice_and_bad_locations(tmp_path) -> None:
    with pytest.raises(OutputError, match="is also the output of --out"):
        OutputSet({"--out": tmp_path / "r.json", "--rrd": tmp_path / "." / "r.json"})
    (tmp_path / "file").write_text("")
    with pytest.raises(OutputError, match=r"file is not a folder"):
        OutputSet({"--out": tmp_path / "file" / "x.csv"})
    with pytest.raises(OutputError, match="is a folder, expected a file name"):
        OutputSet({"--out": tmp_path})
    with pytest.raises(OutputError, match="is inside the SOURCE folder"):
        OutputSet({"--out": tmp_path / "x.csv"}, {"SOURCE": tmp_path})


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes anywhere")
def test_output_set_refuses_a_folder_it_cannot_write(tmp_path) -> None:
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o555)
    with pytest.raises(OutputError, match="permission denied"):
        OutputSet({"--out": locked / "a.csv"})


# ------------------------------------------------------------------------------ commands
@pytest.fixture
def files(tmp_path, panda):
    """A small set of inputs: robot files, samples, fixtures, a mocap recording."""
    rng = np.random.default_rng(3)
    save_robot(panda, tmp_path / "robot.yaml")
    save_robot(panda, tmp_path / "calibrated.yaml")
    q = panda.random_configurations(60, rng)
    labels = np.repeat(["P1", "P2", "P3"], 20)
    write_samples(tmp_path / "samples.csv", Dataset(labels=labels, q=q))
    write_fixtures(tmp_path / "fixtures.yaml", FixtureSpec(("P1", "P2", "P3"), {"P1": np.array([0.5, 0.0, 0.3]),
                                                                               "P2": np.array([0.5, 0.2, 0.3]),
                                                                               "P3": np.array([0.4, -0.2, 0.3])}))
    write_mocap_csv(tmp_path / "mocap.csv", MocapMeasurement(q=q, tool=tool_point(panda, q)))
    (tmp_path / "candidates.yaml").write_text("candidates:\n  C1: {position: [0.5, 0.0, 0.3]}\n")
    return tmp_path


def test_simulate_never_overwrites_its_fixtures_input(files, capsys) -> None:
    # `simulate --out DIR --fixtures DIR/fixtures.yaml` used to overwrite the input with the written one
    refused(["simulate", "--out", files, "--fixtures", files / "fixtures.yaml", "--seconds", "1", "--per-fixture",
             "10"], files, capsys, "fixtures.yaml: field '--out': is the --fixtures file")


def test_simulate_refuses_before_any_work_when_one_of_its_files_cannot_be_written(files, capsys) -> None:
    out = files / "sim"
    (out / "truth.yaml").mkdir(parents=True)
    refused(["simulate", "--out", out, "--seconds", "1", "--per-fixture", "10"], files, capsys,
            "truth.yaml: field '--out': is a folder")


@pytest.mark.parametrize(("argv", "expected"), [
    # each wrote its file with exit 0, and the next command read it by its name: 'invalid XML: line 1, column 1'
    (["calibrate", "--robot", "robot.yaml", "--samples", "samples.csv", "--out", "cal.urdf"],
     "cal.urdf: field '--out': a calibrated robot file (YAML) named .urdf would be read as URDF; name it .yaml"),
    (["tool", "calibrated.yaml", "--offset", "0", "0", "0.1", "--out", "tcp.urdf"],
     "named .urdf would be read as URDF"),
    (["export", "calibrated.yaml", "--format", "urdf", "--out", "arm.yaml", "--effort", "1,1,1,1,1,1,1"],
     "arm.yaml: field '--out': a URDF (--format urdf) named .yaml would be read as YAML; name it .urdf"),
    (["export", "calibrated.yaml", "--format", "mjcf", "--out", "arm.urdf"],
     "an MJCF model (--format mjcf) named .urdf"),
    (["export", "calibrated.yaml", "--format", "yaml", "--out", "arm.xml"],
     "a robot file (YAML) (--format yaml) named .xml"),
    # a user: 'export --format urdf --out arm.xml' was written, under the ending of the MJCF export (--format mjcf)
    (["export", "calibrated.yaml", "--format", "urdf", "--out", "arm.xml", "--effort", "1,1,1,1,1,1,1"],
     "arm.xml: field '--out': a URDF (--format urdf) named .xml would be taken for an MJCF model (--format mjcf "
     "writes .xml); name it .urdf"),
    (["export", "calibrated.yaml", "--format", "urdf", "--out", "arm.XML"], "named .xml would be taken for an MJCF"),
    # plan, validate: a Rerun recording or a JSON report written under a name another reader would take
    (["plan", "--candidates", "candidates.yaml", "--fixture-count", "1", "--rrd", "plan.json"],
     "plan.json: field '--rrd': a Rerun recording named .json would be read as JSON; name it .rrd"),
    (["validate", "--nominal", "robot.yaml", "--calibrated", "calibrated.yaml", "--samples", "samples.csv",
      "--out", "report.yaml"], "report.yaml: field '--out': a JSON report named .yaml would be read as YAML"),
    (["validate", "--nominal", "robot.yaml", "--calibrated", "calibrated.yaml", "--samples", "samples.csv",
      "--rrd", "spread.csv"], "spread.csv: field '--rrd': a Rerun recording named .csv"),
    (["plan", "--analysis", "design.json"], "design.json: field '--analysis': a Markdown document named .json"),
])
def test_an_output_named_for_another_format_is_refused(files, capsys, monkeypatch, argv, expected) -> None:
    monkeypatch.chdir(files)
    refused(argv, files, capsys, expected)


@pytest.mark.parametrize(("argv", "expected"), [
    # the Rerun viewer opens a recording only by its ending (re_data_loader's RrdLoader: .rrd, .rbl)
    (["validate", "--nominal", "robot.yaml", "--calibrated", "calibrated.yaml", "--samples", "samples.csv",
      "--rrd", "spread.txt"], "spread.txt: field '--rrd': a Rerun recording must be named .rrd (the Rerun viewer "
     "opens a recording only by that ending)"),
    (["plan", "--candidates", "candidates.yaml", "--fixture-count", "1", "--rrd", "plan"],
     "plan: field '--rrd': a Rerun recording must be named .rrd"),
    # Rerun (and ROS tools) read a URDF by its ending: spherecal reads an XML <robot> as one, they do not
    (["export", "calibrated.yaml", "--format", "urdf", "--out", "arm.txt", "--effort", "1,1,1,1,1,1,1"],
     "arm.txt: field '--out': a URDF (--format urdf) must be named .urdf (Rerun opens a URDF only by that ending)"),
])
def test_an_output_read_by_its_ending_is_refused_under_another(files, capsys, monkeypatch, argv, expected) -> None:
    monkeypatch.chdir(files)
    refused(argv, files, capsys, expected)


def test_a_robot_file_under_any_other_ending_is_written_and_read_back(files, capsys, monkeypatch) -> None:
    """A robot file is read by its content (every name but .urdf as YAML, unless it is an XML <robot>): 'tool --out
    t.txt' is the user's choice, and the next command reads it."""
    from spherecal.cli import main
    from spherecal.correction import load_robot

    monkeypatch.chdir(files)
    assert main(["tool", "calibrated.yaml", "--offset", "0", "0", "0.1", "--out", "tcp.txt"]) == 0
    assert load_robot("tcp.txt").tool.tolist() == [0.0, 0.0, 0.1]


def test_simulate_keeps_a_recording_in_its_out_folder(files, capsys) -> None:
    # `simulate --out DIR` into a folder holding a real recording (samples.csv, fixtures.yaml) replaced both with
    # simulated data, exit 0
    refused(["simulate", "--out", files, "--seconds", "0.01", "--per-fixture", "5"], files, capsys,
            "samples.csv: field '--out': exists and was not written by an earlier `spherecal simulate`")
    (files / "fixtures.yaml").unlink()  # the samples alone are still the recording
    refused(["simulate", "--out", files, "--seconds", "0.01", "--per-fixture", "5"], files, capsys,
            "samples.csv: field '--out'")


def test_simulate_replaces_its_own_earlier_outputs(tmp_path, capsys) -> None:
    from spherecal.cli import main

    out = tmp_path / "sim"
    assert main(["simulate", "--out", str(out), "--seconds", "0.01", "--per-fixture", "5", "--seed", "1"]) == 0
    first = (out / "samples.csv").read_text()
    assert main(["simulate", "--out", str(out), "--seconds", "0.01", "--per-fixture", "5", "--seed", "2"]) == 0
    assert (out / "samples.csv").read_text() != first  # replaced by the new run
    # an imported samples.csv beside the simulation's YAML files is not the simulation's: refused
    write_samples(out / "samples.csv", Dataset(labels=np.repeat(["A"], 5), q=np.zeros((5, 7))), "command: import")
    refused(["simulate", "--out", out, "--seconds", "0.01", "--per-fixture", "5"], tmp_path, capsys,
            "samples.csv: field '--out': exists and was not written")


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["calibrate", "--robot", "robot.yaml", "--samples", "samples.csv", "--out", "samples.csv"],
         "is the --samples file"),
        (["calibrate", "--robot", "robot.yaml", "--samples", "samples.csv", "--out", "link.yaml"],
         "is the --robot file"),
        (["calibrate", "--robot", "robot.yaml", "--samples", "samples.csv", "--fixtures", "fixtures.yaml",
          "--out", "./fixtures.yaml"], "is the --fixtures file"),
        (["export", "robot.yaml", "--format", "yaml", "--out", "hard.yaml"], "is the CAL.yaml file"),
        (["validate", "--nominal", "robot.yaml", "--calibrated", "calibrated.yaml", "--mocap", "mocap.csv",
          "--out", "mocap.csv"], "is the --mocap file"),
        (["validate", "--nominal", "robot.yaml", "--calibrated", "calibrated.yaml", "--mocap", "mocap.csv",
          "--out", "r.json", "--rrd", "r.json"], "is also the output of --out"),
        (["validate", "--nominal", "robot.yaml", "--calibrated", "calibrated.yaml", "--samples", "samples.csv",
          "--rrd", "calibrated.yaml"], "is the --calibrated file"),
        (["plan", "--candidates", "candidates.yaml", "--rrd", "candidates.yaml"], "is the --candidates file"),
        (["plan", "--samples", "samples.csv", "--rrd", "samples.csv"], "is the --samples file"),
        (["import", "samples.csv", "--format", "csv", "--robot", "robot.yaml", "--out", "."],
         "holds the input"),
    ],
)
def test_no_command_writes_over_an_input(files, capsys, monkeypatch, argv, expected) -> None:
    monkeypatch.chdir(files)
    (files / "link.yaml").symlink_to(files / "robot.yaml")
    os.link(files / "robot.yaml", files / "hard.yaml")
    refused(argv, files, capsys, expected)


def test_demo_and_campaign_refuse_before_any_work(files, capsys) -> None:
    (files / "demo").mkdir()
    (files / "demo" / "demo.json").mkdir()  # one of the demo's files cannot be written
    refused(["demo", "--out", files / "demo", "--source", "synthetic"], files, capsys,
            "demo.json: field '--out': is a folder")
    refused(["campaign", "--out", files / "samples.csv"], files, capsys, "field '--out': exists and is not a folder")


@pytest.mark.parametrize("command, out, meant", [
    (["import", "samples.csv", "--format", "csv", "--robot", "robot.yaml"], "train/samples.csv", "--out train"),
    (["import", "samples.csv", "--format", "csv", "--robot", "robot.yaml"], "train.csv", "--out train"),
    (["simulate"], "sim/fixtures.yaml", "--out sim"),
    (["campaign"], "tables/table2.md", "--out tables"),
])
def test_a_folder_option_named_like_a_file_is_refused(files, capsys, monkeypatch, command, out, meant) -> None:
    # `import ... --out train/samples.csv` (a user trial) created a folder samples.csv holding samples.csv and
    # fixtures.yaml, exit 0, and the next `calibrate --samples train/samples.csv` found a folder
    monkeypatch.chdir(files)
    line = refused(command + ["--out", out], files, capsys, "field '--out': a folder named like a file", meant)
    assert line.startswith(f"spherecal {command[0]}: error: {out}: ")


def test_an_existing_folder_named_like_a_file_is_used(files, monkeypatch) -> None:
    from spherecal.cli import main

    monkeypatch.chdir(files)
    (files / "kept.csv").mkdir()  # the user's own folder, named so: used as named
    assert main(["import", "samples.csv", "--format", "csv", "--robot", "robot.yaml", "--out", "kept.csv"]) == 0
    assert sorted(p.name for p in (files / "kept.csv").iterdir()) == ["fixtures.yaml", "samples.csv"]


def test_validate_writes_report_and_recording_together(files, capsys, monkeypatch) -> None:
    # the report used to be written first; a recording failing after it left a report without its recording
    import spherecal.validation.validate_files as validate_files  # the recording's writer, where validate calls it

    def broken(recording, *args, **kwargs):
        recording.stream.log("x", recording.rr.Points3D([[0.0, 0.0, 0.0]]))  # something was recorded already
        raise OutputError("disk full (simulated)")

    monkeypatch.setattr(validate_files, "record_validate_run", broken)
    argv = ["validate", "--nominal", files / "robot.yaml", "--calibrated", files / "calibrated.yaml",
            "--mocap", files / "mocap.csv", "--out", files / "r.json", "--rrd", files / "r.rrd"]
    refused(argv, files, capsys, "disk full (simulated)")
    monkeypatch.undo()
    from spherecal.cli import main

    assert main([str(a) for a in argv]) == 0
    assert (files / "r.json").stat().st_size > 0 and (files / "r.rrd").stat().st_size > 0
    assert not [p for p in files.iterdir() if p.name.startswith(".")]  # nothing staged left behind


def test_an_unwritable_recording_is_one_line_before_anything_is_written(files, capsys) -> None:
    argv = ["validate", "--nominal", files / "robot.yaml", "--calibrated", files / "calibrated.yaml",
            "--mocap", files / "mocap.csv", "--out", files / "r.json", "--rrd", files / "samples.csv" / "r.rrd"]
    refused(argv, files, capsys, "r.rrd: field '--rrd':", "samples.csv is not a folder")


#: Commands writing one output, the name of which ends each list (``OUT``, replaced per test).
OUT = "OUT"
WRITERS = [
    ["calibrate", "--robot", "robot.yaml", "--samples", "samples.csv", "--out", OUT],
    ["validate", "--nominal", "robot.yaml", "--calibrated", "calibrated.yaml", "--mocap", "mocap.csv", "--out", OUT],
    ["export", "calibrated.yaml", "--format", "urdf", "--out", OUT],
    ["tool", "calibrated.yaml", "--offset", "0", "0", "0.1", "--out", OUT],
]


def _naming(argvs: list[list[str]], name: str) -> list[list[str]]:
    return [[name if a == OUT else a for a in argv] for argv in argvs]


@pytest.mark.parametrize("argv", _naming(WRITERS, "special"))
def test_an_output_that_is_a_device_or_pipe_is_refused_and_left_in_place(files, capsys, monkeypatch, argv) -> None:
    # `--out /dev/full` (or /dev/null, a named pipe) was staged beside it and renamed over it: as root the device
    # node itself became a regular file holding the result, and the command said "wrote /dev/full"
    monkeypatch.chdir(files)
    os.mkfifo(files / "special")  # a pipe stands for a device node: both are replaced the same way
    refused(argv, files, capsys, "special: field '--out': is a device, pipe or socket, not a regular file")
    assert not (files / "special").is_file() and (files / "special").is_fifo()


def test_an_output_name_ending_in_a_slash_is_refused(files, capsys) -> None:
    # `--out results/` wrote the calibrated robot file as a FILE named `results` (Path() drops the slash)
    refused(["calibrate", "--robot", files / "robot.yaml", "--samples", files / "samples.csv",
             "--out", f"{files / 'results'}/"], files, capsys, "results/: field '--out': ends with '/', a folder name")


def test_atomic_write_refuses_a_device_or_pipe(tmp_path) -> None:
    from spherecal.correction import atomic_write_text

    os.mkfifo(tmp_path / "pipe")
    with pytest.raises(OutputError, match="is a device, pipe or socket"):
        atomic_write_text(tmp_path / "pipe", "x")
    assert (tmp_path / "pipe").is_fifo() and [p.name for p in tmp_path.iterdir()] == ["pipe"]


@pytest.mark.parametrize(
    "argv",
    [
        *_naming(WRITERS[:1], "loop.yaml"),
        ["validate", "--nominal", "robot.yaml", "--calibrated", "calibrated.yaml", "--mocap", "mocap.csv",
         "--rrd", "loop.yaml"],
        ["export", "calibrated.yaml", "--format", "yaml", "--out", "loop.yaml"],
        ["campaign", "--out", "loop.yaml"],
        ["demo", "--out", "loop.yaml", "--source", "synthetic"],
        ["simulate", "--out", "loop.yaml"],
        ["import", "samples.csv", "--format", "csv", "--robot", "robot.yaml", "--out", "loop.yaml"],
    ],
)
def test_an_output_in_a_symbolic_link_loop_is_one_line(files, capsys, monkeypatch, argv) -> None:
    # Path.resolve raised "RuntimeError: Symlink loop" from the output checks: a 30-line traceback
    monkeypatch.chdir(files)
    (files / "loop.yaml").symlink_to(files / "loop.yaml")
    refused(argv, files, capsys, "loop.yaml: field '--")


def test_an_output_inside_the_installed_package_is_refused_before_any_work(files, capsys, monkeypatch) -> None:
    # demo, campaign and export wrote into the package's own folders (exit 0): files mixed into the code
    import spherecal.controller as controller_package
    import spherecal.correction as correction_package

    package = Path(controller_package.__file__).parent
    expected = f"is inside the installed spherecal package ({package.resolve()})"
    refused(["demo", "--out", package / "demo_out", "--source", "synthetic"], package, capsys, expected)
    refused(["campaign", "--out", package / "campaign"], package, capsys, expected)
    refused(["export", files / "robot.yaml", "--format", "yaml", "--out", package / "cal.yaml"], package, capsys,
            expected)
    monkeypatch.chdir(Path(correction_package.__file__).parent)  # a relative name, from inside the package
    refused(["export", files / "robot.yaml", "--format", "urdf", "--out", "cal.urdf"], package, capsys,
            "cal.urdf: field '--out': is inside the installed spherecal package")


def test_campaign_and_plan_keep_a_users_file_and_replace_their_own(tmp_path, capsys, monkeypatch) -> None:
    """`campaign --out DIR` replaced a user's own table2.csv and `plan --out FILE` a user's FILE, exit 0 (a review);
    as simulate and demo do, they replace only what an earlier run of theirs wrote (its provenance line)."""
    from spherecal.cli import main
    from spherecal.correction.files.earlier_run import written_by

    campaign = ["campaign", "--sets", "1", "--per-fixture", "20", "--configurations", "50", "--rows", "P1", "--out"]
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "table2.csv").write_text("my own table\n")
    refused([*campaign, mine], tmp_path, capsys,
            "table2.csv: field '--out': exists and was not written by an earlier `spherecal campaign`")
    assert (mine / "table2.csv").read_text() == "my own table\n"
    monkeypatch.setattr("sys.argv", ["spherecal", *campaign, str(tmp_path / "c")])  # the command line it records
    assert main([*campaign, str(tmp_path / "c")]) == 0 and main([*campaign, str(tmp_path / "c")]) == 0  # its own
    assert written_by(tmp_path / "c" / "table2.csv", "spherecal campaign")
    assert written_by(tmp_path / "c" / "table2.md", "spherecal campaign")
    assert not written_by(tmp_path / "c" / "table2.csv", "spherecal plan")
    report = tmp_path / "report.json"
    report.write_text('{"provenance": {"command": "spherecal plan --out report.json"}}')
    assert written_by(report, "spherecal plan") and not written_by(report, "spherecal campaign")
    old = tmp_path / "design.md"  # written before the program's path was shortened to its name
    old.write_text("<!--\ncommand: /work/venv/bin/spherecal plan --analysis design.md\ncreated: 2026-11-22\n-->\n")
    assert written_by(old, "spherecal plan") and not written_by(old, "spherecal plant")
    # a run without arguments ('command: spherecal campaign', nothing after it): h10 could not run it again
    bare = tmp_path / "table2.csv"
    bare.write_text("# command: spherecal campaign\n# created: 2026-11-29\nset,n\n")
    assert written_by(bare, "spherecal campaign") and not written_by(bare, "spherecal campaign2")
    report.write_text('{"a": 1}')
    refused(["plan", "--samples", tmp_path / "c" / "table2.csv", "--out", report], tmp_path, capsys,
            "report.json: field '--out': exists and was not written by an earlier `spherecal plan`")


#: One run of each command kind, its output (``OUT``) in a missing folder: the file commands' --out (and --rrd), the
#: folder commands' --out itself.
MISSING = "new/deeper"
CREATING = [
    ([*WRITERS[1][:-1], f"{MISSING}/r.json"], MISSING),
    ([*WRITERS[1][:-2], "--rrd", f"{MISSING}/r.rrd"], MISSING),
    ([*WRITERS[2][:-1], f"{MISSING}/cal.urdf"], MISSING),
    ([*WRITERS[3][:-1], f"{MISSING}/tool.yaml"], MISSING),
    (["simulate", "--seconds", "1", "--per-fixture", "10", "--out", MISSING], MISSING),
    (["import", "samples.csv", "--format", "csv", "--robot", "robot.yaml", "--out", MISSING], MISSING),
    (["campaign", "--sets", "1", "--per-fixture", "20", "--configurations", "50", "--noise", "0", "--rows", "P1",
      "--workers", "1", "--out", MISSING], MISSING),
]


@pytest.mark.parametrize(("argv", "folder"), CREATING, ids=lambda value: value[0] if isinstance(value, list) else "")
def test_every_command_creates_a_missing_output_folder_and_says_so(files, capsys, monkeypatch, argv, folder) -> None:
    """A review: calibrate, export, tool, simulate and import created a missing folder (and its parents) without a
    word, so that a mistyped --out went unseen. Every command still creates it (as a folder command must), and says
    so in one line; an existing folder gets no line."""
    from spherecal.cli import main

    monkeypatch.chdir(files)
    monkeypatch.setattr("sys.argv", ["spherecal", *argv])  # the command line a campaign's tables record as theirs
    assert main(argv) == 0, capsys.readouterr().err
    out = capsys.readouterr().out.splitlines()
    assert f"spherecal {argv[0]}: created the folder {folder} (it did not exist)" in out
    assert (files / folder).is_dir()
    if argv[0] in ("simulate", "import"):  # they refuse a folder that holds their files (nothing to say either way)
        return
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "created the folder" not in out
    for option in ("--out", "--rrd", "--analysis"):  # each output file the second run replaced is named
        if option in argv and argv[0] not in ("campaign", "demo"):
            assert f"spherecal {argv[0]}: replaced {argv[argv.index(option) + 1]} (it existed)" in out.splitlines()


def test_calibrate_creates_a_missing_output_folder_and_says_so(tmp_path, capsys, monkeypatch) -> None:
    from spherecal.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "--seconds", "2", "--per-fixture", "40", "--out", "sim"]) == 0
    argv = ["calibrate", "--robot", "panda", "--samples", "sim/samples.csv", "--fixtures", "sim/fixtures.yaml",
            "--force", "--out", f"{MISSING}/cal.yaml"]  # --force: 40 samples per fixture are too few to beat nominal
    capsys.readouterr()
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert f"spherecal calibrate: created the folder {MISSING} (it did not exist)" in out and "replaced" not in out
    assert (tmp_path / MISSING / "cal.yaml").is_file()
    assert main(argv) == 0  # a user trial: the second run replaced the first without a word
    assert f"spherecal calibrate: replaced {MISSING}/cal.yaml (it existed)" in capsys.readouterr().out.splitlines()


def test_a_refused_command_leaves_no_folder_and_says_none_was_created(files, capsys, monkeypatch) -> None:
    monkeypatch.chdir(files)
    refused(["tool", "calibrated.yaml", "--offset", "0", "0", "0.1", "--out", f"{MISSING}/tool.urdf"], files, capsys,
            "named .urdf would be read as URDF")
    assert not (files / "new").exists()


def test_the_folder_commands_are_those_whose_out_is_a_folder() -> None:
    from spherecal.cli import COMMANDS, build_parser
    from spherecal.options import FOLDER_OUT

    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command").choices
    folders = {name for name in COMMANDS for a in sub[name]._actions
               if a.dest == "out" and "folder" in (a.help or "")}
    assert folders == set(FOLDER_OUT)
