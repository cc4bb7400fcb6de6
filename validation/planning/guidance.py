"""Recording guidance: which plate placement to record next on a real arm, and when to stop.

Start from what has been recorded: calibrate it (:func:`calibrate_recording`: the model choice of
the one calibration workflow, :func:`identification.workflow.run_workflow`, as `calibrate` runs it)
and measure its noise ``sigma``, the residual per axis. Every candidate placement is judged at that
calibration, not at the nominal arm: the configurations a person would record there are added to the
recorded ones with the placement's known distances. Those configurations (:data:`POSTURES`): ``"recorded"``
(default), the postures the person has recorded so far carried over to the candidate's sockets
(:func:`.hand_guiding.carried_over`: each recorded configuration moved onto the socket); ``"walk"``, random
walks through the self-motion from the most comfortable postures (:func:`.hand_guiding.hand_guided`).

Where and how a candidate is judged (:data:`JUDGED_ON`):

* ``"sockets"`` (default): what MUKCa's test MAE and a socket-only `validate` measure, the spread of the
  calibrated tool point at sockets not used for fitting, here the *other* candidates' sockets (the placements the
  user considers: a sample of where the arm is used; all of them for a lone candidate). Per configuration, the
  parameters' error less its mean over the socket (:func:`identification.prediction.predict_accuracy` on
  :func:`sockets_of`, at the sockets' own noise), the arm's unmodelled joint-angle error as the fit leaves it there
  (:func:`identification.prediction.held_out_joint_error`: one realisation over the training and held-out
  configurations, so that what the fit absorbed where it was recorded cancels part of it nearby), and the sockets'
  own noise. As the self-check does (:data:`UNMODELLED` ``"declared"``), the data rows' residual beyond the
  declared noise is that joint-angle error and the socket noise is the smaller of the two; ``"variogram"`` splits
  the residual by :func:`noise_split` instead.
* ``"whole"``: the registered tool-point error over the whole workspace, the configurations of every candidate
  (its own included), parameters as above at ``sigma`` plus an unexplained part, a Gaussian process over joint
  space (squared-exponential kernel of length :data:`LENGTH` [rad]) whose scales :data:`SMOOTH` sets
  (``"variogram"``: ``sigma^2`` split by :func:`noise_split`; ``"residual"``: ``sigma`` for both), its posterior
  variance given the recorded and candidate configurations.
* ``"held-out"``: as ``"whole"`` over the other candidates' configurations only.

``error = sqrt(mean of (parameter error^2 + unexplained^2) + socket noise^2)`` [m] over the configurations a
candidate is judged on (socket noise on sockets only), its gain the recording's error over the same configurations
minus its own; candidates are ranked by the gain (the same set on both sides: choosing a candidate takes it out of
the held-out set, and the recording's error differs between sets).

On MUKCa's real placements (bench/plan_real.py: first placement recorded, the other recorded placements as
candidates at the first calibration's tool point, 5 plan seeds; actual = `spherecal calibrate`'s workflow on
first + candidate, test MAE on the rest, change against the first's calibration on the same sockets), the pick in
the better half of the candidates (with 2 or 3 candidates: the best one), the defaults against ``whole`` with
walks (the defaults before): panda_2_clean 40/40 against 23/40 (mean change of the picks -0.126 mm against
-0.107, random -0.097, best -0.128; Spearman of the plan's order against the change 0.35 against 0.04),
panda_4_clean 5/15 against 8/15 (-0.033 against -0.045, random -0.043: one first's two candidates differ by
0.001 mm, another's order follows which socket is left to test, whose own noise the plan cannot know), dinova_1
15/20 against 8/20 (-1.279 against -0.896, random -0.489). One part at a time (better half, panda_2 / panda_4 /
dinova_1): sockets with walks 22/7/6, held-out with the recorded postures 33/5/9, whole with them 19/10/0,
sockets with the variogram split 35/5/12: the recorded postures and judging where the test measures decide it
together. With the actual outcome by plain least squares (``--actual plain``): 40/40, 10/15, 15/20 against 21/40,
7/15, 8/20, the picks' mean change below a random pick's on every arm. The Gen3 lite's 0.7-2.5 mm residual
(0.3 mm declared) is mostly the joint-angle error (2-7 mrad), which ranks its candidates by how close they lie
to the others in joint space. No constant was fitted to these data.

More recording is not worth it when the best candidate's gain of the calibration's own error (the sockets' noise
left out, ``Judged.own_gain``) is below the larger of ``min_gain`` and the
*noise floor* ``sigma / sqrt(N)`` (the standard error per axis of one socket's mean point at the
measured noise and ``N`` samples per socket): a smaller gain could not be seen by validating on a
new socket.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from spherecal.controller.reach import check_fixture, check_fixture_distance
from spherecal.correction import RobotModel, geometric_part, param_jacobian, tool_point
from spherecal.correction.errors import SpherecalError
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.samples import Dataset
from spherecal.identification.build import build_problem
from spherecal.identification.joint_error import kernel
from spherecal.identification.prediction import (
    Prediction,
    Workspace,
    excess_energy,
    held_out_joint_error,
    joint_error_root,
    predict_accuracy,
    remove_rigid_motion,
)
from spherecal.identification.problem import NOISE, SIGMA_FLOOR, samples_location
from spherecal.identification.selfcheck import MAX_SOCKET_NOISE
from spherecal.identification.selfcheck_result import InconsistentDataError
from spherecal.identification.workflow import WorkflowOptions, run_workflow

from .candidates import CandidateError
from .hand_guiding import carried_over, hand_guided
from .placements import Placement, plate_layout, plate_placements, reachable_grid

#: Default smallest gain worth another placement [m].
MIN_GAIN = 1e-5
#: A parameter is "pinned down" by a candidate when its predicted std falls below this share of
#: the recording's (or it becomes identified at all).
PIN_SHARE = 0.7
#: Most workspace configurations the predictions are evaluated on, and most recorded configurations
#: the unexplained-error part conditions on (a random subset, seeded).
CONFIGURATIONS = 500
#: Correlation length of the unexplained error over joint space [rad] (1 and 2 rank alike on real data).
LENGTH = 1.0
#: Scales of the unexplained error: ``"variogram"`` or ``"residual"`` (see the module docstring).
SMOOTH = "variogram"
#: Where and how a candidate is judged: ``"sockets"`` (the spread at the other candidates' sockets, MUKCa's test
#: MAE, with the arm's unmodelled joint-angle error), ``"whole"`` (the registered error over the whole workspace,
#: its own configurations included) or ``"held-out"`` (the same over the other candidates' configurations); see the
#: module docstring.
JUDGED_ON = "sockets"
#: The arm's unmodelled joint-angle error (judged on sockets): ``"declared"`` (the data rows' residual beyond the
#: declared noise, as the self-check) or ``"variogram"`` (the residual's smooth share, :func:`noise_split`).
UNMODELLED = "declared"
#: Configurations at a candidate: ``"recorded"`` (the recorded postures carried over) or ``"walk"`` (random walks).
POSTURES = "recorded"


@dataclass(frozen=True, eq=False)
class Recorded:
    """The calibration of what has been recorded: where every prediction starts.

    Attributes:
        model: the calibrated robot.
        dataset, spec: the recording and its fixtures.
        noise: measured noise, the residual std per axis [m].
        per_socket: median samples per recorded socket.
        centres: fixture name -> (3,) calibrated centre [m].
        model_choice: ``dh`` or ``elastic`` and why.
        smooth, white: the unexplained error's smooth part and its white noise, std per axis [m] (:data:`SMOOTH`).
        socket_noise: where a ball sits in its socket, std per axis [m]: the smaller of the declared noise and the
            data rows' residual (as the self-check records it).
        joint_error: std of each joint's unmodelled angle error [rad] that leaves the residual beyond the declared
            noise (:func:`identification.prediction.joint_error_root`, as the self-check; 0: none).
    """

    model: RobotModel
    dataset: Dataset
    spec: FixtureSpec
    noise: float
    per_socket: int
    centres: dict[str, np.ndarray]
    model_choice: str
    smooth: float = 0.0
    white: float = 0.0
    socket_noise: float = 0.0
    joint_error: float = 0.0


@dataclass(frozen=True, eq=False)
class Judged:
    """One candidate placement, judged.

    Attributes:
        placement: the candidate.
        reason: why it cannot be recorded (one line), or ``""``.
        q: socket name -> (K, n) configurations a person would record there [rad].
        error: predicted rms tool-point error with it recorded as well [m], over the configurations it is judged on
            (:data:`JUDGED_ON`; the recording so far: over the whole workspace).
        prediction: the parameter part (None when refused).
        unexplained: the unexplained part, rms over the same configurations [m].
        gain: the recording's predicted error over the same configurations minus this one [m].
        pinned: (parameter, std ratio) it pins down, strongest first (ratio 0: newly identified).
        parameters: the parameter part, rms over the same configurations [m].
        squared: (N,) predicted mean squared error at each workspace configuration [m^2] (parameters and
            unexplained part; empty when refused).
        noise: the sockets' own noise in ``error`` and ``gain``, rms over the axes [m] (judged on sockets: the spread
            a validation there measures holds it; 0 otherwise).
        own_gain: the gain of the calibration's own error, the sockets' noise left out [m] (what the stop line weighs;
            ``gain`` when ``noise`` is 0).
    """

    placement: Placement
    reason: str = ""
    q: dict[str, np.ndarray] = field(default_factory=dict)
    error: float = math.inf
    prediction: Prediction | None = None
    unexplained: float = 0.0
    gain: float = 0.0
    pinned: tuple[tuple[str, float], ...] = ()
    parameters: float = 0.0
    squared: np.ndarray = field(default_factory=lambda: np.zeros(0))
    noise: float = 0.0
    own_gain: float = 0.0


@dataclass(frozen=True, eq=False)
class Guidance:
    """The outcome of :func:`rank_placements`.

    Attributes:
        recorded: the calibration of the recording so far.
        baseline: the recording so far, judged like a candidate (its predicted error, no candidate added).
        ranking: the candidates that can be recorded, best (largest predicted gain) first.
        refused: the candidates that cannot, in input order, each with its reason.
        min_gain: the stated threshold [m].
        per_socket: configurations per candidate socket.
        seconds: stage -> wall time [s].
    """

    recorded: Recorded
    baseline: Judged
    ranking: list[Judged]
    refused: list[Judged]
    min_gain: float
    per_socket: int
    seconds: dict[str, float] = field(default_factory=dict)

    @property
    def floor(self) -> float:
        """Noise floor of a gain [m]: the standard error per axis of a socket's mean point."""
        return self.recorded.noise / math.sqrt(self.recorded.per_socket)

    @property
    def worth_it(self) -> bool:
        """Whether the best candidate gains more than the threshold and the noise floor (its calibration's own
        error: the sockets' noise left out)."""
        return bool(self.ranking) and self.ranking[0].own_gain > max(self.min_gain, self.floor)

    def stop_line(self) -> str:
        """One line: record the best candidate next, or stop (and why)."""
        limit = f"the noise floor {self.floor * 1e3:.3g} mm and the threshold {self.min_gain * 1e3:.3g} mm"
        if not self.ranking:
            return "no candidate can be recorded: nothing to add"
        best = self.ranking[0]
        if self.worth_it:
            gain = mm_text(best.own_gain, ".3g")
            return (f"record {best.placement.name} next: its calibration's own error gains {gain} mm (column 'own'), "
                    f"more than {limit}")
        return (f"more recording is not worth it: the best candidate {best.placement.name} gains "
                f"{mm_text(best.own_gain, '.3g')} mm of the calibration's own error (column 'own'), not more than "
                f"{limit}")


