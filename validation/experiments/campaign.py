"""Campaigns: the paper's simulated protocol and its Table 2.

For each fixture set (``P1``, ``P2``, ``P3`` alone, and ``Pall``: all three with their distances
known) and each noise level (none, 0.3 mm): ``sets`` motion sets (10), each a fresh seeded true robot
with ``samples`` configurations per fixture (500) drawn from its self-motion, calibrated from the
nominal model and validated on random workspace configurations against the exact tool point. A
set's *average* error is the mean over those configurations, its *maximal* error the max; the table
gives, per row, the mean, std and max over the sets of both (mm), as the paper's Table 2.

Two protocols:

* ``realistic`` (default): the true robot is the nominal Panda perturbed (1 mm, 0.2 deg, 1 mm tool),
  the calibration starts from and is anchored to the nominal model, as on a real arm.
* ``paper``: as the paper's simulation, the true robot IS the nominal model and the optimisation
  starts from a perturbed one; a single fixture's centre is pinned at the mean of the nominal (=
  true) forward kinematics, so its scale is exact.

Every task is seeded from ``(seed, row, set)`` alone, so the table does not depend on the number of
workers, on where they run (this process, the process pool, a Dask cluster: :mod:`validation.parallel`)
or on the order the tasks finish in.
"""

from __future__ import annotations

import csv
import io
import os
import time
from collections.abc import Callable, Iterable
from concurrent.futures import Executor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spherecal.correction import SpherecalError
from spherecal.correction.elastic import with_stiffness
from spherecal.correction.files.earlier_run import refuse_unless_own, written_by
from spherecal.correction.files.outputs import OutputSet
from spherecal.correction.files.provenance import comment_block, provenance
from spherecal.identification.workflow import WorkflowOptions, run_workflow

from .. import parallel
from ..parallel import Failure, run_tasks
from ..pipeline import RANDOM_SET, validate_models
from ..progress import progress_bar
from .experiment import ExperimentError, default_fixtures, motion_set, nominal_robot, true_robot

#: The paper's simulated Table 2 (mm): row -> (mean of average error, mean of maximal error).
PAPER_TABLE2 = {
    "P1": (0.00, 0.01),
    "P2": (0.10, 0.34),
    "P3": (0.01, 0.03),
    "P1N": (0.24, 0.50),
    "P2N": (0.99, 2.87),
    "P3N": (0.27, 0.87),
}
FIXTURE_SETS: dict[str, tuple[str, ...]] = {"P1": ("P1",), "P2": ("P2",), "P3": ("P3",), "Pall": ("P1", "P2", "P3")}
NOISE_LEVELS = (0.0, 0.3e-3)  # [m] fixture noise in the calibration data


@dataclass(frozen=True)
class CampaignConfig:
    """The protocol's sizes.

    Attributes:
        sets: motion sets per row.
        samples: samples per fixture in each set.
        configurations: random workspace configurations each set is validated on.
        seconds: simulated self-motion per fixture [s] (MuJoCo source).
        source: ``"mujoco"`` (self-motion through the QP controller on the plant) or ``"synthetic"``
            (kinematic spherical-joint data, no dynamics).
        protocol: ``"realistic"`` or ``"paper"`` (see the module docstring).
        seed: base seed.
        fixture_sets: names of the fixture sets to run (keys of :data:`FIXTURE_SETS`).
        noise_levels: fixture noise levels [m].
        stiffness: (n,) joint stiffness of the true robot [Nm/rad], 0 = rigid (empty: a rigid arm); its links
            sag under gravity (:mod:`correction.elastic`); rows get an ``E``.
        model: what is calibrated: ``dh``, ``elastic`` or ``auto`` (identification.selection); rows other
            than ``dh`` get ``/elastic`` or ``/auto``.
    """

    sets: int = 10
    samples: int = 500
    configurations: int = 5000
    seconds: float = 20.0
    source: str = "synthetic"
    protocol: str = "realistic"
    seed: int = 0
    fixture_sets: tuple[str, ...] = tuple(FIXTURE_SETS)
    noise_levels: tuple[float, ...] = NOISE_LEVELS
    stiffness: tuple[float, ...] = ()
    model: str = "dh"


