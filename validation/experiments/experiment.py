"""The shared steps of a simulated experiment (demo and campaigns): true robot, motion, calibration.

Thin adapters over the controller (MuJoCo self-motion) and identification (calibration) packages,
so the demo and the campaign workers run exactly the same steps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from spherecal.correction import RobotModel, SpherecalError, frames, load_robot, perturb
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.robots import reference_robot
from spherecal.identification.calibrate import calibrate
from spherecal.identification.synthetic import make_dataset

from ..planning.postures import reaches


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


#: Shares of the scaled distance from the column top tried in turn until the arm reaches a default fixture inside
#: its joint limits (:func:`default_fixtures`).
PULL_IN = (1.0, 0.9, 0.8, 0.7, 0.6, 0.5)


def column_top(model: RobotModel) -> np.ndarray:
    """(3,) the top of ``model``'s base column [m]: the first joint's fixed point (modified DH: the origin of frame
    1; standard DH: ``d1`` along the first axis), the column :func:`controller.reach.check_fixture` checks."""
    f = frames(model, np.zeros((1, model.n_joints)))
    a = f.origin[0, :, 0]
    return f.origin[1, :, 0] if model.convention == "modified" else a + model.d[0] * f.z[0, :, 0]


def fixtures_arm() -> RobotModel:
    """The arm :func:`default_fixtures`'s points were chosen on: the embedded Panda, read once per process
    (:func:`correction.files.robots.reference_robot`; measured, never handed out: its reach beyond its base column,
    1.06 m, and its column's top, 0.333 m above the base, are what another arm's points are scaled from)."""
    return reference_robot("panda")


def reach_scale(model: RobotModel) -> float:
    """``model``'s :func:`arm_reach` over that of :func:`fixtures_arm` (the Panda's 1.06 m): how much larger the arm
    is than the one the default fixtures were chosen on (a 0.45 m six-joint arm 0.42, an iiwa14 0.89)."""
    return arm_reach(model) / arm_reach(fixtures_arm())


def arm_reach(model: RobotModel) -> float:
    """How far the arm reaches beyond its base column [m]: :attr:`~correction.RobotModel.reach` (the links' and the
    tool's lengths) less the column's height (the base origin to :func:`column_top`)."""
    base = frames(model, np.zeros((1, model.n_joints))).origin[0, :, 0]
    return model.reach - float(np.linalg.norm(column_top(model) - base))


def default_fixtures(model: RobotModel | None = None) -> dict[str, np.ndarray]:
    """The three fixture centres P1, P2, P3 in the base frame [m]: ``spherecal simulate``'s defaults.

    The Panda's points (chosen by the controller for joint coverage under self-motion,
    ``controller.self_motion.DEFAULT_FIXTURES``) for ``model`` None or an arm that reaches all three inside its joint
    limits (the Panda, the FR3, the iiwa14, the Gen3 lite, a 1.3 m six-joint arm). An arm that does not reach one
    of them (a 0.45 m arm: 0.24 m short of P1) gets the same points scaled about the top of its base column by its
    reach over the Panda's (:func:`reach_scale`), where they sit for the Panda relative to the
    arm's size; a point the arm does not reach there is pulled towards the column top (:data:`PULL_IN`) until it
    does, and one still unreached is returned as scaled (the simulation refuses it, naming it).

    Scaling every arm's points was tried and not kept: at the scaled points a 1.3 m six-joint arm calibrated worse
    (workspace error against the truth 1.41, 1.71, 0.40 mm against 0.86, 0.18, 0.98 mm at the Panda's, seeds 0-2),
    the Gen3 lite's P2 covered 2 % of its base joint (17 % at the Panda's).
    """
    from spherecal.controller.self_motion import DEFAULT_FIXTURES  # MuJoCo: only a simulation needs it (start-up)

    points = {name: np.asarray(centre, dtype=float) for name, centre in DEFAULT_FIXTURES.items()}
    if model is None or all(reaches(model, p) for p in points.values()):
        return points
    scale = reach_scale(model)
    top, panda_top = column_top(model), column_top(fixtures_arm())
    return {name: _reached(model, [top + (p - panda_top) * scale * share for share in PULL_IN])
            for name, p in points.items()}


def _reached(model: RobotModel, tries: list[np.ndarray]) -> np.ndarray:
    """The first of ``tries`` (3,) [m] the arm reaches (:func:`.planning.postures.reaches`), else the first."""
    return next((point for point in tries if reaches(model, point)), tries[0])


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