def mm_text(value: float, spec: str) -> str:
    """``value`` [m] in millimetres formatted by ``spec`` (``"7.4f"``, ``"+.3f"``, ``".3g"``); a value that rounds to
    zero is printed as zero, never ``-0.000`` (a gain or loss too small to show has no sign)."""
    text = format(value * 1e3, spec)
    return format(0.0, spec) if float(text) == 0 else text


def measured_noise(result) -> float:
    """Residual std per axis [m] of a :class:`CalibrationResult` (``sqrt(|r|^2 / (M - F))``), floored
    at the solver's :data:`SIGMA_FLOOR`."""
    r = result.problem.residuals(result.x)
    dof = max(result.problem.n_residuals - result.problem.n_unknowns, 1)
    return max(float(np.sqrt(r @ r / dof)), SIGMA_FLOOR)


def calibrate_recording(
    nominal: RobotModel,
    dataset: Dataset,
    spec: FixtureSpec | None,
    noise: float = NOISE,
    model: str = "auto",
    seed: int = 0,
) -> Recorded:
    """Calibrate the recording so far (model choice as `calibrate`, no self-check) and measure its noise.

    Args:
        nominal: the robot.
        dataset: (K, n) recorded joint angles [rad] with fixture labels.
        spec: its known distances and positions (None: nothing known).
        noise: expected fixture noise [m] (the fit's robust scale and distance weight).
        model: ``dh``, ``elastic`` or ``auto``.
        seed: seeds the model selection.

    Raises:
        DatasetError, UnidentifiableError, ImplausibleCalibrationError: the recording cannot be calibrated.
        InconsistentDataError: it leaves more than the self-check's :data:`.selfcheck.MAX_SOCKET_NOISE` per axis (a
            recording of 10 slipped samples: 23.8 mm; the plan ranked candidates on it and said 'not worth it').
    """
    spec = FixtureSpec.unknown(dataset.fixture_names) if spec is None else spec
    # The one calibration workflow, as `calibrate` runs it (prior, model choice); force: the plan judges
    # the recording by its measured noise, it does not refuse it.
    done = run_workflow(nominal, dataset, spec, WorkflowOptions(model=model, noise=noise, seed=seed, dedup_tol=None,
                                                                 force=True))
    result, selection = done.result, done.selection
    sigma = measured_noise(result)
    residuals = tool_point(result.model, dataset.q) - np.array([result.centres[n] for n in dataset.labels])
    # as the self-check: the data rows' residual beyond the declared noise is the arm's own unmodelled error
    unknowns = result.problem.n_unknowns if result.effective_unknowns is None else result.effective_unknowns
    shown = result.problem.data_sigma(result.x, unknowns)
    if shown > MAX_SOCKET_NOISE:  # the self-check's bar: beyond it no model describes the arm, no gain means anything
        raise InconsistentDataError(
            f"{samples_location(dataset)}: the recording so far leaves {shown * 1e3:.3g} mm per axis after calibration "
            f"(a ball held in a socket stays within {MAX_SOCKET_NOISE * 1e3:.0f} mm): no candidate can be judged on it "
            "(spherecal calibrate on it says why)")
    dof = max(result.problem.n_data - unknowns, 0.0)
    if UNMODELLED == "variogram":
        share = noise_split(residuals, dataset.q, dataset.labels)
        excess, socket = shown * math.sqrt(share * dof), shown * math.sqrt(1.0 - share)
    else:
        excess, socket = excess_energy(shown, noise, dof), min(shown, noise)
    joint_error, _ = joint_error_root(result.problem.model, result.problem, noise, excess)
    return Recorded(
        model=result.model,
        dataset=dataset,
        spec=spec,
        noise=sigma,
        per_socket=int(np.median(list(dataset.counts().values()))),
        centres=result.centres,
        model_choice=f"{selection.chosen} ({selection.reason})",
        **_scales(sigma, residuals, dataset),
        socket_noise=max(socket, SIGMA_FLOOR),
        joint_error=joint_error,
    )