@dataclass(frozen=True)
class Task:
    """One motion set of one row: what a worker needs, nothing else.

    Attributes:
        row: the row's name in Table 2 (``P1``, ``PallN``, ``P2E/elastic``): a label, never parsed.
        fixture_set: the fixture set (a key of :data:`FIXTURE_SETS`): what ``--rows`` takes to run the row again.
        noise: fixture noise std [m].
        index: the set's number in its row.
        seed: what the set's generator is seeded from.
        config: the protocol.
    """

    row: str
    fixture_set: str
    noise: float
    index: int
    seed: tuple[int, ...]
    config: CampaignConfig

    @property
    def fixtures(self) -> tuple[str, ...]:
        """The fixtures of :attr:`fixture_set`."""
        return FIXTURE_SETS[self.fixture_set]


@dataclass(frozen=True)
class TaskResult:
    """A motion set's outcome: average and maximal error [m] against the exact tool point, and
    the same against a simulated 0.3 mm mocap (for reference)."""

    row: str
    index: int
    mean: float
    max: float
    mocap_mean: float
    nominal_mean: float
    seconds: float
    refused: str = ""  # the one-line reason when the calibration refused this set's data


def row_name(fixture_set: str, noise: float) -> str:
    """``P1`` / ``P1N`` as in the paper (N: with noise)."""
    return fixture_set + ("N" if noise > 0 else "")


def tasks(config: CampaignConfig) -> list[Task]:
    """Every (row, set) task, seeded from (seed, row number, set number).

    The row number is the row's place in the full table (noise level, then :data:`FIXTURE_SETS`
    order), so a row gives the same sets whichever other rows are run with it.
    """
    out = []
    names = list(FIXTURE_SETS)
    for level, noise in enumerate(config.noise_levels):
        for name in config.fixture_sets:
            row = level * len(names) + names.index(name)
            for index in range(config.sets):
                seed = (config.seed, row, index)
                label = row_name(name, noise) + ("E" if any(config.stiffness) else "")
                label += "" if config.model == "dh" else f"/{config.model}"
                out.append(Task(label, name, noise, index, seed, config))
    return out


def run_task(task: Task) -> TaskResult:
    """Simulate one motion set on a fresh true robot, calibrate, validate (runs in a worker)."""


    clock = time.perf_counter()
    rng = np.random.default_rng(task.seed)
    nominal = nominal_robot()
    perturbed = true_robot(nominal, rng)
    if task.config.protocol == "paper":
        truth, start = nominal, perturbed
    else:
        truth, start = perturbed, nominal
    fixtures = {name: default_fixtures()[name] for name in task.fixtures}
    if any(task.config.stiffness):
        truth = with_stiffness(truth, task.config.stiffness)
    data = motion_set(
        truth, start, fixtures, task.config.samples, task.noise, rng, task.config.source, task.config.seconds
    )
    try:
        calibrated = _calibrate(task.config.model, nominal, start, data, task.config.protocol == "paper")
    except SpherecalError as error:  # a refusal is a result of the protocol, not a crash of the campaign
        nan = float("nan")
        return TaskResult(task.row, task.index, nan, nan, nan, nan, time.perf_counter() - clock, str(error))
    report = validate_models(start, calibrated, rng, truth=truth, configurations=task.config.configurations)
    random = report.comparison(RANDOM_SET)
    return TaskResult(
        row=task.row,
        index=task.index,
        mean=random.vs_exact["calibrated"].mean,
        max=random.vs_exact["calibrated"].max,
        mocap_mean=random.vs_mocap["calibrated"].mean,
        nominal_mean=random.vs_exact["nominal"].mean,
        seconds=time.perf_counter() - clock,
    )


def _calibrate(model: str, nominal, start, data, paper: bool = False):
    """The calibrated robot of ``model`` (a candidate of identification.selection or ``auto``): the library's one
    workflow (identification.workflow), every sample kept, its cross-validation folds not self-checked, and no
    prior toward the nominal model (plain least squares, as the paper: in the ``paper`` protocol the nominal
    model IS the true robot, a prior toward it would flatter the calibration).

    ``paper``: written whatever the self-check says (``force``). Its nominal model is the true robot, which fits the
    samples already: the self-check refused every set ('there is nothing here to calibrate', 80 of 80; h10's docs
    walk-through), which is right for a user's arm and meaningless for the paper's protocol."""
    options = WorkflowOptions(model=model, dedup_tol=None, prior=0.0, force=paper)
    return run_workflow(nominal, data.dataset, data.spec, options, start=start).model


