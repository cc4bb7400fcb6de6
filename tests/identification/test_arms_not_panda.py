"""Issue 20 item 7: arms that are not Pandas. Recordings past a URDF's joint limits are used with one warning;
a socket that drifts while recorded is named with its trend; a fixture can be left out; residuals above the
declared noise are judged at the noise they show (written with a warning when the calibration still helps)."""

from __future__ import annotations

import json
import re
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml

from spherecal.cli import main
from spherecal.correction import load_robot, perturb
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.samples import Dataset, DatasetError, JointLimitWarning
from spherecal.correction.files.samples_csv import read_samples, write_samples
from spherecal.correction.files.urdf_to_dh import NearlyParallelAxesWarning
from spherecal.identification.calibrate import calibrate
from spherecal.identification.selfcheck import InconsistentDataError
from spherecal.identification.synthetic import PANDA_FIXTURES, fixture_samples, make_dataset
from spherecal.identification.training import exclude_fixtures
from tests.refusal import refused

ROOT = Path(__file__).resolve().parents[1] / "data"
GEN3LITE = ROOT / "urdf" / "gen3lite.urdf"  # MUKCa's: joint_6 limited to +-2.09 rad
MUKCA = ROOT / "mukca"


def test_angles_past_the_limits_warn_once_naming_every_joint_and_are_used(tmp_path, panda) -> None:
    dataset, _ = make_dataset(panda, per_fixture=10, rng=np.random.default_rng(0))
    q = dataset.q.copy()
    q[2, 5] = panda.upper[5] + 0.3
    q[7, 5] = panda.upper[5] + 0.4
    q[4, 0] = panda.lower[0] - 0.1
    q[5, 5] = panda.lower[5] - 0.2  # the same joint past both of its limits: both named
    write_samples(tmp_path / "samples.csv", Dataset(labels=dataset.labels, q=q))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        read = read_samples(tmp_path / "samples.csv", panda)
    limits = [w for w in caught if issubclass(w.category, JointLimitWarning)]
    assert len(limits) == 1  # one per run, every joint in it
    text = str(limits[0].message)
    assert "q1 by up to 0.1 rad (5.73 deg) below -2.897 (row 6)" in text
    assert "q6 by up to 0.4 rad (22.9 deg) above 3.752 (row 9)" in text
    assert "q6 by up to 0.2 rad (11.5 deg) below -0.0175 (row 7)" in text
    assert text.endswith("(the arm's range is wider than its robot file says, or the file is another arm's)")
    np.testing.assert_array_equal(read.q, q)  # used as recorded
    q[7, 5] = panda.upper[5] + 2.0  # beyond a quarter turn: not an angle of that joint
    write_samples(tmp_path / "samples.csv", Dataset(labels=dataset.labels, q=q))
    with pytest.raises(DatasetError, match=r"samples.csv: row 9, field 'q6': .* more than a quarter turn"):
        read_samples(tmp_path / "samples.csv", panda)


def test_a_joint_of_a_full_turn_has_no_limits_to_warn_about(tmp_path, panda) -> None:
    # a URDF "continuous" joint becomes [-pi, pi]: angles past pi wrap, and the warning said "the arm's range is
    # wider than its robot file says" of a joint whose file states no range at all
    from dataclasses import replace

    turning = replace(panda, lower=np.r_[panda.lower[:6], -np.pi], upper=np.r_[panda.upper[:6], np.pi])
    dataset, _ = make_dataset(panda, per_fixture=10, rng=np.random.default_rng(0))
    q = dataset.q.copy()
    q[3, 6] = np.pi + 0.5
    write_samples(tmp_path / "samples.csv", Dataset(labels=dataset.labels, q=q))
    with warnings.catch_warnings():
        warnings.simplefilter("error", JointLimitWarning)
        read = read_samples(tmp_path / "samples.csv", turning)
    np.testing.assert_array_equal(read.q, q)
    with pytest.warns(JointLimitWarning, match="q7 by up to"):  # the same angle on the Panda's own joint 7
        read_samples(tmp_path / "samples.csv", panda)