def _scales(sigma: float, residuals: np.ndarray, dataset: Dataset) -> dict[str, float]:
    if SMOOTH == "residual":
        return {"smooth": sigma, "white": sigma}
    share = noise_split(residuals, dataset.q, dataset.labels)
    return {"smooth": sigma * math.sqrt(share), "white": sigma * math.sqrt(1.0 - share)}


def noise_split(residuals: np.ndarray, q: np.ndarray, labels: np.ndarray, length: float = LENGTH) -> float:
    """Share of the residual variance that is a smooth error of the configuration (0: white, 1: all smooth).

    Within each socket, every pair's semivariance per axis ``|r_i - r_j|^2 / 6`` is fitted by
    ``white + smooth (1 - exp(-|q_i - q_j|^2 / (2 length^2)))`` (least squares, both >= 0).

    Args:
        residuals: (K, 3) tool point minus its socket's centre [m].
        q: (K, n) configurations [rad].
        labels: (K,) socket of each sample.
        length: correlation length [rad].
    """
    g, f = [], []
    for name in np.unique(labels):
        mine = labels == name
        r, c = residuals[mine], q[mine]
        i, j = np.triu_indices(len(r), 1)
        g.append(((r[i] - r[j]) ** 2).sum(axis=1) / 6.0)
        f.append(1.0 - np.exp(-((c[i] - c[j]) ** 2).sum(axis=1) / (2.0 * length**2)))
    g, f = np.concatenate(g), np.concatenate(f)
    if g.size < 3 or np.ptp(f) == 0:
        return 0.0
    (white, smooth), *_ = np.linalg.lstsq(np.stack([np.ones_like(f), f], axis=1), g, rcond=None)
    if smooth <= 0:
        return 0.0
    if white <= 0:
        return 1.0
    return float(smooth / (smooth + white))


