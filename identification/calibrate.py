"""Calibrate: build the problem, solve it (``lm``, ``pso`` or ``pso+lm``), report what was found."""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass, field, replace

import numpy as np

from spherecal.correction import RobotModel, param_jacobian, registered_errors, tool_point
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.samples import Dataset
from spherecal.correction.layout import COMPLIANCE

from .build import build_problem
from .fixture_noise import FixtureNoise, fixture_noise
from .identifiability import Identifiability, normal_inverse, predicted_std
from .misplaced import misplaced
from .problem import (
    GAUGE,
    NOISE,
    OUTLIER,
    SIGMA_FLOOR,
    ZERO_TOLERANCE,
    CalibrationProblem,
    ImplausibleCalibrationError,
    prior_std,
    row_list,
    samples_location,
    tolerance,
    zero_indices,
)
from .pruning import generic_excitation, prune
from .selfcheck import MAX_SOCKET_NOISE, InconsistentDataError, SelfCheck, self_check
from .selfcheck_result import ONLY_FIXTURE, Advice, Piece, told
from .solvers import solve_lm, solve_pso

METHODS: tuple[str, ...] = ("lm", "pso", "pso+lm")
#: The ``auto`` loss's Huber scale, in multiples of the noise the first (least-squares) fit's residuals show
#: (:attr:`.FixtureNoise.level`, each fixture's rows weighed to it): Rousseeuw and Leroy's 2.5 sigma cut-off of
#: reweighted least squares ("Robust Regression and Outlier Detection", 1987). Rows within it are least squares,
#: so Gaussian noise loses almost nothing; a press taken before the ball sat in its socket pulls with a bounded
#: weight.
ROBUST_CUT = 2.5
#: The summary names the identified parameters whose estimate the data gives less than this share of
#: (:meth:`.problem.CalibrationProblem.data_share`): the prior toward nominal holds them near their start (a
#: compliance of a joint gravity barely loads, such as a vertical first joint's). A report line only: it fixes nothing.
PRIOR_HELD = 0.1
#: Largest plausible tool-point change of a calibration, in multiples of what a real arm's
#: errors (:func:`.problem.tolerance`: 1 mm, 0.2 deg, a joint's zero 1 deg) typically move it (about 15 mm on the
#: Panda, so about 62 mm).
MAX_CHANGE = 4.0
#: Residual noise above this multiple of the expected ``noise`` gets a warning (a wrong distance or
#: position, a moved fixture, or ``noise`` set too small).
NOISE_RATIO = 3.0
#: Random configurations the plausibility of a calibration is judged on.
PLAUSIBILITY_CONFIGURATIONS = 2000


