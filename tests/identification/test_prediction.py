"""Predicted calibration accuracy: rigid-motion projection against Kabsch, covariance algebra, scaling
laws, and (slow) agreement with measured campaigns."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.correction import load_robot, param_jacobian, registered_errors, tool_point
from spherecal.identification.identifiability import normal_inverse, predicted_std, symmetric_root
from spherecal.identification.prediction import Workspace, predict_accuracy, remove_rigid_motion, socket_spreads
from spherecal.identification.synthetic import make_dataset

FIXTURES = {"P1": (0.5, -0.25, 0.5), "P2": (0.5, 0.0, 0.4), "P3": (0.45, 0.25, 0.45)}


@pytest.fixture(scope="module")
def data(panda):
    return make_dataset(panda, FIXTURES, 120, np.random.default_rng(3))


@pytest.fixture(scope="module")
def workspace(panda):
    return Workspace.of(panda, 400, np.random.default_rng(4))


def test_rigid_field_is_removed(rng):
    points = rng.normal(size=(50, 3))
    w, t = rng.normal(size=3), rng.normal(size=3)
    rigid = (t + np.cross(w, points)).reshape(-1, 1)
    assert np.abs(remove_rigid_motion(rigid, points)).max() < 1e-12
    other = rng.normal(size=(150, 2))
    once = remove_rigid_motion(other, points)
    np.testing.assert_allclose(remove_rigid_motion(once, points), once, atol=1e-12)  # a projector


def test_projected_error_matches_kabsch_registration(panda, rng):
    """A small parameter error: |Proj G dp| per point equals the registered error of the two point sets."""
    q = panda.random_configurations(300, rng)
    dp = rng.normal(0.0, 1e-4, panda.n_params) * np.r_[np.ones(4 * panda.n_joints + 3), np.zeros(6)]
    jac, points = param_jacobian(panda, q, return_point=True)
    linear = remove_rigid_motion(jac.reshape(-1, panda.n_params) @ dp[:, None], points).reshape(-1, 3)
    kabsch = registered_errors(tool_point(panda.with_params(panda.params + dp), q), points)
    np.testing.assert_allclose(np.linalg.norm(linear, axis=1), kabsch, rtol=2e-2, atol=2e-8)


def test_normal_inverse_matches_numpy(rng):
    jac = rng.normal(size=(200, 12)) * np.logspace(-3, 2, 12)
    np.testing.assert_allclose(normal_inverse(jac), np.linalg.inv(jac.T @ jac), rtol=1e-8)
    np.testing.assert_allclose(predicted_std(jac, 0.3), 0.3 * np.sqrt(np.diag(np.linalg.inv(jac.T @ jac))), rtol=1e-8)


def test_error_scales_with_noise_and_samples(panda, data, workspace):
    dataset, spec = data
    base = predict_accuracy(panda, dataset, spec, noise=3e-4, workspace=workspace)
    double = predict_accuracy(panda, dataset, spec, noise=6e-4, workspace=workspace)
    more = predict_accuracy(panda, dataset, spec, noise=3e-4, workspace=workspace, sample_weight=4.0)
    assert 0 < base.mean < base.p95
    if not any(why.startswith("barely") for why in base.fixed.values()):
        assert double.mean == pytest.approx(2 * base.mean, rel=0.15)
    assert more.mean == pytest.approx(base.mean / 2, rel=0.25)
    assert predict_accuracy(panda, dataset, spec, noise=0.0, workspace=workspace).mean < 1e-3 * base.mean
    assert base.identifiability.condition_number < 1e4
    assert set(base.identified).isdisjoint(base.fixed)
    assert "predicted tool-point error" in base.summary()


def test_known_distances_remove_the_scale_error(panda, data, workspace):
    dataset, spec = data
    with_d = predict_accuracy(panda, dataset, spec, workspace=workspace)
    without = predict_accuracy(panda, dataset, None, workspace=workspace)
    assert without.mean > 5 * with_d.mean
    # and the printed prediction says why (plan --predict showed 1.5 mm with no word about the scale)
    assert "warning: scale:" in without.summary() and "warning:" not in with_d.summary()


def test_restricted_motion_is_predicted_worse(panda, data, workspace):
    from spherecal.correction.files.samples import Dataset
    from spherecal.validation.planning.candidates import Candidate
    from spherecal.validation.planning.plan import motion_samples

    dataset, spec = data
    rng = np.random.default_rng(5)
    window = np.full(panda.n_joints, 0.15)
    q = [motion_samples(panda, Candidate(k, np.array(c), window), 120, rng) for k, c in FIXTURES.items()]
    small = Dataset(labels=np.repeat(list(FIXTURES), 120), q=np.concatenate(q), fixture_names=tuple(FIXTURES))
    full = predict_accuracy(panda, dataset, spec, workspace=workspace)
    poor = predict_accuracy(panda, small, spec, workspace=workspace)
    assert poor.mean > 2 * full.mean
    assert poor.identifiability.condition_number > full.identifiability.condition_number
    assert poor.weak or any(why.startswith("barely") for why in poor.fixed.values())


@pytest.mark.slow
def test_predicted_mean_within_25_percent_of_a_10_set_campaign(panda):
    """Two and three fixtures, distances known, 0.3 mm: prediction from one data set vs 10 calibrations."""
    from spherecal.identification.calibrate import calibrate
    from spherecal.validation.experiments.experiment import default_fixtures, true_robot

    workspace = Workspace.of(panda, 1000)
    for k in (2, 3):
        fixtures = dict(list(default_fixtures().items())[:k])
        measured, predicted = [], None
        for index in range(10):
            rng = np.random.default_rng((7, k, index))
            truth = true_robot(panda, rng)
            dataset, spec = make_dataset(truth, fixtures, 500, rng, 3e-4)
            if predicted is None:
                predicted = predict_accuracy(panda, dataset, spec, noise=3e-4, workspace=workspace).mean
            model = calibrate(panda, dataset, spec).model
            q = truth.random_configurations(2000, rng)
            measured.append(registered_errors(tool_point(model, q), tool_point(truth, q)).mean())
        ratio = predicted / np.mean(measured)
        print(
            f"{k} fixtures: predicted {predicted * 1e3:.4f} mm, measured {np.mean(measured) * 1e3:.4f} mm, "
            f"ratio {ratio:.2f}"
        )
        assert 0.75 < ratio < 1.25


def test_the_error_covariance_at_the_samples_noise_is_the_map_estimates_over_refits(panda):
    # explicit refits of the linearised MAP calibration (prior rows at the default weight and 0.3 mm) of an arm 3x the
    # prior spread off nominal, sockets at 0.1 mm: the error x - dp of x = A^-1 J_d^T (J_d dp + n) against the
    # covariance deviation_root records for validate. The judgement's form, every row at the noise, is not it here
    # (the prior's part is exact only when noise^2 = W noise_p^2).
    from spherecal.correction.files.fixtures import FixtureSpec
    from spherecal.identification.build import build_problem
    from spherecal.identification.prediction import _linearised, deviation_root
    from spherecal.identification.problem import prior_std

    data, _ = make_dataset(panda, {"a": (0.5, 0.1, 0.3), "b": (0.5, 0.15, 0.3)}, 40, np.random.default_rng(5))
    problem = build_problem(panda, data, FixtureSpec(names=("a", "b"), distances=[("a", "b", 0.05)]), prior_weight=0.5)
    noise, scale = 1e-4, 3.0
    _, _, pruned, _, _, jac, inverse = _linearised(problem, noise)
    root, _, _, _ = deviation_root(panda, problem, noise, bias_scale=scale, data_noise=noise)
    assert root.shape[1] == pruned.n_free_params  # nothing left at nominal: the covariance alone
    fp, rows = pruned.n_free_params, ~pruned.prior_rows()
    stated = np.full(rows.sum(), pruned.noise)  # the distance's row at its stated accuracy, the samples' at theirs
    stated[: 3 * data.n_samples] = noise
    rng = np.random.default_rng(6)
    draws = 4000
    dp = np.zeros((jac.shape[1], draws))
    dp[:fp] = scale * prior_std(panda)[pruned.free, None] * rng.standard_normal((fp, draws))
    y = jac[rows] @ dp + stated[:, None] * rng.standard_normal((rows.sum(), draws))
    error = (inverse @ (jac[rows].T @ y) - dp)[:fp]
    gains = param_jacobian(panda, panda.random_configurations(50, np.random.default_rng(7))).reshape(-1, panda.n_params)
    measured = np.sum((gains[:, pruned.free] @ error) ** 2) / draws
    predicted = np.sum((gains @ root) ** 2)
    assert abs(predicted / measured - 1.0) < 0.08, (predicted, measured)
    judged, _, _, _ = deviation_root(panda, problem, noise, bias_scale=scale)
    assert np.sum((gains @ judged) ** 2) / measured < 0.7  # the prior's part charged at the samples' noise


def test_the_draws_root_does_not_depend_on_how_eigh_signs_its_vectors() -> None:
    # a prediction moved 2 % between two calibrations equal to 1e-15 (MUKCa's kuka_14 raised_left, validate: 0.442
    # and 0.450 mm): eigh flipped eigenvector signs, and every Monte Carlo draw through the root with them
    rng = np.random.default_rng(3)
    a = rng.standard_normal((12, 8))
    cov = a @ a.T * 1e-8  # rank 8 of 12, as a covariance with gauge directions
    root = symmetric_root(cov)
    assert np.allclose(root @ root.T, cov, rtol=0, atol=1e-20)
    perm = rng.permutation(12)  # the same matrix handed to eigh in another order: other signs
    again = symmetric_root(cov[np.ix_(perm, perm)])[np.argsort(perm)]
    assert np.abs(again - root).max() < 1e-6 * np.abs(root).max()  # the zero directions: rounding (1e-8)
    kept = symmetric_root(cov, floor=1e-9)  # the zero directions left out
    assert kept.shape == (12, 8) and np.allclose(kept @ kept.T, cov, rtol=0, atol=1e-20)
    # the same draws, so the same predicted spread, through the function validate calls
    panda = load_robot("panda")
    q = [panda.random_configurations(20, np.random.default_rng(1))]
    wide = np.zeros((panda.n_params, 12))
    wide[:12] = root
    wide_again = np.zeros((panda.n_params, 12))
    wide_again[:12] = again
    assert socket_spreads(panda, wide, q, 1e-4)[0] == pytest.approx(socket_spreads(panda, wide_again, q, 1e-4)[0],
                                                                    rel=1e-6)


def test_a_parameter_left_at_nominal_is_charged_at_its_tolerance() -> None:
    """What the calibration left at nominal is charged at what pruning judged it against: a joint's zero at its
    1 deg tolerance (stop 10: a real arm's zero is 1-3 deg off), a length at its 1 mm prior spread."""
    from spherecal.identification.build import build_problem
    from spherecal.identification.prediction import deviation_root
    from spherecal.identification.problem import ZERO_TOLERANCE

    panda = load_robot("panda")
    dataset, spec = make_dataset(panda, per_fixture=30, rng=np.random.default_rng(0))
    problem = build_problem(panda, dataset, spec)
    left = [panda.param_index("theta4"), panda.param_index("d3")]
    root, *_ = deviation_root(panda, problem, 3e-4, free=np.setdiff1d(problem.free, left))
    std = np.sqrt((root**2).sum(axis=1))
    assert std[left[0]] == pytest.approx(ZERO_TOLERANCE, rel=1e-9) and ZERO_TOLERANCE == pytest.approx(np.deg2rad(1))
    assert std[left[1]] == pytest.approx(1e-3, rel=1e-9)