def test_the_gen3_lite_recordings_past_its_urdf_limits_import_with_one_warning(tmp_path, capsys) -> None:
    # MUKCa's Gen3 lite passes gen3lite.urdf's joint_6 limit of 2.09 rad by up to 0.65 rad: refused before
    argv = ["import", str(MUKCA / "dinova_1/left"), "--format", "mukca", "--robot", str(GEN3LITE), "--tip-link",
            "ball_link", "--out", str(tmp_path / "out")]
    assert main(argv) == 0
    err = capsys.readouterr().err
    limit_lines = [line for line in err.splitlines() if "beyond the joint limits" in line]
    assert len(limit_lines) == 1 and "q6 by up to 0.652 rad (37.4 deg) below -2.09 (hole_1.csv: row 12)" in err


def _drifting(panda, true, drift: float, seed: int = 3) -> tuple[Dataset, object]:
    """Four Panda fixtures, 40 samples each; fixture P2's socket moves by ``drift`` [m] along x while recorded."""
    rng = np.random.default_rng(seed)
    dataset, spec = make_dataset(true, per_fixture=40, rng=rng, noise=2e-4)
    if drift:
        parts = [fixture_samples(true, PANDA_FIXTURES["P2"] + np.array([drift * k / 3, 0, 0]), 10, rng, 2e-4)
                 for k in range(4)]
        q = dataset.q.copy()
        q[dataset.labels == "P2"] = np.concatenate(parts)
        dataset = Dataset(labels=dataset.labels, q=q, fixture_names=dataset.fixture_names)
    return dataset, spec


def test_a_socket_that_moves_while_recorded_is_named_with_its_trend(panda) -> None:
    true = perturb(panda, np.random.default_rng(1))
    dataset, spec = _drifting(panda, true, 0.004)
    result = calibrate(panda, dataset, spec, force=True)
    trends = {f.check: f for f in result.selfcheck.findings if f.check.startswith("trend")}
    assert [name for name, f in trends.items() if f.figures["trend"]] == ["trend P2"]
    figures = trends["trend P2"].figures
    assert "the residual at fixture P2 moves" in trends["trend P2"].message
    assert 3.0 < figures["change_mm"] < 5.0  # the socket moved 4 mm
    assert any("trend" in w or "recording order" in w for w in result.selfcheck.block()["warnings"])
    steady, spec = _drifting(panda, true, 0.0)
    checked = calibrate(panda, steady, spec).selfcheck
    assert not any(f.figures.get("trend") for f in checked.findings)


def test_exclude_fixture_leaves_it_and_its_distances_out(tmp_path, capsys, panda) -> None:
    true = perturb(panda, np.random.default_rng(1))
    dataset, spec = _drifting(panda, true, 0.004)
    kept, kept_spec = exclude_fixtures(dataset, spec, ["P2"])
    assert "P2" not in kept.fixture_names and all("P2" not in (a, b) for a, b, _ in kept_spec.distances)
    assert len(kept_spec.distances) == 1
    from spherecal.correction.files.fixtures import write_fixtures

    write_samples(tmp_path / "samples.csv", dataset)
    write_fixtures(tmp_path / "fixtures.yaml", spec)
    argv = ["calibrate", "--robot", "panda", "--samples", str(tmp_path / "samples.csv"), "--fixtures",
            str(tmp_path / "fixtures.yaml"), "--out", str(tmp_path / "cal.yaml"), "--model", "dh"]
    assert main([*argv, "--exclude-fixture", "P2"]) == 0
    block = load_robot(tmp_path / "cal.yaml").extras["calibration"]
    assert set(block["samples_per_fixture"]) == {"P1", "P3"} and block["options"]["exclude_fixture"] == ["P2"]
    assert set(block["trained_on"]["fixtures"]) == {"P1", "P3"}
    (tmp_path / "cal.yaml").unlink()
    refused([*argv, "--exclude-fixture", "P9"], tmp_path, capsys,
            "field 'fixture': --exclude-fixture 'P9' is not a fixture of the samples (they have P1, P2, P3)")


