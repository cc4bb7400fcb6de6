"""The default loss (``auto``): least squares, then Huber at 2.5x the noise the residuals show. A press taken before
the ball sat in its socket (about 1 mm off among 0.15 mm of noise: MUKCa's real iiwa14, the first two presses of
``raised_left_h0``) pulls with a bounded weight; clean Gaussian data keeps its least-squares accuracy. The truth is
known (simulation): accuracy is the calibrated tool point against the true arm's over random configurations."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.cli import main
from spherecal.correction import Dataset, load_robot, perturb, registered_errors, tool_point
from spherecal.correction.files.fixtures import write_fixtures
from spherecal.correction.files.samples_csv import write_samples
from spherecal.identification.build import build_problem
from spherecal.identification.calibrate import ROBUST_CUT, robust_noise
from spherecal.identification.synthetic import PANDA_FIXTURES, make_dataset, unseated
from spherecal.identification.workflow import WorkflowOptions, run_workflow

NOISE, PER_FIXTURE = 1.5e-4, 60


def _aligned_error(model, true, q) -> float:
    """RMS distance [m] of ``model``'s tool points from ``true``'s at ``q`` after the best rigid fit (the world frame
    of a calibration from unknown sockets is free)."""
    return float(np.sqrt(np.mean(registered_errors(tool_point(model, q), tool_point(true, q)) ** 2)))


def _recording(seed: int, count: int, offset: float = 1.5e-3):
    """(nominal Panda, true arm, samples, spec): three sockets, ``count`` presses per socket ``offset`` [m] off."""
    panda = load_robot("panda")
    rng = np.random.default_rng(seed)
    true = perturb(panda, rng)
    data, spec = make_dataset(true, per_fixture=PER_FIXTURE, rng=rng, noise=NOISE)
    return panda, true, unseated(true, data, PANDA_FIXTURES, count, offset, rng), spec


def _errors(seed: int, unseated: int) -> dict[str, float]:
    panda, true, data, spec = _recording(seed, unseated)
    q = panda.random_configurations(1000, np.random.default_rng(7))
    return {loss: _aligned_error(run_workflow(panda, data, spec, WorkflowOptions(loss=loss)).model, true, q)
            for loss in ("auto", "linear")}


@pytest.mark.slow
def test_unseated_presses_pull_less_and_clean_data_keeps_least_squares_accuracy() -> None:
    # 3 of 60 presses per socket 1.5 mm off: least squares 0.106 mm, the default 0.078 mm (8 of 8 seeds better);
    # clean: 0.0667 both (simulations of this commit)
    unseated = [_errors(seed, 3) for seed in (1, 2, 3)]
    assert all(e["auto"] < e["linear"] for e in unseated), unseated
    assert np.mean([e["auto"] for e in unseated]) < 0.85 * np.mean([e["linear"] for e in unseated]), unseated
    clean = [_errors(seed, 0) for seed in (1, 2)]
    assert all(e["auto"] <= 1.03 * e["linear"] for e in clean), clean


def test_robust_noise_is_the_gaussian_std_and_ignores_a_few_presses_far_off() -> None:
    panda = load_robot("panda")
    rng = np.random.default_rng(3)
    data, spec = make_dataset(panda, per_fixture=400, rng=rng, noise=2e-4)
    problem = build_problem(panda, data, spec)
    centres = np.array([tool_point(panda, data.q[data.labels == n]).mean(axis=0) for n in data.fixture_names])
    x = problem.pack(panda.params, centres)  # the true arm, each socket at its samples' mean
    assert robust_noise(problem, x) == pytest.approx(2e-4, rel=0.1)
    far = data.q.copy()
    far[::20] = panda.random_configurations(len(far[::20]), rng)  # 5 % of the presses anywhere in the workspace
    spoiled = build_problem(panda, Dataset(labels=data.labels, q=far, fixture_names=data.fixture_names), spec)
    assert robust_noise(spoiled, x) == pytest.approx(2e-4, rel=0.2)
    assert np.std(spoiled.sample_errors(x)) > 100 * 2e-4  # least squares' noise would read them


def test_the_file_and_report_name_the_loss_and_linear_stays_plain(tmp_path, capsys) -> None:
    panda, _, data, spec = _recording(4, 2)
    samples = write_samples(tmp_path / "samples.csv", data)
    fixtures = write_fixtures(tmp_path / "fixtures.yaml", spec)
    base = ["calibrate", "--robot", "panda", "--samples", str(samples), "--fixtures", str(fixtures), "--model", "dh"]
    assert main([*base, "--out", str(tmp_path / "auto.yaml")]) == 0
    printed = capsys.readouterr().out
    block = load_robot(tmp_path / "auto.yaml").extras["calibration"]
    assert block["options"]["loss"] == "auto" and block["loss"] == "huber"
    assert block["loss_scale_m"] == pytest.approx(ROBUST_CUT * NOISE, rel=0.25)
    line = next(line for line in printed.splitlines() if line.startswith("loss: huber at "))
    assert f"at {block['loss_scale_m'] * 1e3:.3f} mm, 2.5x the " in line, line
    shown = float(line.split("x the ")[1].split(" mm")[0])  # the least-squares residuals' noise, printed
    assert shown == pytest.approx(block["loss_scale_m"] * 1e3 / ROBUST_CUT, abs=1e-3), line
    beyond = int(line.split("median: ")[1].split(" of ")[0])
    assert 2 * len(data.fixture_names) <= beyond <= 2 * len(data.fixture_names) + 0.15 * data.n_samples, line
    assert "(Gaussian noise puts 3.7 % there)" in line
    assert main([*base, "--loss", "linear", "--out", str(tmp_path / "linear.yaml")]) == 0
    block = load_robot(tmp_path / "linear.yaml").extras["calibration"]
    assert block["loss"] == "linear" and block["loss_scale_m"] is None
    assert "loss: " not in capsys.readouterr().out


def test_a_socket_that_moved_while_recorded_is_still_refused_not_discounted() -> None:
    # the Gen3 lite's front_h0 drifts 13.5 mm over its presses; with front, left and raised_back the default's
    # Huber fit discounted its far presses and wrote the calibration (the refusal's advice, --exclude-fixture
    # front_h0, gave 4.66 mm held out at lower_left, this 5.01 mm)
    from pathlib import Path

    from spherecal.identification.ingest.importers import read_mukca
    from spherecal.identification.selfcheck import InconsistentDataError

    data = Path(__file__).parents[1] / "data" / "mukca"
    kinova = load_robot(data / "gen3lite_ball.yaml")
    recording, spec = read_mukca(data / "dinova_1", kinova)
    dataset = Dataset(labels=recording.labels, q=recording.q, fixture_names=spec.names)
    with pytest.raises(InconsistentDataError, match="front_h0 moves .* with recording order"):
        run_workflow(kinova, dataset, spec, WorkflowOptions())