def pinned_down(before: Prediction, after: Prediction, share: float = PIN_SHARE) -> tuple[tuple[str, float], ...]:
    """(parameter, std after / std before) of the parameters ``after`` determines much better, strongest first;
    a parameter ``before`` did not identify has ratio 0."""
    out = []
    for name, std in after.std.items():
        old = before.std.get(name)
        if old is None:
            out.append((name, 0.0))
        elif old > 0 and std < share * old:
            out.append((name, std / old))
    return tuple(sorted(out, key=lambda item: item[1]))


def workspace_of(model: RobotModel, q: np.ndarray) -> Workspace:
    """The workspace at configurations ``q`` (N, n) [rad], rigid motions of their tool points removed."""
    jac, points = param_jacobian(model, q, return_point=True)
    return Workspace(q=q, sensitivity=remove_rigid_motion(jac.reshape(3 * len(q), -1), points))


def sockets_of(model: RobotModel, q: np.ndarray, labels: np.ndarray) -> Workspace:
    """The sockets at configurations ``q`` (N, n) [rad] of sockets ``labels`` (N,): each socket's mean tool-point
    shift removed (what its spread, MUKCa's MAE, does not see; a rigid motion of the whole shifts a socket's
    points alike, so it goes too)."""
    jac = param_jacobian(model, q)  # (N, 3, P)
    names, index = np.unique(labels, return_inverse=True)
    mean = np.zeros((len(names), *jac.shape[1:]))
    np.add.at(mean, index, jac)
    jac = jac - (mean / np.bincount(index, minlength=len(names))[:, None, None])[index]
    return Workspace(q=q, sensitivity=jac.reshape(3 * len(q), -1))