def test_a_refusal_after_exclude_fixture_names_the_distance_as_the_file_numbers_it(tmp_path, capsys, panda) -> None:
    # four fixtures, six distances; P1 left out drops the first three: a 10 mm typo in the file's last one
    # must be named as row and field of the file (it was 'distances[2]' of the shortened list, the wrong row)
    from spherecal.correction.files.fixtures import write_fixtures

    true = perturb(panda, np.random.default_rng(2))
    centres = {**PANDA_FIXTURES, "P4": np.array([0.45, -0.35, 0.25])}
    dataset, spec = make_dataset(true, centres, 150, np.random.default_rng(3), noise=1e-4)
    a, b, value = spec.distances[-1]
    assert (a, b) == ("P3", "P4") and len(spec.distances) == 6
    typo = FixtureSpec(spec.names, distances=[*spec.distances[:-1], (a, b, value + 0.01)])
    write_samples(tmp_path / "samples.csv", dataset)
    write_fixtures(tmp_path / "fixtures.yaml", typo)
    line = next(i for i, text in enumerate((tmp_path / "fixtures.yaml").read_text().splitlines(), 1)
                if text.startswith("- [P3, P4"))
    argv = ["calibrate", "--robot", "panda", "--samples", str(tmp_path / "samples.csv"), "--fixtures",
            str(tmp_path / "fixtures.yaml"), "--out", str(tmp_path / "cal.yaml"), "--model", "dh",
            "--exclude-fixture", "P1"]
    refused(argv, tmp_path, capsys, f"fixtures.yaml: row {line}, field 'distances[5]': distance P3-P4")


def test_more_noise_than_declared_is_judged_at_the_noise_the_residuals_show(panda) -> None:
    # 1 mm noise declared as 0.3 mm: residuals 3x the declared noise. Refused before; now written with a
    # warning, because at 1 mm the calibration is still expected to beat nominal (and does)
    true = perturb(panda, np.random.default_rng(1))
    dataset, spec = make_dataset(true, per_fixture=60, rng=np.random.default_rng(2), noise=1e-3)
    result = calibrate(panda, dataset, spec, noise=3e-4)
    level = next(f for f in result.selfcheck.findings if f.check == "residual level")
    assert level.passed and level.figures["honest_noise_warning"] and level.figures["ratio"] > 2.0
    assert "judged at that noise, the calibration is still expected to beat nominal" in level.message
    q = panda.random_configurations(500, np.random.default_rng(4))
    from spherecal.correction import registered_errors, tool_point

    def error(model):
        return float(registered_errors(tool_point(model, q), tool_point(true, q)).mean())

    assert error(result.model) < 0.5 * error(panda)
    # 5 mm noise declared as 0.3 mm at one fixture. 20 samples: expected to beat nominal near the recording and over
    # the whole workspace, and by the truth it does (written; refused before stop 10, when the joints' zeros were
    # pruned at 0.2 deg). 10 samples: over the whole workspace not (and it does not); from one socket that refuses,
    # saying what noise the residuals show and what the calibration would reach at it
    from spherecal.identification.selfcheck import InconsistentDataError

    few, _ = make_dataset(true, {"P1": PANDA_FIXTURES["P1"]}, 20, np.random.default_rng(3), noise=5e-3)
    assert error(calibrate(panda, few, noise=3e-4).model) < error(panda)
    fewer, _ = make_dataset(true, {"P1": PANDA_FIXTURES["P1"]}, 10, np.random.default_rng(3), noise=5e-3)
    with pytest.raises(InconsistentDataError, match=r"residual noise \d\.\d+ mm per axis is .*at the noise the "
                       r"residuals show, .*over the whole workspace .*predicted spread \d"):
        calibrate(panda, fewer, noise=3e-4)
    written = calibrate(panda, fewer, noise=3e-4, force=True)
    assert error(written.model) > error(panda)  # the whole workspace: worse, as predicted


