"""The held-out socket prediction a calibration records, against a simulated arm whose truth is known."""

from __future__ import annotations

import numpy as np

from spherecal.correction import load_robot, perturb, tool_point
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.samples import Dataset
from spherecal.identification.joint_error import LENGTH, field_root
from spherecal.identification.prediction import socket_spreads
from spherecal.identification.problem import NOISE
from spherecal.identification.synthetic import make_dataset
from spherecal.identification.workflow import WorkflowOptions, run_workflow
from spherecal.validation.sockets import recorded_prediction, socket_validation


def _spread(points: np.ndarray) -> float:
    return float(np.linalg.norm(points - points.mean(axis=0), axis=1).mean())


def test_a_well_made_arm_far_from_its_prior_is_predicted_at_its_own_socket_noise() -> None:
    # MUKCa-like: two sockets 50 mm apart, 30 presses each, 0.1 mm noise (below the declared 0.3 mm), an arm 3x
    # the prior spread off nominal. The prior's penalty is no noise: counted as such, the socket noise read 0.25 mm
    # and the held-out prediction was 2x the measured spread.
    noise = 1e-4
    nominal = load_robot("panda")
    true = perturb(nominal, np.random.default_rng(3), 3e-3, np.deg2rad(0.6), 3e-3)
    train, _ = make_dataset(true, {"a": (0.5, 0.1, 0.0), "b": (0.5, 0.15, 0.0)}, 30, np.random.default_rng(13), noise)
    held, _ = make_dataset(true, {"c": (-0.1, 0.5, 0.4), "d": (0.35, -0.35, 0.75), "e": (0.3, 0.3, 0.3)}, 30,
                           np.random.default_rng(23), noise)
    calibrated = run_workflow(nominal, train, FixtureSpec(names=("a", "b"), distances=[("a", "b", 0.05)])).model
    held_out = recorded_prediction(calibrated)
    root, socket_noise = held_out.root, held_out.noise
    assert abs(socket_noise / noise - 1.0) < 0.2, socket_noise
    sockets = [held.for_fixture(name) for name in held.fixture_names]
    measured = np.mean([_spread(tool_point(calibrated, q)) for q in sockets])
    predicted = np.mean(socket_spreads(calibrated, root, sockets, socket_noise))
    assert 0.5 < measured / predicted < 2.0, (measured, predicted)


def test_an_unmodelled_joint_angle_error_is_measured_and_predicted_at_held_out_sockets() -> None:
    # an arm whose joint angles are off by a smooth error of the configuration (a 3 mrad Gaussian process over joint
    # space, the length the prediction assumes) that no kinematic parameter describes, sockets at 0.1 mm
    std, noise = 3e-3, 1e-4
    nominal = load_robot("panda")
    true = perturb(nominal, np.random.default_rng(1))
    train, _ = make_dataset(true, {"h0": (0.5, -0.05, 0.45), "h1": (0.5, 0.0, 0.45)}, 40, np.random.default_rng(2),
                            noise)
    held, _ = make_dataset(true, {"a": (0.45, 0.25, 0.5), "b": (0.55, -0.3, 0.35), "c": (0.4, 0.1, 0.6)}, 30,
                           np.random.default_rng(3), noise)
    q = np.concatenate([train.q, held.q])
    root = field_root(q, LENGTH)
    recorded = q - std * root @ np.random.default_rng(4).standard_normal((root.shape[1], q.shape[1]))
    train = Dataset(labels=train.labels, q=recorded[: len(train.q)], fixture_names=train.fixture_names)
    held = Dataset(labels=held.labels, q=recorded[len(train.q):], fixture_names=held.fixture_names)
    spec = FixtureSpec(names=("h0", "h1"), distances=[("h0", "h1", 0.05)])
    calibrated = run_workflow(nominal, train, spec, WorkflowOptions(force=True)).model
    prediction = recorded_prediction(calibrated)
    assert abs(prediction.joint_error / std - 1.0) < 0.2, prediction.joint_error  # was: none (0)
    # the rest of the residual is the arm's, not the socket's: at most the declared noise, and the white part
    # (0.24 mm; the truth 0.1 mm) no longer the whole residual
    assert noise < prediction.noise <= NOISE, prediction.noise
    report = socket_validation({"nominal": nominal, "calibrated": calibrated}, held, prediction=prediction)
    measured, _ = report.summary("calibrated")
    assert 0.5 < measured / report.predicted_summary() < 2.0, (measured, report.predicted_summary())
    assert "the prediction includes the arm's unmodelled joint-angle error, " in report.format()