@dataclass(frozen=True)
class CampaignRun:
    """The outcome of :func:`run_campaign`.

    Attributes:
        results: the finished tasks' results, in (row order, set index): independent of scheduling.
        failures: the tasks that raised (each also reported by a TaskFailedWarning), not in ``results``.
        workers: worker -> its package versions (for the provenance of the files written).
        failed_rows: the row of each task in ``failures``, in the same order.
        rows: every row of the campaign, in table order (a row whose every set failed is one of them).
        failed_sets: the fixture set of each task in ``failures`` (:attr:`Task.fixture_set`), in the same order:
            the ``--rows`` that runs them again.
    """

    results: list[TaskResult]
    failures: list[Failure]
    workers: dict[str, dict[str, str]]
    failed_rows: tuple[str, ...] = ()
    rows: tuple[str, ...] = ()
    failed_sets: tuple[str, ...] = ()

    def table(self) -> list[TableRow]:
        """Table 2 of this run: every row of the campaign in its order, the failed sets counted in their rows."""
        return table(self.results, self.failed_rows, self.rows)


def run_campaign(
    config: CampaignConfig,
    workers: int = 2,
    progress: bool = True,
    runner: Callable[[Task], TaskResult] = run_task,
    executor: Executor | None = None,
    scheduler: str | None = None,
) -> CampaignRun:
    """Run every task with a progress bar that follows finished tasks (:func:`..progress.progress_bar`: on a
    terminal only).

    Args:
        config: the protocol.
        workers: processes of the built-in pool (1: in this process), or of ``scheduler="local"``.
        progress: show the progress bar (when stderr is a terminal).
        runner: the task function (module-level: it is sent to the workers).
        executor: run on this executor instead (any concurrent.futures.Executor, e.g. a Dask
            client's ``get_executor()``); ``workers`` and ``scheduler`` are then unused.
        scheduler: a dask.distributed scheduler's address, or ``"local"`` (see :func:`validation.parallel.executor`).
    """
    todo = tasks(config)
    names = [f"{task.row} set {task.index}" for task in todo]
    # a bar on a pipe or log file (tqdm's default) put lines before a refusal's one line on stderr
    with progress_bar(len(todo), "campaign", "set", quiet=not progress) as update:
        if executor is not None:
            outcome = run_tasks(runner, todo, executor, names, update)
        else:
            with parallel.executor(workers, scheduler) as own:
                outcome = run_tasks(runner, todo, own, names, update)
    results = [result for result in outcome.results if result is not None]
    failed = [task for task, result in zip(todo, outcome.results, strict=True) if result is None]
    return CampaignRun(results, outcome.failures, outcome.workers, tuple(task.row for task in failed),
                       tuple(dict.fromkeys(task.row for task in todo)), tuple(task.fixture_set for task in failed))


@dataclass(frozen=True)
class TableRow:
    """One row of Table 2: statistics over the motion sets [m]."""

    name: str
    sets: int
    average: tuple[float, float, float]  # mean, std, max of the sets' average errors
    maximal: tuple[float, float, float]  # mean, std, max of the sets' maximal errors
    mocap_average: float  # mean of the sets' average error against a 0.3 mm mocap
    nominal_average: float  # mean of the nominal model's average error
    refused: int = 0  # sets whose data the calibration refused (not in the statistics)
    failed: int = 0  # sets that raised (not in the statistics): the row is incomplete


def table(results: list[TaskResult], failed: Iterable[str] = (), order: Iterable[str] = ()) -> list[TableRow]:
    """Aggregate task results into Table 2 rows.

    Args:
        results: the finished sets.
        failed: the row of each set that raised: counted in its row's ``failed``, a row whose every set raised kept
            (no statistics), so that the table says it is incomplete.
        order: rows in the order to list them (a campaign's, :attr:`CampaignRun.rows`); any other row follows in the
            order it first appears in ``results``, then in ``failed``.
    """
    failed = list(failed)
    rows = []
    for name in dict.fromkeys([*order, *(r.row for r in results), *failed]):
        mine = [r for r in results if r.row == name and not r.refused]
        means, maxes = np.array([r.mean for r in mine]), np.array([r.max for r in mine])

        def stats(values: np.ndarray) -> tuple[float, float, float]:
            if values.size == 0:
                return (float("nan"),) * 3
            return float(values.mean()), float(values.std()), float(values.max())

        rows.append(
            TableRow(
                name=name,
                sets=len(mine),
                average=stats(means),
                maximal=stats(maxes),
                mocap_average=float(np.mean([r.mocap_mean for r in mine])) if mine else float("nan"),
                nominal_average=float(np.mean([r.nominal_mean for r in mine])) if mine else float("nan"),
                refused=sum(1 for r in results if r.row == name and r.refused),
                failed=failed.count(name),
            )
        )
    return [row for row in rows if row.sets or row.refused or row.failed]  # an ``order`` row that did not run