def test_gen3_lite_trained_on_each_real_placement_is_written_or_refused_with_its_reason(tmp_path, capsys) -> None:
    """The real case (tests/data has front and left): front's socket front_h0 drifts and is refused, named with
    its trend, and the refusal says what its advice gives: without front_h0 one socket is left, which is refused
    too, so leaving it out does not help (the advice sent the user from one refusal to the next before); left is
    written with a warning and beats the nominal on front_h1 (held out)."""
    for placement in ("front", "left"):
        assert main(["import", str(MUKCA / "dinova_1" / placement), "--format", "mukca", "--robot", str(GEN3LITE),
                     "--tip-link", "ball_link", "--out", str(tmp_path / placement)]) == 0
    capsys.readouterr()

    def calibrate_on(placement: str, *extra: str) -> int:
        return main(["calibrate", "--robot", str(GEN3LITE), "--tip-link", "ball_link", "--samples",
                     str(tmp_path / placement / "samples.csv"), "--fixtures",
                     str(tmp_path / placement / "fixtures.yaml"), "--out", str(tmp_path / f"cal_{placement}.yaml"),
                     *extra])

    assert calibrate_on("front") == 1
    err = capsys.readouterr().err
    assert "fixture front_h0" in err and "the residual at fixture front_h0 moves" in err
    assert ("leaving front_h0 out does not help: without front_h0 the rest is refused too (calibrate "
            "--exclude-fixture front_h0 says why)" in err)
    # the advice it tried is not given as well (h8: 'leave it out (calibrate --exclude-fixture front_h0) or record it
    # again', then 'leaving front_h0 out does not help')
    assert "leave it out" not in err and "\n  record it again\n" in err
    assert calibrate_on("front", "--exclude-fixture", "front_h0") == 1  # as the refusal said
    assert "--exclude-fixture front_h0" not in capsys.readouterr().err
    assert calibrate_on("left") == 0
    assert "judged at that noise, the calibration is still expected to beat nominal" in capsys.readouterr().out
    assert main(["validate", "--nominal", str(GEN3LITE), "--tip-link", "ball_link", "--calibrated",
                 str(tmp_path / "cal_left.yaml"), "--samples", str(tmp_path / "front" / "samples.csv"), "--out",
                 str(tmp_path / "v.json")]) == 0
    fixtures = json.loads((tmp_path / "v.json").read_text())["sockets"]["fixtures"]
    spread = fixtures["front_h1"]["spread_mean"]
    assert spread["calibrated"] < 0.7 * spread["nominal"]


def test_gen3_lite_placements_that_a_rigid_model_cannot_join_within_a_millimetre_are_written(tmp_path, capsys) -> None:
    """Two real Gen3 lite placements (front without its drifting front_h0, raised_back): no DH model fits both to
    the residual each shows alone (1 mm), so each fixture, left out, disagrees with the other placement's fit by
    ~5 mm. That is the arm's unmodelled error over its workspace, which the others' residual shows beyond the
    declared noise, not a fixture that moved: refused before ("the samples at fixture raised_back_h0 disagree with
    the other fixtures by 5.72 mm rms"); now written, and better than nominal on the held-out placement left.
    front_h0's residual trends with recording order (the socket moved): it was refused with it until stop 19. With
    the prior at the 1.7 mm per axis the residuals show (joints' zeros at their 1 deg tolerance,
    ``calibrate.prior_at_shown_noise``) the rest carries it within the arm's error: written, the trend named, and
    at the held-out placements left and lower_left better than without front_h0 (3.71 / 3.97 mm, nominal 4.91)."""
    both = tmp_path / "recorded"
    for placement in ("front", "raised_back"):
        shutil.copytree(MUKCA / "dinova_1" / placement, both / placement)
    assert main(["import", str(both), "--format", "mukca", "--robot", str(GEN3LITE), "--tip-link", "ball_link",
                 "--out", str(tmp_path / "train")]) == 0
    assert main(["import", str(MUKCA / "dinova_1" / "left"), "--format", "mukca", "--robot", str(GEN3LITE),
                 "--tip-link", "ball_link", "--out", str(tmp_path / "test")]) == 0
    capsys.readouterr()
    calibrate_argv = ["calibrate", "--robot", str(GEN3LITE), "--tip-link", "ball_link", "--samples",
                      str(tmp_path / "train" / "samples.csv"), "--fixtures", str(tmp_path / "train" / "fixtures.yaml"),
                      "--out", str(tmp_path / "cal.yaml")]
    # the socket that moved while recorded: written with the trend named (with it and without it)
    assert main(calibrate_argv) == 0, capsys.readouterr().err
    out = capsys.readouterr().out
    assert "the residual at fixture front_h0 moves" in out and "mm per axis the residuals show" in out
    without = [*calibrate_argv[:-1], str(tmp_path / "without.yaml"), "--exclude-fixture", "front_h0"]
    assert main(without) == 0, capsys.readouterr().err
    for written in ("cal.yaml", "without.yaml"):
        assert main(["validate", "--nominal", str(GEN3LITE), "--tip-link", "ball_link", "--calibrated",
                     str(tmp_path / written), "--samples", str(tmp_path / "test" / "samples.csv"), "--out",
                     str(tmp_path / f"v_{written}.json")]) == 0
        fixtures = json.loads((tmp_path / f"v_{written}.json").read_text())["sockets"]["fixtures"]
        for socket in ("left_h0", "left_h1"):
            spread = fixtures[socket]["spread_mean"]
            assert spread["calibrated"] < 0.8 * spread["nominal"], (written, socket, spread)


