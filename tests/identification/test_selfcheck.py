"""The calibration self-check: leave-one-out against explicit refits, the slips it must refuse (each
with its culprit), clean and real data that it must let through, and `calibrate --force`."""

from __future__ import annotations

import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml

from spherecal.correction import load_robot, perturb, registered_errors, tool_point
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.samples import Dataset, DatasetError
from spherecal.identification.calibrate import calibrate
from spherecal.identification.leave_out import leave_out
from spherecal.identification.problem import PRIOR, samples_location, samples_rows
from spherecal.identification.selfcheck import InconsistentDataError
from spherecal.identification.selfcheck_result import Advice, Finding, leave_out_advice
from spherecal.identification.synthetic import PANDA_FIXTURES, make_dataset


@pytest.fixture(scope="module")
def arm():
    panda = load_robot("panda")
    return panda, perturb(panda, np.random.default_rng(1))


@pytest.fixture(scope="module")
def noisy(arm):
    """3 x 300 samples at 0.3 mm noise, every distance known."""
    return make_dataset(arm[1], per_fixture=300, rng=np.random.default_rng(3), noise=3e-4)


def _error(model, true) -> float:
    q = true.random_configurations(2000, np.random.default_rng(5))
    return float(registered_errors(tool_point(model, q), tool_point(true, q)).mean())


# ----------------------------------------------------------------------------- leave one out
def test_leave_out_matches_explicit_refits() -> None:
    rng = np.random.default_rng(0)
    a = rng.normal(size=(60, 5))
    a[:, 4] = 0.0
    a[50:53, 4] = rng.normal(size=3)  # only rows 50-52 see unknown 4: that group is checked on 2 rows
    y = a @ rng.normal(size=5) + rng.normal(0, 0.1, 60)
    x = np.linalg.lstsq(a, y, rcond=None)[0]
    r = a @ x - y  # residual at the solution, Jacobian a
    groups = {"block": np.arange(10), "row": np.array([20]), "alone": np.array([50, 51, 52])}
    ssr, rank, left = leave_out(a, r, groups)
    assert ssr == pytest.approx(r @ r) and rank == 5
    for name, rows in groups.items():
        keep = np.setdiff1d(np.arange(60), rows)
        x_rest = np.linalg.lstsq(a[keep], y[keep], rcond=None)[0]
        rest = left[name]
        assert rest.ssr_rest == pytest.approx(np.sum((a[keep] @ x_rest - y[keep]) ** 2), rel=1e-9)
        assert rest.delta_ssr == pytest.approx(r @ r - rest.ssr_rest, rel=1e-9)
        if name != "alone":  # unknown 4 is free without the group: its prediction there is arbitrary
            assert np.allclose(rest.predicted, a[rows] @ x_rest - y[rows], atol=1e-10)
    assert left["block"].dof == 10 and left["row"].dof == 1 and left["alone"].dof == 2


# ------------------------------------------------------------------------------ clean data
@pytest.mark.parametrize("fixtures", [1, 2, 3])
def test_clean_data_is_written(arm, noisy, fixtures) -> None:
    panda, true = arm
    dataset, spec = noisy
    names = dataset.fixture_names[:fixtures]
    subset = dataset.select(np.flatnonzero(np.isin(dataset.labels, names)))
    distances = [d for d in spec.distances if d[0] in names and d[1] in names]
    result = calibrate(panda, subset, FixtureSpec(names, distances=distances))
    check = result.selfcheck
    assert check.consistent and check.refusal == ""
    block = result.block()["self_check"]
    assert block["verdict"] == "consistent" and block["failed"] == []
    assert 0.8 < block["checks"]["residual level"]["ratio"] < 1.2
    assert _error(result.model, true) < 0.5 * _error(panda, true)
    assert "self-check: consistent" in result.summary()


def test_a_single_distance_is_reported_unchecked(arm, noisy) -> None:
    # two fixtures and their distance: the distance alone sets the scale, nothing can check it
    panda, _ = arm
    dataset, spec = noisy
    subset = dataset.select(np.flatnonzero(np.isin(dataset.labels, ["P1", "P2"])))
    result = calibrate(panda, subset, FixtureSpec(("P1", "P2"), distances=spec.distances[:1]))
    finding = next(f for f in result.selfcheck.findings if f.check == "distance P1-P2")
    assert finding.passed and finding.figures == {"unchecked": True}
    assert any(line.startswith("  unchecked: distance P1-P2") for line in result.selfcheck.lines())


