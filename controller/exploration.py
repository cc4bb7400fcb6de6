"""Secondary-task velocities ``q_r`` that drive self-motion: random or coverage-directed.

An exploration is asked for a new ``q_r`` target at decision times; :class:`Ramp` blends
from the current ``q_r`` to the new one with a raised cosine over a few hundred
milliseconds (a step change kicks the tool off the fixture by 0.1 mm or more). The QP then
projects ``q_r`` into the null space of the tool-point task.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .ik import Kinematics, ik

MODES: tuple[str, ...] = ("coverage", "random")
#: Defaults: exploration speed [rad/s], decision periods [s], ramp duration [s], histogram bins.
RANDOM_SPEED = 0.6  # each joint uniform in [-speed, speed]
COVERAGE_SPEED = 1.5  # |q_r| toward a goal
SPEED = COVERAGE_SPEED
RANDOM_PERIOD = 2.0
COVERAGE_PERIOD = 2.0
RAMP_TIME = 0.3
GOAL_STEP = 0.6  # [rad]
GOAL_MARGIN = 0.03  # [rad] goals stay this far inside the limits
GOAL_RESTARTS = 4  # random IK starts when the goal is not found from the current configuration
GOAL_SAME_START = 0.01  # [rad] a goal not found at GOAL_MISSES decisions from within this of one configuration
GOAL_MISSES = 3  # is not sought again from there (a saturated fixture)


#: One turn [rad]: the most of a revolute joint's range the kinematics can tell apart.
TURN = 2 * np.pi


def joint_coverage(q: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Share of each joint's distinct angles visited by a continuous trajectory (the paper's Fig. 5).

    A continuous path visits every angle between its extremes. Every joint spherecal models is revolute (the URDF
    reader refuses prismatic ones), so ``q_j`` and ``q_j + 2 pi`` put every link in the same place: a joint limited to
    +-2 pi (a UR's) has one turn of distinct poses, and a sweep of one turn has seen them all. So::

        coverage_j = min(max q_j - min q_j, 2 pi) / min(upper_j - lower_j, 2 pi)

    the share of the range for a joint of one turn or less (a Panda's, a UR's elbow). A UR trial's q1 swept through a
    full turn read 50 % against the whole range.

    Args:
        q: (K, n) joint angles [rad] (K >= 1; a (n,) configuration reads as K = 1).
        lower, upper: (n,) limits [rad].

    Returns:
        (n,) shares, 1 for a full turn or the whole range (0 for a joint without range); samples past the limits
        (the samples reader lets a reading through a little beyond them) can read a little above 1.
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    return range_share(q.min(axis=0), q.max(axis=0), np.asarray(lower, dtype=float), np.asarray(upper, dtype=float))


def range_share(low: np.ndarray, high: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """(n,) ``min(high - low, 2 pi) / min(upper - lower, 2 pi)``, 0 for a joint without range: :func:`joint_coverage`
    of a trajectory with extremes ``low``, ``high`` (n,) [rad] between the limits ``lower``, ``upper`` (n,) [rad]."""
    span = np.minimum(upper - lower, TURN)
    return np.divide(np.minimum(high - low, TURN), span, out=np.zeros(span.shape), where=span > 0)


class RunningExtent:
    """Smallest and largest value of each joint over a history that only grows, kept as it grows.

    :meth:`update` reads only the rows appended since its last call: the time of a decision does not grow
    with the length of the recording. The last row of each call is read again at the next (the caller
    may still overwrite the row it is filling); the extremes are those of the whole history, exactly.
    """

    def __init__(self, n: int):
        self._restart(n)

    def _restart(self, n: int) -> None:
        self.lower, self.upper = np.full(n, np.inf), np.full(n, -np.inf)  # of the rows before ``count``
        self.count = 0

    def update(self, history: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n,) smallest and (n,) largest value of each column of ``history`` (K, n), K >= 1.

        ``history`` is the one of the last call with rows appended; a shorter one starts over.
        """
        if history.shape[0] <= self.count:
            self._restart(history.shape[1])
        done = history.shape[0] - 1
        if done > self.count:
            settled = history[self.count:done]
            self.lower = np.minimum(self.lower, settled.min(axis=0))
            self.upper = np.maximum(self.upper, settled.max(axis=0))
            self.count = done
        last = history[done]
        return np.minimum(self.lower, last), np.maximum(self.upper, last)