@dataclass(frozen=True, eq=False)
class CalibrationResult:
    """A calibration: the model, what was identified and how well.

    Attributes:
        model: the calibrated robot.
        nominal: the robot it started from.
        method: ``lm``, ``pso`` or ``pso+lm``.
        centres: fixture name -> (3,) centre [m] (estimated, known or pinned).
        identified: names of the identified parameters.
        fixed: name -> reason, every parameter left at its start value.
        condition_number: of the column-scaled Jacobian at the solution.
        std: name -> standard deviation of every unknown (parameters [m or rad], centres ``P1.x`` [m]).
        residual_before, residual_after: (K,) distance between each sample's tool point and its
            fixture centre [m], at the start (centres at the mean tool point) and at the end.
        samples_per_fixture: fixture -> samples used.
        warnings: what the user must know.
        timings: stage -> wall time [s].
        problem: the final problem (inspectable).
        x: (F,) its solution.
        selfcheck: the statistical self-check (:mod:`.selfcheck`), None when it was not run.
        effective_unknowns: effective number of unknowns of the (regularised) fit, the trace of its hat
            matrix (:meth:`CalibrationProblem.effective_unknowns`); the unknowns' count without a prior.
        data_share: identified parameter -> the share of its estimate the data gives, 0..1
            (:meth:`CalibrationProblem.data_share`; the prior toward nominal gives the rest).
        loss: the loss the fit used: ``linear``, ``soft_l1`` or ``huber`` (``auto`` resolves to ``huber``).
        loss_scale: its residual scale [m] (None with ``linear``).
        loss_noise: with ``auto``, the noise per coordinate [m] the least-squares residuals showed
            (:attr:`.FixtureNoise.level`), of which ``loss_scale`` is :data:`ROBUST_CUT` times; None otherwise.
        fixture_noise: with ``auto``, the noise each fixture showed and the weights its rows had in the solves
            (:mod:`.fixture_noise`); None otherwise.
    """

    model: RobotModel
    nominal: RobotModel
    method: str
    centres: dict[str, np.ndarray]
    identified: tuple[str, ...]
    fixed: dict[str, str]
    condition_number: float
    std: dict[str, float]
    residual_before: np.ndarray
    residual_after: np.ndarray
    samples_per_fixture: dict[str, int]
    warnings: tuple[str, ...]
    timings: dict[str, float] = field(default_factory=dict)
    problem: CalibrationProblem | None = None
    x: np.ndarray | None = None
    selfcheck: SelfCheck | None = None
    effective_unknowns: float | None = None
    data_share: dict[str, float] = field(default_factory=dict)
    loss: str = "linear"
    loss_scale: float | None = None
    loss_noise: float | None = None
    fixture_noise: FixtureNoise | None = None

    @staticmethod
    def _stats(r: np.ndarray) -> tuple[float, float]:
        return float(np.sqrt(np.mean(r**2))), float(np.max(r))

    @property
    def rms_before(self) -> float:
        """RMS of :attr:`residual_before` [m]."""
        return self._stats(self.residual_before)[0]

    @property
    def rms_after(self) -> float:
        """RMS of :attr:`residual_after` [m]."""
        return self._stats(self.residual_after)[0]

    def changes(self) -> list[tuple[str, float, float, float]]:
        """(name, start value, calibrated value, std) of every identified parameter."""
        names = self.model.param_names
        start, end = self.nominal.params, self.model.params
        return [(n, float(start[names.index(n)]), float(end[names.index(n)]), self.std[n]) for n in self.identified]

    def block(self) -> dict:
        """The ``calibration:`` block of the output robot file (plain Python, metres, radians, mm where named)."""
        rms_b, max_b = self._stats(self.residual_before)
        rms_a, max_a = self._stats(self.residual_after)
        return {
            "method": self.method,
            "samples_per_fixture": dict(self.samples_per_fixture),
            "residual_mm": {
                "before": {"rms": rms_b * 1e3, "max": max_b * 1e3},
                "after": {"rms": rms_a * 1e3, "max": max_a * 1e3},
            },
            "fixture_centres": {k: [float(v) for v in c] for k, c in self.centres.items()},
            "pinned_fixtures": list(self.problem.pinned) if self.problem else [],
            "identified": list(self.identified),
            "fixed": dict(self.fixed),
            "condition_number": float(self.condition_number),
            "std": {k: float(v) for k, v in self.std.items()},
            "warnings": list(self.warnings),
            "prior_weight": float(self.problem.prior_weight) if self.problem else 0.0,
            # the noise the prior was weighed at, where the residuals showed more than the default (zeros at 1 deg)
            "prior_noise_m": (float(self.problem.prior_noise)
                              if self.problem and self.problem.prior_noise is not None else None),
            "prior_tail_spreads": (float(self.problem.prior_tail)
                                   if self.problem and np.isfinite(self.problem.prior_tail) else None),
            "effective_unknowns": self.effective_unknowns,
            "data_share": {k: float(v) for k, v in self.data_share.items()},
            "loss": self.loss,
            "loss_scale_m": self.loss_scale,
            **({"fixture_noise": self.fixture_noise.block()} if self.fixture_noise is not None else {}),
            **({"self_check": self.selfcheck.block()} if self.selfcheck is not None else {}),
            "timings_s": {k: float(v) for k, v in self.timings.items()},
        }

    def _prior_noise_clause(self) -> str:
        """`` at the 0.8 mm per axis the residuals show (joints' zeros at 1 deg)`` where the prior was weighed at it
        (:func:`prior_at_shown_noise`), else ``""``."""
        if self.problem is None or self.problem.prior_noise is None:
            return ""
        return (f" at the {self.problem.prior_noise * 1e3:.3g} mm per axis the residuals show, above the default "
                f"{self.problem.noise * 1e3:.3g} mm (joints' zeros at {np.rad2deg(ZERO_TOLERANCE):g} deg)")

    def _tail_line(self) -> list[str]:
        """The parameters in the prior's heavy tail (a large error of this arm: a joint zero, a tool mount), if any."""
        problem = self.problem
        if problem is None or problem.prior_curvature is None or problem.prior_centre is None:
            return []
        z = (self.model.params - problem.prior_centre) / problem.prior_spread()
        tail = [i for i in problem.free if abs(z[i]) > problem.prior_tail]
        if not tail:
            return []
        names = self.model.param_names
        return [f"beyond the prior's {problem.prior_tail:g}-spread core (large errors of this arm): "
                + ", ".join(f"{names[i]} {z[i]:+.1f} spreads" for i in tail)]

    def _loss_line(self) -> list[str]:
        """How many samples a robust loss weighed less (a coordinate beyond its scale); with ``auto``, beside the
        share Gaussian noise puts beyond 2.5 sigma (a few bad presses, or residuals with heavy tails)."""
        if self.loss == "linear" or self.loss_scale is None or self.problem is None or self.x is None:
            return []
        errors = self.problem.sample_errors(self.x)
        shown = self.fixture_noise
        if shown is not None:  # each fixture's rows at its weight: the loss's scale is in units of its own noise
            errors = errors * self.problem.weighted(shown.weights).sample_weights()[:, None]
        beyond = np.abs(errors) > self.loss_scale
        count = f"{int(beyond.any(axis=1).sum())} of {len(beyond)} samples beyond it weigh less"
        if self.loss_noise is None:
            return [f"loss: {self.loss} at {self.loss_scale * 1e3:.3f} mm (the fit's noise, --noise): {count}"]
        ratio = self.loss_scale / self.loss_noise
        gaussian = 1.0 - (1.0 - math.erfc(ratio / math.sqrt(2.0))) ** 3
        uneven = shown is not None and shown.uneven()
        shows = ("every fixture's rows show at their weight (below)" if uneven else
                 "the least-squares residuals show by their median")
        lines = [f"loss: {self.loss} at {self.loss_scale * 1e3:.3f} mm, {ratio:g}x the {self.loss_noise * 1e3:.3f} mm "
                 f"per axis {shows}: {count} (Gaussian noise puts {100 * gaussian:.1f} % there)"]
        if uneven:
            lines.append(f"fixtures weighed by the noise each shows (per axis, by the median of its least-squares "
                         f"residuals; a quieter socket counts more): {shown.text()}")
        return lines

    def summary(self) -> str:
        """One screen: residuals before/after, parameter changes with std, fixed parameters, warnings."""
        rms_b, max_b = self._stats(self.residual_before)
        rms_a, max_a = self._stats(self.residual_after)
        counts = ", ".join(f"{k} {v}" for k, v in self.samples_per_fixture.items())
        lines = [
            f"calibration ({self.method}): {sum(self.samples_per_fixture.values())} samples ({counts})",
            f"residual [mm]   before: rms {rms_b * 1e3:.4f}  max {max_b * 1e3:.4f}"
            f"   after: rms {rms_a * 1e3:.4f}  max {max_a * 1e3:.4f}",
            f"identified {len(self.identified)} parameters, condition number {self.condition_number:.3g}"
            + (f", prior weight {self.problem.prior_weight:g}{self._prior_noise_clause()} "
               f"({self.effective_unknowns:.1f} effective unknowns with "
               f"the {self.problem.n_unknowns - self.problem.n_free_params} fixture centre coordinates)"
               if self.problem is not None and self.problem.prior_weight > 0 else ""),
            f"  {'parameter':<9} {'unit':<7} {'change':>10} {'std':>10}"
            + (f" {'data %':>7}" if self.data_share else ""),
        ]
        for name, start, end, std in self.changes():
            layout = self.model.layout
            kind = layout.kinds[layout.index(name)]
            scale, unit = kind.display_scale, kind.display_unit
            share = f" {100 * self.data_share[name]:7.0f}" if name in self.data_share else ""
            lines.append(f"  {name:<9} {unit:<7} {(end - start) * scale:10.5f} {std * scale:10.5f}{share}")
        held = [name for name, v in self.data_share.items() if v < PRIOR_HELD]
        if held:  # the data barely moves them: the prior toward nominal holds them
            lines.append(f"  held by the prior (the data gives under {100 * PRIOR_HELD:g} % of the estimate): "
                         + ", ".join(held))
        lines.extend(self._tail_line())
        lines.extend(self._loss_line())
        groups: dict[str, list[str]] = {}
        for name, reason in self.fixed.items():
            groups.setdefault(reason, []).append(name)
        lines.append(f"fixed {len(self.fixed)} parameters:")
        for reason, names in groups.items():
            lines.append(f"  {', '.join(names)}: {reason}")
        fixed_point = {"float_kind": "{:.6f}".format}  # metres to the micrometre, never an exponent
        for name, c in self.centres.items():
            lines.append(f"centre {name} [m]: {np.array2string(np.asarray(c), formatter=fixed_point)}")
        lines.extend(f"warning: {w}" for w in self.warnings)
        if self.selfcheck is not None:
            lines.extend(self.selfcheck.lines())
        return "\n".join(lines)