def unexplained_variance(
    observed: np.ndarray, at: np.ndarray, smooth: float, white: float, length: float = LENGTH
) -> np.ndarray:
    """(M,) posterior variance per axis [m^2] at each configuration of ``at`` (M, n) of the unexplained error, a
    Gaussian process over joint space (prior std ``smooth`` [m], squared-exponential kernel of ``length`` [rad])
    observed at ``observed`` (K, n) [rad] through white noise of std ``white`` [m]."""
    if smooth <= 0:
        return np.zeros(len(at))
    cross = kernel(at, observed, length)
    gram = kernel(observed, observed, length) + max((white / smooth) ** 2, 1e-6) * np.eye(len(observed))
    return smooth**2 * (1.0 - np.einsum("ij,ji->i", cross, np.linalg.solve(gram, cross.T)))


def judge(
    recorded: Recorded, placement: Placement, q: dict[str, np.ndarray], workspace: Workspace, observed: np.ndarray,
    sockets: np.ndarray | None = None,
) -> Judged:
    """Predicted error of the recording plus ``placement``'s configurations ``q`` (socket -> (K, n) [rad]) over
    the whole ``workspace`` (:func:`judged_over` restricts it); ``observed`` (K, n): the recorded configurations
    the unexplained part conditions on. With ``sockets`` (N,), the socket of each workspace configuration
    (:func:`sockets_of`): the spread there, at the socket noise, with the arm's unmodelled joint-angle error
    (:func:`identification.prediction.held_out_joint_error`) instead of the Gaussian process over tool points."""
    data, spec = recorded.dataset, recorded.spec
    names = tuple(placement.sockets)
    added = [q[s] for s in names]
    labels = np.concatenate([data.labels.astype(str), np.repeat(np.array(names, dtype=str), [len(a) for a in added])])
    dataset = Dataset(labels=labels, q=np.concatenate([data.q, *added]), fixture_names=data.fixture_names + names,
                      source=data.source)
    both = FixtureSpec(names=spec.names + names, positions=spec.positions,
                       distances=list(spec.distances) + list(placement.distances), source=spec.source)
    noise = recorded.noise if sockets is None else recorded.socket_noise
    try:
        problem = build_problem(recorded.model, dataset, both, noise=max(noise, SIGMA_FLOOR))
        prediction = predict_accuracy(recorded.model, dataset, both, noise=noise, workspace=workspace, problem=problem)
    except SpherecalError as error:
        return Judged(placement, f"candidate {placement.name}: {str(error).splitlines()[0]}", q)
    if sockets is None:
        variance = 3.0 * unexplained_variance(np.concatenate([observed, *added]), workspace.q, recorded.smooth,
                                              recorded.white)
    else:
        variance = held_out_joint_error(recorded.model, problem, noise, recorded.joint_error, workspace.q, sockets)
    parameters = np.mean(prediction.errors**2, axis=1)
    socket = 0.0 if sockets is None else math.sqrt(3.0) * noise
    return Judged(placement, "", q, math.sqrt(np.mean(parameters + variance) + socket**2), prediction,
                  math.sqrt(np.mean(variance)), parameters=prediction.rms, squared=parameters + variance, noise=socket)


