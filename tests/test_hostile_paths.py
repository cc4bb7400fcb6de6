"""A third round of hostile inputs on the newest paths (issue 21's hidden check): tool swaps onto the wrong link,
numbers argparse or numpy misread, plan's candidates, socket-only validate, awkward real recordings. Each case
that exited 0 with a wrong result, crashed or spoke in several lines is refused in one line naming file and
field (exit 1, nothing written), or handled and said."""

from __future__ import annotations

import re
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from spherecal.cli import main
from spherecal.correction import load_robot, perturb, save_robot
from spherecal.correction.files.samples import Dataset
from spherecal.correction.files.samples_csv import read_samples, write_samples
from spherecal.identification.synthetic import make_dataset
from spherecal.validation.planning.candidates import MAX_CANDIDATES, CandidateError
from spherecal.validation.planning.placements import plate_placements, read_placements
from tests.correction.urdf_helpers import DATA as URDF
from tests.refusal import refused
from tests.test_trust import _calibrated, _validate

MUKCA = Path(__file__).resolve().parent / "data" / "mukca"
PANDA = MUKCA / "panda_ball.yaml"


# ----------------------------------------------------------------------------------------- tool
@pytest.mark.parametrize(("links", "field", "expected"), [
    (["--tip-link", "panda_link3"], "--tip-link", "the chain from 'panda_link0' to 'panda_link3' has 3 joints, "
                                                  "the calibrated arm 7: the tool link must lie beyond"),
    (["--tip-link", "panda_hand_tcp", "--base-link", "panda_link3"], "--base-link",
     "the chain from 'panda_link3' to 'panda_hand_tcp' has 4 joints"),
])
def test_a_tool_link_before_the_flange_is_named(tmp_path, capsys, links, field, expected) -> None:
    # was: 'tool description: joints: 3 joints, expected 7' (no file, no option)
    refused(["tool", "panda", "--urdf", URDF / "panda.urdf", *links, "--out", tmp_path / "new.yaml"], tmp_path,
            capsys, f"panda.urdf: field '{field}': {expected}")


def test_a_tool_urdf_of_another_arm_names_the_file(tmp_path, capsys) -> None:
    # was: 'tool description: its last frame is 178 mm ...' without the file
    refused(["tool", "panda", "--urdf", URDF / "iiwa14.urdf", "--out", tmp_path / "new.yaml"], tmp_path, capsys,
            "iiwa14.urdf: field '--urdf': the chain from 'base_link' to 'ball_link': its last frame is")


def test_a_huge_tool_offset_is_refused_in_metres_not_inf(tmp_path, capsys) -> None:
    # was: 'is inf m from the last frame ... (after 1 warning: overflow encountered in dot)'
    err = refused(["tool", "panda", "--offset", "0", "1e300", "0.1", "--out", tmp_path / "new.yaml"], tmp_path,
                  capsys, "is 1e+300 m from the last frame")
    assert "inf" not in err and "warning" not in err


def test_a_negative_number_in_exponent_notation_is_a_value(tmp_path, capsys) -> None:
    # was: 'argument --offset: expected 3 arguments' (argparse took -1e-2 for an option)
    out = tmp_path / "new.yaml"
    assert main(["tool", "panda", "--offset", "-1e-2", "0", "0.2", "--out", str(out)]) == 0
    assert load_robot(out).tool.tolist() == [-0.01, 0.0, 0.2]
    refused(["tool", "panda", "--offset", "-inf", "0", "0.2", "--out", tmp_path / "other.yaml"], tmp_path, capsys,
            "field '--offset': expected a finite number, got '-inf'")


def test_a_tool_swap_of_a_forced_calibration_says_so(tmp_path, capsys) -> None:
    # export and validate warned of a calibration written with --force; tool wrote its new file without a word
    panda = load_robot("panda")
    block = {"self_check": {"verdict": "inconsistent", "failed": ["samples.csv: rows 2-9: a reason"]}}
    save_robot(replace(panda, extras={**panda.extras, "calibration": block}), tmp_path / "forced.yaml")
    assert main(["tool", str(tmp_path / "forced.yaml"), "--offset", "0", "0", "0.2", "--out",
                 str(tmp_path / "new.yaml")]) == 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "INCONSISTENT: samples.csv: rows 2-9: a reason" in err