@dataclass
class Ramp:
    """Raised-cosine blend of ``q_r`` from ``start`` to ``end`` over ``duration`` seconds."""

    n: int
    duration: float = RAMP_TIME
    start: np.ndarray = field(init=False)
    end: np.ndarray = field(init=False)  # the last value returned
    t0: float = 0.0

    def __post_init__(self) -> None:
        self.start = np.zeros(self.n)
        self.end = np.zeros(self.n)

    def retarget(self, t: float) -> None:
        """Start a new blend at time ``t`` [s] from the last value returned."""
        self.start = self.end.copy()
        self.t0 = t

    def __call__(self, t: float, command: np.ndarray) -> np.ndarray:
        """(n,) ``q_r`` at time ``t`` [s]: from the frozen start toward the live ``command`` (n,)."""
        s = (t - self.t0) / self.duration
        if s >= 1.0:
            self.end = command
        else:
            w = 0.5 - 0.5 * np.cos(np.pi * max(s, 0.0))
            self.end = self.start + w * (command - self.start)
        return self.end


class RandomExploration:
    """The paper's: uniformly random joint velocities, renewed every ``period`` seconds."""

    def __init__(self, n: int, rng: np.random.Generator, speed: float = SPEED, period: float = RANDOM_PERIOD):
        self.n, self.rng, self.speed, self.period = n, rng, speed, period
        self._q_r = np.zeros(n)

    def decide(self, t: float, q_history: np.ndarray, jac: np.ndarray) -> None:
        """Draw new joint velocities in ``[-speed, speed]`` (the arguments are unused)."""
        self._q_r = self.rng.uniform(-self.speed, self.speed, self.n)

    def done(self, q: np.ndarray) -> bool:
        """Never early: decisions come every ``period``."""
        return False

    def command(self, q: np.ndarray) -> np.ndarray:
        """(n,) the current random ``q_r`` [rad/s]."""
        return self._q_r


@dataclass(frozen=True)
class _Miss:
    """A goal not found: where it was last sought (n,) [rad], at which decision, at how many decisions near there."""

    q: np.ndarray
    decision: int
    misses: int


