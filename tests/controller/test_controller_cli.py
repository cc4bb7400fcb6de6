"""`spherecal simulate`: files written on success, nothing and one line on bad input."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.cli import main
from spherecal.correction import load_robot
from spherecal.correction.files.fixtures import read_fixtures
from spherecal.correction.files.robot_file import EMBEDDED_ROBOTS
from spherecal.correction.files.samples_csv import read_samples
from tests.refusal import refused


def _simulate(tmp_path, *extra):
    out = tmp_path / "out"
    code = main(["simulate", "--out", str(out), "--seconds", "0.5", "--per-fixture", "40", "--seed", "4", *extra])
    return code, out


def test_simulate_writes_three_readable_files(tmp_path, capsys):
    code, out = _simulate(tmp_path, "--known-distances")
    assert code == 0
    assert sorted(p.name for p in out.iterdir()) == ["fixtures.yaml", "samples.csv", "truth.yaml"]
    truth = load_robot(out / "truth.yaml")
    data = read_samples(out / "samples.csv", truth)
    spec = read_fixtures(out / "fixtures.yaml")
    assert data.fixture_names == spec.names == ("P1", "P2", "P3")
    assert data.q.shape == (120, 7) and data.t is not None
    sim = truth.extras["simulation"]
    made = sim["provenance"]
    assert made["seed"] == 4 and {"numpy", "scipy", "mujoco", "spherecal"} <= set(made["versions"])
    assert spec.extras["simulation"]["provenance"] == made  # one block in all three files
    assert (out / "samples.csv").read_text().startswith(f"# command: {made['command']}\n# created: ")
    centres = {k: np.array(v) for k, v in sim["fixtures"].items()}
    assert not spec.positions  # the centres are what calibration estimates
    for a, b, distance in spec.distances:
        assert distance == pytest.approx(np.linalg.norm(centres[a] - centres[b]), abs=1e-12)
    assert len(spec.distances) == 3
    assert not truth.same_as(load_robot("panda"), atol=1e-6)  # the true robot is perturbed


def test_simulate_prints_its_coverage_table_on_stdout_and_nothing_on_stderr(tmp_path, capsys):
    # a review: the table went to stderr, where warnings and errors go
    out = tmp_path / "out"
    assert main(["simulate", "--out", str(out), "--seconds", "0.01", "--per-fixture", "5"]) == 0
    printed, err = capsys.readouterr()
    recorded = load_robot(out / "truth.yaml").extras["simulation"]["coverage"]  # fixture -> per-joint share
    head, *rows = printed.splitlines()[:1 + len(recorded)]
    assert head.split()[:2] == ["fixture", "q1%"] and err == ""
    assert [row.split()[0] for row in rows] == list(recorded)


def test_simulate_is_reproducible(tmp_path):
    _, out1 = _simulate(tmp_path / "a", "--noise", "0")
    _, out2 = _simulate(tmp_path / "b", "--noise", "0")
    rows1, rows2 = ([line for line in (out / "samples.csv").read_text().splitlines() if not line.startswith("#")]
                    for out in (out1, out2))
    assert rows1 == rows2 and len(rows1) > 100  # the provenance comment differs only by its time


def _write(tmp_path, text: str):
    path = tmp_path / "fixtures.yaml"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    "text, message",
    [
        ("fixtures:\n  A: {position: [0.5, 0.0, 0.4]}\n  B: {position: [2.0, 0.0, 0.3]}\n",
         "fixture B .* out of reach"),
        ("fixtures:\n  A: {position: [0.0, 0.05, 0.2]}\n", "fixture A .* inside the robot"),
        ("fixtures:\n  A: {position: [0.5, 0.0]}\n", "row 2, field 'fixtures.A.position'"),
        ("fixtures:\n  A: {}\n", "fixtures.A.position.*true centre"),
        ("fixtures: [unclosed\n", "invalid YAML"),
    ],
)
def test_bad_fixtures_exit_nonzero_and_write_nothing(tmp_path, capsys, text, message):
    import re

    path = _write(tmp_path, text)
    code, out = _simulate(tmp_path, "--fixtures", str(path))
    err = capsys.readouterr().err.strip()
    assert code == 1
    assert len(err.splitlines()) == 1 and err.startswith("spherecal simulate: error:")
    assert re.search(message, err), err
    assert not out.exists()


@pytest.mark.parametrize("args", [["--seconds", "0"], ["--per-fixture", "100000"], ["--noise", "-1"],
                                  ["--seconds", "inf"], ["--noise", "inf"], ["--length-std", "nan"],
                                  ["--seed", "-1"], ["--seconds", "0.0004"],
                                  ["--solver", "nope"], ["--robot", "missing.yaml"]])
def test_bad_options_exit_nonzero_and_write_nothing(tmp_path, capsys, args):
    code, out = _simulate(tmp_path, *args)
    assert code == 1 and len(capsys.readouterr().err.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.parametrize("command", [
    ["simulate", "--out", "out", "--seconds", "0.01", "--per-fixture", "5"],
    ["calibrate", "--samples", "s.csv", "--out", "cal.yaml"],
    ["plan", "--grid", "0.3,0.5,2;-0.1,0.1,2;0.2,0.4,2"],
    ["validate", "--calibrated", "panda", "--samples", "s.csv"],
])
def test_an_unknown_robot_name_is_refused_with_the_embedded_names(tmp_path, capsys, monkeypatch, command):
    # a review: 'simulate --robot ur5x' said 'ur5x: cannot read: No such file or directory', not which names are
    # known; the loader says it, for every command
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.csv").write_text("fixture,q1,q2,q3,q4,q5,q6,q7\n")
    option = "--nominal" if command[0] == "validate" else "--robot"
    refused([*command, option, "ur5x"], tmp_path, capsys,
            f"ur5x: field '{option}': no such file, nor an embedded robot (" + ", ".join(EMBEDDED_ROBOTS) + ")")


def test_out_below_a_file_fails_before_simulating(tmp_path, capsys):
    (tmp_path / "plain").write_text("x")
    code = main(["simulate", "--out", str(tmp_path / "plain" / "sub"), "--seconds", "0.5", "--per-fixture", "10"])
    err = capsys.readouterr().err.strip()
    assert code == 1 and err.startswith("spherecal simulate: error: ") and "field '--out'" in err and "\n" not in err
    assert "P1" not in err and sorted(p.name for p in tmp_path.iterdir()) == ["plain"]


def test_arm_without_self_motion_is_refused(tmp_path, capsys, panda):
    """A point fixture leaves n - 3 degrees of freedom: a 3-joint arm cannot move at all."""
    from dataclasses import replace

    from spherecal.correction import save_robot, tool_point

    arm = replace(panda, **{k: getattr(panda, k)[:3] for k in ("a", "alpha", "d", "theta", "lower", "upper")},
                  tool=[0.3, 0.0, 0.0], extras={"inertials": panda.extras["inertials"][:3]})  # one per joint
    robot = save_robot(arm, tmp_path / "r3.yaml")
    centre = tool_point(arm, np.array([0.2, 0.5, 0.1])).tolist()
    fixtures = _write(tmp_path, f"fixtures:\n  A: {{position: {centre}}}\n")
    code, out = _simulate(tmp_path, "--robot", str(robot), "--fixtures", str(fixtures))
    err = capsys.readouterr().err.strip()
    assert code == 1 and "3 joints" in err and "\n" not in err and not out.exists()