# ----------------------------------------------------------------------------------------- plan
@pytest.mark.parametrize(("sockets", "distances", "expected"), [
    ("{a: [0.42, 0.21, 0.02], b: [0.42, 0.26, 0.02]}", "[[a, b, 0.5]]",
     "row 4, field 'candidates.left.distances[0]': a - b is 500 mm here, but their positions are 50 mm apart"),
    ("{a: [0.42, 0.21, 0.02], b: [0.42, 0.21, 0.02]}", "[]",
     "row 3, field 'candidates.left.sockets.b': 0 mm from socket a: sockets closer than 20 mm are one socket under "
     "two names"),
])
def test_a_candidate_plate_that_contradicts_itself_is_refused(tmp_path, sockets, distances, expected) -> None:
    # was: exit 0, a plate whose drawing says 500 mm between sockets placed 50 mm apart ranked as given; two sockets
    # at one point refused later as 'p2/samples.csv: all rows, field 'fixture': fixture b holds the same ...'
    path = tmp_path / "candidates.yaml"
    path.write_text(f"candidates:\n  left:\n    sockets: {sockets}\n    distances: {distances}\n")
    with pytest.raises(CandidateError, match=re.escape(f"candidates.yaml: {expected}")):
        read_placements(path)
    path.write_text("candidates:\n  left:\n    sockets: {a: [0.42, 0.21, 0.02], b: [0.42, 0.26, 0.02]}\n"
                    "    distances: [[a, b, 0.051]]\n")  # a plate placed by eye: its drawing's distance stands
    assert read_placements(path)[0].distances == (("a", "b", 0.051),)


def test_too_many_candidates_are_refused_before_any_survey(tmp_path, capsys) -> None:
    # was: 10^4 candidates from a file surveyed for 12 minutes (1000: 70 s on one core)
    path = tmp_path / "candidates.yaml"
    path.write_text("candidates:\n" + "".join(f"  C{k}: {{position: [0.5, {k * 1e-4:.4f}, 0.3]}}\n"
                                              for k in range(MAX_CANDIDATES + 1)))
    refused(["plan", "--candidates", path], tmp_path, capsys,
            f"candidates.yaml: field 'candidates': {MAX_CANDIDATES + 1} candidates, at most {MAX_CANDIDATES}")
    refused(["plan", "--grid", "0.3,0.6,40;-0.3,0.3,40;0.3,0.3,1"], tmp_path, capsys, "1600 points, at most 1000")
    with pytest.raises(CandidateError, match="500 points x 3 orientations make 1500 placements, at most 1000"):
        plate_placements({"h0": np.zeros(3), "h1": np.array([0.05, 0, 0])}, "0.3,0.6,50;-0.3,0.3,10;0.02,0.02,1",
                         3)


def test_plan_never_chooses_fixtures_closer_than_the_calibration_accepts(tmp_path, capsys) -> None:
    # a grid of 5 mm: exit 0, 'best set: C1, C2, C3; measure distances: C2-C3' (5 mm apart; calibrate refuses
    # fixtures closer than 20 mm)
    fine = ["plan", "--grid", "0.5,0.51,3;0,0,1;0.3,0.3,1", "--workers", "1", "--per-fixture", "50"]
    refused(fine, tmp_path, capsys, "no 3 of the 3 reachable candidates lie at least 20 mm apart")
    assert main([*fine[:2], "0.5,0.53,3;0,0,1;0.3,0.3,1", *fine[3:], "--fixture-count", "2"]) == 0
    assert "best set (exhaustive search): C1, C3;" in capsys.readouterr().out  # the one pair 20 mm apart or more


def test_a_candidate_socket_named_like_a_recorded_fixture_names_the_file(tmp_path, capsys) -> None:
    # was: 'candidate left: socket 'front_center_h0' is a recorded fixture's name' (no file, no field)
    out = _imported(tmp_path)
    path = tmp_path / "candidates.yaml"
    path.write_text("candidates:\n  left:\n    sockets: {front_center_h0: [0.42, 0.21, 0.02], x: [0.42, 0.26, 0.02]}\n")
    refused(["plan", "--robot", PANDA, "--samples", out / "samples.csv", "--fixtures", out / "fixtures.yaml",
             "--candidates", path], tmp_path, capsys,
            "candidates.yaml: field 'candidates.left.sockets.front_center_h0': socket 'front_center_h0' is a "
            "recorded fixture's name")