def _already_calibrated(nominal: RobotModel, checked: SelfCheck) -> str:
    """The reason a refusal "cannot beat the nominal model" has when the nominal model is itself a calibration
    (its robot file carries a ``calibration`` block): "" otherwise."""
    if not isinstance(nominal.extras.get("calibration"), dict):
        return ""
    if not any(f.check == "prediction" for f in checked.failed):
        return ""
    return ("; the --robot model is already a calibration (its file has a 'calibration' block): calibrate from "
            "the nominal robot file, or check this one on these samples with validate")


def calibrate(
    nominal: RobotModel,
    dataset: Dataset,
    spec: FixtureSpec | None = None,
    method: str = "lm",
    start: RobotModel | None = None,
    seed: int = 0,
    loss: str = "linear",
    noise: float = NOISE,
    pso_options: dict | None = None,
    max_change: float = MAX_CHANGE,
    check: bool = True,
    force: bool = False,
    prior: float = 0.0,
    noise_declared: bool = True,
    prior_tail: float | None = None,
    report: bool = True,
) -> CalibrationResult:
    """Identify the parameters of ``nominal`` that put every sample's tool point on its fixture.

    Args:
        nominal: the robot to calibrate (its convention and limits are kept).
        dataset: samples (deduplicate / subsample first: :meth:`Dataset.deduplicated`).
        spec: known fixture positions and distances (all unknown when None).
        method: ``lm``, ``pso`` or ``pso+lm``.
        start: start model of the identified parameters (default ``nominal``); the fixed ones keep
            their nominal values.
        seed: seeds PSO.
        loss: ``linear``, ``soft_l1`` or ``huber`` at the scale ``noise`` (``lm`` only), or ``auto``: least
            squares, then from there each fixture's rows weighed by the noise they show and Huber at
            :data:`ROBUST_CUT` x that noise (:mod:`.fixture_noise`; least squares with ``pso``).
        noise: expected fixture noise [m] (robust-loss scale, distance weight).
        pso_options: keyword arguments of :func:`solve_pso`.
        max_change: largest plausible tool-point change from the start model, in multiples of what
            a real arm's errors (:func:`.problem.tolerance`: 1 mm, 0.2 deg, a joint's zero 1 deg) typically cause;
            a fit beyond it is refused.
        check: run the self-check (False for a cross-validation fold: the self-check judges the
            calibration that is written).
        force: return the result even when the self-check refuses it.
        prior: weight ``W`` of the prior toward ``nominal`` (:mod:`.problem`): each identified parameter's
            deviation over its prior spread, at the declared ``noise``; 0 (default) is plain least squares
            (the workflow and `calibrate` use :data:`.problem.PRIOR`).
        prior_tail: where the prior's heavy tail starts [prior spreads] (default :data:`.problem.PRIOR_TAIL`;
            inf: a Gaussian prior).
        noise_declared: ``noise`` is what the user states of this data (a floor of the self-check's accuracy
            judgement); False: a default, and the accuracy is judged at the noise the residuals show.
        report: False: only the model is wanted (a cross-validation fold, judged on held-out samples by its model
            alone; ``check=False`` only): the stds, condition number, effective unknowns and data shares at the
            solution, and the warnings that read them, are not computed (``condition_number`` NaN, ``std`` and
            ``data_share`` empty, ``effective_unknowns`` None). The solve, the pruning and the plausibility check
            are the same, so is the model.

    Returns:
        The :class:`CalibrationResult`.

    Raises:
        DatasetError, UnidentifiableError: see :func:`build_problem`.
        ImplausibleCalibrationError: the fit moved the tool point ``max_change`` times further than
            a real arm's errors do (see :func:`check_plausible`).
        InconsistentDataError: the self-check failed (not with ``force``): one line naming the
            inconsistent distance, position or fixture, or the failed figure.
    """
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}, expected one of {METHODS}")
    if check and not report:
        raise ValueError("report=False needs check=False: the self-check reads the fit's figures")
    timings: dict[str, float] = {}
    clock = time.perf_counter()
    problem = build_problem(nominal, dataset, spec, noise=noise, prior_weight=prior, prior_tail=prior_tail)
    built = problem
    before = problem.start_distances()
    timings["build"] = time.perf_counter() - clock
    x = problem.x0 if start is None else problem.start_from(start)
    if method in ("pso", "pso+lm"):
        solution = solve_pso(problem, seed=seed, x0=x, **(pso_options or {}))
        x, timings["pso"] = solution.x, solution.seconds
    # ``auto``: the solves weigh each fixture by the noise it shows in the least-squares fit (:mod:`.fixture_noise`)
    # and use Huber at that scale; every figure (pruning, stds, the self-check) reads all samples as least squares
    # does: a press 50 mm off (the wrong socket) is refused and named, not discounted
    figures = fit_loss = "linear" if loss == "auto" else loss
    scale, shown = None, None
    if method in ("lm", "pso+lm"):
        x_start = x
        solution = solve_lm(problem, x, loss=fit_loss)
        x, timings["lm"] = solution.x, solution.seconds
        honest_prior = not noise_declared and problem.n_prior
        # the least-squares residuals' noise: auto's weights and scale, and the prior's noise (the samples' rows alone)
        seen = fixture_noise(problem, x) if loss == "auto" or honest_prior else None
        if honest_prior:
            honest = prior_at_shown_noise(problem, seen.level)
            if honest is not problem and loss != "auto":  # auto's next solve is from here anyway
                solution = solve_lm(honest, x, loss=fit_loss)
                x, timings["lm"] = solution.x, timings["lm"] + solution.seconds
            problem = honest
        if loss == "auto":
            shown = seen
            fit_loss, scale = "huber", ROBUST_CUT * shown.level
            solution = solve_lm(problem.weighted(shown.weights), x, loss=fit_loss, f_scale=scale)
            x, timings["lm"] = solution.x, timings["lm"] + solution.seconds
        # The data's own noise decides what it can see, judged near the start (a poorly excited
        # data set lets the first fit wander to a far, wrong basin); re-solve without what it cannot
        # see, from the start again rather than from where the first fit wandered.
        sigma = max(_sigma(problem, x, loss=figures), SIGMA_FLOOR)
        pruned, _ = prune(problem, x, sigma, excitation=generic_excitation(problem))
        if pruned is not problem:
            x_restart = pruned.pack(*problem.unpack(x_start))
            problem = pruned
            solving = problem if shown is None else problem.weighted(shown.weights)
            solution = solve_lm(solving, x_restart, loss=fit_loss, f_scale=scale)
            x, timings["lm"] = solution.x, timings["lm"] + solution.seconds
    clock = time.perf_counter()
    problem = problem.reweighted(x)  # a heavy-tailed prior's rows at their curvature here (stds, self-check)
    jac = inverse = edf = None  # report=False: none of the figures at the solution
    if report:
        jac = problem.jacobian(x)
        inverse = normal_inverse(jac)  # one SVD for both
        edf = problem.effective_unknowns(jac, inverse)
        sigma = _sigma(problem, x, edf, figures)
        std_values = predicted_std(jac, sigma, inverse)
        ident = Identifiability.of(jac)
    params, centres = problem.unpack(x)
    timings["covariance"] = time.perf_counter() - clock
    clock = time.perf_counter()
    checked = (self_check(problem, x, nominal, built, loss=figures, declared=noise_declared, unknowns=edf,
                          inverse=inverse) if check else None)
    hint, moved_by_hint = (), ()
    if checked is not None and not checked.consistent and scale is not None:
        # ``auto`` refused at least squares' figures. Where a few presses far off are all that is wrong (judged
        # without them, as --loss huber judges, the data is consistent) the refusal names them and the remedies; the
        # user decides. Writing such recordings anyway hid a wrong known distance, a share of a socket recorded in a
        # second place and rows of another arm (review). Not where the nominal model already shows a gross
        # misplacement or a socket's residual trends with recording order: those refusals name their own cause.
        moved = any(f.figures.get("trend") for f in checked.findings)
        if not moved and misplaced(nominal, dataset, spec) is None:
            if self_check(problem, x, nominal, built, loss=fit_loss, declared=noise_declared).consistent:
                hint, moved_by_hint = _far_presses(problem, x)
    timings["self_check"] = time.perf_counter() - clock
    if checked is not None and force and not checked.consistent:  # the summary says why it is written
        checked = replace(checked, forced=True)
    if checked is not None and not force:
        try:
            checked.raise_if_inconsistent()
        except InconsistentDataError as refused:
            # far presses explain it: the remedy is theirs (a crowded socket, or none for a few presses), not the
            # culprit fixture's (without a trend: a hint is only sought then)
            raise InconsistentDataError((*refused.pieces, *hint, _already_calibrated(nominal, checked)),
                                        moved_by_hint if hint else refused.moved) from None
    clock = time.perf_counter()
    check_plausible(problem, params, max_change)
    model = problem.model.with_params(params)
    after = np.linalg.norm(problem.sample_errors(x), axis=1)
    timings["plausibility"] = time.perf_counter() - clock
    warnings = list(problem.warnings)
    if report:  # what the figures at the solution say
        if sigma > NOISE_RATIO * noise and not _level_says_noise(checked):
            warnings.append(_noise_warning(problem, x, sigma, noise, noise_declared))
        if ident.condition_number > 1e8:
            warnings.append(f"ill-conditioned: condition number {ident.condition_number:.3g} at the solution")
        warnings.extend(_negative_compliances(model, problem.free, std_values))
    warnings.extend(_far_zeros(problem, params))
    if figures != "linear":  # the user's robust loss (auto judges as least squares and refuses such a socket)
        warnings.extend(_discounted_socket(problem, x, figures))
    if hint:  # written with --force: the refusal's remedy stays with the file
        warnings.append(told(hint).removeprefix("; "))
    if method == "pso" and report:
        warnings.extend(_short_of_minimum(problem, x, jac, inverse))
    return CalibrationResult(
        model=model,
        nominal=nominal,
        method=method,
        centres=problem.centre_dict(centres),
        identified=problem.identified,
        fixed=problem.fixed,
        condition_number=ident.condition_number if report else float("nan"),
        std=dict(zip(problem.unknown_names, (float(s) for s in std_values), strict=True)) if report else {},
        residual_before=before,
        residual_after=after,
        samples_per_fixture=dataset.counts(),
        warnings=tuple(warnings),
        timings=timings,
        problem=problem,
        x=x,
        selfcheck=checked,
        effective_unknowns=edf,
        data_share=dict(zip(problem.identified, (float(v) for v in problem.data_share(jac, inverse)), strict=True))
        if report else {},
        loss=fit_loss,
        loss_scale=None if fit_loss == "linear" else (scale or noise),
        loss_noise=None if scale is None else scale / ROBUST_CUT,
        fixture_noise=shown,
    )


