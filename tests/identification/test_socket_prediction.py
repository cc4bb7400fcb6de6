"""The held-out socket prediction a calibration records, against a simulated arm whose truth is known."""

from __future__ import annotations

import numpy as np

from spherecal.correction import load_robot, perturb, tool_point
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.identification.prediction import socket_spreads
from spherecal.identification.synthetic import make_dataset
from spherecal.identification.workflow import run_workflow
from spherecal.validation.sockets import recorded_prediction


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
    root, socket_noise = recorded_prediction(calibrated)
    assert abs(socket_noise / noise - 1.0) < 0.2, socket_noise
    sockets = [held.for_fixture(name) for name in held.fixture_names]
    measured = np.mean([_spread(tool_point(calibrated, q)) for q in sockets])
    predicted = np.mean(socket_spreads(calibrated, root, sockets, socket_noise))
    assert 0.5 < measured / predicted < 2.0, (measured, predicted)
