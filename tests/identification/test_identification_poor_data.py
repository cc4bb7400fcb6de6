"""Poorly excited data: the calibration is never worse than nominal, or it is refused loudly."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.correction import load_robot, perturb, registered_errors, tool_point
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.identification.build import build_problem
from spherecal.identification.calibrate import calibrate, check_plausible
from spherecal.identification.problem import ImplausibleCalibrationError
from spherecal.identification.synthetic import make_dataset


def _mean_error(model, true) -> float:
    q = true.random_configurations(2000, np.random.default_rng(5))
    return float(registered_errors(tool_point(model, q), tool_point(true, q)).mean())


def test_one_second_of_self_motion_does_not_make_the_arm_worse() -> None:
    """Regression: 1 s per fixture in MuJoCo (60 samples, 0.3 mm compliance, seed 3) once sent the
    first fit 150 deg away and the 'calibrated' arm ended 29 mm off against 7.7 mm nominal."""
    from spherecal.controller.self_motion import SelfMotionSettings, collect_self_motion
    from spherecal.validation.experiments.experiment import default_fixtures

    nominal = load_robot("panda")
    rng = np.random.default_rng(3)
    true = perturb(nominal, rng)
    fixtures = default_fixtures()
    run = collect_self_motion(true, nominal, fixtures, rng, SelfMotionSettings(seconds=1.0, samples=60, noise=3e-4))
    names = tuple(fixtures)
    distances = [
        (a, b, float(np.linalg.norm(fixtures[a] - fixtures[b]))) for i, a in enumerate(names) for b in names[i + 1 :]
    ]
    result = calibrate(nominal, run.dataset(), FixtureSpec(names=names, distances=distances), force=True)
    assert _mean_error(result.model, true) < _mean_error(nominal, true)
    # but so little data cannot be trusted to: the self-check refuses it without force (predicted 4.3 mm
    # against 5.2 mm expected of nominal, a 2x margin asked; 2 s at seed 5 ends worse than nominal)
    assert [f.check for f in result.selfcheck.failed] == ["prediction"]
    # what it could not see stayed at nominal, and says why
    assert any(reason.startswith("barely excited") for reason in result.fixed.values())


def test_a_wild_fit_is_refused_with_one_line() -> None:
    nominal = load_robot("panda")
    true = perturb(nominal, np.random.default_rng(1))
    dataset, spec = make_dataset(true, per_fixture=40, rng=np.random.default_rng(2))
    problem = build_problem(nominal, dataset, spec)
    check_plausible(problem, nominal.params)  # nominal itself is plausible
    check_plausible(problem, perturb(nominal, np.random.default_rng(3), 3e-3, np.deg2rad(0.6), 3e-3).params)
    params = nominal.params.copy()
    k = nominal.param_index("alpha3")
    params[k] += np.deg2rad(150.0)
    with pytest.raises(ImplausibleCalibrationError, match=r"field 'alpha3': the fit moves the tool point .* mm") as e:
        check_plausible(problem, params)
    assert "\n" not in str(e.value) and "changing alpha3 by 150 deg" in str(e.value)
    assert "record more self-motion" in str(e.value) and "robot file" not in str(e.value)


def test_a_wild_fit_from_another_arms_file_asks_for_the_robot_file() -> None:
    # a review fed a real Panda's recording to MUKCa's iiwa14 URDF (both 7 joints): refused as 'the samples do not
    # determine the parameters; record more self-motion', which sends the user to record again. The nominal model
    # puts the samples far more than a socket's play from their centres: the refusal asks about the robot file
    nominal = load_robot("panda")
    true = perturb(nominal, np.random.default_rng(1))
    dataset, spec = make_dataset(true, per_fixture=40, rng=np.random.default_rng(2))
    wrong = nominal.with_params(nominal.params + 0.08 * np.eye(nominal.n_params)[nominal.param_index("d3")])
    problem = build_problem(wrong, dataset, spec)
    params = wrong.params.copy()
    params[wrong.param_index("alpha3")] += np.deg2rad(150.0)
    asked = r"the nominal model puts the samples [\d.]+ mm rms from their fixtures' centres.*is the robot file this"
    with pytest.raises(ImplausibleCalibrationError, match=asked):
        check_plausible(problem, params)


def test_a_degenerate_direction_is_not_refused() -> None:
    """On the nominal Panda (tool point on the last axis) alpha7 trades against theta6, d6, a7 and the
    tool point: a fit of data from an exactly nominal arm may move it by degrees while every tool point
    stays put (seen in the paper's protocol). That is no reason to refuse the model."""
    from scipy.optimize import least_squares

    nominal = load_robot("panda")
    dataset, spec = make_dataset(nominal, per_fixture=40, rng=np.random.default_rng(2))
    problem = build_problem(nominal, dataset, spec)
    q = nominal.random_configurations(300, np.random.default_rng(4))
    target = tool_point(nominal, q)
    alpha7 = nominal.param_index("alpha7")
    others = [nominal.param_index(n) for n in ("theta6", "d6", "a7", "tool_x", "tool_y", "tool_z", "a6", "alpha6")]

    def params_of(x):
        params = nominal.params.copy()
        params[alpha7] += np.deg2rad(10.0)
        params[others] += x
        return params

    fit = least_squares(lambda x: (tool_point(nominal.with_params(params_of(x)), q) - target).ravel(), np.zeros(8))
    params = params_of(fit.x)
    assert np.abs(tool_point(nominal.with_params(params), q) - target).max() < 1e-5  # the same tool points
    check_plausible(problem, params)


def test_a_fixture_per_pair_of_samples_is_refused_before_the_memory_runs_out(tmp_path) -> None:
    # a fixture column naming every pair of rows (10 000 fixtures of 2 samples: 30 037 unknowns): the dense
    # Jacobian would be 14 GB; the process grew until the kernel killed it after a minute, with no message.
    # Run under a 3 GB address-space limit so that a regression fails here quickly instead of swapping.
    import resource
    import subprocess
    import sys

    from spherecal.correction import save_robot
    from spherecal.correction.files.samples import Dataset
    from spherecal.correction.files.samples_csv import write_samples

    panda = load_robot("panda")
    q = panda.random_configurations(20_000, np.random.default_rng(0))
    path = write_samples(tmp_path / "samples.csv", Dataset(labels=np.array([f"F{k // 2}" for k in range(20_000)]),
                                                           q=q))
    save_robot(panda, tmp_path / "robot.yaml")

    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (3_000_000_000, 3_000_000_000))

    run = subprocess.run([sys.executable, "-c", "import sys; from spherecal.cli import main; sys.exit(main())",
                          "calibrate", "--robot", str(tmp_path / "robot.yaml"), "--samples", str(path), "--out",
                          str(tmp_path / "cal.yaml")], capture_output=True, text=True, timeout=120, preexec_fn=limit)
    assert run.returncode == 1 and len(run.stderr.strip().splitlines()) == 1, run.stderr[-800:]
    assert "field 'fixture': 10000 fixtures and 20000 samples make 30037 unknowns" in run.stderr
    assert "14.4 GB Jacobian (at most 0.5 GB): does the fixture column name each sample?" in run.stderr
    assert not (tmp_path / "cal.yaml").exists()