class CoverageExploration:
    """Steer toward the least-visited part of the least-covered joint's range.

    At each decision the joint ``j`` with the smallest coverage (skipping joints whose last
    goal could not be found or reached) gets a goal value just past the visited part of its
    range, on the side with more unvisited range. A goal configuration with ``q_j`` at that
    value is found on the self-motion manifold by IK on the controller's model with joint
    ``j`` pinned, started at the current configuration; ``q_r`` then points from ``q`` to that
    configuration (the QP keeps only its null-space part). A new decision is taken when the
    goal is reached or after ``period`` seconds.

    Args:
        model: the controller's model (nominal).
        target: (3,) fixture centre [m] (where the controller's model believes the tool is).
        rng: seeded generator.
        speed: ``|q_r|`` far from the goal [rad/s].
        period: longest time spent on one goal [s].
        step: how far past the visited range a goal is set [rad].
        kinematics: the model's tool point and Jacobian computed elsewhere (see :func:`controller.ik.ik`;
            the controller's MuJoCo kinematics: a few microseconds per configuration), or None.
    """

    def __init__(self, model, target: np.ndarray, rng: np.random.Generator, speed: float = SPEED,
                 period: float = COVERAGE_PERIOD, step: float = GOAL_STEP, kinematics: Kinematics | None = None):
        self.model, self.target, self.rng = model, np.asarray(target, float), rng
        self.kinematics = kinematics
        margin = np.minimum(GOAL_MARGIN, 0.5 * (model.upper - model.lower))  # a locked joint: its value
        self.lower, self.upper = model.lower + margin, model.upper - margin
        self.n = self.lower.size
        self.speed, self.period, self.step = speed, period, step
        self.goal: np.ndarray | None = None
        self._tabu = np.zeros(self.n)
        self._joint = -1
        self._extent = RunningExtent(self.n)
        self._missed: dict[tuple[int, float], _Miss] = {}  # (j, value) not found
        self._decisions = 0

    def _find_goal(self, q: np.ndarray, j: int, value: float) -> np.ndarray | None:
        """(n,) a configuration on the self-motion manifold with ``q_j = value``, near ``q``, or None.

        A goal not found at :data:`GOAL_MISSES` decisions from within :data:`GOAL_SAME_START` of one
        configuration is not sought again from there: None at once, with the restarts the search would have
        drawn drawn from ``rng`` all the same (the random stream, hence the samples kept and the next fixture,
        stay those of a failed search). At a saturated fixture no goal is found, the arm stands still and the
        same searches failed at every check (every 50 ms): most of a long simulation's time. A judgement, not a
        proof: the search's random restarts might still find the goal (none did in the runs checked: their
        samples are those of the searches made). Within one decision a goal is sought again (a goal at the limit
        is the same for every step): a restart found one there.
        """
        lower, upper = self.lower.copy(), self.upper.copy()
        lower[j] = upper[j] = value
        pinned = replace(self.model, lower=lower, upper=upper)
        key = (int(j), float(value))
        missed = self._missed.get(key)
        near = missed is not None and float(np.max(np.abs(q - missed.q))) < GOAL_SAME_START
        if near and missed.misses >= GOAL_MISSES and missed.decision < self._decisions:
            pinned.random_configurations(GOAL_RESTARTS, self.rng)  # what the failed search drew
            return None
        start = q.copy()
        start[j] = value
        result = ik(pinned, self.target, start, max_iter=50, restarts=GOAL_RESTARTS, rng=self.rng,
                    kinematics=self.kinematics, lockstep=self.kinematics is not None)
        if result.converged:
            self._missed.pop(key, None)
            return result.q
        misses = missed.misses + int(missed.decision < self._decisions) if near else 1
        self._missed[key] = _Miss(q.copy(), self._decisions, misses)
        return None

    def decide(self, t: float, q_history: np.ndarray, jac: np.ndarray) -> None:
        """Choose the next goal.

        Args:
            t: time [s].
            q_history: (K, n) every joint reading of this fixture so far (K >= 1): the history of the last
                call with rows appended (only the new rows and the last one are read; see :class:`RunningExtent`).
            jac: (3, n) the controller's Jacobian at the current configuration (unused).
        """
        self._decisions += 1
        q = q_history[-1]
        if self.goal is not None and np.linalg.norm(self.goal - q) > 0.1:
            self._tabu[self._joint] = 2  # not reached in time: try others first
        lo, hi = self._extent.update(q_history)
        coverage = range_share(lo, hi, self.lower, self.upper)
        self.goal = None
        for j in np.argsort(coverage + 10.0 * (self._tabu > 0)):
            below, above = lo[j] - self.lower[j], self.upper[j] - hi[j]
            sides = [(-1.0, below), (1.0, above)]
            sides.sort(key=lambda s: -s[1])
            for direction, room in sides:
                if room < 0.02:
                    continue
                for step in (self.step, 0.5 * self.step, 0.25 * self.step):
                    value = (lo[j] - min(step, room)) if direction < 0 else (hi[j] + min(step, room))
                    goal = self._find_goal(q, j, value)
                    if goal is not None:
                        self.goal, self._joint = goal, int(j)
                        break
                if self.goal is not None:
                    break
            if self.goal is not None:
                break
            self._tabu[j] = 2
        self._tabu = np.maximum(self._tabu - 1, 0)

    def done(self, q: np.ndarray) -> bool:
        """True when the goal is reached (a new decision is due)."""
        return self.goal is None or float(np.linalg.norm(self.goal - q)) < 0.05

    def command(self, q: np.ndarray) -> np.ndarray:
        """(n,) ``q_r`` toward the goal [rad/s]: ``speed`` far away, proportional within 0.3 rad."""
        if self.goal is None:
            return np.zeros(self.n)
        delta = self.goal - q
        return delta * (self.speed / max(float(np.linalg.norm(delta)), 0.3))


def make_exploration(mode: str, model, target: np.ndarray, rng: np.random.Generator, speed: float | None = None,
                     kinematics: Kinematics | None = None):
    """The exploration of ``mode`` (``"coverage"`` or ``"random"``) for ``model`` at ``target`` (3,) [m]
    (``kinematics``: see :class:`CoverageExploration`)."""
    if mode == "coverage":
        return CoverageExploration(model, target, rng, COVERAGE_SPEED if speed is None else speed,
                                   kinematics=kinematics)
    if mode == "random":
        return RandomExploration(model.n_joints, rng, RANDOM_SPEED if speed is None else speed)
    raise ValueError(f"unknown exploration mode {mode!r}, expected one of {MODES}")
