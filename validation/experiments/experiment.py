"""The shared steps of a simulated experiment (demo and campaigns): true robot, motion, calibration.

Thin adapters over the controller (MuJoCo self-motion) and identification (calibration) packages,
so the demo and the campaign workers run exactly the same steps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from spherecal.correction import RobotModel, SpherecalError, load_robot, perturb
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.identification.calibrate import calibrate
from spherecal.identification.synthetic import make_dataset


class ExperimentError(SpherecalError):
    """A simulated experiment that cannot be run as asked (one line naming the option, file or field)."""


def joint_stiffness(text: str | None, n: int) -> list[float] | None:
    """(n,) joint stiffness [Nm/rad] of ``K`` (every joint) or ``K,K,...`` (one per joint), 0 = rigid;
    None when ``text`` is None.

    Raises:
        ExperimentError: not numbers, not 1 or ``n`` of them, or one not finite and >= 0 (naming ``--stiffness``).
    """
    if text is None:
        return None
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise ExperimentError(f"field '--stiffness': {text!r}: expected numbers [Nm/rad] separated by commas") from None
    if len(values) == 1:
        values = values * n
    if len(values) != n or not all(math.isfinite(v) and v >= 0 for v in values):
        raise ExperimentError(f"field '--stiffness': {text!r}: expected 1 or {n} finite values >= 0 [Nm/rad] "
                              "(0 = rigid)")
    return values


def nominal_robot() -> RobotModel:
    """The embedded nominal Panda."""
    return load_robot("panda")


def true_robot(nominal: RobotModel, rng: np.random.Generator) -> RobotModel:
    """A seeded "true" robot: the nominal one perturbed by the issues' default spread
    (lengths 1 mm, angles 0.2 deg, tool 1 mm std; base not perturbed)."""
    return perturb(nominal, rng)


def default_fixtures() -> dict[str, np.ndarray]:
    """The three fixture centres P1, P2, P3 in the base frame [m]: ``spherecal simulate``'s defaults
    (chosen by the controller for joint coverage under self-motion)."""
    from spherecal.controller.self_motion import DEFAULT_FIXTURES  # MuJoCo: only a simulation needs it (start-up)

    return {name: np.asarray(centre, dtype=float) for name, centre in DEFAULT_FIXTURES.items()}


@dataclass
class MotionData:
    """Calibration data of one simulated experiment.

    Attributes:
        dataset: the recorded samples (:class:`spherecal.correction.files.samples.Dataset`).
        spec: the fixtures (:class:`spherecal.correction.files.fixtures.FixtureSpec`), distances exact.
        trajectory: the MuJoCo run (controller's result) when simulated with dynamics, else None.
    """

    dataset: object
    spec: object
    trajectory: object = None


def fixture_spec(fixtures: dict[str, np.ndarray], known_distances: bool):
    """Fixtures with unknown centres; with ``known_distances``, every pairwise distance (exact)."""

    names = tuple(fixtures)
    distances = []
    if known_distances:
        pairs = [(a, b) for i, a in enumerate(names) for b in names[i + 1 :]]
        distances = [(a, b, float(np.linalg.norm(fixtures[a] - fixtures[b]))) for a, b in pairs]
    return FixtureSpec(names=names, distances=distances)


def motion_set(
    truth: RobotModel,
    nominal: RobotModel,
    fixtures: dict[str, np.ndarray],
    samples: int,
    noise: float,
    rng: np.random.Generator,
    source: str = "synthetic",
    seconds: float = 20.0,
    progress=None,
) -> MotionData:
    """Calibration samples at every fixture on the true robot.

    Args:
        truth: the true robot (the plant).
        nominal: the model the controller runs on (MuJoCo source).
        fixtures: name -> (3,) centre [m].
        samples: samples kept per fixture.
        noise: fixture noise std [m] (the physical point moves, the joint readings do not).
        rng: seeded generator.
        source: ``"synthetic"`` (kinematic projection onto the self-motion manifold) or ``"mujoco"``
            (self-motion through the QP controller on the MuJoCo plant).
        seconds: simulated time per fixture [s] (MuJoCo).
        progress: MuJoCo only: called with the simulated seconds done since its last call, or None.
    """
    if source == "synthetic":

        dataset, _ = make_dataset(truth, fixtures, samples, rng, noise)
        return MotionData(dataset, fixture_spec(fixtures, len(fixtures) > 1))
    if source == "mujoco":
        return _mujoco_motion(truth, nominal, fixtures, samples, noise, rng, seconds, progress)
    raise ValueError(f"unknown motion source {source!r}, expected 'synthetic' or 'mujoco'")


def _mujoco_motion(truth, nominal, fixtures, samples, noise, rng, seconds, progress=None) -> MotionData:
    from spherecal.controller.self_motion import (  # MuJoCo: only a simulation needs it (start-up)
        SelfMotionSettings,
        collect_self_motion,
    )

    settings = SelfMotionSettings(seconds=seconds, samples=samples, noise=noise)
    run = collect_self_motion(truth, nominal, fixtures, rng, settings, progress=progress)
    return MotionData(run.dataset(), fixture_spec(fixtures, len(fixtures) > 1), run)


def calibrate_from(nominal: RobotModel, data: MotionData, start: RobotModel | None = None, force: bool = False):
    """Calibrate ``nominal`` from the data with identification's default method (``lm``).

    Args:
        nominal: the model calibrated (fixed parameters and a pinned single fixture come from it).
        data: the samples and fixture spec.
        start: start of the optimisation (default ``nominal``).
        force: return the result even when its self-check refuses it (the failures are in
            ``result.selfcheck``); otherwise the refusal is raised.

    Returns:
        The :class:`identification.calibrate.CalibrationResult` (``.model`` is the calibrated robot).
    """

    return calibrate(nominal, data.dataset, data.spec, start=start, force=force)