def test_another_arms_fixture_is_still_named_on_an_arm_with_unmodelled_error(panda) -> None:
    """The allowance for an arm's unmodelled error comes from the OTHER fixtures' residual: a fixture recorded on
    another arm is still refused, named, when every sample carries 0.6 mm of noise against the declared 0.3 mm
    (the wrong fixture inflates only the others' allowance, not its own)."""
    true = perturb(panda, np.random.default_rng(1))
    other = perturb(panda, np.random.default_rng(2))
    rng = np.random.default_rng(5)
    dataset, spec = make_dataset(true, per_fixture=40, rng=rng, noise=6e-4)
    q = dataset.q.copy()
    q[dataset.labels == "P3"] = fixture_samples(other, PANDA_FIXTURES["P3"], 40, rng, 6e-4)
    wrong = Dataset(labels=dataset.labels, q=q, fixture_names=dataset.fixture_names)
    with pytest.raises(InconsistentDataError, match=r"fixture P3 disagree with the other fixtures by [\d.]+ mm rms "
                                                    r"\(the others alone: residual [\d.]+ mm per axis, and the arm's "
                                                    r"unmodelled error expected there"):
        calibrate(panda, wrong, spec, noise=3e-4)


def test_a_second_gen3_lite_is_written_where_it_helps_with_its_trending_socket_named(tmp_path, capsys) -> None:
    """MUKCa's dinova_2 (a second real Gen3 lite): its one two-socket placement ``front_rotated``, 1.3 mm of noise per
    axis. All 20 presses per socket: front_rotated_h1 trends with recording order; refused until stop 10 (the trend
    took the leave-one-out's allowance for the arm's error away, and the joint zeros were pruned at 0.2 deg), now
    written, the trend named, and at the five sockets recorded at other placements it beats nominal (5.58 -> 2.59 mm;
    MUKCa 3.91). The first 8 presses per socket: written too (2.51 mm). Left with h0 alone (one socket), refused:
    single-socket Gen3 lite calibrations were 1.02-1.30x nominal there."""
    data = MUKCA / "dinova_2"
    assert main(["import", str(data / "front_rotated"), "--format", "mukca", "--robot", str(GEN3LITE), "--tip-link",
                 "ball_link", "--out", str(tmp_path / "all")]) == 0
    first = tmp_path / "first8"
    for hole in ("hole_0.csv", "hole_1.csv"):
        (first / "front_rotated").mkdir(parents=True, exist_ok=True)
        lines = (data / "front_rotated" / hole).read_text().splitlines(keepends=True)
        (first / "front_rotated" / hole).write_text("".join(lines[:8]))
    assert main(["import", str(first / "front_rotated"), "--format", "mukca", "--robot", str(GEN3LITE), "--tip-link",
                 "ball_link", "--out", str(tmp_path / "few")]) == 0
    capsys.readouterr()

    def calibrate_on(folder: str, *extra: str, out: str | None = None) -> int:
        return main(["calibrate", "--robot", str(GEN3LITE), "--tip-link", "ball_link", "--samples",
                     str(tmp_path / folder / "samples.csv"), "--fixtures", str(tmp_path / folder / "fixtures.yaml"),
                     "--out", str(tmp_path / (out or f"cal_{folder}.yaml")), *extra])

    assert calibrate_on("all") == 0
    said = capsys.readouterr().out
    assert "the residual at fixture front_rotated_h1 moves" in said and "--exclude-fixture front_rotated_h1" in said
    # written: the trend is named, and kept without advising to leave it out (that is refused, below, and the socket
    # helps at held-out sockets: 2.59 against 2.91 mm)
    assert ("the checks find it consistent with the rest, so it is kept (calibrate --exclude-fixture "
            "front_rotated_h1 leaves it out)" in said) and "leave it out (calibrate" not in said
    warned = yaml.safe_load((tmp_path / "cal_all.yaml").read_text())["calibration"]["self_check"]["warnings"]
    assert any("so it is kept" in w for w in warned)
    assert calibrate_on("all", "--exclude-fixture", "front_rotated_h1", out="h0.yaml") == 1
    assert "at the noise the residuals show" in capsys.readouterr().err
    assert not (tmp_path / "h0.yaml").exists()
    assert calibrate_on("few") == 0
    with pytest.warns(NearlyParallelAxesWarning):  # joint_3 beside joint_2: a Hayati beta, said
        nominal = load_robot(GEN3LITE, tip_link="ball_link")
    from spherecal.correction import tool_point

    def spread(model, q):
        p = tool_point(model, q)
        return float(np.linalg.norm(p - p.mean(axis=0), axis=1).mean())

    held, beyond, recorded = [], [], {}
    for placement in sorted(p.name for p in data.iterdir() if p.name != "front_rotated"):
        assert main(["import", str(data / placement), "--format", "mukca", "--robot", str(GEN3LITE), "--tip-link",
                     "ball_link", "--out", str(tmp_path / placement)]) == 0
        with warnings.catch_warnings(record=True) as caught:  # q6 beyond the URDF's +-2.09 rad: used, and said
            warnings.simplefilter("always", JointLimitWarning)
            q = recorded[placement] = read_samples(tmp_path / placement / "samples.csv", nominal).q
        beyond += [str(w.message) for w in caught if issubclass(w.category, JointLimitWarning)]
        held.append([spread(load_robot(tmp_path / f"cal_{f}.yaml"), q) for f in ("all", "few")] + [spread(nominal, q)])
    mean = np.mean(held, axis=0)
    assert len(held) == 5 and mean[0] < 0.6 * mean[2] and mean[1] < 0.6 * mean[2], held
    assert len(beyond) >= 4 and all("used as recorded" in text and "q6" in text for text in beyond), beyond
    # into the arm's own URDF: its theta2 moved -3 deg, and export --into refused it as another robot (tool points 51 mm
    # from the URDF's with the calibrated zeros, stop 10); compared at the URDF's zeros it is written with the
    # calibrated ones and carries the file's accuracy (a dh model: exactly)
    assert main(["export", str(tmp_path / "cal_all.yaml"), "--format", "urdf", "--into", str(GEN3LITE), "--out",
                 str(tmp_path / "all.urdf")]) == 0, capsys.readouterr().err
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        urdf = load_robot(tmp_path / "all.urdf", tip_link="ball_link")
    q = np.vstack([recorded["left"], recorded["right-high"]])
    assert np.abs(tool_point(urdf, q) - tool_point(load_robot(tmp_path / "cal_all.yaml"), q)).max() < 1e-6


