"""plan --fixtures-out: the chosen set as a fixtures.yaml that simulate takes (new-arm trial)."""

from __future__ import annotations

from spherecal.cli import main
from spherecal.correction.files.fixtures import read_fixtures
from tests.validation.new_arm_urdfs import small_urdf

GRID = "0.1,0.4,3;-0.3,0.3,3;0.0,0.4,3"


def test_the_chosen_fixtures_go_to_simulate_as_written(tmp_path, capsys):
    """The plan printed its chosen set in a table only: for a new arm the engineer copied three positions by hand
    into a fixtures.yaml for simulate --fixtures (and the real recording)."""
    robot = tmp_path / "small.urdf"
    robot.write_text(small_urdf())
    planned = tmp_path / "planned.yaml"
    assert main(["plan", "--robot", str(robot), "--tip-link", "ball", "--grid", GRID, "--workers", "1",
                 "--fixtures-out", str(planned)]) == 0
    said = capsys.readouterr().out
    spec = read_fixtures(planned)
    chosen = said.split("best set (")[1].split(": ")[1].split(";")[0].split(", ")
    assert list(spec.names) == chosen and set(spec.positions) == set(chosen)
    assert spec.extras["plan"]["measure_distances"] and spec.extras["plan"]["predicted_error_m"]["mean"] > 0
    assert not spec.distances  # planned distances are to be measured, not taken as known
    assert main(["simulate", "--robot", str(robot), "--tip-link", "ball", "--fixtures", str(planned),
                 "--out", str(tmp_path / "sim"), "--seconds", "1", "--per-fixture", "50"]) == 0
    truth = read_fixtures(tmp_path / "sim" / "fixtures.yaml")
    assert truth.names == spec.names
    # a file the plan did not write is refused, as for --rrd (its own, by its provenance line, is replaced)
    (tmp_path / "mine.yaml").write_text("fixtures:\n  A: {position: [0.2, 0, 0.2]}\n")
    assert main(["plan", "--robot", str(robot), "--tip-link", "ball", "--grid", GRID, "--workers", "1",
                 "--fixtures-out", str(tmp_path / "mine.yaml")]) == 1
    assert "--fixtures-out" in capsys.readouterr().err


def test_the_help_says_the_planned_positions_are_not_for_calibrate(capsys):
    """A planned position given to calibrate is taken for a measured centre: the help said 'or as the recording's
    template'."""
    main(["plan", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "not for calibrate, which would take the planned positions for measured centres" in text


def test_fixtures_out_is_an_output_as_out_and_rrd_are(tmp_path, capsys, monkeypatch):
    """--fixtures-out was left out of the command line's output options: its missing folder was created and an
    existing file replaced without the line every other output gets, and a recorded option special-cased it."""
    candidates = tmp_path / "c.yaml"
    candidates.write_text("candidates:\n  A: {position: [0.5, -0.25, 0.5]}\n  B: {position: [0.5, 0.25, 0.5]}\n")
    out = tmp_path / "new" / "fixtures.yaml"
    argv = ["plan", "--candidates", str(candidates), "--fixture-count", "1", "--per-fixture", "100",
            "--fixtures-out", str(out)]
    monkeypatch.setattr("sys.argv", ["spherecal", *argv])  # the command line it records: the file is plan's own
    assert main(argv) == 0
    assert f"created the folder {out.parent} (it did not exist)" in capsys.readouterr().out
    assert main(argv) == 0
    assert f"replaced {out} (it existed)" in capsys.readouterr().out