def judged_over(judged: Judged, before: Judged, mask: np.ndarray) -> Judged:
    """``judged`` over the workspace configurations ``mask`` (N,) bool only, its gain against ``before``
    (the recording so far) over the same configurations (with the sockets' noise, and without: ``own_gain``)."""
    own, was = math.sqrt(np.mean(judged.squared[mask])), math.sqrt(np.mean(before.squared[mask]))
    error = math.sqrt(own**2 + judged.noise**2)
    parameters = math.sqrt(np.mean(np.mean(judged.prediction.errors[mask] ** 2, axis=1)))
    unexplained = math.sqrt(max(own**2 - parameters**2, 0.0))
    return replace(judged, error=error, parameters=parameters, unexplained=unexplained,
                   gain=math.sqrt(was**2 + judged.noise**2) - error, own_gain=was - own)


def rank_placements(
    recorded: Recorded,
    placements: list[Placement],
    rng: np.random.Generator,
    per_socket: int | None = None,
    min_gain: float = MIN_GAIN,
) -> Guidance:
    """Rank candidate placements by the error the calibration would reach with each recorded as well.

    Args:
        recorded: the calibration of the recording so far (:func:`calibrate_recording`).
        placements: the candidates.
        rng: seeds the hand-guided configurations and the workspace subset.
        per_socket: configurations per candidate socket (default: as many as recorded per socket).
        min_gain: smallest gain worth another placement [m].

    Raises:
        CandidateError: no candidates, none reachable, or a candidate socket named like a recorded fixture.
        UnidentifiableError: the recording so far cannot be predicted.
    """
    if not placements:
        raise CandidateError("no candidate placements given")
    given = list(placements)
    taken = set(recorded.dataset.fixture_names)
    for p in placements:
        clash = taken & set(p.sockets)
        if clash:
            name = sorted(clash)[0]
            where = f"{p.source}: field 'candidates.{p.name}.sockets.{name}': " if p.source else f"candidate {p.name}: "
            raise CandidateError(f"{where}socket {name!r} is a recorded fixture's name (name it differently)")
    per_socket = recorded.per_socket if per_socket is None else per_socket
    clock = time.perf_counter()
    inside, kept = [], []
    for p in placements:
        try:
            for socket, centre in p.sockets.items():
                if p.source:  # from the user's file: beyond any posture's reach is said so (millimetres?)
                    check_fixture_distance(recorded.model, socket, centre)
                check_fixture(recorded.model, socket, centre)
            kept.append(p)
        except SpherecalError as error:
            inside.append(Judged(p, f"candidate {p.name}: {error}"))
    placements = kept
    if not placements:
        raise CandidateError(f"no candidate can be recorded: {inside[0].reason}")
    centres = np.array([c for p in placements for c in p.sockets.values()])
    # Walked on the calibration's geometric part: an elastic model's gravity torques (and their finite
    # differences in every joint Jacobian) made this stage 10-15x slower for a sub-millimetre shift of where
    # the walk lands, which the prediction (parameter Jacobians at these configurations) does not need.
    if POSTURES == "recorded":
        q, reachable = carried_over(geometric_part(recorded.model), centres, recorded.dataset.q, per_socket, rng)
    else:
        q, reachable = hand_guided(geometric_part(recorded.model), centres, per_socket, rng)
    seconds = {"configurations": time.perf_counter() - clock}
    clock = time.perf_counter()
    configurations, refused, k = {}, inside, 0
    for p in placements:
        names = list(p.sockets)
        ok = reachable[k : k + len(names)]
        if ok.all():
            configurations[p.name] = {name: q[k + i] for i, name in enumerate(names)}
        else:
            socket = names[int(np.argmin(ok))]
            where = np.round(p.sockets[socket], 4).tolist()
            named = p.located.get(socket) or f"candidate {p.name}"  # a candidates file's: its file, row and field
            refused.append(Judged(p, f"{named}: socket {socket} at {where} m is out of reach inside the joint limits"))
        k += len(names)
    if not configurations:
        raise CandidateError(f"no candidate can be recorded: {refused[0].reason}")
    everything = np.concatenate([a for c in configurations.values() for a in c.values()])
    owners = np.concatenate([np.full(sum(map(len, c.values())), i) for i, c in enumerate(configurations.values())])
    labels = np.concatenate([np.repeat(np.array(list(c), dtype=str), [len(a) for a in c.values()])
                             for c in configurations.values()])
    chosen = _subset_rows(len(everything), rng)
    owners, labels = owners[chosen], labels[chosen]
    if JUDGED_ON == "sockets":
        workspace = sockets_of(recorded.model, everything[chosen], labels)
    else:
        workspace, labels = workspace_of(recorded.model, everything[chosen]), None
    observed = _subset(recorded.dataset.q, rng)
    none = Placement("recorded so far", {})
    baseline = judge(recorded, none, {}, workspace, observed, labels)
    if baseline.reason:
        raise CandidateError(f"the recording so far cannot be predicted: {baseline.reason}")
    judged = []
    for p in placements:
        if p.name in configurations:
            j = judge(recorded, p, configurations[p.name], workspace, observed, labels)
            if j.prediction is not None:
                # held out: the workspace without the candidate's own configurations (all of it for a lone candidate)
                mine = owners == list(configurations).index(p.name)
                keep = ~mine if JUDGED_ON != "whole" and not mine.all() else np.ones_like(mine)
                j = replace(judged_over(j, baseline, keep),
                            pinned=pinned_down(baseline.prediction, j.prediction))
            (judged if not j.reason else refused).append(j)
    seconds["prediction"] = time.perf_counter() - clock
    if not judged:  # every candidate refused: nothing was ranked, which is no advice (was exit 0, 'nothing to add')
        raise CandidateError(f"no candidate can be recorded: {refused[0].reason}")
    ranking = sorted(judged, key=lambda j: -j.gain)
    order = {p.name: i for i, p in enumerate(given)}
    refused.sort(key=lambda j: order[j.placement.name])
    return Guidance(recorded, baseline, ranking, refused, min_gain, per_socket, seconds)