def test_a_robot_file_with_a_joint_zero_far_off_is_calibrated_and_the_file_is_named(panda) -> None:
    """A robot file whose joint-4 zero is 5 deg off the arm's (a joint zero has a 1 deg tolerance, so the plausibility
    limit no longer refuses it, stop 10): two sockets find it (-4.98 deg, 1.8 mm from the truth against 35.5 nominal),
    one socket does what it can (17 mm); both written with a warning that names the zero and asks about the file."""
    from spherecal.correction import registered_errors, tool_point

    true = perturb(panda, np.random.default_rng(1))
    params = panda.params.copy()
    params[panda.param_index("theta4")] += np.deg2rad(5.0)
    wrong = panda.with_params(params)
    q = panda.random_configurations(500, np.random.default_rng(4))

    def error(model):
        return float(registered_errors(tool_point(model, q), tool_point(true, q)).mean())

    for names, better in ((("P1", "P2"), 0.1), (("P1",), 0.6)):
        data, spec = make_dataset(true, {k: PANDA_FIXTURES[k] for k in names}, 20, np.random.default_rng(3),
                                  noise=1e-3)
        result = calibrate(wrong, data, spec)
        assert error(result.model) < better * error(wrong)
        assert any(w.startswith("the fit moved theta4 -") and "check the robot file" in w for w in result.warnings)
    assert not any("joint zero" in w for w in calibrate(panda, data, spec).warnings)  # the arm's own file: none


