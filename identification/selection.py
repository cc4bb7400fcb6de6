"""Model selection: which terms beside the geometry (``dh``) the data supports.

Candidates (each also usable alone with ``--model``):

* ``dh``: geometry only (DH, tool point);
* ``elastic``: plus joint compliance under gravity (``c1..cn``, needs the robot file's inertials);
* ``scale``: plus a per-joint angle scale (``s1..sn``, :mod:`correction.scale`);
* ``elastic+scale``: both (needs inertials).

``auto`` (the default) judges every candidate the robot file allows

* by **cross-validation** when the fixtures form at least 3 groups. Folds leave one *placement* out:
  fixtures named ``<placement>_h<k>`` (several sockets of one plate, as MUKCa records them) form one
  group; otherwise every fixture is its own group. Each fold's fit (on :data:`CV_SAMPLES` samples per
  fixture) is judged on the held-out group, whose centre is unknown to it::

      error(fold) = mean over its fixtures of  mean_k |p_k - mean(p)|     (the predicted points' spread)
                    and over known distances within the fold of  | |mean_a - mean_b| - D_ab |

  The candidate with the lowest mean error is kept only when its mean improvement over ``dh`` exceeds
  its standard error (the fold-to-fold spread of the differences) and BIC (below) on all samples prefers it
  to ``dh`` too: a richer model must earn its place. The report gives dh's score and the richer ones' against it
  with that standard error, and calls a difference within it, either way, a tie (the folds cannot tell the two
  apart; the simpler ``dh`` is kept). The folds' sockets lie where the recording was, and a
  richer model's extra terms can win there by micrometres and lose millimetres elsewhere: on ten simulated
  rigid Pandas from short self-motion (``spherecal simulate --seconds 10 --per-fixture 200
  --known-distances``, seeds 0-9) the folds alone took elastic+scale twice and elastic once, with 0.83 and
  1.55 mm mean error over the workspace against dh's 0.43 and 0.26 mm; BIC agreeing, every one keeps dh.
  On MUKCa's real Pandas left one placement out (25 trainings) BIC agreed with every choice of the folds.
* by **BIC** otherwise (one placement: two sockets), from each candidate's one fit on all samples (the
  chosen one's is the start of the final, self-checked solve), among ``dh``, ``scale`` and ``elastic``
  (:data:`COMBINED`: below)::

      BIC = M ln(RSS / M) + ln(M) k_eff   M data rows, RSS their residual sum of squares [m^2],
                                           k_eff the effective number of unknowns of the regularised fit

  (the trace of the data rows' hat matrix: with the prior toward nominal a weakly seen parameter counts
  less than one). The lowest BIC wins; a margin under :data:`BIC_TIE` (2) is reported as a tie, no evidence
  either way on the scale of Kass & Raftery (1995). BIC rather than AIC (``2 k_eff``): on simulated single placements
  (kinematic, 2 sockets 50 mm apart, 2 x 250 samples, 0.1 mm noise) AIC took a richer model on 2 of 10
  rigid arms (seeds 7, 9: elastic by 3.3, scale by 0.9), BIC keeps dh on all while an elastic arm's gain
  (about 560) dwarfs either penalty.

What one placement can and cannot tell (``bench/selection_real.py``: each of the 11 placements of the real
Pandas panda_2_clean and panda_4_clean in turn the only training placement, test MAE on the others; mean ratio
to dh / worst ratio): always scale 1.20 / 2.15, elastic 1.03 / 1.76, elastic+scale 1.11 / 2.11, the
per-placement best 0.946. What each rule takes: BIC 0.970 / 1.107, AIC 1.107 / 2.114, the Laplace log
evidence of the MAP fit (prior rows read as a Gaussian prior, noise profiled out) 1.087 / 2.114, the
posterior predictive error of the held-out metric at virtual sockets over the workspace 0.990 / 1.010.

Why the richer models fail from one placement: the real arms sit far outside the prior on a few parameters
(panda_2's ``theta4`` 6 prior spreads, about -1.2 deg; panda_4's ``theta5`` and ``tool_x`` 6), and over one
placement's narrow joint range (``q4`` within +-0.2..0.4 rad of -2.0..-2.7 rad) a scale acts as an offset:
elastic+scale moves ``theta4`` back by 0.1-0.4 deg and ``s4 q4`` makes up the difference (``s4`` +1.4..+2.4
prior spreads), which pays less prior penalty (6.3^2 against 4.2^2 + 2.4^2), fits the training sockets, and is
wrong wherever ``q4`` differs. Every criterion computed on the training samples rewards it, the evidence most
(through the lower prior penalty); simulated arms, drawn from the prior, cannot show it (``--simulated``: BIC,
the evidence and the predictive error choose right on 10 of 10 rigid and 10 of 10 elastic arms, AIC 8 and 9).

**The combined model is no candidate from one placement (stop 9).** With fewer than 3 groups ``auto`` chooses among
``dh`` and the models with one kind of term beyond it (``scale``, ``elastic``); ``elastic+scale`` is judged only by
cross-validation (``--model elastic+scale`` fits it on request). Measured against MUKCa itself, reproduced and run
on every placement of eight real arm sets (``bench/mukca.py --mukca-runs``, 27 single-placement trainings): BIC had
taken elastic+scale 4 times, and it was worse than the better one-kind model on 3 of them (panda_1 ``window`` 1.56
against elastic's 0.88 mm, panda_2_clean ``front_right`` 0.64 against 0.57, panda_4_plus ``left`` 0.29 against
0.25), better once (panda_1 ``side_right`` 0.57 against scale's 0.59); the mean ratio to MUKCa went 0.93 -> 0.90
over the six Panda sets, the iiwa14 and the Gen3 lite unchanged. Both kinds together have the most freedom to turn
an offset the prior holds back into terms that fit one placement's narrow joint range, which is what every
in-sample criterion rewards (above).

**A candidate whose own terms are all barely excited is no candidate (stop 10).** Pruning fixes every compliance or
every scale that the data sees worse than its prior spread; the candidate is then ``dh`` fitted along another
pruning path (correlated columns change which geometric parameters are pruned), and its score is no evidence for
its terms. BIC took such an ``elastic`` on the real Gen3 lite's ``left`` by 2.8 (4.35 mm held out against dh's
3.91); ``auto`` now leaves it out, and with cross-validation keeps ``dh`` when the winner's terms are all pruned on
all samples. On MUKCa's Pandas and iiwa14 no choice changed.

BIC stays: the lowest mean at the default prior weight. It is not robust to that weight (``--prior 0.25 / 1 /
2``: BIC 1.022 / 1.062 / 1.040 of dh, worst 1.32-1.99x), where the predictive error is (0.986 / 0.997 / 0.999,
worst 1.013x) but it rarely takes a richer model (it keeps dh where elastic gains 13 % on panda_4 front).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from spherecal.correction import Dataset, FixtureSpec, RobotModel, geometric_part, tool_point
from spherecal.correction.elastic import with_compliance
from spherecal.correction.errors import SpherecalError
from spherecal.correction.gravity import has_inertials, weighs_nothing
from spherecal.correction.scale import with_scale

from .problem import OUTLIER

#: The candidates, simplest first (ties go to the earlier one).
CANDIDATES: tuple[str, ...] = ("dh", "scale", "elastic", "elastic+scale")
MODELS: tuple[str, ...] = (*CANDIDATES, "auto")
#: Candidates that need the robot file's inertials (gravity torques).
NEEDS_INERTIALS: tuple[str, ...] = ("elastic", "elastic+scale")
#: Candidates with both kinds of term beyond the geometry: from one placement (BIC) they are no candidates; only
#: cross-validation over 3 or more fixture groups can earn them (module docstring).
COMBINED: tuple[str, ...] = ("elastic+scale",)
#: Samples per fixture of every fold's fits (the final fit uses all): keeps `calibrate` interactive.
CV_SAMPLES = 150
#: A BIC difference below this is no evidence either way: the report calls it a tie (:func:`_bic_margin`). BIC
#: difference approximates 2 ln(Bayes factor), and Kass & Raftery (1995, J. Am. Stat. Assoc. 90, 773) read 0-2 on
#: that scale as "not worth more than a bare mention", 2-6 as positive evidence.
BIC_TIE = 2.0


def groups_of(names: tuple[str, ...] | list[str]) -> dict[str, str]:
    """Fixture name -> its group: the placement before the last ``_h`` when names carry one, else itself."""
    out = {}
    for name in names:
        head, sep, tail = name.rpartition("_h")
        out[name] = head if sep and head and tail.isdigit() else name
    return out


def held_out_error(model: RobotModel, dataset: Dataset, spec: FixtureSpec | None, robust: bool = False) -> float:
    """Mean spread [m] of ``model``'s tool points around their mean at each fixture of ``dataset``,
    averaged with the errors of the known distances between them (see the module docstring).

    ``robust`` (a fit with a robust loss): a fixture's points farther than :data:`.problem.OUTLIER` x their median
    distance from the mean are left out, as the fit discounted them (ten slipped samples of 100 mm made every
    candidate's score 12.8 mm on MUKCa's Panda, within 0.04 mm of each other: the choice was the outliers')."""
    points = tool_point(model, dataset.q)
    index = dataset.fixture_index
    means, errors = {}, []
    for j, name in enumerate(dataset.fixture_names):
        p = points[index == j]
        distance = np.linalg.norm(p - p.mean(axis=0), axis=1)
        if robust and len(p):
            p = p[distance <= OUTLIER * np.median(distance)]
            distance = np.linalg.norm(p - p.mean(axis=0), axis=1)
        means[name] = p.mean(axis=0)
        errors.append(float(distance.mean()))
    for a, b, distance in [] if spec is None else spec.distances:
        if a in means and b in means:
            errors.append(abs(float(np.linalg.norm(means[a] - means[b])) - distance))
    return float(np.mean(errors))


def elastic_start(nominal: RobotModel) -> RobotModel:
    """``nominal`` with every compliance free to be identified (start: rigid, or its own compliance), no scale."""
    c = nominal.extras.get("compliance")
    return with_scale(with_compliance(nominal, np.zeros(nominal.n_joints) if c is None else c), None)


def start_for(name: str, nominal: RobotModel) -> RobotModel:
    """The start model of candidate ``name``: ``nominal`` with exactly that candidate's terms free
    (compliances and scales start at the nominal file's values, else zero)."""
    if name not in CANDIDATES:
        raise ValueError(f"unknown model {name!r}, expected one of {CANDIDATES}")
    model = elastic_start(nominal) if "elastic" in name else geometric_part(nominal)
    if "scale" in name:
        s = nominal.extras.get("scale")
        model = with_scale(model, np.zeros(nominal.n_joints) if s is None else s)
    return model


def candidates_for(nominal: RobotModel) -> tuple[str, ...]:
    """The candidates the robot file allows (the elastic ones need inertials)."""
    return tuple(c for c in CANDIDATES
                 if c not in NEEDS_INERTIALS or (has_inertials(nominal) and not weighs_nothing(nominal)))


def own_terms(result, nominal: RobotModel) -> set[str]:
    """Names of the parameters a candidate's fit has beyond the geometry (``c1..``, ``s1..``)."""
    return set(result.model.param_names) - set(geometric_part(nominal).param_names)


def information_criterion(result) -> float:
    """BIC of a fitted :class:`.calibrate.CalibrationResult` with its effective unknowns (module docstring)."""
    problem, x = result.problem, result.x
    r = problem.residuals(x)[~problem.prior_rows()]
    m = r.size
    unknowns = result.effective_unknowns if result.effective_unknowns is not None else problem.n_unknowns
    return float(m * np.log(max(float(r @ r), 1e-300) / m) + np.log(m) * unknowns)


@dataclass(frozen=True)
class ModelSelection:
    """What model selection found.

    Attributes:
        requested: a candidate name or ``auto``.
        chosen: the model calibrated.
        reason: one sentence.
        criterion: ``requested``, ``cross-validation`` or ``BIC`` (or ``none`` when only one candidate).
        scores: candidate -> its score: mean held-out error [m] (cross-validation) or BIC (lower is better).
        folds: held-out group names, in order (cross-validation).
        errors: candidate -> (folds,) held-out error [m] (cross-validation).
        samples_per_fixture: samples per fixture of the fold fits.
        seconds: wall time of the selection beyond the chosen model's fit [s].
        fits: candidate -> its full fit (:class:`.calibrate.CalibrationResult`; not written to files).
    """

    requested: str
    chosen: str
    reason: str
    criterion: str = "requested"
    scores: dict[str, float] | None = None
    folds: tuple[str, ...] = ()
    errors: dict[str, np.ndarray] | None = None
    samples_per_fixture: int = 0
    seconds: float = 0.0
    fits: dict | None = None

    def stats(self, name: str | None = None) -> tuple[float, float, float, float] | None:
        """(mean dh, mean ``name``, mean improvement over dh, its standard error) [m] of the folds
        (``name``: the chosen model, or the best richer one), or None without folds."""
        if not self.errors:
            return None
        if name is None:
            richer = [k for k in self.errors if k != "dh"]
            name = self.chosen if self.chosen != "dh" else min(richer, key=lambda k: self.errors[k].mean())
        dh, other = self.errors["dh"], self.errors[name]
        diff = dh - other
        se = float(np.std(diff, ddof=1) / np.sqrt(diff.size)) if diff.size > 1 else float("inf")
        return float(dh.mean()), float(other.mean()), float(diff.mean()), se

    def summary(self) -> str:
        lines = [f"model: {self.chosen} ({self.reason})"]
        if self.scores:
            unit = " [mm]" if self.criterion == "cross-validation" else ""
            factor = 1e3 if self.criterion == "cross-validation" else 1.0
            scores = ", ".join(f"{k} {v * factor:.4f}" if unit else f"{k} {v:.1f}" for k, v in self.scores.items())
            lines.append(f"{self.criterion} score{unit} (lower is better): {scores}")
        if self.errors:
            lines.append(f"cross-validation, leave one of {len(self.folds)} groups out ({self.samples_per_fixture} "
                         f"samples per fixture per fit, {self.seconds:.2f} s): held-out error [mm]")
            for k, name in enumerate(self.folds):
                row = "  ".join(f"{m} {e[k] * 1e3:.4f}" for m, e in self.errors.items())
                lines.append(f"  {name:<16} {row}")
        return "\n".join(lines)

    def block(self) -> dict:
        """The ``model_selection`` entry of the result file (metres)."""
        out = {"requested": self.requested, "chosen": self.chosen, "reason": self.reason, "criterion": self.criterion}
        if self.scores:
            out["scores"] = {k: float(v) for k, v in self.scores.items()}
        if self.fits:
            out["effective_unknowns"] = {k: float(f.effective_unknowns) for k, f in self.fits.items()}
        if self.errors:
            out.update({
                "folds": list(self.folds),
                "held_out_error_m": {k: [float(v) for v in e] for k, e in self.errors.items()},
                "samples_per_fixture": self.samples_per_fixture,
            })
        if self.seconds:
            out["seconds"] = self.seconds
        return out


def _sub_spec(spec: FixtureSpec | None, names: tuple[str, ...]) -> FixtureSpec:
    if spec is None:
        return FixtureSpec.unknown(names)
    keep = set(names)
    kept = [k for k, (a, b, _) in enumerate(spec.distances) if a in keep and b in keep]
    return replace(spec.keep_distances(kept), names=tuple(n for n in spec.names if n in keep),
                   positions={k: v for k, v in spec.positions.items() if k in keep})


def cross_validate(fit, names: tuple[str, ...], nominal: RobotModel, dataset: Dataset,
                   spec: FixtureSpec | None, samples: int = CV_SAMPLES, seed: int = 0, robust: bool = False
                   ) -> tuple[tuple[str, ...], dict[str, np.ndarray], int]:
    """Held-out errors of the candidates ``names``, one fold per group.

    Args:
        fit: ``fit(start_model, dataset, spec, warm) -> CalibrationResult`` (the calibration as the caller runs
            it; ``warm``: the model to start the optimisation from, None here: a fold starts from nominal); only
            its result's ``model`` is read.
        samples: samples per fixture of the fold fits (drawn once, seeded); the held-out group is judged on
            all of its samples.
        robust: the fits use a robust loss: the held-out group is judged without its outliers (:func:`held_out_error`).

    Returns:
        folds, candidate -> (folds,) errors [m], samples per fixture used.
    """
    groups = groups_of(dataset.fixture_names)
    folds = tuple(dict.fromkeys(groups.values()))
    small = dataset.subsampled(samples, np.random.default_rng(seed))
    errors: dict[str, list[float]] = {name: [] for name in names}
    for fold in folds:
        held = np.array([groups[label] == fold for label in small.labels])
        train = small.select(~held)
        test = dataset.select(np.array([groups[label] == fold for label in dataset.labels]))
        train_spec = _sub_spec(spec, train.fixture_names)
        for name in names:
            model = fit(start_for(name, nominal), train, train_spec, None).model
            errors[name].append(held_out_error(model, test, spec, robust))
    used = min(samples, min(dataset.counts().values()))
    return folds, {k: np.array(v) for k, v in errors.items()}, used


def select_model(requested: str, fit, nominal: RobotModel, dataset: Dataset, spec: FixtureSpec | None,
                 samples: int = CV_SAMPLES, seed: int = 0, robust: bool = False, fold_fit=None) -> ModelSelection:
    """Choose the model (see the module docstring).

    Args:
        fit: ``fit(start_model, dataset, spec, warm) -> CalibrationResult`` without the self-check (``warm``:
            None, or the model to start the optimisation from).
        robust: ``fit`` uses a robust loss (the held-out groups are judged without their outliers).
        fold_fit: the cross-validation folds' ``fit`` (default ``fit``): only the model of its result is read, so it
            may leave out the stds and figures (``calibrate(..., report=False)``); the same model as ``fit``'s.

    Returns:
        The :class:`ModelSelection`; with BIC its ``fits`` hold every candidate's fit on all samples (the
        chosen one's is the caller's warm start).

    Raises:
        SpherecalError: an elastic model requested for a robot without ``inertials``.
        ValueError: unknown ``requested``.
    """
    if requested not in MODELS:
        raise ValueError(f"unknown model {requested!r}, expected one of {MODELS}")
    if requested != "auto":
        if requested in NEEDS_INERTIALS and not has_inertials(nominal):
            raise SpherecalError(f"{nominal.extras.get('source') or nominal.name}: field 'inertials': --model "
                                 f"{requested} needs the link masses ({nominal.name} has none and matches no embedded "
                                 f"arm): give them with --inertials FILE or {_masses_go(nominal)}")
        if requested in NEEDS_INERTIALS and weighs_nothing(nominal):
            source = nominal.extras.get("inertials_source") or nominal.extras.get("source") or nominal.name
            raise SpherecalError(f"{source}: field 'inertials': every link mass and the payload are 0 kg, so "
                                 f"gravity loads no joint and --model {requested} has no compliance to fit (give the "
                                 "link masses [kg], or --model dh)")
        return ModelSelection(requested, requested, "requested")
    selection = _auto(fit, nominal, dataset, spec, samples, seed, robust, fold_fit)
    # said where the choice is printed: a URDF without masses lost them without a word (a new arm's trial)
    why = (f"{nominal.name} has no link masses and matches no embedded arm: give them with --inertials FILE or "
           f"{_masses_go(nominal)}" if not has_inertials(nominal) else
           "every link mass and the payload are 0 kg: gravity loads no joint" if weighs_nothing(nominal) else None)
    if why:
        left = " and ".join(c for c in CANDIDATES if c in NEEDS_INERTIALS)
        selection = replace(selection, reason=f"{selection.reason}; {left} not tried ({why})")
    return selection


def _masses_go(nominal: RobotModel) -> str:
    """Where a robot file gives its link masses: a URDF's ``<inertial>`` elements, a robot file's inertials block."""
    return ("<inertial> elements in its URDF" if str(nominal.extras.get("source", "")).endswith(".urdf")
            else "an inertials block in the robot file")


def _auto(fit, nominal: RobotModel, dataset: Dataset, spec: FixtureSpec | None, samples: int, seed: int,
          robust: bool, fold_fit) -> ModelSelection:
    """``select_model("auto", ...)``: cross-validation with 3 or more fixture groups, else BIC (module docstring)."""
    clock = time.perf_counter()
    names = candidates_for(nominal)
    groups = set(groups_of(dataset.fixture_names).values())
    if len(groups) >= 3:  # the folds judge; no full fit needed beyond the chosen one (the caller's)
        try:
            folds, errors, used = cross_validate(fold_fit or fit, names, nominal, dataset, spec, samples, seed,
                                                 robust)
        except SpherecalError as error:  # a fold the data cannot calibrate: no evidence for a richer model
            return ModelSelection("auto", "dh", f"a cross-validation fold could not be calibrated ({error})",
                                  "cross-validation", seconds=time.perf_counter() - clock)
        scores = {k: float(e.mean()) for k, e in errors.items()}
        best = min(names, key=lambda k: (scores[k], names.index(k)))
        selection = ModelSelection("auto", "dh", "", "cross-validation", scores, folds, errors, used,
                                   time.perf_counter() - clock)
        if best == "dh" or not _beats_dh(selection, best):
            return replace(selection, reason=_kept_reason(selection))
        won = (f"{best} predicts held-out fixtures better than dh, by more than the standard error of the difference: "
               f"{_against_dh(selection, [best])}")
        fits = {}
        for name in ("dh", best):  # BIC on all samples must agree (module docstring)
            try:
                fits[name] = fit(start_for(name, nominal), dataset, spec, None)
            except SpherecalError as error:
                if name == "dh":
                    raise
                return replace(selection, reason=f"{won}, but it cannot be fitted to all samples ({error})",
                               seconds=time.perf_counter() - clock)
        below = information_criterion(fits["dh"]) - information_criterion(fits[best])
        selection = replace(selection, fits=fits, seconds=time.perf_counter() - clock)
        if not own_terms(fits[best], nominal) & set(fits[best].identified):
            return replace(selection, reason=f"{won}, but on all samples every term of its own is barely excited: "
                                             "the simpler model is kept")
        if below > 0:
            return replace(selection, chosen=best, reason=f"{won}; {_bic_on_all(below, best)}")
        return replace(selection, reason=f"{won}, but {_bic_on_all(below, best)}: the simpler model is kept")
    left_out = [k for k in names if k in COMBINED]
    names = tuple(k for k in names if k not in COMBINED)
    fits = {}
    for name in names:
        try:
            fits[name] = fit(start_for(name, nominal), dataset, spec, None)
        except SpherecalError as error:  # a candidate the data cannot calibrate is no candidate
            if name == "dh":
                raise
            fits[name] = error
    failed = {k: str(v) for k, v in fits.items() if isinstance(v, SpherecalError)}
    fits = {k: v for k, v in fits.items() if k not in failed}
    # a candidate whose own terms the data barely excites (every compliance or scale fixed by pruning) is dh fitted
    # along another pruning path, not that model: no candidate
    unseen = [k for k, f in fits.items() if k != "dh" and not own_terms(f, nominal) & set(f.identified)]
    fits = {k: v for k, v in fits.items() if k not in unseen}
    names = tuple(fits)
    note = "" if not failed else f"; not fitted: {', '.join(failed)}"
    if unseen:  # a review read 'scale, elastic: every term of its own barely excited'
        whose = "its" if len(unseen) == 1 else "their"
        note += f"; {listed(unseen)} left out: every term of {whose} own barely excited"
    if left_out:
        note += f"; {listed(left_out)} only with 3 or more groups, by cross-validation"
    if len(names) == 1:
        only = "the only candidate left" if unseen else "the only candidate"
        return ModelSelection("auto", "dh", only + note, "none", fits=fits, seconds=time.perf_counter() - clock)
    scores = {k: information_criterion(f) for k, f in fits.items()}
    best = min(names, key=lambda k: (scores[k], names.index(k)))
    # a review read '1 fixture group(s), too few to cross-validate (need 3): lowest BIC (effective unknowns of the
    # regularised fit), 86.6 below dh; ...': the choice first, and no parentheses within the summary's
    many = len(groups) > 1
    reason = (f"lowest BIC, counting the regularised fit's effective unknowns, {_bic_margin(scores, best)}; "
              f"{len(groups)} fixture group{'s' if many else ''} {'are' if many else 'is'} too few to cross-validate, "
              "which needs 3")
    return ModelSelection("auto", best, reason + note, "BIC", scores, fits=fits, seconds=time.perf_counter() - clock)


def _beats_dh(selection: ModelSelection, name: str) -> bool:
    """Cross-validation's rule: candidate ``name``'s mean held-out gain over dh exceeds its standard error over the
    folds (:meth:`ModelSelection.stats`)."""
    _, _, gain, se = selection.stats(name)
    return gain > se


def _ties_dh(selection: ModelSelection, name: str) -> bool:
    """Candidate ``name`` and dh are a tie on the folds: their mean held-out errors differ, either way, by no more than
    the standard error of that difference over the folds (the fold-by-fold differences' std / sqrt(folds)).

    The resolution is the criterion's own: the figure a richer model's gain must exceed to be chosen
    (:func:`_beats_dh`), and a difference within one standard error of 0 is one the folds cannot tell from none (a
    review: ``model: dh (no richer model predicts held-out fixtures better than dh)`` where elastic scored 0.0005 mm
    from dh). In a tie the simpler dh is kept, as it is whenever the gain does not exceed it."""
    _, _, gain, se = selection.stats(name)
    return abs(gain) <= se


def _against_dh(selection: ModelSelection, names: list[str]) -> str:
    """The held-out errors of dh and the candidates ``names``, each with its difference from dh and that difference's
    standard error over the folds [mm]: ``held-out error dh 0.4690 mm, scale 0.4733 mm (+0.0043 mm, standard error
    over the 3 folds 0.0081 mm)``."""
    parts = [f"held-out error dh {selection.scores['dh'] * 1e3:.4f} mm"]
    for k, name in enumerate(names):
        _, other, gain, se = selection.stats(name)
        over = f" over the {len(selection.folds)} folds" if k == 0 else ""
        parts.append(f"{name} {other * 1e3:.4f} mm ({-gain * 1e3:+.2g} mm, standard error{over} {se * 1e3:.2g} mm)")
    return ", ".join(parts)


def _kept_reason(selection: ModelSelection) -> str:
    """Why cross-validation keeps dh, with the scores: the richer candidates that tie with it (:func:`_ties_dh`),
    else the nearest one (no richer model is better); and any that beats dh by more than its standard error without
    scoring lowest (the rule judges the lowest score only)."""
    richer = sorted((k for k in selection.errors if k != "dh"), key=lambda k: selection.scores[k])
    ties = [k for k in richer if _ties_dh(selection, k)]
    if ties:
        reason = (f"{listed(ties)} {'ties' if len(ties) == 1 else 'tie'} with dh on held-out fixtures, within the "
                  f"standard error of the difference, so the simpler dh is kept: {_against_dh(selection, ties)}")
    else:
        reason = (f"no richer model predicts held-out fixtures better than dh; the nearest is {richer[0]}: "
                  f"{_against_dh(selection, richer[:1])}")
    beyond = [k for k in richer if _beats_dh(selection, k)]
    if beyond:
        reason += (f"; {listed(beyond)} {'beats' if len(beyond) == 1 else 'beat'} dh by more than the standard error "
                   f"({_against_dh(selection, beyond)}), but the rule judges the lowest score only, {richer[0]}'s")
    return reason


def _bic_on_all(below: float, best: str) -> str:
    """What BIC on all samples says of cross-validation's winner ``best`` (``below``: dh's BIC minus ``best``'s): it
    agrees (``below`` >= :data:`BIC_TIE`), prefers dh (<= -2), or, in between, neither, a tie that the rule reads by
    its sign (``best`` is taken where ``below`` > 0)."""
    if below >= BIC_TIE:
        return f"BIC on all samples agrees ({below:.1f} below dh)"
    if below <= -BIC_TIE:
        return f"BIC on all samples prefers dh ({-below:.1f} below {best})"
    said, lower = (("does not disagree", f"{best} {below:.1f} below dh") if below > 0 else
                   ("does not agree", f"dh {-below:.1f} below {best}"))
    return f"BIC on all samples {said} ({lower}{_no_evidence(abs(below))})"


def _bic_margin(scores: dict[str, float], best: str) -> str:
    """The BIC choice's margin: ``best``'s score below dh's, or dh's below the next candidate's, with
    :func:`_no_evidence`. A tie leaves the choice to the lowest score, as the rule does: dh where it scores lowest (the
    simpler kept), a richer model where it does (the margin then says it is no evidence)."""
    if best == "dh":
        runner = min((k for k in scores if k != "dh"), key=scores.get)
        margin = scores[runner] - scores["dh"]
        kept = ", and the simpler dh is kept" if margin < BIC_TIE else ""
        return f"{margin:.1f} below the next candidate, {runner}{_no_evidence(margin)}{kept}"
    margin = scores["dh"] - scores[best]
    taken = f", and {best} is taken as the lowest all the same" if margin < BIC_TIE else ""
    return f"{margin:.1f} below dh{_no_evidence(margin)}{taken}"


def _no_evidence(margin: float) -> str:
    """``", under 2: a tie, no evidence either way"`` for a BIC margin under :data:`BIC_TIE`, else ``""``."""
    return f", under {BIC_TIE:g}: a tie, no evidence either way" if margin < BIC_TIE else ""


def listed(names) -> str:
    """Names in a sentence: ``"a"``, ``"a and b"``, ``"a, b and c"`` (also the workflow's fixtures)."""
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"