COLUMNS = (
    "set",
    "sets",
    "refused",
    "failed",
    "average_mean_mm",
    "average_std_mm",
    "average_max_mm",
    "maximal_mean_mm",
    "maximal_std_mm",
    "maximal_max_mm",
    "vs_mocap_average_mean_mm",
    "nominal_average_mean_mm",
    "paper_average_mean_mm",
    "paper_maximal_mean_mm",
)


def _cells(row: TableRow) -> list[str]:
    paper = PAPER_TABLE2.get(row.name)
    values = [*row.average, *row.maximal, row.mocap_average, row.nominal_average]
    return (
        [row.name, str(row.sets), str(row.refused), str(row.failed)]
        + [f"{v * 1e3:.3f}" for v in values]
        + (["", ""] if paper is None else [f"{paper[0]:.2f}", f"{paper[1]:.2f}"])
    )


def format_table(rows: list[TableRow]) -> str:
    """The printed table (mm), the paper's simulated means beside ours; the set column as wide as its longest name
    (``P1/elastic``, ``PallNE/auto``)."""
    w = max([6, *(len(row.name) for row in rows)])
    head = (
        f"{'set':<{w}} {'n':>3} {'ref':>3} {'err':>3} | {'average error [mm]':^26} | {'maximal error [mm]':^26} | "
        f"{'vs mocap':>8} {'nominal':>8} | {'paper avg/max':>13}\n"
        f"{'':<{w}} {'':>3} {'':>3} {'':>3} | {'mean':>8} {'std':>8} {'max':>8} | {'mean':>8} {'std':>8} {'max':>8} | "
        f"{'avg':>8} {'avg':>8} | {'mean':>13}"
    )
    lines = [head]
    for row in rows:
        c = _cells(row)
        paper = f"{c[12]} / {c[13]}" if c[12] else "-"
        lines.append(
            f"{c[0]:<{w}} {c[1]:>3} {c[2]:>3} {c[3]:>3} | {c[4]:>8} {c[5]:>8} {c[6]:>8} | {c[7]:>8} {c[8]:>8} "
            f"{c[9]:>8} | {c[10]:>8} {c[11]:>8} | {paper:>13}"
        )
    return "\n".join(lines)


def table_csv(rows: list[TableRow], comment: str = "") -> str:
    """The table as CSV (mm), provenance as ``#`` comment lines first."""
    buffer = io.StringIO()
    for line in comment.splitlines():
        buffer.write(f"# {line}\n")
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(COLUMNS)
    writer.writerows(_cells(row) for row in rows)
    return buffer.getvalue()


def table_markdown(rows: list[TableRow], comment: str = "") -> str:
    """The table as Markdown (mm), provenance as an HTML comment first."""
    lines = [f"<!--\n{comment}\n-->", ""] if comment else []
    lines.append("| " + " | ".join(COLUMNS) + " |")
    lines.append("|" + "---|" * len(COLUMNS))
    lines.extend("| " + " | ".join(_cells(row)) + " |" for row in rows)
    return "\n".join(lines) + "\n"


#: The files :func:`write_tables` writes into its folder.
TABLE_FILES = ("table2.csv", "table2.md")


def refuse_foreign_tables(folder: str | os.PathLike) -> None:
    """Refuse to replace an existing ``table2.csv`` or ``table2.md`` in ``folder`` that an earlier ``spherecal
    campaign`` did not write (its provenance line), as ``simulate`` and ``demo`` do (a review: a user's own
    ``table2.csv`` was overwritten).

    Raises:
        OutputError: one line naming the file and ``--out``.
    """
    refuse_unless_own([Path(folder) / name for name in TABLE_FILES], "--out", "spherecal campaign",
                      lambda path: written_by(path, "spherecal campaign"))


