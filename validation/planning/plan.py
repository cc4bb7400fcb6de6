"""Experiment planning: where to put the fixtures, which distances to measure.

For every candidate fixture position: can the arm's tool point reach it inside the joint limits,
and how much of each joint's range does its self-motion cover there? Then the subset of the
reachable candidates (and of their centre-to-centre distances) that minimises the predicted
calibration error (:func:`identification.prediction.predict_accuracy`).

Two ways to explore a candidate's self-motion (``motion``):

* ``"kinematic"`` (default): random configurations projected onto the candidate on the nominal
  model (:func:`identification.synthetic.fixture_samples`): the whole self-motion manifold inside
  the limits, what a long exploration reaches. About 0.1 s per candidate. An arm of at most
  :data:`BRANCH_JOINTS` joints has no self-motion with the ball held but the tool's turning about it,
  and its configurations there fall into branches (shoulder front or back, elbow up or down, wrist
  flipped) that no such motion joins: a random configuration projected onto the candidate lands in
  any of them, a recording stays in one. Its survey is one hand-guided walk through the self-motion
  from the reach configuration furthest from the joint limits
  (:func:`.hand_guiding.hand_guided`, one walker), as ``simulate`` and a person record (a 1.3 m
  six-joint arm: the whole manifold put 53-100 % of joints 1-3 in reach and predicted 0.036 mm for the
  chosen set, the simulated recording covered 4-13 % and calibrated to 0.270 mm against the truth; one
  walk covers 4-13 % and predicts 0.226 mm).
* ``"controller"``: the null-space controller on the MuJoCo plant for ``seconds`` per candidate
  (:func:`controller.self_motion.collect_self_motion`, nominal plant): what a short real run covers.

A candidate may restrict the self-motion of some joints (``joint_range``: share of each joint's
range, e.g. an obstacle or a fixture that blocks joints 2 and 3): its samples then come from a
window of that width around a well-centred reach configuration.
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import math
import time
from concurrent.futures import Executor
from dataclasses import dataclass, field, replace

import numpy as np

from spherecal.controller.exploration import joint_coverage
from spherecal.controller.reach import UnreachableFixtureError, check_fixture, check_fixture_distance
from spherecal.correction import RobotModel
from spherecal.correction.errors import SpherecalError
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.samples import Dataset
from spherecal.identification.prediction import Prediction, Workspace, predict_accuracy
from spherecal.identification.selfcheck import MIN_SEPARATION
from spherecal.identification.synthetic import fixture_samples

from ..parallel import Outcome, run_tasks
from .candidates import Candidate, CandidateError
from .hand_guiding import hand_guided
from .postures import reach_configuration

MOTIONS: tuple[str, ...] = ("kinematic", "controller")
#: An arm of at most this many joints is surveyed kinematically along one branch of its self-motion (one
#: hand-guided walk), not over the whole manifold (the module docstring).
BRANCH_JOINTS = 6
#: Samples per candidate used for planning (each stands for ``samples / PLAN_SAMPLES`` recorded ones).
PLAN_SAMPLES = 120
#: Exhaustive search over fixture subsets up to this many combinations, greedy above.
EXHAUSTIVE_LIMIT = 300
#: A distance is recommended when it lowers the predicted mean error by more than this share.
DISTANCE_GAIN = 0.05


@dataclass(frozen=True, eq=False)
class Survey:
    """What the arm can do at one candidate.

    Attributes:
        candidate: the candidate.
        reachable: whether the tool point reaches it inside the joint limits.
        reason: why not (one line), or ``""``.
        q: (K, n) self-motion samples [rad] (empty when unreachable).
        coverage: (n,) share of each joint's range covered by the samples, a range longer than a turn counted
            as one turn (:func:`spherecal.controller.exploration.joint_coverage`; zeros when unreachable).
        alone: predicted accuracy of this candidate alone (None when unreachable or unidentifiable).
    """

    candidate: Candidate
    reachable: bool
    reason: str
    q: np.ndarray
    coverage: np.ndarray
    alone: Prediction | None = None


@dataclass(frozen=True, eq=False)
class FixtureSet:
    """A scored set of fixtures.

    Attributes:
        names: candidate names.
        distances: measured centre-to-centre distances, as name pairs.
        prediction: predicted accuracy with those distances.
        without_distances: predicted accuracy with no distance measured (None for one fixture).
    """

    names: tuple[str, ...]
    distances: tuple[tuple[str, str], ...]
    prediction: Prediction
    without_distances: Prediction | None = None


@dataclass(frozen=True, eq=False)
class Plan:
    """The outcome of :func:`plan`.

    Attributes:
        surveys: one per candidate, in input order (unreachable ones included).
        best: the chosen fixture set.
        search: ``"exhaustive"`` or ``"greedy"``.
        motion, noise, samples: the settings planned for.
        seconds: wall time per stage [s].
        workers: worker -> its package versions (the survey's tasks; for the provenance).
    """

    surveys: list[Survey]
    best: FixtureSet | None
    search: str
    motion: str
    noise: float
    samples: int
    seconds: dict[str, float] = field(default_factory=dict)
    workers: dict[str, dict[str, str]] = field(default_factory=dict)

    def ranked(self) -> list[Survey]:
        """Reachable candidates by predicted error alone (best first), then the unreachable ones."""
        scored = [s for s in self.surveys if s.alone is not None]
        rest = [s for s in self.surveys if s.alone is None]
        return sorted(scored, key=lambda s: s.alone.mean) + rest


# --------------------------------------------------------------------------------------- survey
def restricted(model: RobotModel, q0: np.ndarray, joint_range: np.ndarray) -> RobotModel:
    """The model with each joint's limits narrowed to ``joint_range`` of its range around ``q0``
    (the window is shifted to stay inside the original limits)."""
    width = np.asarray(joint_range) * (model.upper - model.lower)
    lower = np.clip(q0 - width / 2, model.lower, model.upper - width)
    return replace(model, lower=lower, upper=lower + width)


def motion_samples(
    model: RobotModel,
    candidate: Candidate,
    count: int,
    rng: np.random.Generator,
    motion: str = "kinematic",
    seconds: float = 3.0,
    noise: float = 0.0,
    truth: RobotModel | None = None,
) -> np.ndarray:
    """(count, n) self-motion samples at a candidate (see the module docstring for ``motion``).

    Args:
        model: the nominal robot (reach and, with ``motion="controller"``, the controller's model).
        candidate: where, and the allowed share of each joint's range.
        count: samples.
        rng: seeded generator.
        motion: ``"kinematic"`` or ``"controller"``.
        seconds: controller run per candidate [s].
        noise: fixture noise per coordinate [m] (moves the physical point, not the joints).
        truth: the robot the samples are taken on (default ``model``).

    Raises:
        FixtureInsideRobotError, UnreachableFixtureError: the candidate cannot be used (one the user gave
            (:attr:`.candidates.Candidate.source`) farther than the arm reaches in any posture: before any IK).
    """
    truth = model if truth is None else truth
    centre = candidate.position
    if candidate.source:  # the user's: beyond any posture's reach is said so (millimetres?), not as an IK miss
        check_fixture_distance(model, candidate.name, centre)
    check_fixture(model, candidate.name, centre)
    if candidate.joint_range is not None:
        window = candidate.joint_range
        truth = restricted(truth, reach_configuration(truth, centre, rng), window)
        model = replace(model, lower=truth.lower, upper=truth.upper)
    if motion == "controller":
        # MuJoCo: only the controller's self-motion needs it (start-up)
        from spherecal.controller.self_motion import SelfMotionSettings, collect_self_motion

        settings = SelfMotionSettings(seconds=seconds, samples=count, noise=noise)
        return collect_self_motion(truth, model, {candidate.name: centre}, rng, settings).q
    if motion != "kinematic":
        raise ValueError(f"unknown motion {motion!r}, expected one of {MOTIONS}")
    named = f"{candidate.located}: " if candidate.located else ""  # a candidates file's: its file, row and field
    unreachable = UnreachableFixtureError(
        f"{named}fixture {candidate.name} at {np.round(centre, 4).tolist()} m is out of reach inside the joint limits")
    if one_branch(truth.n_joints):
        q, reached = hand_guided(truth, centre[None], count, rng, walkers=1, noise=noise)
        if not reached[0]:
            raise unreachable
        return q[0]
    try:
        return fixture_samples(truth, centre, count, rng, noise, max_rounds=3)
    except ValueError:
        raise unreachable from None


def one_branch(n_joints: int) -> bool:
    """Whether the kinematic survey of an arm of ``n_joints`` walks one branch of its self-motion
    (:data:`BRANCH_JOINTS`, the module docstring) instead of sampling the whole manifold."""
    return n_joints <= BRANCH_JOINTS


def plan_seed(seed: int | np.random.Generator) -> int:
    """The plan's integer seed: ``seed`` itself, or one integer drawn from a generator."""
    return int(seed.integers(2**63)) if isinstance(seed, np.random.Generator) else int(seed)


def candidate_rng(seed: int, candidate: Candidate) -> np.random.Generator:
    """The candidate's own generator, from the plan's seed and the candidate's name (not its place in
    the list): candidates are surveyed apart, in any order, on any worker, with the same samples."""
    key = int.from_bytes(hashlib.sha256(candidate.name.encode()).digest()[:8], "little")
    return np.random.default_rng([seed, 1, key])


def survey_candidate(
    model: RobotModel, candidate: Candidate, seed: int, motion: str = "kinematic", seconds: float = 3.0,
    count: int = PLAN_SAMPLES,
) -> Survey:
    """Reach and self-motion coverage at one candidate, drawn from :func:`candidate_rng` (a task)."""
    try:
        q = motion_samples(model, candidate, count, candidate_rng(seed, candidate), motion, seconds)
    except SpherecalError as error:
        return Survey(candidate, False, str(error), np.zeros((0, model.n_joints)), np.zeros(model.n_joints))
    return Survey(candidate, True, "", q, joint_coverage(q, model.lower, model.upper))


def survey(
    model: RobotModel,
    candidates: list[Candidate],
    seed: int | np.random.Generator,
    motion: str = "kinematic",
    seconds: float = 3.0,
    count: int = PLAN_SAMPLES,
    executor: Executor | None = None,
) -> list[Survey]:
    """Reach and self-motion coverage at every candidate (unreachable ones kept, with the reason), each
    candidate a task on ``executor`` (None: in this process) seeded by :func:`candidate_rng`; a task
    that crashed is reported (TaskFailedWarning) and kept as unreachable, its ``reason`` naming the error."""
    return _surveyed(model, candidates, plan_seed(seed), motion, seconds, count, executor)[0]


def _surveyed(model, candidates, seed, motion, seconds, count, executor) -> tuple[list[Survey], Outcome]:
    task = functools.partial(survey_candidate, model, seed=seed, motion=motion, seconds=seconds, count=count)
    outcome = run_tasks(task, candidates, executor, [c.name for c in candidates])
    failed = {f.name: f.error for f in outcome.failures}
    empty = np.zeros((0, model.n_joints)), np.zeros(model.n_joints)
    surveys = [s if s is not None else Survey(c, False, f"failed: {failed[c.name]}", *empty)
               for c, s in zip(candidates, outcome.results, strict=True)]
    return surveys, outcome


# -------------------------------------------------------------------------------------- scoring
def dataset_of(surveys: list[Survey]) -> Dataset:
    """The samples of several surveyed candidates as one data set."""
    names = tuple(s.candidate.name for s in surveys)
    labels = np.concatenate([np.full(len(s.q), s.candidate.name) for s in surveys])
    return Dataset(labels=labels, q=np.concatenate([s.q for s in surveys]), fixture_names=names)


def score(
    model: RobotModel,
    surveys: list[Survey],
    distances: tuple[tuple[str, str], ...],
    noise: float,
    samples: int,
    workspace: Workspace,
) -> Prediction:
    """Predicted accuracy of the surveyed candidates with those distances measured, for ``samples``
    recorded samples per fixture (each planning sample stands for ``samples / K`` of them)."""
    position = {s.candidate.name: s.candidate.position for s in surveys}
    spec = FixtureSpec(
        names=tuple(position),
        distances=[(a, b, float(np.linalg.norm(position[a] - position[b]))) for a, b in distances],
    )
    weight = samples / min(len(s.q) for s in surveys)
    return predict_accuracy(model, dataset_of(surveys), spec, noise=noise, workspace=workspace, sample_weight=weight)


def all_pairs(names: tuple[str, ...]) -> tuple[tuple[str, str], ...]:
    """Every centre-to-centre pair."""
    return tuple(itertools.combinations(names, 2))


def choose_distances(
    model: RobotModel, surveys: list[Survey], noise: float, samples: int, workspace: Workspace
) -> FixtureSet:
    """The fewest distances (greedy) whose predicted error is within :data:`DISTANCE_GAIN` of all of them."""
    names = tuple(s.candidate.name for s in surveys)
    none = score(model, surveys, (), noise, samples, workspace) if len(names) > 1 else None
    every = all_pairs(names)
    full = score(model, surveys, every, noise, samples, workspace)
    if len(every) <= 1:
        return FixtureSet(names, every, full, none)
    chosen: tuple[tuple[str, str], ...] = ()
    current = none
    while current.mean > (1 + DISTANCE_GAIN) * full.mean and len(chosen) < len(every):
        options = [
            (score(model, surveys, chosen + (p,), noise, samples, workspace), p) for p in every if p not in chosen
        ]
        current, pair = min(options, key=lambda o: o[0].mean)
        chosen += (pair,)
    return FixtureSet(names, chosen, current if chosen else none, none)


def plan(
    model: RobotModel,
    candidates: list[Candidate],
    fixtures: int,
    seed: int | np.random.Generator,
    noise: float = 3e-4,
    samples: int = 500,
    motion: str = "kinematic",
    seconds: float = 3.0,
    configurations: int = 1000,
    executor: Executor | None = None,
) -> Plan:
    """Survey the candidates, then choose ``fixtures`` of them (and the distances to measure).

    ``seed`` (or one integer drawn from a generator) seeds each candidate's survey by its name
    (:func:`candidate_rng`) and the workspace by ``(seed, 0)``: the plan is the same whether the
    candidates are surveyed in this process or as tasks on ``executor`` (a process pool, a Dask
    client's executor; :mod:`validation.parallel`). Scoring runs here.

    Subsets are scored with every distance among them known (the best case), exhaustively when
    there are at most :data:`EXHAUSTIVE_LIMIT` of them, else greedily (add the candidate that lowers
    the predicted mean error most); the winner's distances are then thinned by :func:`choose_distances`.

    Raises:
        CandidateError: no candidates, or ``fixtures`` outside 1..4.
    """

    if not candidates:
        raise CandidateError("no candidate fixture positions given")
    if not 1 <= fixtures <= 4:
        raise CandidateError(f"field '--fixture-count': expected an integer in 1..4, got {fixtures}")
    clock = time.perf_counter()
    seed = plan_seed(seed)
    surveys, outcome = _surveyed(model, candidates, seed, motion, seconds, PLAN_SAMPLES, executor)
    seconds_taken = {"survey": time.perf_counter() - clock}
    clock = time.perf_counter()
    workspace = Workspace.of(model, configurations, np.random.default_rng([seed, 0]))
    scored = []
    for s in surveys:
        if s.reachable:
            try:
                s = replace(s, alone=score(model, [s], (), noise, samples, workspace))
            except SpherecalError as error:
                s = replace(s, reason=f"not identifiable alone: {error}")
        scored.append(s)
    usable = [s for s in scored if s.reachable]
    best, search = None, "none"
    if len(usable) >= fixtures:
        best, search = _search(model, usable, fixtures, noise, samples, workspace)
    seconds_taken["score"] = time.perf_counter() - clock
    return Plan(scored, best, search, motion, noise, samples, seconds_taken, outcome.workers)


def _apart(group) -> bool:
    """No two candidates of ``group`` closer than the self-check's :data:`MIN_SEPARATION` (fixtures that close are
    one socket under two names to the calibration, which refuses them)."""
    points = [s.candidate.position for s in group]
    return all(np.linalg.norm(points[i] - points[j]) >= MIN_SEPARATION
               for i in range(len(points)) for j in range(i + 1, len(points)))


def _search(model, usable, fixtures, noise, samples, workspace) -> tuple[FixtureSet, str]:
    """The best ``fixtures`` of the ``usable`` surveys, at least :data:`MIN_SEPARATION` apart (a grid finer than
    that chose three points 5 mm apart, which the calibration refuses).

    Raises:
        CandidateError: no such set.
    """
    def value(group) -> float:
        try:
            names = tuple(s.candidate.name for s in group)
            return score(model, list(group), all_pairs(names), noise, samples, workspace).mean
        except SpherecalError:
            return math.inf

    refusal = CandidateError(f"no {fixtures} of the {len(usable)} reachable candidates lie at least "
                             f"{MIN_SEPARATION * 1e3:.0f} mm apart: fixtures closer than that are one socket under two "
                             "names to the calibration (a coarser --grid, or candidates further apart)")
    if math.comb(len(usable), fixtures) <= EXHAUSTIVE_LIMIT:
        groups = [g for g in itertools.combinations(usable, fixtures) if _apart(g)]
        if not groups:
            raise refusal
        group, search = min(groups, key=value), "exhaustive"
    else:
        ranked = sorted((s for s in usable if s.alone is not None), key=lambda s: s.alone.mean)
        group, search = [ranked[0]] if ranked else [usable[0]], "greedy"
        while len(group) < fixtures:
            options = [s for s in usable if s not in group and _apart([*group, s])]
            if not options:
                raise refusal
            group.append(min(options, key=lambda s: value([*group, s])))
    return choose_distances(model, list(group), noise, samples, workspace), search