def test_a_single_long_distance_with_the_prior_is_checked_against_the_nominal_lengths(arm, noisy) -> None:
    # two fixtures 0.82 m apart, their exact distance, 0.3 mm noise, the MAP prior of the workflow: the leave-one-out
    # refit, with nothing but the prior to hold the scale, shrinks the arm for the noise (17 mm over 0.82 m); that
    # shrink is computed (consistency.scale_shrink) and taken out, and what is left is the prior's disagreement
    panda, true = arm
    dataset, spec = noisy
    subset = dataset.select(np.flatnonzero(np.isin(dataset.labels, ["P1", "P2"])))
    subset = Dataset(subset.labels, subset.q, fixture_names=("P1", "P2"))
    result = calibrate(panda, subset, FixtureSpec(("P1", "P2"), distances=spec.distances[:1]), prior=PRIOR)
    finding = next(f for f in result.selfcheck.findings if f.check == "distance P1-P2")
    assert finding.passed and "unchecked" not in finding.figures
    assert finding.figures["disagreement_mm"] < 2.0 * finding.figures["fit_std_mm"]
    assert _error(result.model, true) < 0.5 * _error(panda, true)
    (a, b, value), = spec.distances[:1]
    wrong = FixtureSpec(("P1", "P2"), distances=[(a, b, value * 1.02)], source="fixtures.yaml")  # 16 mm, 2 %
    with pytest.raises(InconsistentDataError, match=r"field 'distances\[0\]': distance P1-P2 .* disagrees with the "
                                                    r"arm's nominal lengths"):
        calibrate(panda, subset, wrong, prior=PRIOR)


@pytest.mark.parametrize("per_fixture", [30, 500])
def test_a_sole_50mm_distance_1mm_off_is_refused_and_the_right_one_written(arm, per_fixture) -> None:
    # a review (MUKCa kuka_14): 0.051 m typed for a plate's 0.050 doubled the residual and was written 'consistent',
    # the distance 'unchecked'; without the noise's shrink taken out, 500 samples a socket read the right distance as
    # 1 mm off (1.5 % of the scale), 30 samples as 0.08 mm
    panda, true = arm
    centres = {"A": np.array([0.5, 0.0, 0.2]), "B": np.array([0.5, 0.05, 0.2])}
    dataset, spec = make_dataset(true, centres, per_fixture, np.random.default_rng(4), noise=3e-4)
    result = calibrate(panda, dataset, spec, prior=PRIOR)
    finding = next(f for f in result.selfcheck.findings if f.check == "distance A-B")
    assert finding.passed and finding.figures["disagreement_mm"] < 0.3
    (a, b, value), = spec.distances
    for off in (0.001, 0.003, 0.005):  # a review: 53 and 55 mm went 'unchecked' (the refit held as a runaway)
        wrong = FixtureSpec(spec.names, distances=[(a, b, value + off)], source="fixtures.yaml")
        with pytest.raises(InconsistentDataError, match=rf"fixtures.yaml: field 'distances\[0\]': distance A-B "
                                                        rf"\({value + off:.6g} m\) disagrees with the arm's nominal"):
            calibrate(panda, dataset, wrong, prior=PRIOR)


# ------------------------------------------------------------------------------ the slips
def test_a_2mm_typo_in_a_distance_is_refused_by_name(arm, noisy) -> None:
    panda, _ = arm
    dataset, spec = noisy
    (a, b, value), *rest = spec.distances
    typo = FixtureSpec(spec.names, distances=[(a, b, value + 0.002), *rest], source="fixtures.yaml")
    with pytest.raises(InconsistentDataError) as error:
        calibrate(panda, dataset, typo)
    message = str(error.value)
    assert message.startswith("fixtures.yaml: field 'distances[0]': distance P1-P2")
    assert re.search(r"disagrees with the samples by (1\.9[5-9]|2\.0\d)\d mm", message), message
    assert "its stated accuracy 0.001 mm" in message
    assert "\n" not in message


