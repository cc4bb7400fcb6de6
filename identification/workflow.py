"""One calibration workflow: dedup, subsample, model selection, calibrate, the result file's block.

What ``spherecal calibrate`` does, as one library call (the command parses, calls
:func:`calibrate_files`, prints), and what the campaign and the bench scripts call on data they
already hold (:func:`run_workflow`)::

    options = WorkflowOptions(model="auto", seed=0)
    done = run_workflow(nominal, dataset, spec, options)
    done.model                      # the calibrated robot, its extras["calibration"] block filled
    print(done.summary())

Cross-validation folds of the model selection are fitted with ``lm``, the user's loss and noise and
*without* the self-check: the self-check judges the calibration that is written, not each fold's (a
fold's refusal would only turn ``auto`` back to ``dh`` for a reason that says nothing about the models,
and it costs a self-check per fold), and without the stds and figures at their solution (``report=False``:
a fold is judged by its model alone).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from spherecal.correction import RobotModel, load_robot, save_robot
from spherecal.correction.errors import SpherecalError
from spherecal.correction.files.fixtures import FixtureSpec, read_fixtures
from spherecal.correction.files.outputs import OutputSet
from spherecal.correction.files.provenance import provenance
from spherecal.correction.files.samples import DEDUP_TOL, Dataset
from spherecal.correction.files.samples_csv import read_samples
from spherecal.correction.tool import TIP_MOVED

from .build import build_problem
from .calibrate import MAX_CHANGE, CalibrationResult, calibrate
from .misplaced import misplaced
from .problem import NOISE, PRIOR, ImplausibleCalibrationError
from .selection import ModelSelection, listed, select_model, start_for
from .selfcheck_result import InconsistentDataError
from .tool_fit import recentred_tool
from .training import exclude_fixtures, training_record


@dataclass(frozen=True)
class WorkflowOptions:
    """How to calibrate (every field is recorded in the result file's ``options``).

    Attributes:
        method: ``lm``, ``pso`` or ``pso+lm``.
        model: ``dh``, ``elastic``, ``scale``, ``elastic+scale`` or ``auto`` (:mod:`.selection`).
        loss: ``auto`` (default: least squares, then Huber at the scale the residuals show,
            :func:`.calibrate.calibrate`), ``linear``, ``soft_l1`` or ``huber``.
        noise: declared fixture noise std per axis [m], or None (default): not declared, the fit weighs the
            samples at :data:`.problem.NOISE` and the self-check judges the accuracy at the noise the residuals
            show (a declared noise is a floor of that judgement: :func:`.selfcheck.self_check`).
        max_per_fixture: keep at most this many samples per fixture (random, seeded), None for all.
        dedup_tol: drop a sample within this of an earlier one of its fixture, every joint [rad];
            None keeps every sample.
        max_change: plausibility limit (:func:`.calibrate.check_plausible`), a factor.
        force: write even when the self-check finds the data inconsistent.
        seed: seeds subsampling, cross-validation and PSO.
        prior: weight ``W`` of the prior toward the nominal model (:mod:`.problem`), 0 = plain least squares.
        exclude_fixtures: fixtures left out (their samples and every known distance naming them).
    """

    method: str = "lm"
    model: str = "auto"
    loss: str = "auto"
    noise: float | None = None
    max_per_fixture: int | None = None
    dedup_tol: float | None = DEDUP_TOL
    max_change: float = MAX_CHANGE
    force: bool = False
    seed: int = 0
    prior: float = PRIOR
    exclude_fixtures: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        # pso fits least squares: a robust loss would be ignored and recorded as used (auto resolves to linear)
        if self.method == "pso" and self.loss not in ("linear", "auto"):
            raise SpherecalError(f"field '--loss': {self.loss}: the pso method fits plain least squares; a robust "
                                 "loss needs --method lm or pso+lm (its lm stage)")

    @property
    def fit_noise(self) -> float:
        """The noise the fit weighs the samples at [m]: the declared one, else :data:`.problem.NOISE`."""
        return NOISE if self.noise is None else self.noise

    def record(self) -> dict:
        """The ``options`` entry of the result file (metres, radians; the seed is recorded beside it)."""
        return {
            "method": self.method,
            "loss": self.loss,
            "noise_m": self.fit_noise,
            "noise_declared": self.noise is not None,
            "max_per_fixture": self.max_per_fixture,
            "dedup_tol_rad": None if self.dedup_tol is None else float(self.dedup_tol),
            "max_change": self.max_change,
            "model": self.model,
            "force": self.force,
            "prior": self.prior,
            "exclude_fixture": list(self.exclude_fixtures),
        }


@dataclass(frozen=True, eq=False)
class WorkflowResult:
    """A calibration as the workflow made it.

    Attributes:
        model: the calibrated robot; ``extras["calibration"]`` holds :attr:`block`.
        result: the final fit (:class:`.calibrate.CalibrationResult`).
        selection: what model selection found.
        duplicates_dropped: samples dropped as duplicates.
        dedup_tol: the tolerance used [rad] (None: no deduplication).
        block: the ``calibration:`` block of the result file (plain Python).
    """

    model: RobotModel
    result: CalibrationResult
    selection: ModelSelection
    duplicates_dropped: int
    dedup_tol: float | None
    block: dict

    def summary(self) -> str:
        """The fit's summary, the model choice, and the duplicates dropped."""
        lines = [self.result.summary(), self.selection.summary()]
        if self.duplicates_dropped:
            lines.append(f"dropped {self.duplicates_dropped} duplicate samples "
                         f"(within {np.rad2deg(self.dedup_tol):.3g} deg)")
        return "\n".join(lines)


def run_workflow(nominal: RobotModel, dataset: Dataset, spec: FixtureSpec | None,
                 options: WorkflowOptions = WorkflowOptions(), start: RobotModel | None = None,
                 inputs: dict | None = None, try_remedy: bool = True) -> WorkflowResult:
    """Deduplicate, subsample, select the model, calibrate and assemble the result block.

    Args:
        nominal: the robot to calibrate.
        dataset: the samples, as read.
        spec: known fixture positions and distances (None: all unknown).
        options: how (:class:`WorkflowOptions`).
        start: start of the final optimisation (default ``nominal``; rigid or elastic as chosen).
        inputs: name -> input file (a :class:`~pathlib.Path`, recorded with its digest) or value, for
            the provenance block (``correction.files.provenance.provenance``).
        try_remedy: a refusal that names fixtures to leave out (whose residual trends with recording order, or the
            one fixture that alone explains the inconsistency) says what that gives: this workflow is run again
            without them (the strongest trend first, then the next, up to all of them), and the refusal ends with
            its verdict (the rest written without the fewest that suffice, or refused too), so that the advice is
            never a loop.

    Returns:
        The :class:`WorkflowResult`.

    Raises:
        SpherecalError: the data cannot support the calibration (see :func:`.calibrate.calibrate`).
    """
    recorded = (dataset, spec)  # as given, for the remedy's run
    dataset, spec = exclude_fixtures(dataset, spec, options.exclude_fixtures)
    as_read = dataset
    read = dataset.n_samples
    if options.dedup_tol is not None:
        dataset = dataset.deduplicated(options.dedup_tol)
    dropped = read - dataset.n_samples
    dataset = dataset.subsampled(options.max_per_fixture, np.random.default_rng(options.seed))
    given = nominal
    nominal, tool_note = recentred_tool(nominal, dataset, options.max_change)

    candidate_loss = "linear" if options.loss == "auto" else options.loss  # auto's Huber: the final fit's

    def fit(begin, data, fixtures, warm=None, report=True):  # a candidate's or a fold's fit: lm, no self-check
        return calibrate(begin, data, fixtures, start=warm, loss=candidate_loss, noise=options.fit_noise,
                         max_change=options.max_change, check=False, prior=options.prior, report=report,
                         noise_declared=options.noise is not None)

    def fold_fit(begin, data, fixtures, warm=None):  # a fold's model alone is judged: no stds or figures
        return fit(begin, data, fixtures, warm, report=False)

    def refusal(refused: SpherecalError) -> SpherecalError:  # its named cause, or the remedy's verdict
        named = _named_cause(refused, nominal, dataset, spec, options)
        if named is refused and try_remedy and getattr(refused, "moved", ()):
            named = _remedy_tried(refused, given, *recorded, options, start)
        return named

    try:
        selection = select_model(options.model, fit, nominal, dataset, spec, seed=options.seed,
                                 robust=candidate_loss != "linear", fold_fit=fold_fit)
    except (InconsistentDataError, ImplausibleCalibrationError) as refused:
        raise refusal(refused) from None
    begin = start_for(selection.chosen, nominal)
    if start is not None:
        warm = start_for(selection.chosen, start)
    elif selection.fits and selection.chosen in selection.fits and options.method == "lm":
        warm = selection.fits[selection.chosen].model  # its full fit: the final solve starts at the answer
    else:
        warm = None
    try:
        result = calibrate(
            begin, dataset, spec, method=options.method, start=warm, seed=options.seed, loss=options.loss,
            noise=options.fit_noise, max_change=options.max_change, force=options.force, prior=options.prior,
            noise_declared=options.noise is not None,
        )
    except (InconsistentDataError, ImplausibleCalibrationError) as refused:
        raise refusal(refused) from None
    if tool_note is not None:  # 'before' is the robot file as given, not the tool the samples showed
        shift = (result.model.tool - given.tool) * 1e3  # the table's tool rows count from the samples' tool
        tool_note += (f"; calibrated, [{shift[0]:.1f}, {shift[1]:.1f}, {shift[2]:.1f}] mm from the robot file's (the "
                      "tool rows of the table count from where the samples put it)")
        before = build_problem(given, dataset, spec, noise=options.fit_noise).start_distances()
        result = replace(result, residual_before=before, warnings=(tool_note, *result.warnings))
    block = result.block()
    block["model_selection"] = selection.block()
    if selection.seconds:
        block["timings_s"]["model_selection"] = selection.seconds
    block["duplicates_dropped"] = dropped
    block["nominal_tool"] = [float(v) for v in given.tool]  # a tool swap carries the tool's correction over
    # where the samples put the ball, when beyond a calibration's correction of the file's tool: a tool swap and a
    # controller must be told whether that offset is an adapter every tool sits on (correction.tool.with_tool)
    shown = nominal.tool if tool_note is not None else result.model.tool
    if np.linalg.norm(shown - given.tool) > TIP_MOVED:
        block["samples_tool"] = [float(v) for v in shown]
    block["trained_on"] = training_record(as_read, dataset)  # validate recognises these samples by content
    block["options"] = options.record()
    block["provenance"] = provenance(options.seed, {**(inputs or {}), **options.record()})
    extras = {k: v for k, v in result.model.extras.items() if k != "calibration"}  # compliance, scale
    extras["calibration"] = block
    return WorkflowResult(replace(result.model, extras=extras), result, selection, dropped, options.dedup_tol,
                          block)


def _named_cause(refused: SpherecalError, nominal: RobotModel, dataset: Dataset, spec: FixtureSpec | None,
                 options: WorkflowOptions) -> SpherecalError:
    """A refusal with the cause the nominal model already shows in its place (:func:`.misplaced.misplaced`:
    samples of two sockets under one name, samples in the wrong socket, a wrong known distance), if any."""
    cause = misplaced(nominal, dataset, spec, discounted=options.loss in ("soft_l1", "huber"))
    return refused if cause is None else type(refused)(cause)


def _remedy_tried(refused: InconsistentDataError, nominal: RobotModel, dataset: Dataset, spec: FixtureSpec | None,
                  options: WorkflowOptions, start: RobotModel | None) -> InconsistentDataError:
    """``refused``, which names fixtures to leave out (:attr:`.InconsistentDataError.moved`, in the order to try them:
    the fixture that stands out, then the strongest trend first), ending with what that gives. The workflow runs
    again without the first, then without the first two, ..., until the rest is written (the advice holds for those:
    the others are not left out, a socket that did not move keeps its samples and its known distances) or every one
    is left out and the rest is refused too (then leaving them out does not help: a real Gen3 lite's drifting socket
    left one socket that cannot be calibrated, and the advice sent the user from one refusal to the next)."""
    names = refused.moved

    def flags(left_out: tuple[str, ...]) -> str:  # the command line of the run without them
        return " ".join(f"--exclude-fixture {name}" for name in (*options.exclude_fixtures, *left_out))

    for count in range(1, len(names) + 1):
        left_out = names[:count]
        without = replace(options, exclude_fixtures=(*options.exclude_fixtures, *left_out))
        try:
            done = run_workflow(nominal, dataset, spec, without, start=start, try_remedy=False)
        except SpherecalError:
            continue
        except Exception:  # noqa: BLE001 - the remedy's run is advice: a fault in it must not hide the refusal itself
            return refused
        them = listed(left_out)
        check = done.result.selfcheck
        # whether it warns, not how often: the run also prints the robot file's and the recording's own warnings,
        # and the self-check's trend lines carry no 'warning:' label, so a count never matched what it prints (a
        # review: 'with 4 warnings' where the run printed 5 'warning:' lines, 'with 5' where it printed 4)
        warned = ", with warnings" if done.result.warnings or (check is not None and check.warnings) else ""
        return InconsistentDataError((*refused.pieces, f"; without {them} the rest is consistent and is written"
                                                        f"{warned} (calibrate {flags(left_out)})"), left_out)
    them = listed(names)
    # the advice tried: what is left of it, 'record it again' (h8's trial read 'leave it out', then 'does not help')
    return InconsistentDataError(f"{refused.told(names)}; leaving {them} out does not help: without {them} the rest "
                                 f"is refused too (calibrate {flags(names)} says why)", names)


def calibrate_files(robot: str, samples: str | Path, fixtures: str | Path | None, out: str | Path,
                    options: WorkflowOptions = WorkflowOptions(), outputs: OutputSet | None = None,
                    **robot_options) -> WorkflowResult:
    """Read the robot, samples and fixtures files, run :func:`run_workflow`, write ``out`` atomically.

    Args:
        robot: robot name or file (``correction.load_robot``).
        samples: samples CSV.
        fixtures: fixtures YAML, or None.
        out: calibrated robot file to write (YAML).
        options: how (:class:`WorkflowOptions`).
        outputs: the staged outputs holding ``out`` (checked by the caller before any work); a fresh
            one when None.
        **robot_options: keyword arguments of ``load_robot`` (a URDF's base and tip links).

    Returns:
        The :class:`WorkflowResult`; nothing is written when it raises.
    """
    nominal = load_robot(robot, **robot_options)
    dataset = read_samples(samples, nominal)
    spec = read_fixtures(fixtures) if fixtures else None
    inputs = {"robot": Path(robot), "samples": Path(samples)}
    if fixtures:
        inputs["fixtures"] = Path(fixtures)
    done = run_workflow(nominal, dataset, spec, options, inputs=inputs)
    header = f"calibrated by spherecal calibrate ({options.method}) from {samples}"
    outputs = OutputSet({"--out": out}) if outputs is None else outputs
    with outputs:
        save_robot(done.model, outputs.stage(out), header=header)
    return done
