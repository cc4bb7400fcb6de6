"""`spherecal calibrate`: output file, bad input (one line, exit 1, no output), light start-up."""

from __future__ import annotations

import hashlib
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from spherecal.cli import main
from spherecal.correction import load_robot, perturb, save_robot
from spherecal.correction.files.fixtures import write_fixtures
from spherecal.correction.files.samples_csv import write_samples
from spherecal.identification.synthetic import make_dataset

ROOT = Path(__file__).parents[2]
HEADER = "fixture,q1,q2,q3,q4,q5,q6,q7\n"


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cal")
    panda = load_robot("panda")
    true = perturb(panda, np.random.default_rng(11))
    dataset, spec = make_dataset(true, per_fixture=200, rng=np.random.default_rng(12))
    save_robot(panda, folder / "robot.yaml")
    write_samples(folder / "samples.csv", dataset)
    write_fixtures(folder / "fixtures.yaml", spec)
    return folder


def test_calibrate_writes_a_robot_file_with_its_provenance(inputs, tmp_path, capsys) -> None:
    out = tmp_path / "cal.yaml"
    args = ["calibrate", "--robot", str(inputs / "robot.yaml"), "--samples", str(inputs / "samples.csv")]
    code = main(args + ["--fixtures", str(inputs / "fixtures.yaml"), "--max-per-fixture", "150", "--out", str(out)])
    assert code == 0
    printed = capsys.readouterr().out
    assert "residual [mm]" in printed and "fixed" in printed
    model = load_robot(out)  # any consumer of robot files can read it
    block = model.extras["calibration"]
    assert block["method"] == "lm" and block["samples_per_fixture"] == {"P1": 150, "P2": 150, "P3": 150}
    # noise-free data, the default prior (W 0.5 at the declared 0.3 mm) pulls toward nominal by micrometres
    assert block["residual_mm"]["after"]["rms"] < 5e-3
    assert block["prior_weight"] == block["options"]["prior"] == 0.5
    assert 0 < block["effective_unknowns"] < len(block["identified"]) + 3 * 3
    assert {"d7", "theta7", "a1", "base_x"} <= set(block["fixed"])
    assert set(block["identified"]) <= set(block["std"])
    made = block["provenance"]
    assert len(made["inputs"]["samples"]["sha256"]) == 64 and "fixtures" in made["inputs"]
    assert made["inputs"]["samples"]["sha256"] == hashlib.sha256((inputs / "samples.csv").read_bytes()).hexdigest()
    assert {"numpy", "scipy", "mujoco", "spherecal"} <= set(made["versions"]) and made["seed"] == 0
    assert set(block["fixture_centres"]) == {"P1", "P2", "P3"}


def _bad(tmp_path, samples_text=None, fixtures_text=None, inputs=None):
    samples = tmp_path / "s.csv"
    if samples_text is not None:
        samples.write_text(samples_text)
    else:
        samples.write_text((inputs / "samples.csv").read_text())
    args = ["calibrate", "--robot", "panda", "--samples", str(samples), "--out", str(tmp_path / "cal.yaml")]
    if fixtures_text is not None:
        (tmp_path / "f.yaml").write_text(fixtures_text)
        args += ["--fixtures", str(tmp_path / "f.yaml")]
    return args


GOOD = "P1,0,0,0,-1,0,1,0\nP1,0.1,0,0,-1,0,1,0\n"


@pytest.mark.parametrize(
    ("samples", "fixtures", "where"),
    [
        (HEADER + GOOD + "P1,0,0,nan,-1,0,1,0\n", None, ("s.csv", "row 4", "field 'q3'")),
        (HEADER + GOOD + "P1,0,0,x,-1,0,1,0\n", None, ("s.csv", "row 4", "field 'q3'")),
        ("fixture,q1,q2,q3,q4,q5,q6\nP1,0,0,0,-1,0,1\n", None, ("s.csv", "row 1", "field 'q*'")),
        (HEADER + GOOD + "P1,0,0,0,2.2,0,1,0\n", None, ("s.csv", "row 4", "field 'q4'")),  # > a quarter turn past
        ("", None, ("s.csv", "row 1", "field 'fixture'")),
        (HEADER + GOOD, None, ("s.csv", "rows 2-3", "field 'fixture'")),  # fewer samples than unknowns
        (
            None,
            "fixtures: {P1: {}, P2: {}, P3: {}, P4: {}}\ndistances:\n  - [P1, P4, 0.5]\n",
            ("f.yaml", "row 3", "field 'distances[0]'", "'P4' has no samples"),
        ),
        (
            None,
            "fixtures: {P1: {}, P2: {}, P3: {}}\ndistances:\n  - [P1, P2, -0.5]\n",
            ("f.yaml", "row 3", "field 'distances[0][2]'"),
        ),
    ],
)
def test_bad_input_one_line_exit_1_no_output(inputs, tmp_path, capsys, samples, fixtures, where) -> None:
    args = _bad(tmp_path, samples, fixtures, inputs)
    assert main(args) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("spherecal calibrate: error: "), err
    for part in where:
        assert part in err, err
    assert not (tmp_path / "cal.yaml").exists()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".cal.yaml")]