def test_a_known_position_2mm_off_is_refused_by_name(arm, noisy) -> None:
    panda, _ = arm
    dataset, spec = noisy
    positions = {k: np.asarray(c, float) for k, c in PANDA_FIXTURES.items()}
    calibrate(panda, dataset, FixtureSpec(spec.names, positions=dict(positions)))  # exact: written
    positions["P2"] = positions["P2"] + np.array([0.002, 0.0, 0.0])
    with pytest.raises(
        InconsistentDataError, match=r"field 'fixtures.P2.position': the samples put P2 (1\.9[5-9]|2\.0\d)\d mm"
    ):
        calibrate(panda, dataset, FixtureSpec(spec.names, positions=positions))


@pytest.mark.parametrize("distances", [True, False])
def test_samples_of_two_arms_are_refused_naming_the_fixture(arm, noisy, distances) -> None:
    panda, _ = arm
    dataset, spec = noisy
    other, _ = make_dataset(perturb(panda, np.random.default_rng(11)), per_fixture=300, rng=np.random.default_rng(4))
    mine, theirs = dataset.labels != "P3", other.labels == "P3"
    mixed = Dataset(
        np.concatenate([dataset.labels[mine], other.labels[theirs]]),
        np.concatenate([dataset.q[mine], other.q[theirs]]),
        fixture_names=dataset.fixture_names,
    )
    known = FixtureSpec(spec.names, distances=spec.distances if distances else [])
    with pytest.raises(
        InconsistentDataError, match=r"field 'fixture': the samples at fixture P3 disagree with the other"
    ):
        calibrate(panda, mixed, known)


def test_two_fixtures_declared_1mm_apart_are_refused(arm, noisy) -> None:
    panda, _ = arm
    dataset, spec = noisy
    (a, b, _), *rest = spec.distances
    # refused when the problem is built, before a fit that pulls the two sockets together
    with pytest.raises(DatasetError, match=r"field 'distances\[0\]': distance P1-P2 is 1 mm: fixtures closer"):
        calibrate(panda, dataset, FixtureSpec(spec.names, distances=[(a, b, 0.001), *rest]))


def test_noise_declared_far_too_small_is_judged_at_the_noise_the_residuals_show(arm, noisy) -> None:
    # issue 20 item 7: refused before; residuals that look like noise and a calibration that still beats
    # nominal at that noise are written, with the figure as a warning
    panda, _ = arm
    dataset, spec = noisy
    level = next(f for f in calibrate(panda, dataset, spec, noise=5e-5).selfcheck.findings
                 if f.check == "residual level")
    assert level.passed and level.figures["honest_noise_warning"]
    assert re.search(r"residual noise 0\.\d+ mm per axis is \d\.\d+x the declared 0\.05 mm", level.message)


def test_the_honest_noise_warning_names_the_file_and_rows_as_samples_location_does(arm, noisy) -> None:
    # a review: the warning took its rows by cutting the file name off samples_location's text; a later one read
    # 'warning: rows 7-46: residual noise ...' under a summary that names no file, where every other location names it
    panda, _ = arm
    dataset, spec = noisy
    dataset = replace(dataset, source="samples.csv", lines=np.arange(dataset.n_samples) + 2)
    level = next(f for f in calibrate(panda, dataset, spec, noise=5e-5).selfcheck.findings
                 if f.check == "residual level")
    assert level.figures["honest_noise_warning"]
    assert level.message.startswith(f"warning: samples.csv: rows 2-{dataset.n_samples + 1}: residual noise ")
    assert samples_location(dataset) == f"samples.csv: rows 2-{dataset.n_samples + 1}"


@pytest.mark.parametrize(("source", "lines", "rows", "location"), [
    ("samples.csv", [4, 9, 7], "rows 4-9", "samples.csv: rows 4-9"),
    ("samples.csv", [37], "row 37", "samples.csv: row 37"),
    ("", None, "all rows", "samples: all rows"),
])
def test_samples_rows_is_the_rows_part_of_samples_location(noisy, source, lines, rows, location) -> None:
    dataset, _ = noisy
    picked = dataset.select(np.arange(len(lines) if lines else 3))
    picked = replace(picked, source=source, lines=None if lines is None else np.array(lines))
    assert samples_rows(picked) == rows and samples_location(picked) == location