def _subset_rows(count: int, rng: np.random.Generator, most: int = CONFIGURATIONS) -> np.ndarray:
    """Indices of at most ``most`` of ``count`` rows, a random subset (seeded), in order."""
    return np.arange(count) if count <= most else np.sort(rng.choice(count, most, replace=False))


def _subset(q: np.ndarray, rng: np.random.Generator, most: int = CONFIGURATIONS) -> np.ndarray:
    """At most ``most`` rows of ``q``, a random subset (seeded)."""
    return q[_subset_rows(len(q), rng, most)]


def recording_guidance(
    nominal: RobotModel,
    dataset: Dataset,
    spec: FixtureSpec | None,
    rng: np.random.Generator,
    candidates: list[Placement] | None = None,
    plate_grid: str | None = None,
    orientations: int = 2,
    per_socket: int | None = None,
    min_gain: float = MIN_GAIN,
    noise: float = NOISE,
    model: str = "auto",
) -> Guidance:
    """What to record next: calibrate the recording so far, then rank the candidates (given ones, and the
    recorded plate placed over ``plate_grid`` in ``orientations`` turns, see :func:`.placements.plate_placements`).

    Args:
        nominal: the robot.
        dataset, spec: the recording so far and its fixtures.
        rng: seeds everything random (model selection folds, hand-guided configurations, workspace subset).
        candidates: candidate placements.
        plate_grid: ``"xmin,xmax,nx;ymin,ymax,ny;zmin,zmax,nz"`` [m] of plate centres, ``"auto"`` (5 x 5 over
            the reach at the recorded plate's height on its side of the base, :func:`.placements.reachable_grid`),
            or None.
        orientations: turns of the plate per grid point.
        per_socket: configurations per candidate socket (default: as recorded).
        min_gain: smallest gain worth another placement [m].
        noise: expected fixture noise of the fit [m].
        model: ``dh``, ``elastic`` or ``auto`` (as `calibrate`).

    Raises:
        CandidateError: no candidates, or none that can be recorded; SpherecalError: the recording cannot be
            calibrated.
    """
    clock = time.perf_counter()
    recorded = calibrate_recording(nominal, dataset, spec, noise, model, seed=int(rng.integers(2**31)))
    calibrated = time.perf_counter() - clock
    placements = list(candidates or [])
    if plate_grid is not None:
        layout = plate_layout(recorded.spec, recorded.centres)
        if plate_grid == "auto":
            centre = np.mean([recorded.centres[n] for n in recorded.dataset.fixture_names], axis=0)
            plate_grid = reachable_grid(recorded.model, float(centre[2]), rng, toward=centre)
        placements += plate_placements(layout, plate_grid, orientations)
    guidance = rank_placements(recorded, placements, rng, per_socket, min_gain)
    return replace(guidance, seconds={"calibration": calibrated, **guidance.seconds})
