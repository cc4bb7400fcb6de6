"""The measurement protocol in simulation: self-motion at spherical-joint fixtures.

At each fixture: reach it with IK on the TRUE model (the plant), engage the ``connect``
equality, then drive self-motion with :class:`NullSpaceController` running on the NOMINAL
model, exactly as on a real arm, and record the joint readings at 1 kHz. The closed chain, not
the nominal model, keeps the true tool point on the fixture. ``N`` random samples per fixture
are kept; the whole run is also offered decimated (every 10 ms) for viewing.

The physics and the recording run at 1 kHz (:data:`TIMESTEP`); the controller (QP, exploration)
runs at ``control_rate`` (250 Hz by default) and the joint velocity command between two control
steps is extrapolated from the last two (a first-order hold, clipped to the last velocity bounds),
as a slower outer loop on a real arm would interpolate its setpoints. The connect residual stays
that of a 1 kHz controller (a held command would raise it by ~10 % at 200 Hz, ~30 % at 100 Hz).

Optional fixture compliance (the paper's measurement noise) moves the physical anchor point
of the fixture, never the joint readings.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from spherecal.correction import RobotModel
from spherecal.correction.errors import SpherecalError
from spherecal.correction.files.samples import Dataset

from .exploration import COVERAGE_PERIOD, RANDOM_PERIOD, Ramp, joint_coverage, make_exploration
from .home import home
from .ik import ik
from .nullspace import NullSpaceController
from .plant import TIMESTEP, build_plant
from .qp_ik import LIMIT_MARGIN
from .reach import UnreachableFixtureError, check_fixture, check_fixture_distance, fixture_centre

#: Default fixtures [m], base frame: over the front of the Panda's workspace, chosen by the
#: coverage table (every joint >= 30% of its range in 20 s with coverage exploration).
DEFAULT_FIXTURES: dict[str, tuple[float, float, float]] = {
    "P1": (0.5, -0.25, 0.5),
    "P2": (0.5, 0.0, 0.4),
    "P3": (0.45, 0.25, 0.45),
}

#: Random restarts of the reach IK, which starts at :func:`controller.home.home`.
REACH_RESTARTS = 20
#: Correlation time of the fixture compliance [s]: a new offset every this often, blended.
NOISE_PERIOD = 0.05
#: How often the exploration is asked whether its goal is reached [s].
CHECK_PERIOD = 0.05
#: How often the optional progress callback is called [s of simulated time].
PROGRESS_PERIOD = 0.1
#: Default rate of the controller (QP and exploration) [Hz]; the physics runs at ``1 / TIMESTEP``.
CONTROL_RATE = 250.0


class InvalidSettingsError(SpherecalError):
    """Self-motion settings that cannot be simulated."""


@dataclass(frozen=True)
class SelfMotionSettings:
    """Settings of :func:`collect_self_motion`.

    Attributes:
        seconds: self-motion per fixture [s].
        samples: samples kept per fixture (drawn at random from the 1 kHz record).
        mode: ``"coverage"`` (default) or ``"random"`` exploration.
        noise: std of the fixture compliance per axis [m] (0: ideal fixture).
        noise_period: correlation time of the compliance [s] (a new offset this often).
        speed: exploration speed [rad/s] (None: the mode's default).
        decimate: period of the decimated trajectory [s].
        solver: QP solver name (``"osqp"`` persistent by default).
        control_rate: rate of the controller [Hz], a divisor of the physics rate ``1 / TIMESTEP``
            (1000 Hz: a QP every physics step); in between, the command is extrapolated
            (:func:`command_block`).
    """

    seconds: float = 20.0
    samples: int = 500
    mode: str = "coverage"
    noise: float = 0.0
    noise_period: float = NOISE_PERIOD
    speed: float | None = None
    decimate: float = 0.01
    solver: str = "osqp"
    control_rate: float = CONTROL_RATE

    def control_steps(self) -> int:
        """Physics steps per control step (``1 / (control_rate * TIMESTEP)``, an integer).

        Raises:
            InvalidSettingsError: the rate is not a positive divisor of the physics rate.
        """
        ratio = 1.0 / (self.control_rate * TIMESTEP) if self.control_rate > 0 else 0.0
        steps = int(round(ratio))
        if steps < 1 or abs(ratio - steps) > 1e-9 * steps:
            raise InvalidSettingsError(
                f"control rate {self.control_rate:g} Hz must divide the physics rate {1 / TIMESTEP:g} Hz "
                "(e.g. 1000, 500, 250, 200, 125, 100)")
        return steps


@dataclass(frozen=True, eq=False)
class SelfMotionRun:
    """Everything a self-motion run produced.

    Attributes:
        true_model, nominal_model: the plant's robot and the controller's.
        fixture_names: (F,) names in run order; ``fixture_centres`` (F, 3) true centres [m].
        t, q, labels, tool: kept samples: (K,) time [s], (K, n) joint readings [rad], (K,)
            fixture names, (K, 3) TRUE tool point (plant's site) [m].
        trajectory_t, trajectory_q, trajectory_labels, trajectory_tool: the whole run every
            ``settings.decimate`` seconds, same shapes.
        coverage: (F, n) share of each joint's range visited.
        max_violation: (F,) largest distance between tool site and fixture anchor [m].
        max_deviation: (F,) largest distance between tool site and the fixture centre [m]
            (differs from ``max_violation`` only with compliance noise).
        rms_deviation: (F,) root-mean-square distance between tool site and fixture centre [m]
            (the effective measurement noise; sqrt(3) x the per-axis std).
        limit_excess: (F,) largest excursion beyond a joint limit [rad] (0: none).
        reach_q: (F, n) configuration where each fixture was engaged.
        fallbacks: QP steps that fell back to the damped pseudo-inverse.
        settings: what made it.
    """

    true_model: RobotModel
    nominal_model: RobotModel
    fixture_names: tuple[str, ...]
    fixture_centres: np.ndarray
    t: np.ndarray
    q: np.ndarray
    labels: np.ndarray
    tool: np.ndarray
    trajectory_t: np.ndarray
    trajectory_q: np.ndarray
    trajectory_labels: np.ndarray
    trajectory_tool: np.ndarray
    coverage: np.ndarray
    max_violation: np.ndarray
    max_deviation: np.ndarray
    rms_deviation: np.ndarray
    limit_excess: np.ndarray
    reach_q: np.ndarray
    fallbacks: int = 0
    settings: SelfMotionSettings = field(default_factory=SelfMotionSettings)

    def dataset(self):
        """The kept samples as an :class:`spherecal.correction.files.samples.Dataset` (with times)."""

        return Dataset(labels=self.labels, q=self.q, t=self.t, fixture_names=self.fixture_names)

    def coverage_table(self) -> str:
        """Per-fixture coverage [%] per joint, violation [mm] and limit excess [rad], as text."""
        n = self.coverage.shape[1]
        head = "fixture " + " ".join(f"{f'q{j + 1}%':>5}" for j in range(n)) + "   min%  viol_mm  limit_rad"
        rows = [head]
        for k, name in enumerate(self.fixture_names):
            cov = self.coverage[k] * 100
            rows.append(f"{name:<7} " + " ".join(f"{c:5.1f}" for c in cov)
                        + f"  {cov.min():5.1f}  {self.max_violation[k] * 1e3:7.4f}  {self.limit_excess[k]:9.2e}")
        return "\n".join(rows)


def reach_fixture(model: RobotModel, name: str, centre: np.ndarray, rng: np.random.Generator,
                  margin: float = 2 * LIMIT_MARGIN) -> np.ndarray:
    """(n,) joint angles putting ``model``'s tool point on ``centre``, ``margin`` inside the limits.

    Raises:
        FixtureInsideRobotError, UnreachableFixtureError (farther than the arm reaches in any posture: in millimetres?
            before the IK is tried).
    """
    check_fixture_distance(model, name, centre)
    check_fixture(model, name, centre)
    margin = np.minimum(margin, 0.5 * (model.upper - model.lower))  # a joint narrower than 2 margins: its middle
    inner = replace(model, lower=model.lower + margin, upper=model.upper - margin)
    result = ik(inner, centre, home(inner), restarts=REACH_RESTARTS, rng=rng)
    if not result.converged:
        raise UnreachableFixtureError(
            f"fixture {name} at {np.round(centre, 4).tolist()} m is out of reach "
            f"(IK inside the joint limits misses it by {result.position_error * 1e3:.1f} mm)", name)
    return result.q


def compliance_path(std: float, steps: int, rng: np.random.Generator, period: float = NOISE_PERIOD) -> np.ndarray:
    """Smooth random offset of a fixture's anchor at every physics step: knots N(0, std^2) every
    ``period`` seconds, cosine-blended.

    Starts at zero (where the fixture was reached) so that engaging it does not jump.

    Args:
        std: per-axis std of the knots [m].
        steps: number of physics steps (times ``k * TIMESTEP``).
        rng: seeded generator (draws the knots' normals at once).
        period: time between knots [s].

    Returns:
        (steps, 3) offsets [m].
    """
    phase = np.arange(steps) * (TIMESTEP / period)
    index = np.floor(phase + 1e-9).astype(int)  # knot interval (t = k * period starts interval k)
    count = int(np.floor((steps - 1) * TIMESTEP / period + 1e-9)) + 1 if steps else 0
    knots = np.vstack([np.zeros((1, 3)), rng.normal(0.0, std, (count, 3))])
    w = (0.5 - 0.5 * np.cos(np.pi * np.clip(phase - index, 0.0, 1.0)))[:, None]
    return knots[index] + w * (knots[index + 1] - knots[index])


def command_block(command: np.ndarray, previous: np.ndarray | None, lb: np.ndarray, ub: np.ndarray,
                  steps: int) -> np.ndarray:
    """Joint velocity commands for the physics steps of one control period: a first-order hold.

    ``command + i * (command - previous) / steps`` at step ``i`` (the trend of the last two control
    steps carried on), clipped to the bounds of the control step; ``command`` held when there is no
    previous one.

    Args:
        command: (n,) this control step's command [rad/s].
        previous: (n,) the last control step's command [rad/s], or None.
        lb, ub: (n,) velocity bounds at this control step [rad/s].
        steps: physics steps per control step.

    Returns:
        (steps, n) commands [rad/s].
    """
    if previous is None or steps == 1:
        return np.broadcast_to(command, (steps, command.size))
    ramp = np.arange(steps)[:, None] * ((command - previous) / steps)
    return np.clip(command + ramp, lb, ub)


def collect_self_motion(
    true_model: RobotModel,
    nominal_model: RobotModel,
    fixtures: dict[str, np.ndarray],
    rng: np.random.Generator,
    settings: SelfMotionSettings | None = None,
    progress: Callable[[float], None] | None = None,
) -> SelfMotionRun:
    """Run the protocol at every fixture and return what was recorded.

    Args:
        true_model: the plant's robot (perturbed "true" parameters).
        nominal_model: the controller's kinematics.
        fixtures: name -> (3,) true centre in the world [m], visited in order.
        rng: seeded generator (exploration, sample choice, noise, IK restarts).
        settings: :class:`SelfMotionSettings` (defaults when None).
        progress: called with the simulated seconds done since its last call (every
            :data:`PROGRESS_PERIOD` of simulated time, and at the end of each fixture), or None.

    Raises:
        ShapeError: a fixture centre that is not three numbers, naming it (before anything is simulated).
        FixtureInsideRobotError, UnreachableFixtureError: before anything is simulated.
    """
    settings = settings or SelfMotionSettings()
    every_control = settings.control_steps()
    fixtures = {str(k): fixture_centre(str(k), v) for k, v in fixtures.items()}
    names = tuple(fixtures)
    reach = np.array([reach_fixture(true_model, k, c, rng) for k, c in fixtures.items()]).reshape(len(names), -1)
    plant = build_plant(true_model, fixtures)
    controller = NullSpaceController(nominal_model, solver=settings.solver, dt=every_control * TIMESTEP)
    n = true_model.n_joints
    steps = int(round(settings.seconds / TIMESTEP))
    keep = min(settings.samples, steps)
    every = max(int(round(settings.decimate / TIMESTEP)), 1)
    out = {key: [] for key in ("t", "q", "labels", "tool", "tt", "tq", "tlabels", "ttool")}
    coverage = np.zeros((len(names), n))
    violation, deviation, rms, excess = (np.zeros(len(names)) for _ in range(4))
    report_every = max(int(round(PROGRESS_PERIOD / TIMESTEP)), 1)
    period = int(round((COVERAGE_PERIOD if settings.mode == "coverage" else RANDOM_PERIOD) / TIMESTEP))
    check = max(int(round(CHECK_PERIOD / TIMESTEP)), 1)
    for k, name in enumerate(names):
        exploration = make_exploration(settings.mode, nominal_model, fixtures[name], rng, settings.speed,
                                       kinematics=controller.kinematics)
        ramp = Ramp(n)
        centre = fixtures[name]
        anchor = centre + compliance_path(settings.noise, steps, rng, settings.noise_period) if settings.noise > 0 \
            else None
        plant.move_fixture(name, centre)
        plant.set_state(reach[k])
        plant.engage(name)
        q_log = np.empty((steps, n))
        tool_log = np.empty((steps, 3))
        next_decision, next_check, reported = 0, 0, 0
        previous = None
        for s in range(0, steps, every_control):
            stop = min(s + every_control, steps)
            q = plant.q.copy()
            q_log[s] = q
            t = s * TIMESTEP
            due = s >= next_decision
            if s >= next_check:  # is the goal reached? asked every CHECK_PERIOD
                due = due or exploration.done(q)
                next_check = s + check
            if due:
                exploration.decide(t, q_log[: s + 1], controller.kinematics(q)[1])
                ramp.retarget(t)
                next_decision = s + period
            command = controller.step(q, ramp(t, exploration.command(q)))
            block = command_block(command, previous, *controller.last_bounds, every_control)
            previous = command
            plant.advance(s, q_log, tool_log, block[: stop - s], anchor, fixture=k)
            if progress is not None and stop - reported >= report_every:
                progress((stop - reported) * TIMESTEP)
                reported = stop
        if progress is not None and steps > reported:
            progress((steps - reported) * TIMESTEP)
        plant.release()
        offset = k * settings.seconds
        chosen = np.sort(rng.choice(steps, size=keep, replace=False))
        label = np.full(keep, name)
        out["t"].append(offset + chosen * TIMESTEP)
        out["q"].append(q_log[chosen])
        out["labels"].append(label)
        out["tool"].append(tool_log[chosen])
        out["tt"].append(offset + np.arange(0, steps, every) * TIMESTEP)
        out["tq"].append(q_log[::every])
        out["tlabels"].append(np.full(q_log[::every].shape[0], name))
        out["ttool"].append(tool_log[::every])
        coverage[k] = joint_coverage(q_log, true_model.lower, true_model.upper)
        violation[k] = np.linalg.norm(tool_log - (centre if anchor is None else anchor), axis=1).max()
        distance = np.linalg.norm(tool_log - centre, axis=1)
        deviation[k] = distance.max()
        rms[k] = np.sqrt(np.mean(distance**2))
        excess[k] = max(0.0, float(np.max(true_model.lower - q_log)), float(np.max(q_log - true_model.upper)))
    cat = {key: np.concatenate(v) for key, v in out.items()}
    return SelfMotionRun(
        true_model=true_model, nominal_model=nominal_model, fixture_names=names,
        fixture_centres=np.array([fixtures[k] for k in names]).reshape(-1, 3),
        t=cat["t"], q=cat["q"], labels=cat["labels"], tool=cat["tool"],
        trajectory_t=cat["tt"], trajectory_q=cat["tq"], trajectory_labels=cat["tlabels"],
        trajectory_tool=cat["ttool"], coverage=coverage, max_violation=violation, max_deviation=deviation,
        rms_deviation=rms, limit_excess=excess, reach_q=reach, fallbacks=controller.report.fallbacks,
        settings=settings,
    )