#: Share of a fixture's samples beyond :data:`.problem.OUTLIER` x the median distance above which they are no longer a
#: few presses taken before the ball sat (the first one to three of a socket's presses) but the socket's or its
#: ball's moving: the refusal then names the fixture and advises leaving it out (a review: a joint drifting 2 deg
#: over one socket's presses put 24 of its 60 beyond, and ``--loss huber`` wrote 0.35 mm where leaving the socket
#: out wrote 0.10 mm).
MOVED_SHARE = 0.25


def _crowded(problem: CalibrationProblem, far: np.ndarray) -> tuple[str, int, int] | None:
    """(fixture, how many of the samples ``far`` (indices) it holds, its samples) when one fixture holds most of them
    and they are over :data:`MOVED_SHARE` of its samples: that socket's moving, not presses before the ball sat."""
    dataset = problem.dataset
    if not far.size:
        return None
    index = dataset.fixture_index[far]
    j = int(np.bincount(index, minlength=len(dataset.fixture_names)).argmax())
    held, total = int(np.count_nonzero(index == j)), int(np.count_nonzero(dataset.fixture_index == j))
    return (dataset.fixture_names[j], held, total) if 2 * held >= far.size and held > MOVED_SHARE * total else None


#: What a socket whose samples crowd far from it may be (:func:`_crowded`).
_CROWDED_CAUSE = ("too many for presses taken before the ball sat; the ball plays in that socket, or the socket or the "
                  "ball moved while it was recorded")