def test_an_honest_large_noise_is_judged_at_the_declared_noise(arm, noisy) -> None:
    # 0.3 mm data declared at 5 mm: written (the result is good), but its accuracy is judged at 5 mm
    panda, true = arm
    dataset, spec = noisy
    result = calibrate(panda, dataset, spec, noise=5e-3)
    prediction = next(f for f in result.selfcheck.findings if f.check == "prediction").figures
    assert prediction["noise_used_mm"] == pytest.approx(5.0)
    assert prediction["predicted_mean_mm"] > 10 * 1e3 * _error(result.model, true)
    level = next(f for f in result.selfcheck.findings if f.check == "residual level")
    assert "accuracy is judged at the declared noise" in level.message


def test_data_that_cannot_beat_nominal_is_refused(arm) -> None:
    # 20 samples at one fixture with 10 mm noise, honestly declared: the fit is worse than nominal
    panda, true = arm
    dataset, _ = make_dataset(true, {"P1": PANDA_FIXTURES["P1"]}, 20, np.random.default_rng(3), noise=1e-2)
    forced = calibrate(panda, dataset, noise=1e-2, force=True)
    assert _error(forced.model, true) > _error(panda, true)
    refusal = r"cannot be expected to beat the nominal model by 2x.*is needed: predicted mean error"
    with pytest.raises(InconsistentDataError, match=refusal):
        calibrate(panda, dataset, noise=1e-2)


def test_a_fixture_whose_samples_hardly_move_the_arm_is_refused(arm, noisy) -> None:
    panda, _ = arm
    dataset, spec = noisy
    q = dataset.q.copy()
    still = dataset.labels == "P2"
    q[still] = q[still][0] + np.random.default_rng(0).normal(0, 1e-3, (still.sum(), 7))
    with pytest.raises(InconsistentDataError, match=r"the samples at fixture P2 hardly move the arm") as refused:
        calibrate(panda, Dataset(dataset.labels, q), FixtureSpec(spec.names))
    # a review: a pause in transit with hand tremor segmented into a fixture was told to record self-motion there;
    # it is no socket, and leaving it out is the remedy too
    assert str(refused.value).endswith("record self-motion there, or, if it is no socket (a pause with the ball in "
                                       "the air, taken for one by the segmentation), leave it out (calibrate "
                                       "--exclude-fixture P2)")


# ------------------------------------------------------------------------------ command line
def test_cli_refuses_with_one_line_and_force_writes_the_failures(arm, noisy, tmp_path, capsys) -> None:
    from spherecal.cli import main
    from spherecal.correction.files.fixtures import write_fixtures
    from spherecal.correction.files.samples_csv import write_samples

    _, _ = arm
    dataset, spec = noisy
    small = dataset.select(np.arange(0, dataset.n_samples, 3))
    (a, b, value), *rest = spec.distances
    write_samples(tmp_path / "samples.csv", small)
    write_fixtures(tmp_path / "fixtures.yaml", replace(spec, distances=[(a, b, value + 0.002), *rest]))
    args = [
        "calibrate",
        "--robot",
        "panda",
        "--samples",
        str(tmp_path / "samples.csv"),
        "--fixtures",
        str(tmp_path / "fixtures.yaml"),
        "--out",
        str(tmp_path / "cal.yaml"),
    ]
    assert main(args) == 1
    err = capsys.readouterr().err.strip()
    first, *details = err.splitlines()  # a long refusal: its reason in one line, its detail indented below it
    assert first.startswith("spherecal calibrate: error: refused: ") and all(d.startswith("  ") for d in details)
    assert "distance P1-P2" in first and "disagrees" in first
    assert not (tmp_path / "cal.yaml").exists()
    assert main([*args, "--force"]) == 0
    block = yaml.safe_load((tmp_path / "cal.yaml").read_text())["calibration"]
    assert block["provenance"]["inputs"]["force"] is True
    assert block["self_check"]["verdict"] == "inconsistent"
    assert any("distance P1-P2" in line for line in block["self_check"]["failed"])
    out = capsys.readouterr().out
    assert "FAILED: " in out
    # written because forced, not because it passed (a review: a forced run's level line ended ': written')
    assert re.search(r"^self-check: INCONSISTENT \(\d+ failed\): written only because forced \(--force\)$", out,
                     re.MULTILINE), out