def test_lm_path_imports_no_simulator_viewer_or_swarm(inputs, tmp_path) -> None:
    code = (
        "import sys; from spherecal.cli import main;"
        f"main(['calibrate','--robot','panda','--samples',{str(inputs / 'samples.csv')!r},"
        f"'--fixtures',{str(inputs / 'fixtures.yaml')!r},'--out',{str(tmp_path / 'c.yaml')!r}]);"
        "print(sorted(m for m in ('mujoco','rerun','pyswarms') if m in sys.modules), file=sys.stderr)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert out.stderr.strip().splitlines()[-1] == "[]"
    assert yaml.safe_load((tmp_path / "c.yaml").read_text())["calibration"]["method"] == "lm"
    assert not (tmp_path / "report.log").exists()


@pytest.mark.parametrize("model", ["dh", "auto"])
def test_calibrate_imports_no_scipy(inputs, tmp_path, model) -> None:
    """`calibrate` (lm, plain loss; dh, or auto with its elastic folds) runs our own solver and chi-square
    tail: scipy (0.3 s of start-up for scipy.optimize, as much for scipy.special) is never imported, nor
    MuJoCo, Rerun or pyswarms."""
    code = (
        "import sys; from spherecal.cli import main;"
        f"main(['calibrate','--robot','panda','--model',{model!r},'--samples',{str(inputs / 'samples.csv')!r},"
        f"'--fixtures',{str(inputs / 'fixtures.yaml')!r},'--out',{str(tmp_path / 'c.yaml')!r}]);"
        "heavy = ('scipy', 'mujoco', 'rerun', 'pyswarms', 'dask');"
        "print(sorted(m for m in heavy if m in sys.modules), file=sys.stderr)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert out.stderr.strip().splitlines()[-1] == "[]"
    assert (tmp_path / "c.yaml").exists()


def test_a_seed_nothing_random_uses_is_refused(tmp_path, capsys, monkeypatch) -> None:
    """A review: 'calibrate --seed' may be unused. It seeds --max-per-fixture's subsampling, --model auto's
    cross-validation folds and PSO; with --method lm, a --model other than auto and every sample kept, the calibrated
    model is the same whatever the seed (the evidence below), and the option is refused in one line."""
    from spherecal.correction import tool_point
    from spherecal.identification.workflow import WorkflowOptions, run_workflow
    from tests.refusal import refused

    panda = load_robot("panda")
    dataset, spec = make_dataset(perturb(panda, np.random.default_rng(3)), per_fixture=40,
                                 rng=np.random.default_rng(4))
    fits = [run_workflow(panda, dataset, spec, WorkflowOptions(model="dh", seed=seed)).model for seed in (0, 7)]
    q = panda.random_configurations(50, np.random.default_rng(5))
    np.testing.assert_array_equal(tool_point(fits[0], q), tool_point(fits[1], q))
    monkeypatch.chdir(tmp_path)  # the inputs need not exist: the option is refused before any is read
    argv = ["calibrate", "--robot", "panda", "--samples", "s.csv", "--out", "c.yaml", "--seed", "3"]
    refused([*argv, "--model", "dh"], tmp_path, capsys, "error: field '--seed': ", "--method lm")
    refused([*argv, "--model", "elastic", "--method", "lm"], tmp_path, capsys, "error: field '--seed': ")
    for uses in (["--model", "auto"], ["--model", "dh", "--method", "pso"], ["--model", "dh", "--max-per-fixture",
                                                                              "20"]):
        err = refused([*argv, *uses], tmp_path, capsys, "s.csv")  # refused for the missing samples only
        assert "--seed" not in err, uses