def _far_presses(problem: CalibrationProblem, x: np.ndarray) -> tuple[tuple[Piece, ...], tuple[str, ...]]:
    """The clause a refusal gains when samples far from their socket are all that is wrong (``auto``), and the
    fixture it advises leaving out: the one that holds most of them when they are over :data:`MOVED_SHARE` of its
    samples (then they are that socket's moving, not presses before the ball sat), else none."""
    dataset = problem.dataset
    far = np.flatnonzero(~problem.inliers(x))
    one = far.size == 1
    rows = "" if dataset.lines is None else f" ({row_list(dataset, far)})"
    head = (f"; {far.size} of {dataset.n_samples} samples{rows} {'lies' if one else 'lie'} over {OUTLIER:g}x the "
            f"median distance from {'its' if one else 'their'} socket, and without them the rest is consistent")
    crowded = _crowded(problem, far)
    if crowded is not None:
        name, held, total = crowded
        return (f"{head}; {'all' if held == far.size else held} of them are at fixture {name}, {held} of its {total} "
                f"samples: {_CROWDED_CAUSE}; ", Advice(name)), (name,)
    return (f"{head}: remove them if the ball was not seated in its socket, or calibrate --loss huber to discount "
            "them",), ()


def _discounted_socket(problem: CalibrationProblem, x: np.ndarray, loss: str) -> list[str]:
    """A warning when the robust ``loss`` the user chose discounted a socket's worth of samples (:func:`_crowded`):
    judged without them the self-check passes, and nothing else would say that a socket moved (a review: a joint
    drifting 2 deg over one socket put 23 of its 37 samples beyond, refused by ``auto`` and written silently by
    ``--loss huber``)."""
    crowded = _crowded(problem, np.flatnonzero(~problem.inliers(x)))
    if crowded is None:
        return []
    name, held, total = crowded
    remedy = (f" (calibrate --exclude-fixture {name} leaves it out)" if len(problem.dataset.fixture_names) > 1 else
              f"; {ONLY_FIXTURE}")  # no advice to leave out all there is
    return [f"{held} of the {total} samples at fixture {name} lie over {OUTLIER:g}x the median distance from their "
            f"socket and were discounted by the {loss} loss: {_CROWDED_CAUSE}{remedy}"]