# ------------------------------------------------------------------------------ real data
def _mukca() -> Path | None:
    for base in Path(__file__).resolve().parents:
        for candidate in (base / "shared" / "data" / "mukca", base / "tests" / "data" / "mukca"):
            if (candidate / "data" / "panda_2_clean").is_dir():
                return candidate / "data"
    return None


def _panda_ball():
    """The embedded Panda with MUKCa's ball centre as tool point: their urdf/panda.urdf from panda_link7
    (flange 0.107 m, hand rotated -45 deg about z, TCP 0.1034 m, ball offset), written out here."""
    c, s = np.cos(-np.pi / 4), np.sin(-np.pi / 4)
    ball = np.array([7.773732033005863e-05, -4.214022515884392e-05, 0.030128297908475325])
    tool = np.array([0.0, 0.0, 0.107]) + np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ (
        np.array([0, 0, 0.1034]) + ball
    )
    return replace(load_robot("panda"), tool=tool)


@pytest.mark.parametrize("placement", ["front_center", None])
def test_real_recordings_are_not_refused(placement) -> None:
    root = _mukca()
    if root is None:
        pytest.skip("the MUKCa recordings (shared/data/mukca) are not beside this checkout")
    robot = root / "panda_2_clean"
    chosen = [placement] if placement else sorted(p.name for p in robot.iterdir() if p.is_dir())
    labels, rows, distances = [], [], []
    for name in chosen:
        for hole in (0, 1):
            q = np.loadtxt(robot / name / f"hole_{hole}.csv", delimiter=",", ndmin=2)
            labels += [f"{name}_h{hole}"] * len(q)
            rows.append(q)
        distances.append((f"{name}_h0", f"{name}_h1", 0.05))
    dataset = Dataset(np.array(labels), np.concatenate(rows))
    result = calibrate(_panda_ball(), dataset, FixtureSpec(dataset.fixture_names, distances=distances))
    assert result.selfcheck.consistent
    assert 0.05e-3 < result.selfcheck.sigma < 0.3e-3  # real residuals: 0.1-0.2 mm per axis


