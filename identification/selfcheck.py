"""The statistical self-check of a calibration: is the data consistent, and will the result beat nominal?

Run on every calibration (:func:`self_check`), its findings travel with the result. Checks:

* **geometry**: two fixtures closer than :data:`MIN_SEPARATION` (declared by a distance or two
  positions, or where the fit put them), a fixture whose samples hardly move the arm
  (largest joint range below :data:`MIN_MOTION`);
* **residual level**: the residual std per coordinate against the declared ``noise``, overall (a
  chi-square with the fit's degrees of freedom ``3 K + distances - unknowns``) and per fixture;
  refused above :data:`LEVEL_FACTOR` x ``noise`` (a factor, not the chi-square's tail: real
  recordings are not Gaussian, see below);
* **leave one out** (:mod:`.leave_out`, linearised): every known distance, every known position
  (freed: three unknowns with a prior of its stated accuracy) and every fixture's samples, refitted
  without them; the disagreement in mm and ``dSSR / sigma^2 ~ chi2(dof)`` with ``sigma`` the larger
  of the declared noise and the residual std of the rest. A group is inconsistent when that test's
  p-value is below :data:`ALPHA` over the number of groups (Bonferroni) and its disagreement exceeds
  :data:`GROUP_FACTOR` x ``sigma`` per coordinate (so that a fixture recorded with a little more
  play than the others, which hundreds of samples make "significant", is not a culprit). A group with
  nothing to check it against (the one distance that sets the scale) is reported as unchecked;
* **prediction**: the predicted mean tool-point error of the result (:func:`predict_accuracy`) at
  the larger of the declared and the measured noise, against the error the nominal model is expected
  to have (the prior spread, 1 mm and 0.2 deg, through the same workspace): a calibration that cannot
  be expected to beat nominal with a margin (:data:`BEAT`) is refused. The larger noise, because the residuals
  cannot refute a declared noise from below: play that the fit absorbs into the parameters, or a
  fixture that moved between recordings, leaves small residuals and a wrong model.

The refusal is one line naming the culprit (file, row, field; the disagreement in mm and the stated
accuracy) or, without one, the figure that failed.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from spherecal.correction import RobotModel
from spherecal.correction.errors import SpherecalError

from .leave_out import LeftOut, leave_out
from .problem import DISTANCE_STD, CalibrationProblem, prior_std, samples_location

#: Stated accuracy of a known fixture position [m] (fixtures.yaml has no field for it yet).
POSITION_STD = DISTANCE_STD
#: Std per axis [m] of where a ball realises its socket's centre (play, printed or machined shape): a
#: known distance or position is compared with the samples within it, besides its stated accuracy. The
#: real MUKCa plate (8 placements, one printed plate) shows 0.11 mm: its 50 mm distances disagree with
#: each other by 0.17 mm rms, of which the fit explains 0.05 mm.
SOCKET_STD = 1e-4
#: Typical refit change of a centre [m], for :func:`.leave_out.leave_out`'s runaway test.
CENTRE_SPREAD = 0.05
#: Fixtures closer than this are degenerate (one socket under two names, or a typo) [m].
MIN_SEPARATION = 0.02
#: A fixture whose largest joint range is below this hardly moves the arm [rad] (2 deg).
MIN_MOTION = float(np.deg2rad(2.0))
#: Residual std per coordinate above this multiple of the declared noise is refused.
LEVEL_FACTOR = 2.0
#: Family-wise false-alarm probability of the leave-one-out tests (Gaussian noise at the declared level).
ALPHA = 1e-3
#: A left-out group must also disagree by this multiple of the noise (per coordinate, RMS) to be a culprit.
GROUP_FACTOR = 2.0
#: With a robust loss, samples farther from their centre than this multiple of the median are outliers.
OUTLIER = 4.0
#: Failed groups explaining within this share of the best one contend for the culprit.
CONTENDERS = 0.1
#: ... and of two contenders of one size, the better must explain this much more (chi-square units).
MARGIN = 10.0
#: The predicted mean error must be below this share of the nominal model's expected error: a 2x margin,
#: because one arm's nominal error varies about the expectation (4.7 mm against 5.2 mm expected for the
#: arm of the tests) and the prediction assumes independent noise (correlated compliance noise in
#: MuJoCo at 5 mm: 2.9 mm reached, 1.8 mm predicted).
BEAT = 0.5


class InconsistentDataError(SpherecalError):
    """The samples, fixtures and declared noise contradict each other, or the result cannot beat nominal."""


@dataclass(frozen=True)
class Finding:
    """One check.

    Attributes:
        check: what was checked (``"residual level"``, ``"distance P1-P2"``, ``"position P2"``,
            ``"fixture P3"``, ``"prediction"``, ``"separation P1-P2"``, ``"motion P2"``).
        passed: False when the check failed (True also for ``unchecked`` findings).
        message: one line for humans (the refusal's text when it failed).
        figures: plain numbers (mm where the key says so).
        culprit: a failure that names the one input to fix.
    """

    check: str
    passed: bool
    message: str
    figures: dict = field(default_factory=dict)
    culprit: bool = False


@dataclass(frozen=True)
class SelfCheck:
    """Every finding of the self-check and the verdict.

    Attributes:
        findings: all checks, in the order they ran.
        noise: declared noise per coordinate [m].
        sigma: residual std per coordinate of the fit [m].
    """

    findings: tuple[Finding, ...]
    noise: float
    sigma: float

    @property
    def failed(self) -> tuple[Finding, ...]:
        return tuple(f for f in self.findings if not f.passed)

    @property
    def consistent(self) -> bool:
        return not self.failed

    @property
    def culprit(self) -> Finding | None:
        """The failed check that names the one input to fix, if there is one."""
        return next((f for f in self.failed if f.culprit), None)

    @property
    def refusal(self) -> str:
        """The one line of a refusal ("" when consistent): the culprit, else the failed level or
        prediction figure, else the most inconsistent group with the note that no single one explains it."""
        failed = self.failed
        if not failed:
            return ""
        if self.culprit is not None:
            return self.culprit.message
        figures = [f for f in failed if f.check in ("residual level", "prediction")]
        if figures:
            return figures[0].message
        worst = max(failed, key=lambda f: f.figures.get("statistic", 0.0) - f.figures.get("dof", 0))
        others = len(failed) - 1
        return f"{worst.message}; {others} other check(s) failed too and no single one explains the data"

    def raise_if_inconsistent(self) -> None:
        """Raises :class:`InconsistentDataError` with :attr:`refusal` unless consistent."""
        if not self.consistent:
            raise InconsistentDataError(self.refusal)

    def block(self) -> dict:
        """Plain data for the ``calibration:`` block of the written file."""
        return {
            "verdict": "consistent" if self.consistent else "inconsistent",
            "noise_declared_mm": self.noise * 1e3,
            "residual_std_mm": self.sigma * 1e3,
            "failed": [f.message for f in self.failed],
            "checks": {f.check: {"passed": f.passed, **f.figures} for f in self.findings},
        }

    def lines(self) -> list[str]:
        """A few lines for the printed summary."""
        head = "consistent" if self.consistent else f"INCONSISTENT ({len(self.failed)} failed)"
        lines = [f"self-check: {head}"]
        lines += [f"  {f.message}" for f in self.findings if f.check in ("residual level", "prediction") and f.passed]
        worst = _worst_group(self.findings)
        if worst is not None:
            lines.append(f"  most inconsistent left out: {worst.message}")
        lines += [f"  unchecked: {f.message}" for f in self.findings if f.figures.get("unchecked")]
        lines += [f"  FAILED: {f.message}" for f in self.failed]
        return lines


def _worst_group(findings: tuple[Finding, ...]) -> Finding | None:
    groups = [f for f in findings if "log10_p" in f.figures and f.passed and not f.figures.get("unchecked")]
    return min(groups, key=lambda f: f.figures["log10_p"]) if groups else None


def self_check(
    problem: CalibrationProblem,
    x: np.ndarray,
    nominal: RobotModel,
    built: CalibrationProblem | None = None,
    loss: str = "linear",
) -> SelfCheck:
    """Check a solved calibration against its own data, its stated accuracies and the nominal model.

    Args:
        problem: the solved problem (after pruning).
        x: (F,) its solution.
        nominal: the nominal robot (the prediction's start and reference).
        built: the problem as built, before pruning (the prediction prunes it again at the noise it
            judges with); default ``problem``.
        loss: the fit's loss; with a robust one (``soft_l1``, ``huber``) the samples it discounted
            (distance to their centre above :data:`OUTLIER` x the median) are left out of the checks.

    Returns:
        The :class:`SelfCheck` (call :meth:`SelfCheck.raise_if_inconsistent` to refuse).
    """
    noise = problem.noise
    excluded = 0
    if loss != "linear":
        distance = np.linalg.norm(problem.sample_errors(x), axis=1)
        inliers = distance <= OUTLIER * np.median(distance)
        excluded = int((~inliers).sum())
        if excluded and all(
            np.any(inliers[problem.dataset.fixture_index == j]) for j in range(len(problem.dataset.fixture_names))
        ):
            problem = replace(problem, dataset=problem.dataset.select(inliers), _cache={})
    r = problem.residuals(x)
    dof = max(problem.n_residuals - problem.n_unknowns, 1)
    sigma = float(np.sqrt(r @ r / dof))
    findings = _geometry(problem, x)
    findings.append(_level(problem, r, sigma, dof, excluded))
    jac, res, groups, kinds, spread = _augmented(problem, x, r)
    _, _, left = leave_out(jac, res, groups, spread=spread)
    checkable = sum(1 for g in left.values() if g.dof > 0)
    groups = [_group_finding(problem, name, kinds[name], group, checkable) for name, group in left.items()]
    findings += _name_culprit(groups, problem.noise)
    findings.append(_prediction(nominal, built or problem, max(noise, sigma)))
    return SelfCheck(findings=tuple(findings), noise=noise, sigma=sigma)


def _name_culprit(groups: list[Finding], noise: float) -> list[Finding]:
    """Mark the one failed group that explains the data's inconsistency, if there is one.

    Candidates are the failed groups whose removal leaves the rest at most :data:`LEVEL_FACTOR` x
    the noise; what removing them explains beyond noise (``dSSR / sigma^2 - dof``) ranks them.
    Those within :data:`CONTENDERS` of the best explain about as much: the smallest of them (a
    distance before a position before a fixture's samples: the simplest explanation) is the culprit,
    unless a second one of its size comes within :data:`MARGIN` of it (then none is).
    """
    failed = [f for f in groups if not f.passed and f.figures["sigma_rest_mm"] <= LEVEL_FACTOR * noise * 1e3]
    if not failed:
        return groups

    def excess(f: Finding) -> float:
        return f.figures["explained"]

    best = max(excess(f) for f in failed)
    contenders = [f for f in failed if excess(f) >= (1.0 - CONTENDERS) * best]
    smallest = min(f.figures["rows"] for f in contenders)
    same = sorted((f for f in contenders if f.figures["rows"] == smallest), key=excess, reverse=True)
    if len(same) > 1 and excess(same[0]) - excess(same[1]) < MARGIN:
        return groups
    return [replace(f, culprit=True) if f is same[0] else f for f in groups]


def log10_chi2_sf(statistic: float, dof: int) -> float:
    """log10 of the chi-square survival function (floored at -300: beyond, the data are plainly inconsistent)."""
    # function-level: scipy loads slowly (scipy.special is already loaded by the solver; scipy.stats adds 0.4 s)
    from scipy.special import gammaincc

    return float(np.log10(max(gammaincc(dof / 2.0, max(statistic, 0.0) / 2.0), 1e-300)))


# ------------------------------------------------------------------------------------ geometry
def _geometry(problem: CalibrationProblem, x: np.ndarray) -> list[Finding]:
    spec, dataset = problem.spec, problem.dataset
    where = spec.source or "fixtures"
    found: list[Finding] = []
    for k, (a, b, value) in enumerate(spec.distances):
        if value < MIN_SEPARATION:
            found.append(
                Finding(
                    f"separation {a}-{b}",
                    False,
                    f"{where}: {spec._row(f'distances[{k}]')}field 'distances[{k}]': distance {a}-{b} is "
                    f"{value * 1e3:.3g} mm: fixtures closer than {MIN_SEPARATION * 1e3:.0f} mm check nothing "
                    f"(the same socket under two names, or a typo)",
                    {"declared_mm": value * 1e3},
                    culprit=True,
                )
            )
    _, centres = problem.unpack(x)
    names = dataset.fixture_names
    for i, a in enumerate(names):
        for j in range(i + 1, len(names)):
            b = names[j]
            apart = float(np.linalg.norm(centres[i] - centres[j]))
            if apart < MIN_SEPARATION and not any(f.check == f"separation {a}-{b}" for f in found):
                declared = a in spec.positions and b in spec.positions
                field_name = f"fixtures.{b}.position" if declared else "fixture"
                place = f"{where}: {spec._row('fixtures.' + b)}" if declared else f"{samples_location(dataset)}, "
                found.append(
                    Finding(
                        f"separation {a}-{b}",
                        False,
                        f"{place}field '{field_name}': fixtures {a} and {b} are {apart * 1e3:.3g} mm apart: "
                        f"fixtures closer than {MIN_SEPARATION * 1e3:.0f} mm check nothing (the same socket under "
                        f"two names, or a typo)",
                        {"apart_mm": apart * 1e3},
                        culprit=True,
                    )
                )
    for name in names:
        q = dataset.for_fixture(name)
        motion = float(np.ptp(q, axis=0).max()) if len(q) else 0.0
        passed = motion >= MIN_MOTION
        found.append(
            Finding(
                f"motion {name}",
                passed,
                f"{samples_location(dataset.select(np.flatnonzero(dataset.labels == name)))}, field 'q*': the samples "
                f"at fixture {name} hardly move the arm (largest joint range {np.rad2deg(motion):.2g} deg, at least "
                f"{np.rad2deg(MIN_MOTION):.0f} deg needed): record self-motion there",
                {"largest_joint_range_deg": float(np.rad2deg(motion))},
                culprit=not passed,
            )
        )
    return found


# ------------------------------------------------------------------------------- residual level
def _level(problem: CalibrationProblem, r: np.ndarray, sigma: float, dof: int, excluded: int) -> Finding:
    noise = problem.noise
    dataset = problem.dataset
    per_axis = r[: 3 * dataset.n_samples].reshape(-1, 3)
    share = dof / problem.n_residuals  # each fixture's share of the degrees of freedom
    per_fixture = {
        name: float(np.sqrt((per_axis[dataset.fixture_index == j] ** 2).sum() / max(3 * c * share, 1.0)))
        for j, (name, c) in enumerate(dataset.counts().items())
    }
    statistic = float(r @ r) / noise**2
    figures = {
        "residual_std_mm": sigma * 1e3,
        "ratio": sigma / noise,
        "chi2": statistic,
        "dof": dof,
        "log10_p_high": log10_chi2_sf(statistic, dof),
        "per_fixture_std_mm": {k: v * 1e3 for k, v in per_fixture.items()},
        "outliers_excluded": excluded,
    }
    worst = max(per_fixture, key=per_fixture.get)
    text = (
        f"residual {sigma * 1e3:.3g} mm per axis ({sigma / noise:.2g}x the declared noise {noise * 1e3:.3g} mm; "
        f"chi2 {statistic:.4g} on {dof} dof); worst fixture {worst} {per_fixture[worst] * 1e3:.3g} mm"
    )
    if sigma <= LEVEL_FACTOR * noise:
        if sigma < noise / LEVEL_FACTOR:
            text += "; the declared noise is larger than the residuals show: accuracy is judged at the declared noise"
        return Finding("residual level", True, text, figures)
    return Finding(
        "residual level",
        False,
        f"{samples_location(dataset)}: residual noise {sigma * 1e3:.3g} mm per axis is {sigma / noise:.3g}x the "
        f"declared {noise * 1e3:.3g} mm (limit {LEVEL_FACTOR:g}x; worst fixture {worst} {per_fixture[worst] * 1e3:.3g} "
        f"mm) and no single fixture, distance or position explains it: samples of another arm, a fixture that "
        f"moved, or the noise declared too small (--noise)",
        figures,
    )


# ------------------------------------------------------------------------------- leave one out
def _augmented(problem: CalibrationProblem, x: np.ndarray, r: np.ndarray):
    """Jacobian and residuals with every known position freed (3 unknowns, a prior row each), and the groups.

    Returns:
        (M', F') Jacobian, (M',) residuals, group name -> rows, group name -> kind, and (F',) the
        typical change of each unknown (prior spread; :data:`CENTRE_SPREAD` for centres).
    """
    dataset, spec = problem.dataset, problem.spec
    names = dataset.fixture_names
    known = [n for n in names if n not in problem.free_centres and n not in problem.pinned]
    jac = problem.jacobian(x)
    m, f = jac.shape
    count = dataset.n_samples
    weight = problem.noise / POSITION_STD
    extra = np.zeros((m + 3 * len(known), 3 * len(known)))
    _, centres = problem.unpack(x)
    for k, name in enumerate(known):
        j = names.index(name)
        rows = np.flatnonzero(dataset.fixture_index == j)
        for axis in range(3):
            extra[3 * rows + axis, 3 * k + axis] = -1.0
        for d, (a, b, _) in enumerate(spec.distances):
            if name in (a, b):
                delta = centres[names.index(a)] - centres[names.index(b)]
                sign = 1.0 if name == a else -1.0
                extra[3 * count + d, 3 * k : 3 * k + 3] = sign * problem.distance_weight * delta / np.linalg.norm(delta)
        extra[m + 3 * k : m + 3 * k + 3, 3 * k : 3 * k + 3] = weight * np.eye(3)
    full = np.hstack([np.vstack([jac, np.zeros((3 * len(known), f))]), extra])
    res = np.concatenate([r, np.zeros(3 * len(known))])
    groups: dict[str, np.ndarray] = {}
    kinds: dict[str, tuple] = {}
    for d, (a, b, _) in enumerate(spec.distances):
        groups[f"distance {a}-{b}"] = np.array([3 * count + d])
        kinds[f"distance {a}-{b}"] = ("distance", d, problem.distance_weight, DISTANCE_STD)
    for k, name in enumerate(known):
        groups[f"position {name}"] = m + 3 * k + np.arange(3)
        kinds[f"position {name}"] = ("position", name, weight, POSITION_STD)
    if len(names) > 1:
        for j, name in enumerate(names):
            rows = np.flatnonzero(dataset.fixture_index == j)
            groups[f"fixture {name}"] = (3 * rows[:, None] + np.arange(3)).ravel()
            kinds[f"fixture {name}"] = ("fixture", name, name in problem.free_centres, 0.0)
    centres = full.shape[1] - problem.n_free_params
    spread = np.concatenate([prior_std(problem.model)[problem.free], np.full(centres, CENTRE_SPREAD)])
    return full, res, groups, kinds, spread


def _group_finding(problem: CalibrationProblem, name: str, kind: tuple, group: LeftOut, checkable: int) -> Finding:
    what, key, weight, stated = kind
    spec, dataset = problem.spec, problem.dataset
    where = spec.source or "fixtures"
    if group.dof <= 0:
        text = f"{name}: the data cannot check it (it alone determines what it constrains)"
        return Finding(name, True, text, {"unchecked": True})
    scale = max(problem.noise, group.sigma_rest)
    if what == "fixture":
        statistic = max(group.delta_ssr, 0.0) / scale**2
    else:  # the constraint's value as the rest predicts it, against its stated accuracy, socket play and the fit
        play = SOCKET_STD**2 * (2.0 if what == "distance" else 1.0)
        variance = stated**2 + play + group.fit_var * (scale / weight) ** 2
        statistic = float(np.sum((group.predicted / weight) ** 2 / variance))
    log10_p = log10_chi2_sf(statistic, group.dof)
    excess = float(np.sqrt(statistic / group.dof))  # per checked row, in standard deviations
    figures = {
        "statistic": statistic,
        "dof": group.dof,
        "rows": group.rows,
        "log10_p": log10_p,
        "excess": excess,
        "sigma_rest_mm": group.sigma_rest * 1e3,
        "explained": max(group.delta_ssr, 0.0) / scale**2 - group.dof,  # residual removed beyond noise
    }
    significant = log10_p < np.log10(ALPHA / max(checkable, 1)) and excess > GROUP_FACTOR
    if what == "fixture":
        predicted = group.predicted.reshape(-1, 3)
        if weight:  # its centre is an unknown: judge the shape of its samples, not where the rest put it
            predicted = predicted - predicted.mean(axis=0)
        size = float(np.sqrt(np.mean(np.sum(predicted**2, axis=1))))
        figures["disagreement_rms_mm"] = size * 1e3
        rows = dataset.select(np.flatnonzero(dataset.labels == key))
        text = (
            f"{samples_location(rows)}, field 'fixture': the samples at fixture {key} disagree with the other "
            f"fixtures by {size * 1e3:.3g} mm rms (the others alone: residual {group.sigma_rest * 1e3:.3g} mm per "
            f"axis): samples of another arm, a fixture that moved, or a wrong label"
        )
    else:
        value = group.predicted / weight
        size = float(np.linalg.norm(value))
        fit_std = float(np.sqrt(group.fit_var.mean())) * scale / weight
        figures.update({"disagreement_mm": size * 1e3, "stated_accuracy_mm": stated * 1e3, "fit_std_mm": fit_std * 1e3})
        if what == "distance":
            a, b, declared = spec.distances[key]
            text = (
                f"{where}: {spec._row(f'distances[{key}]')}field 'distances[{key}]': distance {a}-{b} "
                f"({declared:.6g} m) disagrees with the samples by {size * 1e3:.3f} mm (its stated accuracy "
                f"{stated * 1e3:.3g} mm, socket play {SOCKET_STD * 1e3:.2g} mm, the fit's {fit_std * 1e3:.2g} mm)"
            )
        else:
            text = (
                f"{where}: {spec._row('fixtures.' + key)}field 'fixtures.{key}.position': the samples put {key} "
                f"{size * 1e3:.3f} mm from its known position (its stated accuracy {stated * 1e3:.3g} mm, socket "
                f"play {SOCKET_STD * 1e3:.2g} mm, the fit's {fit_std * 1e3:.2g} mm)"
            )
    return Finding(name, not significant, text, figures)


# --------------------------------------------------------------------------------- prediction
def nominal_expected(model: RobotModel, sensitivity: np.ndarray, draws: int = 200) -> float:
    """Expected mean tool-point error [m] of a nominal model whose parameters are off by the prior
    spread (base excluded), after registration, over the workspace of ``sensitivity`` (3 N, P)."""
    spread = model.layout.spread().copy()
    spread[model.layout.base] = 0.0
    z = np.random.default_rng(0).standard_normal((model.n_params, draws))
    field_ = sensitivity @ (spread[:, None] * z)
    return float(np.linalg.norm(field_.reshape(-1, 3, draws), axis=1).mean())


def _prediction(nominal: RobotModel, built: CalibrationProblem, noise: float) -> Finding:
    from .prediction import Workspace, predict_accuracy  # prediction imports calibrate, which imports us

    workspace = Workspace.of(nominal, count=500)
    predicted = predict_accuracy(
        nominal, built.dataset, built.spec, noise=noise, workspace=workspace, problem=built, draws=100
    )
    reference = nominal_expected(nominal, workspace.sensitivity)
    figures = {
        "predicted_mean_mm": predicted.mean * 1e3,
        "predicted_p95_mm": predicted.p95 * 1e3,
        "noise_used_mm": noise * 1e3,
        "nominal_expected_mean_mm": reference * 1e3,
    }
    text = (
        f"predicted mean error {predicted.mean * 1e3:.3g} mm at {noise * 1e3:.3g} mm noise, against "
        f"{reference * 1e3:.3g} mm expected of the nominal model (prior spread 1 mm, 0.2 deg)"
    )
    if predicted.mean < BEAT * reference:
        return Finding("prediction", True, text, figures)
    return Finding(
        "prediction",
        False,
        f"{samples_location(built.dataset)}: the calibration cannot be expected to beat the nominal model: {text} "
        f"(at most {BEAT:g}x needed); record more self-motion, more fixtures or known distances, or with less play",
        figures,
    )