def prior_at_shown_noise(problem: CalibrationProblem, level: float) -> CalibrationProblem:
    """``problem`` with its prior weighed at ``level`` [m], the noise per axis its least-squares residuals show
    (:attr:`.FixtureNoise.level`), where that is above the noise it assumes (no noise declared: the default
    :data:`.problem.NOISE`), and each joint's zero spread over its tolerance (:attr:`.CalibrationProblem.prior_noise`);
    else ``problem`` itself.

    The prior weight :data:`.problem.PRIOR` was measured at the default noise on arms quieter than it (MUKCa's Pandas
    and iiwa14, 0.05-0.22 mm per axis): there it holds the fit nearer nominal than their noise alone would. On an arm
    noisier than assumed the same rows would weigh the prior a fraction of what its spreads say (the Gen3 lites,
    0.5-1.4 mm: a third to a twentieth). There the prior is the Bayesian one: at the noise the data shows, with the
    spreads real arms show, a zero set by homing at 1 deg rather than 0.2 (:data:`.problem.ZERO_TOLERANCE`).
    FIGAROH's ``map`` estimation does the same (its noise from a free fit, its joint offsets at 20 mrad). MUKCa's Gen3
    lites, trained on one placement (the user's path, held-out test MAE through the file against nominal's):
    dinova_1 0.615x -> 0.597x over its three written trainings (``left`` 3.910 -> 3.576 mm, ``lower_left`` 3.663 ->
    3.634, ``raised_back`` 3.669 -> 3.701), dinova_2 ``front_rotated`` 2.546 -> 2.469 mm; either half alone does not
    help (the prior at the shown noise with zeros at 0.2 deg 0.675x, zeros at 1 deg at the default noise 0.627x and
    MUKCa's panda_6 above MUKCa's own error). The quieter arms are unchanged."""
    return replace(problem, prior_noise=float(level), _cache={}) if level > problem.noise else problem


def robust_noise(problem: CalibrationProblem, x: np.ndarray) -> float:
    """The noise per coordinate [m] the sample residuals at ``x`` show, robustly: 1.4826 x the median absolute
    residual coordinate (the normal distribution's std from its median absolute deviation; a few presses taken
    before the ball sat in its socket do not move it), at least :data:`.problem.SIGMA_FLOOR`
    (:attr:`.FixtureNoise.common`)."""
    return fixture_noise(problem, x).common


def check_plausible(problem: CalibrationProblem, params: np.ndarray, max_change: float = MAX_CHANGE) -> None:
    """Refuse a calibrated model that moves the tool point implausibly far from the start model.

    Real arms differ from their design by millimetres: the parameter spread of :func:`.problem.tolerance`
    (1 mm, 0.2 deg, a joint's zero 1 deg) moves the tool point by ``typical`` (RMS over the workspace, the gauge
    parameters left out). A fit whose tool points, after the best rigid fit, move ``max_change``
    times further than that has fitted noise along directions the samples barely see and would make
    the arm less accurate than its nominal model. Judged on tool points, not parameters: along a
    degenerate direction (``alpha7`` against the tool point when it sits near the last axis)
    parameters may move far while every tool point stays right.

    Raises:
        ImplausibleCalibrationError: one line naming the samples file, rows and the parameter that
            moved most (in prior spreads).
    """
    model = problem.model
    change, typical = tool_point_change(model, params)
    if change <= max_change * typical:
        return
    free = problem.free
    ratio = np.abs(params - model.params)[free] / tolerance(model)[free]
    worst = int(np.argmax(ratio))
    name = model.param_names[free[worst]]
    dataset = problem.dataset
    remedy = ("the samples do not determine the parameters; record more self-motion (wider joint ranges, more "
              "fixtures or known distances)")
    start = float(np.sqrt(np.mean(problem.start_distances() ** 2)))
    if start > MAX_SOCKET_NOISE:  # no arm is that far off its own description: another arm's file (review, stop 9)
        remedy = (f"the nominal model puts the samples {start * 1e3:.3g} mm rms from their fixtures' centres, farther "
                  f"than a ball held in a socket moves (at most {MAX_SOCKET_NOISE * 1e3:g} mm): is the robot file this "
                  "arm's, its tool point the ball's (an adapter or sensor it lacks), its DH convention and units?")
    raise ImplausibleCalibrationError(
        f"{samples_location(dataset)}, field '{name}': the fit moves the tool point "
        f"{change * 1e3:.1f} mm from the nominal model (mean over the workspace; a real arm's errors move it "
        f"about {typical * 1e3:.1f} mm, limit {max_change:g}x), changing {name} by "
        f"{model.layout.format(name, params[free[worst]] - model.params[free[worst]])}: {remedy}"
    )