def write_tables(rows: list[TableRow], folder: str | os.PathLike, comment: str = "",
                 outputs: OutputSet | None = None) -> tuple[Path, Path]:
    """Write ``table2.csv`` and ``table2.md`` into ``folder``, both or neither (staged in ``outputs``)."""
    folder = Path(folder)
    csv_path, md_path = (folder / name for name in TABLE_FILES)
    outputs = OutputSet({"--out": [csv_path, md_path]}) if outputs is None else outputs
    with outputs:
        outputs.write_text(csv_path, table_csv(rows, comment))
        outputs.write_text(md_path, table_markdown(rows, comment))
    return csv_path, md_path


def refuse_if_none_finished(run: CampaignRun) -> None:
    """Refuse a campaign whose every set failed (raised, each warned as it happened): its table would hold no row
    at all (a review: such a campaign wrote an empty table2.csv and table2.md and exited 1).

    Raises:
        ExperimentError: one line with the number failed and the first failure.
    """
    if run.failures and not run.results:
        first = run.failures[0]
        raise ExperimentError(f"no set could be run ({len(run.failures)} failed); the first, {first.name}: "
                              f"{first.error}")


def refuse_if_none_calibrated(results: list[TaskResult]) -> None:
    """Refuse a campaign whose every finished set the calibration refused: its table would hold no error at all (a
    review: such a campaign wrote a table of nan and exited 0).

    Raises:
        ExperimentError: one line with the number refused and the first one's reason.
    """
    if results and all(result.refused for result in results):
        first = results[0]
        raise ExperimentError(f"no set could be calibrated ({len(results)} refused); the first, {first.row} set "
                              f"{first.index}: {first.refused}")


def failed_comment(run: CampaignRun) -> str:
    """The comment line naming the sets that raised (``""`` when none did), for the provenance of the tables: a
    table with a failed set is incomplete, and its file says so (the ``failed`` column counts them per row)."""
    if not run.failures:
        return ""
    return (f"\nfailed: {len(run.failures)} of {len(run.failures) + len(run.results)} sets, not in the statistics: "
            + "; ".join(f"{f.name} ({f.error})" for f in run.failures))


@dataclass(frozen=True)
class CampaignOutcome:
    """What :func:`run_and_write` did.

    Attributes:
        run: the tasks' results and failures (:class:`CampaignRun`).
        rows: Table 2 (:func:`table`).
        files: the written ``table2.csv`` and ``table2.md``.
        wall: wall time of the tasks [s].
    """

    run: CampaignRun
    rows: list[TableRow]
    files: tuple[Path, Path]
    wall: float


def run_and_write(config: CampaignConfig, folder: str | os.PathLike, inputs: dict, outputs: OutputSet | None = None,
                  workers: int = 2, scheduler: str | None = None,
                  show: Callable[[list[TaskResult], list[TableRow]], None] | None = None) -> CampaignOutcome:
    """Run the campaign (:func:`run_campaign`), make Table 2 and write it into ``folder`` with its provenance.

    Args:
        config: the protocol.
        folder: where ``table2.csv`` and ``table2.md`` go (:data:`TABLE_FILES`).
        inputs: the options of the run as recorded in the provenance (the wall time [s] is added).
        outputs: the staged outputs holding both files (checked by the caller before the run); None: made here.
        workers: processes of the built-in pool, or of ``scheduler="local"``.
        scheduler: a dask.distributed scheduler's address, or ``"local"``; None: the built-in pool.
        show: called with the results and the table before the files are written (a write that fails after a
            long run still shows them).

    Sets that raised while others finished are kept out of the statistics and named: counted in their rows'
    ``failed`` column (a row whose every set raised is listed with none), and listed in a ``failed:`` comment line
    of both files. The files are written all the same (a long campaign keeps the hours of sets it computed; a rerun
    of the failed rows gives the same sets, each seeded by itself); the caller reports the failures and exits 1.

    Raises:
        ExperimentError: every set failed (:func:`refuse_if_none_finished`) or its calibration was refused
            (:func:`refuse_if_none_calibrated`); nothing is shown or written.
    """
    start = time.perf_counter()
    run = run_campaign(config, workers=workers, scheduler=scheduler)
    wall = time.perf_counter() - start
    refuse_if_none_finished(run)
    refuse_if_none_calibrated(run.results)
    rows = run.table()
    if show is not None:
        show(run.results, rows)
    info = provenance(config.seed, {**inputs, "wall_time_s": round(wall, 1)}, workers=run.workers)
    files = write_tables(rows, folder, comment_block(info) + failed_comment(run), outputs)
    return CampaignOutcome(run, rows, files, wall)