def test_a_joint_angle_error_under_the_declared_noise_is_measured_and_predicted_at_held_out_sockets() -> None:
    # MUKCa's Pandas leave 0.08-0.2 mm residuals, under the declared 0.3 mm, yet part of them is the arm's smooth
    # error (0.1-0.3 mrad by maximum likelihood). Simulated: an arm 3x the prior spread off nominal, sockets at 0.1 mm,
    # a 0.3 mrad joint-angle error. Was: none recorded, the socket noise read 0.16-0.20 mm (the whole residual).
    std, noise = 3e-4, 1e-4
    nominal = load_robot("panda")
    found, ratios = [], []
    for seed in range(3):
        true = perturb(nominal, np.random.default_rng(seed), 3e-3, np.deg2rad(0.6), 3e-3)
        train, _ = make_dataset(true, {"a": (0.5, 0.1, 0.3), "b": (0.5, 0.15, 0.3)}, 30,
                                np.random.default_rng(100 + seed), noise)
        held, _ = make_dataset(true, {"c": (-0.1, 0.5, 0.4), "d": (0.35, -0.35, 0.75), "e": (0.3, 0.3, 0.3)}, 30,
                               np.random.default_rng(200 + seed), noise)
        q = np.concatenate([train.q, held.q])
        root = field_root(q, LENGTH)
        recorded = q - std * root @ np.random.default_rng(300 + seed).standard_normal((root.shape[1], q.shape[1]))
        train = Dataset(labels=train.labels, q=recorded[: len(train.q)], fixture_names=train.fixture_names)
        held = Dataset(labels=held.labels, q=recorded[len(train.q):], fixture_names=held.fixture_names)
        spec = FixtureSpec(names=("a", "b"), distances=[("a", "b", 0.05)])
        calibrated = run_workflow(nominal, train, spec, WorkflowOptions(force=True, model="dh")).model
        prediction = recorded_prediction(calibrated)
        found.append((prediction.noise, prediction.joint_error))
        report = socket_validation({"nominal": nominal, "calibrated": calibrated}, held, prediction=prediction)
        ratios.append(report.summary("calibrated")[0] / report.predicted_summary())
    found = np.array(found)
    assert abs(found[:, 1].mean() / std - 1.0) < 0.3, found
    assert abs(found[:, 0].mean() / noise - 1.0) < 0.35, found
    assert all(0.5 < r < 2.0 for r in ratios), ratios


def test_what_a_calibration_leaves_at_nominal_is_predicted_at_the_arms_measured_scale() -> None:
    # an arm 3x the prior spread off nominal, 8 samples per socket at 0.3 mm: a few parameters barely excited, left at
    # nominal, so their error is the arm's own deviation there (known here). The recorded prediction charges them at
    # the scale the nominal model measures on the training sockets (2.5-4.4x), not the prior's 1 mm / 0.2 deg (was:
    # 1x, a third of the truth).
    from spherecal.identification.problem import prior_std

    nominal = load_robot("panda")
    spread = prior_std(nominal)
    recorded, true_error = [], []
    for seed in range(4):
        true = perturb(nominal, np.random.default_rng(seed), 3e-3, np.deg2rad(0.6), 3e-3)
        train, _ = make_dataset(true, {"a": (0.5, 0.1, 0.3), "b": (0.5, 0.15, 0.3)}, 8,
                                np.random.default_rng(100 + seed), 3e-4)
        spec = FixtureSpec(names=("a", "b"), distances=[("a", "b", 0.05)])
        calibrated = run_workflow(nominal, train, spec, WorkflowOptions(force=True, model="dh")).model
        block = calibrated.extras["calibration"]
        left = [nominal.param_names.index(n) for n, why in block["fixed"].items() if why.startswith("barely excited")]
        root = recorded_prediction(calibrated).root
        std = np.sqrt(np.einsum("pk,pk->p", root, root))
        recorded += list(std[left] / spread[left])
        true_error += list(np.abs(true.params - nominal.params)[left] / spread[left])
    assert len(recorded) >= 6, recorded
    ratio = np.sqrt(np.mean(np.square(true_error))) / np.sqrt(np.mean(np.square(recorded)))
    assert 0.6 < ratio < 1.6, (ratio, recorded, true_error)