#: A joint's zero moved more than this many :data:`.problem.ZERO_TOLERANCE` by the fit gets a warning (3 deg).
FAR_ZERO = 3.0


def _far_zeros(problem: CalibrationProblem, params: np.ndarray) -> list[str]:
    """One warning naming the joints whose zero the fit moved beyond :data:`FAR_ZERO` tolerances: within the
    plausibility limit, which counts a zero at 1 deg, but more than the real arms measured here are off (at most 3
    deg): a robot file whose zero, convention or joint order is not this arm's is calibrated as well as one socket
    allows and no better (a review, stop 10: a file 5 deg off on joint 4, one socket at 1-3 mm of noise, 22 mm from
    the truth against 35 nominal, predicted 2.7)."""
    model = problem.model
    zeros = [i for i in zero_indices(model) if i in set(problem.free.tolist())]
    far = [i for i in zeros if abs(params[i] - model.params[i]) > FAR_ZERO * ZERO_TOLERANCE]
    if not far:
        return []
    moved = ", ".join(f"{model.param_names[i]} {np.rad2deg(params[i] - model.params[i]):+.2f} deg" for i in far)
    return [f"the fit moved {moved}, beyond the {FAR_ZERO * np.rad2deg(ZERO_TOLERANCE):g} deg a real arm's joint zero "
            "is off: check the robot file (its joint zeros and order, convention, units) against this arm"]


def tool_point_change(model: RobotModel, params: np.ndarray, zeros: bool = True) -> tuple[float, float]:
    """(change, typical) [m]: how far ``params`` move ``model``'s tool points (mean over the seeded workspace
    configurations, after the best rigid fit), and how far a real arm's errors (:func:`.problem.tolerance`, gauge
    and base left out) typically move them: what :func:`check_plausible` compares. ``zeros=False``: the joints'
    zeros at their prior spread too (:func:`.tool_fit.recentred_tool` judges a tool against the geometry's errors,
    not against a zero's)."""
    q, start_points, typical = _plausibility_reference(model, zeros)
    return float(registered_errors(tool_point(model.with_params(params), q), start_points).mean()), typical


def _plausibility_reference(model: RobotModel, zeros: bool = True) -> tuple[np.ndarray, np.ndarray, float]:
    """What :func:`check_plausible` judges a fit starting from ``model`` against: the configurations
    ((C, n) [rad], seeded), the start model's tool points there ((C, 3) [m]) and the tool-point change a real
    arm's errors typically cause [m] (``zeros``: see :func:`tool_point_change`). They depend on the start model
    alone, so they are computed once per model content and reused (every fold of one model-selection candidate
    and the final fit start from the same model: 13 fits, 4 distinct start models)."""
    key = (
        model.convention, model.hayati, model.params.tobytes(), model.lower.tobytes(), model.upper.tobytes(),
        repr(model.extras),  # compliance, scale, inertials: what the tool point depends on beside the geometry
        zeros,
    )
    with _REFERENCES_LOCK:  # a Dask worker may run calibrations in threads
        found = _REFERENCES.get(key)
    if found is None:
        q = model.random_configurations(PLAUSIBILITY_CONFIGURATIONS, np.random.default_rng(0))
        prior = tolerance(model) if zeros else prior_std(model)
        prior[[model.param_index(name) for name in GAUGE[model.convention]]] = 0.0
        prior[model.layout.base] = 0.0
        typical = float(np.sqrt(((param_jacobian(model, q) * prior) ** 2).sum(axis=(1, 2))).mean())
        found = (q, tool_point(model, q), typical)
        for array in found[:2]:
            array.setflags(write=False)
        with _REFERENCES_LOCK:
            if len(_REFERENCES) >= _MAX_REFERENCES:
                _REFERENCES.pop(next(iter(_REFERENCES)))  # the oldest
            _REFERENCES[key] = found
    return found


#: :func:`_plausibility_reference` by start model content (a few: the model-selection candidates).
_REFERENCES: dict[tuple, tuple[np.ndarray, np.ndarray, float]] = {}
_REFERENCES_LOCK = threading.Lock()
_MAX_REFERENCES = 8


#: ``--method pso`` alone is named as short of the minimum when one Gauss-Newton step lowers the cost by this share.
SHORT_OF_MINIMUM = 0.1