# ----------------------------------------------------------------------------- serial correlation
def test_serial_correlation_reads_a_first_order_noise_in_recording_order(rng) -> None:
    """The lag-1 correlation of the residuals in recording order: an AR(1) noise of 0.6 reads 0.6, a white one 0;
    with time stamps the rows' order in the file does not matter."""
    from spherecal.identification.selfcheck import serial_correlation

    k = 800
    white = rng.normal(0.0, 1e-4, (k, 3))
    ar = np.zeros_like(white)
    for i in range(1, k):
        ar[i] = 0.6 * ar[i - 1] + 0.8 * white[i]
    labels = np.repeat(["P1", "P2"], k // 2)
    ordered = Dataset(labels, np.zeros((k, 7)), t=np.arange(k) * 0.01)
    assert serial_correlation(ordered, ar) == pytest.approx(0.6, abs=0.06)
    assert abs(serial_correlation(ordered, white)) < 0.08
    shuffled = rng.permutation(k)
    assert serial_correlation(ordered.select(shuffled), ar[shuffled]) == pytest.approx(serial_correlation(ordered, ar))
    assert np.isnan(serial_correlation(Dataset(labels[:4], np.zeros((4, 7))), ar[:4]))  # too few samples to judge


def test_residuals_correlated_in_recording_order_are_named_beside_the_prediction(arm, noisy) -> None:
    """A UR-like trial and a plan review: simulated self-motion (noise correlated over 0.05 s, lag-1 0.5-0.6) was
    predicted 1.7-3.6x better than validate measured, the prediction counting every sample as independent. The same
    samples in another order give the same fit; in an order where the noise runs smoothly the self-check says so, and
    by how much to expect more; in their own (random) order it says nothing."""
    panda, _ = arm
    dataset, spec = noisy
    first = calibrate(panda, dataset, spec)
    figures = first.selfcheck.block()["checks"]["prediction"]
    assert abs(figures["residual_lag1_correlation"]) < 0.15
    assert "correlated from one sample to the next" not in first.summary()
    errors = first.problem.sample_errors(first.x)
    smooth = np.concatenate([np.flatnonzero(dataset.labels == name)[np.argsort(errors[dataset.labels == name, 0])]
                             for name in dataset.fixture_names])  # each fixture's rows by their residual's x
    again = calibrate(panda, dataset.select(smooth), spec)
    rho = again.selfcheck.block()["checks"]["prediction"]["residual_lag1_correlation"]
    assert rho > 0.3
    assert re.search(rf"correlated from one sample to the next \(lag-1 {rho:.2f} in recording order\).*expect up "
                     r"to [\d.]+x more", again.summary())


def test_samples_the_nominal_model_already_fits_are_refused_with_the_right_advice() -> None:
    """A user trial: a recording of an arm that is its nominal model was refused with 'record more self-motion, more
    fixtures or known distances, or with less play': more of the same would not help. The refusal says that the
    nominal model already fits the samples within their noise."""
    panda = load_robot("panda")
    dataset, spec = make_dataset(panda, per_fixture=200, rng=np.random.default_rng(4), noise=2e-4)
    with pytest.raises(InconsistentDataError, match=r"the nominal model already fits these samples within their "
                                                    r"noise .*: there is nothing here to calibrate") as refused:
        calibrate(panda, dataset, spec)
    assert "record more self-motion" not in str(refused.value)


# ------------------------------------------------------------------ messages composed of pieces
def _noise_like_level(message: str) -> Finding:
    """A failed residual level whose residuals look like noise, its message worded as ``message``."""
    return Finding("residual level", False, message, {"robust_ratio": 0.9, "residual_std_mm": 1.0},
                   clause="rows 2-9: residual noise 1 mm per axis", remedy="causes")


def _prediction_finding(whole_mm: float) -> Finding:
    """A failed prediction (2x margin) that beats nominal near the recording, ``whole_mm`` over the whole workspace
    against 4 mm of the nominal model."""
    figures = {"predicted_mean_mm": 1.0, "nominal_expected_mean_mm": 1.5, "whole_workspace_predicted_mean_mm": whole_mm,
               "whole_workspace_nominal_expected_mm": 4.0}
    return Finding("prediction", False, "s.csv: rows 2-9: refused by 2x: predicted mean error 1 mm; remedy; serial",
                   figures, clause="predicted mean error 1 mm", remedy="remedy", notes=("serial",))


@pytest.mark.parametrize("wording", ["s.csv: rows 2-9: residual noise 1 mm per axis and no single one: causes",
                                     "reworded: the residual is 1 mm (nothing else named)"])
def test_judged_at_the_noise_shown_the_messages_quote_the_findings_pieces_not_their_wording(wording) -> None:
    # the warning once took the level's message up to ' and no single', and the prediction's from 'predicted mean
    # error ' to its remedy: a reworded message would have changed both silently
    from spherecal.identification.selfcheck import _honest_noise

    findings, prediction = _honest_noise([_noise_like_level(wording)], _prediction_finding(3.0))
    assert findings[0].passed and findings[0].message == (
        "warning: rows 2-9: residual noise 1 mm per axis; judged at that noise, the calibration is still expected to "
        "beat nominal (1 mm against 1.5 mm, the prediction below): written")
    # its figures and notes (the serial correlation's, dropped when the message was cut at its remedy), not its verdict
    assert prediction.passed and prediction.message == "predicted mean error 1 mm; serial"
    # one socket that would make the whole workspace worse: refused, the prediction's figures, remedy and notes quoted
    findings, prediction = _honest_noise([_noise_like_level(wording)], _prediction_finding(5.0), one_fixture=True)
    assert not findings[0].passed and not prediction.passed
    # its remedy is the one socket's, not the 2x margin's the prediction carries (a review, stop 19)
    assert findings[0].message == (
        f"{wording}; at the noise the residuals show, the calibration is expected to beat the nominal model near the "
        "recording, but from one socket it must not be worse over the whole workspace, and it is expected to be: "
        "predicted mean error 1 mm; record a second socket or another placement to calibrate the arm beyond this one; "
        "serial")


def test_beside_another_failed_check_the_level_judged_at_the_noise_shown_does_not_say_written() -> None:
    # a review: a forced run (MUKCa's dinova_1 front, a socket that moved) printed the level's ': written' above the
    # fixture check that refused it; the summary's head says it is written because forced
    from spherecal.identification.selfcheck import _honest_noise
    from spherecal.identification.selfcheck_result import SelfCheck

    moved = Finding("fixture P2", False, "s.csv: rows 2-5, field 'fixture': the samples at fixture P2 disagree")
    findings, prediction = _honest_noise([_noise_like_level("refused"), moved], _prediction_finding(3.0))
    assert findings[0].passed and findings[0].message == (
        "warning: rows 2-9: residual noise 1 mm per axis; judged at that noise, the calibration is still expected to "
        "beat nominal (1 mm against 1.5 mm, the prediction below), but 1 other check failed (below)")
    check = SelfCheck((*findings, prediction), 3e-4, 1e-3)
    assert check.lines()[0] == "self-check: INCONSISTENT (1 failed)"
    assert replace(check, forced=True).lines()[0] == ("self-check: INCONSISTENT (1 failed): written only because "
                                                      "forced (--force)")
    consistent = SelfCheck((findings[0], prediction), 3e-4, 1e-3, forced=True)
    assert consistent.consistent and not consistent.lines()[0].endswith("(--force)")


@pytest.mark.parametrize(("whole_mm", "words"), [
    (5.0, "expected to be worse than nominal"), (4.0, "not expected to beat nominal"),
    (3.0, "expected to beat nominal, but not by 2x")])
def test_the_whole_workspace_warnings_words_follow_its_figures(whole_mm, words) -> None:
    # a review: 'not expected to beat nominal by 2x' was said of 5.88 mm against the nominal's 4.68 mm (MUKCa's dinova_1
    # left), and 'not expected to beat nominal' of 6.88 mm against 4.68 mm (dinova_2 front_rotated): worse than nominal
    from spherecal.identification.selfcheck import _against_nominal, _honest_noise

    assert _against_nominal(whole_mm, 4.0) == words
    _, prediction = _honest_noise([_noise_like_level("refused")], _prediction_finding(whole_mm))
    warning = prediction.figures.get("region_warning")
    if whole_mm < 4.0:  # beats nominal there: judged at the noise shown, nothing to warn of
        assert warning is None
    else:
        assert warning.startswith(f"over the whole workspace the calibration is {words} (predicted {whole_mm:g} mm "
                                  "against 4 mm)"), warning


def test_a_written_calibrations_far_warning_says_worse_than_nominal_where_its_figures_are(tmp_path) -> None:
    """MUKCa's dinova_1 left (the Gen3 lite of the tests' data): near the recording 0.95 mm against the nominal's
    2.86 mm, written; over the whole workspace 3.88 mm against 4.58 mm, and with the bias of the arm's joint-angle
    error 5.66 mm: the warning said 'not expected to beat nominal by 2x'; it says worse than nominal, with both
    figures."""
    from spherecal.cli import main
    from spherecal.identification.workflow import WorkflowOptions, calibrate_files

    data = Path(__file__).resolve().parents[1] / "data" / "mukca"
    robot = data / "gen3lite_ball.yaml"
    assert main(["import", str(data / "dinova_1" / "left"), "--format", "mukca", "--robot", str(robot), "--out",
                 str(tmp_path / "imp")]) == 0
    check = calibrate_files(str(robot), tmp_path / "imp" / "samples.csv", tmp_path / "imp" / "fixtures.yaml",
                            tmp_path / "cal.yaml", WorkflowOptions(model="dh")).result.selfcheck
    figures = next(f for f in check.findings if f.check == "prediction").figures
    biased, nominal, plain = (figures[f"whole_workspace_{k}"] for k in ("predicted_with_joint_error_mm",
                                                                         "nominal_expected_mm", "predicted_mean_mm"))
    assert check.consistent and plain < nominal < biased, (plain, nominal, biased)
    assert figures["region_warning"] == (
        "farther than 300 mm from the recorded tool points the calibration is expected to be worse than nominal (whole "
        f"workspace, counting the bias of the arm's joint-angle error: predicted {biased:.3g} mm against {nominal:.3g} "
        f"mm of the nominal model, {plain:.3g} mm without that bias): record a placement there to calibrate it")
    assert figures["region_warning"] in check.warnings


def test_the_advice_tried_is_replaced_where_it_was_given_and_nowhere_else() -> None:
    # the workflow replaced the advice's text in the whole refusal; now the advice is a piece of its own
    said = f"a message that quotes '{leave_out_advice('A')}'; "
    refused = InconsistentDataError((said, Advice("A"), "; ", Advice("B")), ("A", "B"))
    assert str(refused) == said + leave_out_advice("A") + "; " + leave_out_advice("B")
    assert refused.told(("A",)) == said + "record it again; " + leave_out_advice("B")
    plain = InconsistentDataError("plain")
    assert plain.told(("A",)) == "plain" and plain.pieces == ("plain",)


# ------------------------------------------------------------------ one socket, whatever the noise
def _passed_prediction(whole_mm: float) -> Finding:
    """A prediction that beats nominal by 2x near the recording, ``whole_mm`` over the whole workspace against 4 mm."""
    figures = {"predicted_mean_mm": 1.0, "nominal_expected_mean_mm": 3.0, "whole_workspace_predicted_mean_mm": whole_mm,
               "whole_workspace_nominal_expected_mm": 4.0}
    return Finding("prediction", True, "predicted mean error 1 mm; serial", figures,
                   clause="predicted mean error 1 mm", notes=("serial",))


def test_one_socket_that_would_make_the_whole_workspace_worse_is_refused_at_any_noise() -> None:
    # the rule was applied only where the residuals exceeded the level's limit (_honest_noise); a declared noise that
    # the residuals stay within skipped it
    from spherecal.identification.selfcheck import _one_socket

    dataset = Dataset(np.array(["P1"] * 3), np.zeros((3, 7)), fixture_names=("P1",))
    refused = _one_socket(_passed_prediction(5.0), dataset)
    assert not refused.passed and refused.message == (
        "samples: all rows: the calibration is expected to beat the nominal model near the recording, but from one "
        "socket it must not be worse over the whole workspace, and it is expected to be (5 mm against 4 mm): predicted "
        "mean error 1 mm; record a second socket or another placement to calibrate the arm beyond this one; serial")
    better = _passed_prediction(3.0)
    assert _one_socket(better, dataset) is better
    failed = replace(_passed_prediction(5.0), passed=False)
    assert _one_socket(failed, dataset) is failed


def test_a_declared_noise_does_not_write_one_socket_expected_worse_over_the_whole_workspace() -> None:
    # MUKCa's dinova_1 front_h1 alone at --noise 0.87: written at the default prior (3.92 mm predicted over the whole
    # workspace against 4.68 mm); at --prior 0.1 the fit moves further (5.40 mm against 4.68 mm) and it was written
    # too, the residuals within the declared noise keeping the one-socket rule away; now refused as without --noise
    from spherecal.correction.files.samples import JointLimitWarning
    from spherecal.identification.ingest.importers import read_mukca
    from spherecal.identification.workflow import WorkflowOptions, run_workflow

    root = Path(__file__).resolve().parents[1] / "data" / "mukca"
    with pytest.warns(Warning):  # joint_3 nearly parallel to joint_2: described with a Hayati beta
        nominal = load_robot(root.parent / "urdf" / "gen3lite.urdf", tip_link="ball_link")
    with pytest.warns(JointLimitWarning):
        recording, _ = read_mukca(root / "dinova_1" / "front", nominal)
    kept = recording.labels == "front_h1"
    dataset = Dataset(recording.labels[kept], recording.q[kept], fixture_names=("front_h1",))
    written = run_workflow(nominal, dataset, None, WorkflowOptions(noise=0.87e-3)).result.selfcheck
    assert written.consistent
    with pytest.raises(InconsistentDataError, match="from one socket it must not be worse over the whole workspace"):
        run_workflow(nominal, dataset, None, WorkflowOptions(noise=0.87e-3, prior=0.1))