def test_a_held_out_socket_shares_the_joint_angle_error_the_fit_absorbed() -> None:
    """The unmodelled joint-angle error is one realisation over every configuration: a calibration absorbs it where
    it was recorded, and at a held-out socket near those configurations (in joint space) what it absorbed cancels
    much of the error there. Explicit refits of 32 realisations (the exact kernel's Cholesky root, independent of
    the prediction's eigen-root) against :func:`held_out_joint_error`, per held-out socket; the same refits judged
    against an independent fresh draw at the held-out configurations (the assumption of a socket the calibration
    never saw) show how much the shared realisation matters near the recording. (Measured / predicted 1.10 near,
    1.09 far; leaving the absorbed part out of the prediction gave 0.90 and 1.28.)"""
    from spherecal.identification.build import build_problem
    from spherecal.identification.calibrate import calibrate
    from spherecal.identification.joint_error import kernel
    from spherecal.identification.prediction import held_out_joint_error
    from spherecal.identification.synthetic import project_to_point

    std, noise, draws = 2e-3, 1e-4, 32
    nominal = load_robot("panda")
    train, _ = make_dataset(nominal, {"h0": (0.5, -0.05, 0.45), "h1": (0.5, 0.0, 0.45)}, 30,
                            np.random.default_rng(2), 0.0)
    # near: h1's recorded postures moved onto a socket 1 cm on (close in joint space); far: random postures
    near, ok = project_to_point(nominal, train.for_fixture("h1")[::2], np.array([0.5, 0.01, 0.45]))
    far, _ = make_dataset(nominal, {"far": (-0.1, 0.5, 0.4)}, 20, np.random.default_rng(3), 0.0)
    assert ok.all()
    held = Dataset(labels=np.array(["near"] * len(near) + ["far"] * len(far.q)), q=np.concatenate([near, far.q]),
                   fixture_names=("near", "far"))
    spec = FixtureSpec(names=("h0", "h1"), distances=[("h0", "h1", 0.05)])
    problem = build_problem(nominal, train, spec, noise=noise)
    predicted = held_out_joint_error(nominal, problem, noise, std, held.q, held.labels)
    q = np.concatenate([train.q, held.q])
    n, count = q.shape[1], len(train.q)
    root = np.linalg.cholesky(kernel(q, q) + 1e-10 * np.eye(len(q)))
    lone = np.linalg.cholesky(kernel(held.q, held.q) + 1e-10 * np.eye(len(held.q)))
    rng = np.random.default_rng(4)
    shared, fresh = np.zeros(len(held.q)), np.zeros(len(held.q))

    def spread2(points: np.ndarray) -> np.ndarray:
        out = np.zeros(len(points))
        for name in held.fixture_names:
            mine = held.labels == name
            out[mine] = ((points[mine] - points[mine].mean(axis=0)) ** 2).sum(axis=1)
        return out

    for _ in range(draws):
        recorded = q + std * root @ rng.standard_normal((len(q), n))  # the encoders read the true angle + error
        data = Dataset(labels=train.labels, q=recorded[:count], fixture_names=train.fixture_names)
        model = calibrate(nominal, data, spec, noise=noise, check=False).model
        shared += spread2(tool_point(model, recorded[count:])) / draws
        other = held.q + std * lone @ rng.standard_normal((len(held.q), n))
        fresh += spread2(tool_point(model, other)) / draws
    for name in held.fixture_names:
        mine = held.labels == name
        ratio = shared[mine].mean() / predicted[mine].mean()
        assert 0.8 < ratio < 1.25, (name, shared[mine].mean(), predicted[mine].mean())
    near = held.labels == "near"
    assert fresh[near].mean() > 1.15 * shared[near].mean()  # a fresh draw overstates it (1.3x here)


def test_what_no_configuration_sees_is_left_out_of_the_recorded_covariance() -> None:
    # a UR-like arm's parallel shoulder, elbow and wrist axes: d2, d3 and d4 count only by their sum, and a calibration
    # leaves two of them at nominal, charged at the arm's measured scale of the prior spread. Through the calibrated
    # model's Jacobian (validate's) that combination is no longer exactly unseen: a noise-free arm's held-out spread
    # was predicted at 4-10 um where 0.5-0.7 um was measured (ratio 0.07-0.13). The part removed moves no tool point
    # of the nominal (its parameter Jacobian at other configurations than the ones that found it)
    from spherecal.correction import param_jacobian
    from spherecal.identification.prediction import seen_part

    from ..controller.test_generic_arm import UR5

    rng = np.random.default_rng(7)
    root = rng.standard_normal((UR5.n_params, 5)) * 1e-3
    seen = seen_part(UR5, root)
    jac = param_jacobian(UR5, UR5.random_configurations(50, rng)).reshape(150, -1)
    np.testing.assert_allclose(jac @ seen, jac @ root, atol=1e-12)
    names = UR5.param_names
    redundant = np.zeros(UR5.n_params)
    redundant[[names.index("d2"), names.index("d3")]] = 1.0, -1.0  # parallel axes: moves no tool point
    assert np.abs(redundant @ seen).max() < 1e-12 < np.abs(redundant @ root).max()

    true = perturb(UR5, np.random.default_rng(0), 3e-3, np.deg2rad(0.6), 3e-3)
    centres = {"P1": (0.45, 0.2, 0.3), "P2": (0.3, -0.4, 0.2), "P3": (-0.2, 0.45, 0.4)}
    train, spec = make_dataset(true, centres, 200, np.random.default_rng(100))
    held, _ = make_dataset(true, {"c": (0.45, 0.25, 0.3), "d": (0.2, -0.3, 0.5)}, 30, np.random.default_rng(200))
    calibrated = run_workflow(UR5, train, spec, WorkflowOptions(force=True)).model
    report = socket_validation({"nominal": UR5, "calibrated": calibrated}, held,
                               prediction=recorded_prediction(calibrated))
    measured, predicted = report.summary("calibrated")[0], report.predicted_summary()
    assert 0.5 < measured / predicted < 2.0, (measured, predicted)