# ------------------------------------------------------------------------------------ validate
def test_socket_samples_of_another_arm_with_as_many_joints_are_refused(tmp_path, capsys) -> None:
    # an iiwa's sockets validated with a Panda's files: exit 0, spreads of 112-195 mm per socket and only
    # 'WORSE than nominal' (the real arms' nominal spreads: 8-12 mm)
    iiwa, panda = load_robot("iiwa14"), load_robot("panda")
    dataset, _ = make_dataset(iiwa, per_fixture=20, rng=np.random.default_rng(3))
    q = np.clip(dataset.q, panda.lower, panda.upper)  # within the Panda's limits: read as its angles
    write_samples(tmp_path / "iiwa.csv", Dataset(dataset.labels, q))
    refused(["validate", "--nominal", "panda", "--calibrated", "panda", "--samples", tmp_path / "iiwa.csv"],
            tmp_path, capsys, "iiwa.csv: rows 2-21, field 'q*': at socket ", "every model spreads the tool points",
            "samples of another arm")
    own, _ = make_dataset(perturb(panda, np.random.default_rng(4)), per_fixture=20, rng=np.random.default_rng(5))
    write_samples(tmp_path / "panda.csv", own)  # a Panda 1 mm / 0.2 deg off its nominal model: validated
    assert main(["validate", "--nominal", "panda", "--calibrated", "panda", "--samples",
                 str(tmp_path / "panda.csv")]) == 0


# ------------------------------------------------------------------------------------ calibrate
def _imported(tmp_path) -> Path:
    out = tmp_path / "recorded"
    assert main(["import", str(MUKCA / "panda_2_clean"), "--format", "mukca", "--robot", str(PANDA), "--out",
                 str(out)]) == 0
    return out


def test_a_prior_too_heavy_for_the_arm_is_named_as_the_cause(tmp_path, capsys) -> None:
    # MUKCa's Panda at --prior 50: refused as 'residual noise 0.647 mm per axis ... samples of another arm, a fixture
    # that moved, a fit that did not converge ...' while the samples alone sat at 0.25-0.26 mm (the prior's rows
    # were it)
    out = _imported(tmp_path)
    argv = ["calibrate", "--robot", PANDA, "--samples", out / "samples.csv", "--fixtures", out / "fixtures.yaml",
            "--out", tmp_path / "cal.yaml"]
    err = refused([*argv, "--prior", "50"], tmp_path, capsys, "with the prior's rows (the samples alone 0.2",
                  "the prior (--prior 50, default 0.5) holds the parameters nearer the nominal model than this arm is")
    assert "samples of another arm" not in err
    refused([*argv, "--prior", "1e6"], tmp_path, capsys, "the prior (--prior 1e+06, default 0.5) holding the model "
                                                         "at nominal")
    assert main([str(a) for a in argv]) == 0  # the default prior calibrates


def test_validate_knows_a_subset_of_the_training_samples(tmp_path, capsys) -> None:
    # the training recording imported again with another subsample (every fixture a subset of a trained one):
    # counted as held out, test MAE 0.192 mm on MUKCa's Panda from its own training samples
    _, true, dataset, _, cal = _calibrated(tmp_path, capsys)
    subset = dataset.select(np.flatnonzero(np.arange(dataset.n_samples) % 3 == 1)[::-1])  # another order too
    write_samples(tmp_path / "again.csv", subset)
    printed, _, report = _validate(tmp_path, capsys, tmp_path / "again.csv", cal)
    assert all(not f["held_out"] for f in report["fixtures"].values()) and "front_h0 (fit)" in printed
    held, _ = make_dataset(true, per_fixture=30, rng=np.random.default_rng(9), noise=2e-4)
    write_samples(tmp_path / "held.csv", Dataset(np.where(held.labels == held.fixture_names[0], "front_h0",
                                                          held.labels), held.q))  # new samples, a trained name
    _, _, report = _validate(tmp_path, capsys, tmp_path / "held.csv", cal)
    assert all(f["held_out"] for f in report["fixtures"].values())


def test_a_held_out_spread_far_beyond_the_prediction_is_remarked(tmp_path, capsys) -> None:
    # MUKCa's Gen3 lite trained on 'left', validated on the others (front_h0 moved while recorded): 5.97 mm
    # measured against 2.80 mm predicted, and the only hint was the band printed under the table
    _, true, _, _, cal = _calibrated(tmp_path, capsys)
    held, _ = make_dataset(true, per_fixture=30, rng=np.random.default_rng(9), noise=2e-4)
    write_samples(tmp_path / "held.csv", held)
    _, err, report = _validate(tmp_path, capsys, tmp_path / "held.csv", cal)
    assert "it predicts there" not in err  # the same arm: within the band
    other = perturb(true, np.random.default_rng(12), 0.5e-3, np.deg2rad(0.1), 0.5e-3)  # the arm changed since
    moved, _ = make_dataset(other, per_fixture=30, rng=np.random.default_rng(9), noise=2e-4)
    write_samples(tmp_path / "moved.csv", moved)
    _, err, report = _validate(tmp_path, capsys, tmp_path / "moved.csv", cal)
    ratio = report["held_out"]["calibrated"]["test_mae"] / report["held_out"]["predicted_test_mae"]
    assert ratio > 2 and f"is {ratio:.2g}x the " in err and "beyond 2x" in err