def test_joint_zeros_off_within_their_tolerance_do_not_read_as_noise(panda) -> None:
    """An arm whose zeros sit ~1 deg off (real arms: 1-3 deg), two sockets of 8 presses at 1 mm: the fit moves the
    zeros there, and the prior's rows on them, read at the prior's 0.2 deg, had lifted the residual past the level's
    limit ('residual noise 0.72 mm per axis ... samples of another arm'; a review, stop 10). Read at their 1 deg
    tolerance, the calibration is written, and by the truth it is 0.15x nominal."""
    from spherecal.correction import registered_errors, tool_point
    from spherecal.identification.problem import zero_indices
    from spherecal.identification.workflow import WorkflowOptions, run_workflow

    true = perturb(panda, np.random.default_rng(3))
    params = true.params.copy()
    params[zero_indices(panda)] += np.deg2rad(1.0) * np.random.default_rng(103).normal(size=panda.n_joints)
    true = true.with_params(params)
    data, spec = make_dataset(true, {k: PANDA_FIXTURES[k] for k in ("P1", "P2")}, 8, np.random.default_rng(13),
                              noise=1e-3)
    q = panda.random_configurations(500, np.random.default_rng(4))

    def error(model):
        return float(registered_errors(tool_point(model, q), tool_point(true, q)).mean())

    result = run_workflow(panda, data, spec, WorkflowOptions())
    assert error(result.model) < 0.3 * error(panda)


def test_a_refusal_on_the_residual_level_tries_the_fixture_that_stands_out_first(tmp_path, capsys) -> None:
    """MUKCa's dinova_2 (every placement) with joint 3 offset 2 deg on the second half of gen3lite_left_h0's presses: a
    refusal on the residual level ('worst fixture gen3lite_left_h0 4.46 mm' among 1-1.5 mm) that names two other
    sockets' real trends. Leaving those out did not help and was all the refusal said (a review by command line);
    the socket that stands out is tried first, and without it the rest is written."""
    assert main(["import", str(MUKCA / "dinova_2"), "--format", "mukca", "--robot", str(GEN3LITE), "--tip-link",
                 "ball_link", "--out", str(tmp_path / "d2")]) == 0
    samples = tmp_path / "d2" / "samples.csv"
    with pytest.warns(NearlyParallelAxesWarning):
        nominal = load_robot(GEN3LITE, tip_link="ball_link")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", JointLimitWarning)
        data = read_samples(samples, nominal)
    q = data.q.copy()
    rows = np.flatnonzero(data.labels == "gen3lite_left_h0")
    q[rows[len(rows) // 2:], 2] += np.deg2rad(2.0)
    write_samples(tmp_path / "faulty.csv", Dataset(labels=data.labels, q=q, fixture_names=data.fixture_names))
    capsys.readouterr()
    argv = ["calibrate", "--robot", str(GEN3LITE), "--tip-link", "ball_link", "--samples", str(tmp_path / "faulty.csv"),
            "--fixtures", str(tmp_path / "d2" / "fixtures.yaml"), "--out", str(tmp_path / "cal.yaml")]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "worst fixture gen3lite_left_h0" in err and "no single fixture" in err, err
    assert re.search(r"without gen3lite_left_h0 the rest is consistent and is written(, with warnings)? \(calibrate "
                     r"--exclude-fixture gen3lite_left_h0\)", err), err
    assert main([*argv, "--exclude-fixture", "gen3lite_left_h0"]) == 0, capsys.readouterr().err