def _short_of_minimum(problem: CalibrationProblem, x: np.ndarray, jac: np.ndarray, inverse: np.ndarray) -> list[str]:
    """One warning when a particle swarm's solution ``x`` (F,) is not the least-squares minimum: one Gauss-Newton
    step from it (``jac`` (M, F) and ``inverse = (J^T J)^-1`` there) lowers the cost ``|r|^2`` by
    ``g^T (J^T J)^-1 g``, ``g = J^T r``, more than :data:`SHORT_OF_MINIMUM` of it. PSO alone stops near the minimum,
    not at it (MUKCa's panda_2 front_center: 0.95 mm per axis where lm reaches 0.16 mm), and the self-check judges
    the point it is given: a calibration worse than the data allows would be written as consistent."""
    r = problem.residuals(x)
    g = jac.T @ r
    cost, gain = float(r @ r), float(g @ inverse @ g)
    if cost <= 0 or gain <= SHORT_OF_MINIMUM * cost:
        return []
    rows = 3 * problem.dataset.n_samples
    now = float(np.sqrt(np.mean(r[:rows] ** 2)))
    after = float(np.sqrt(np.mean((r + jac @ (-inverse @ g))[:rows] ** 2)))
    return [f"--method pso stopped short of the least-squares minimum: one Gauss-Newton step from it lowers the cost "
            f"by {100 * gain / cost:.0f}% (samples' residual {now * 1e3:.3g} -> {after * 1e3:.3g} mm per axis); "
            "--method pso+lm polishes the swarm's best with Levenberg-Marquardt"]


#: A fitted joint compliance this many stds below zero is named (:func:`_negative_compliances`).
NEGATIVE_STDS = 2.0


def _negative_compliances(model: RobotModel, free: np.ndarray, std: np.ndarray) -> list[str]:
    """One warning naming the identified joint compliances more than :data:`NEGATIVE_STDS` std below zero
    (``free``: (F,) indices of the identified parameters, ``std``: their stds first).

    No joint gives against its load: a negative compliance is the fit using the term for another error that
    varies with the gravity torque at that joint (a link that bends, an axis that sags, what the other parameters
    leave; MUKCa's Pandas fit c2 at -14 +- 6 urad/Nm). It still describes the arm where the data was recorded, and
    the controller's compensation applies it as fitted; the user must not read it as a stiffness.
    """
    layout, params = model.layout, model.params
    found = [f"{layout.names[i]} {params[i] * 1e6:.3g} +- {s * 1e6:.2g} urad/Nm"
             for i, s in zip(free, std[: len(free)], strict=True)
             if layout.kinds[i] is COMPLIANCE and params[i] < -NEGATIVE_STDS * s]
    if not found:
        return []
    return [f"negative joint compliance: {', '.join(found)}: no joint gives against its load; the elastic model "
            "uses the term for another error that varies with the gravity torque at that joint (a link that bends, "
            "an axis that sags): an effective correction where the data was recorded, not a stiffness"]


def _level_says_noise(checked: SelfCheck | None) -> bool:
    """The self-check ran and its residual level says the residuals exceed the noise (failed, or passed with the
    warning of residuals judged at the noise they show): :func:`_noise_warning` would say it again with other figures
    (a review: 'residual noise 1.22 mm per axis is 4.07x' above the level's '1.09 mm ... (the samples alone 1.22 mm)
    ... 3.62x'; the level's accounts for the prior's rows)."""
    if checked is None:
        return False
    level = next((f for f in checked.findings if f.check == "residual level"), None)
    return level is not None and (not level.passed or bool(level.figures.get("honest_noise_warning")))


def _noise_warning(problem: CalibrationProblem, x: np.ndarray, sigma: float, noise: float,
                   declared: bool = True) -> str:
    """The residuals are far above the expected noise: say so, naming the most strained known distance (``declared``:
    the noise is the user's ``--noise``, else the default the fit assumes). Only where the self-check's residual level
    does not say it (:func:`_level_says_noise`): a fit without the self-check (``check=False``), or one whose level
    passed."""
    expected = (f"the expected {noise * 1e3:.3g} mm (--noise)" if declared else
                f"the {noise * 1e3:.3g} mm the fit assumes (none declared; --noise states it)")
    text = (
        f"residual noise {sigma * 1e3:.3g} mm per axis is {sigma / noise:.3g}x {expected}: check the known distances "
        "and positions, whether a fixture moved during recording, or --noise"
    )
    distances = problem.spec.distances
    if distances:
        strain = np.abs(problem.residuals(x)[3 * problem.dataset.n_samples :][: len(distances)])
        k = int(np.argmax(strain))
        a, b, value = distances[k]
        text += f"; the most strained distance is {a}-{b} ({value:.6g} m in {problem.spec.source or 'the fixtures'})"
    return text


def _sigma(problem: CalibrationProblem, x: np.ndarray, unknowns: float | None = None, loss: str = "linear") -> float:
    """Residual standard deviation per coordinate [m] of the data rows (:meth:`CalibrationProblem.data_sigma`);
    with a robust loss, of the samples it did not discount (:meth:`CalibrationProblem.inliers`): ten
    slipped samples of 100 mm read as 5 mm of noise pruned all but one parameter of MUKCa's Panda."""
    if loss != "linear":
        problem = problem.with_samples(problem.inliers(x))
    return problem.data_sigma(x, unknowns)