def test_guidance_on_a_recording_no_model_describes_is_refused(tmp_path, capsys) -> None:
    # ten samples slipped a tenth of a turn: calibrate refuses the recording (23.8 mm per axis), plan --samples
    # ranked candidates on it ('now: 46.1 mm') and said 'more recording is not worth it', exit 0
    out = _imported(tmp_path)
    dataset = read_samples(out / "samples.csv", load_robot(PANDA))
    q = dataset.q.copy()
    q[np.random.default_rng(0).choice(dataset.n_samples, 10, replace=False), 2] += 0.3
    write_samples(tmp_path / "slipped.csv", Dataset(dataset.labels, q))
    candidates = tmp_path / "candidates.yaml"
    candidates.write_text("candidates:\n  left:\n    sockets: {a: [0.42, 0.21, 0.02], b: [0.42, 0.26, 0.02]}\n")
    refused(["plan", "--robot", PANDA, "--samples", tmp_path / "slipped.csv", "--fixtures", out / "fixtures.yaml",
             "--candidates", candidates], tmp_path, capsys,
            "slipped.csv: rows 2-186: the recording so far leaves ", "mm per axis after calibration (a ball held in a "
            "socket stays within 10 mm): no candidate can be judged on it")


def test_known_distances_all_wrong_alike_are_named_not_the_prior(tmp_path, capsys) -> None:
    # MUKCa's plate imported with --distance 0.06 (its sockets are 50 mm apart): 'samples of another arm, a fixture
    # that moved, a fit that did not converge...' while the samples alone fit at 0.4 mm with a stretched arm
    out = tmp_path / "recorded"
    assert main(["import", str(MUKCA / "panda_2_clean"), "--format", "mukca", "--robot", str(PANDA), "--distance",
                 "0.06", "--out", str(out)]) == 0
    err = refused(["calibrate", "--robot", PANDA, "--samples", out / "samples.csv", "--fixtures",
                   out / "fixtures.yaml", "--out", tmp_path / "cal.yaml"], tmp_path, capsys,
                  "the samples alone 0.4", "known distances or positions that are wrong (all alike")
    assert "--prior" not in err


def test_a_robust_loss_with_the_pso_method_is_refused(tmp_path, capsys) -> None:
    # was: exit 0, the loss ignored by PSO while the file recorded 'loss: soft_l1' and the self-check left out the
    # samples it had 'discounted'
    out = _imported(tmp_path)
    refused(["calibrate", "--robot", PANDA, "--samples", out / "samples.csv", "--method", "pso", "--loss", "huber",
             "--out", tmp_path / "cal.yaml"], tmp_path, capsys,
            "field '--loss': huber: the pso method fits plain least squares; a robust loss needs --method lm or pso+lm")


def test_a_known_distance_below_the_socket_separation_is_refused_before_the_fit(tmp_path, capsys) -> None:
    # MUKCa's panda_2 (16 sockets) imported with --distance 0.0005: calibrate ran for over 90 s (the fit pulling
    # each pair together under a 1 um weight) before the self-check refused it
    out = tmp_path / "recorded"
    assert main(["import", str(MUKCA / "panda_2_clean"), "--format", "mukca", "--robot", str(PANDA), "--distance",
                 "0.0005", "--out", str(out)]) == 0
    start = time.process_time()
    refused(["calibrate", "--robot", PANDA, "--samples", out / "samples.csv", "--fixtures", out / "fixtures.yaml",
             "--out", tmp_path / "cal.yaml"], tmp_path, capsys, "fixtures.yaml: row ", "field 'distances[0]': "
            "distance back_left_h0-back_left_h1 is 0.5 mm: fixtures closer than 20 mm check nothing")
    assert time.process_time() - start < 5.0
    # a review: a distance just under the limit was printed rounded to it ('is 20 mm: fixtures closer than 20 mm')
    (out / "fixtures.yaml").write_text((out / "fixtures.yaml").read_text().replace("0.0005", "0.01998"))
    refused(["calibrate", "--robot", PANDA, "--samples", out / "samples.csv", "--fixtures", out / "fixtures.yaml",
             "--out", tmp_path / "cal.yaml"], tmp_path, capsys, "is 19.98 mm: fixtures closer than 20 mm")
