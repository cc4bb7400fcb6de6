"""The experiment-design analysis (the paper's contribution ii): predicted against measured accuracy.

Cells vary one thing at a time around a base case (the three default fixtures, every distance known,
the whole self-motion, 500 samples per fixture, 0.3 mm fixture noise):

* the number of fixtures (1 to 4) with and without the known centre-to-centre distances;
* the joint range the self-motion covers (a window of a share of every joint's range, and the P3-like
  case: joints 2 and 3 held to 10 %);
* the samples per fixture (50 to 2000);
* the fixture noise (0 to 1 mm);
* the plan: ``spherecal plan``'s best three fixtures on a grid, the defaults, and the P3-like set.

For each cell, ``sets`` seeded motion sets are simulated (kinematic self-motion samples on a fresh
perturbed true robot, as :mod:`validation.campaign` does), calibrated from the nominal model, and
validated on random workspace configurations against the exact tool point after registration. The
prediction (:func:`identification.prediction.predict_accuracy`) is made from the first set's data.

Regenerate ``docs/experiment_design.md``::

    spherecal plan --analysis docs/experiment_design.md      # or: python -m spherecal.validation.planning.analysis
"""

from __future__ import annotations

import argparse
import functools
import itertools
import os
import resource
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from spherecal.correction import atomic_write_text, registered_errors, tool_point
from spherecal.correction.files.provenance import comment_block, provenance
from spherecal.correction.files.samples import Dataset
from spherecal.identification.calibrate import calibrate
from spherecal.identification.prediction import Workspace, predict_accuracy
from spherecal.validation.experiments.experiment import default_fixtures, fixture_spec, nominal_robot, true_robot
from spherecal.validation.planning.candidates import Candidate, grid_candidates
from spherecal.validation.planning.plan import motion_samples, plan
from spherecal.validation.planning.plan_report import format_plan
from spherecal.validation.threads import capped

#: This module's import name, for ``python -m`` (the folder ``validation/`` installs as ``spherecal.validation``).
MODULE = __spec__.name
#: The fourth fixture of the 1-4 fixture rows (low, left of the defaults) [m].
P4 = (0.35, -0.1, 0.2)
#: P3-like restriction: joints 2 and 3 held to 10 % of their range, the others free.
P3_LIKE = (1.0, 0.1, 0.1, 1.0, 1.0, 1.0, 1.0)
#: The grid the analysis plans on (``spherecal plan --grid``).
GRID = "0.2,0.7,5;-0.5,0.5,5;0.1,0.7,3"


@dataclass(frozen=True)
class Cell:
    """One row of the analysis.

    Attributes:
        group: the table it belongs to.
        name: what varies.
        fixtures: name -> (3,) centre [m].
        distances: every centre-to-centre distance known.
        joint_range: (n,) share of each joint's range the self-motion may use (None: all).
        samples: per fixture.
        noise: fixture noise per coordinate [m].
        sets: motion sets.
    """

    group: str
    name: str
    fixtures: tuple[tuple[str, tuple[float, float, float]], ...]
    distances: bool = True
    joint_range: tuple[float, ...] | None = None
    samples: int = 500
    noise: float = 3e-4
    sets: int = 5


@dataclass(frozen=True)
class AnalysisConfig:
    """Sizes of the analysis.

    Attributes:
        sets: motion sets per cell.
        key_sets: motion sets of the two- and three-fixture cells and of the plan comparison.
        configurations: validation configurations per set.
        grid: the candidate grid of the plan rows.
        seed: base seed; every (cell, set) is seeded from it, the cell's number and the set's.
        workers: processes.
    """

    sets: int = 4
    key_sets: int = 10
    configurations: int = 2000
    grid: str = GRID
    seed: int = 0
    workers: int = 2


@dataclass(frozen=True)
class CellResult:
    """Predicted and measured errors of a cell [m]."""

    cell: Cell
    predicted_mean: float
    predicted_p95: float
    measured: np.ndarray  # (sets,) mean error per set
    measured_p95: np.ndarray  # (sets,) 95th percentile per set
    condition: float
    weak: tuple[str, ...]


def _defaults() -> dict[str, tuple[float, float, float]]:

    return {k: tuple(float(x) for x in v) for k, v in default_fixtures().items()}


def cells(config: AnalysisConfig, best: dict[str, tuple[float, float, float]] | None = None) -> list[Cell]:
    """Every cell, in table order (``best``: the plan's set, for the plan rows)."""
    d = _defaults()
    four = {**d, "P4": P4}
    names = list(four)
    out = []
    for k in range(1, 5):
        chosen = tuple((n, four[n]) for n in names[:k])
        key = config.key_sets if k in (2, 3) else config.sets
        for known in ((False,) if k == 1 else (True, False)):
            label = f"{k} fixture{'s' * (k > 1)}"
            out.append(Cell("fixtures", label, chosen, known, sets=key if known else config.sets))
    three = tuple(d.items())
    for share in (0.1, 0.25, 0.5, 1.0):
        label = f"{share:.0%} of every joint"
        out.append(Cell("joint range", label, three, joint_range=(share,) * 7, sets=config.sets))
    out.append(Cell("joint range", "P3-like: q2, q3 at 10 %", three, joint_range=P3_LIKE, sets=config.sets))
    for samples in (50, 200, 500, 2000):
        out.append(Cell("samples", f"{samples} per fixture", three, samples=samples, sets=config.sets))
    for noise in (0.0, 0.1e-3, 0.3e-3, 1e-3):
        out.append(Cell("noise", f"{noise * 1e3:.1f} mm", three, noise=noise, sets=config.sets))
    out.append(Cell("plan", "default fixtures", three, sets=config.key_sets))
    out.append(Cell("plan", "P3-like (defaults, q2, q3 at 10 %)", three, joint_range=P3_LIKE, sets=config.key_sets))
    if best is not None:
        out.append(Cell("plan", "plan's best 3 (grid)", tuple(best.items()), sets=config.key_sets))
    return out


@functools.lru_cache(maxsize=1)
def _workspace():

    return Workspace.of(nominal_robot())


def run_set(cell: Cell, index: int, seed: tuple[int, ...], configurations: int):
    """One motion set of a cell: (measured mean, measured p95, prediction or None) [m]."""

    rng = np.random.default_rng(seed)
    nominal = nominal_robot()
    truth = true_robot(nominal, rng)
    fixtures = {k: np.asarray(v, float) for k, v in cell.fixtures}
    window = None if cell.joint_range is None else np.asarray(cell.joint_range)
    q = [
        motion_samples(nominal, Candidate(k, c, window), cell.samples, rng, noise=cell.noise, truth=truth)
        for k, c in fixtures.items()
    ]
    labels = np.repeat(np.array(list(fixtures)), cell.samples)
    dataset = Dataset(labels=labels, q=np.concatenate(q), fixture_names=tuple(fixtures))
    spec = fixture_spec(fixtures, cell.distances and len(fixtures) > 1)
    prediction = None
    if index == 0:
        prediction = predict_accuracy(nominal, dataset, spec, noise=cell.noise, workspace=_workspace())
    model = calibrate(nominal, dataset, spec).model  # as the campaign does
    configs = truth.random_configurations(configurations, rng)
    errors = registered_errors(tool_point(model, configs), tool_point(truth, configs))
    return float(errors.mean()), float(np.percentile(errors, 95)), prediction


def _task(args):
    return run_set(*args)


def run_cells(todo: list[Cell], config: AnalysisConfig, offset: int = 0) -> list[CellResult]:
    """Every set of every cell over ``config.workers`` processes; seeded by (seed, cell number, set)."""
    jobs = [
        (c, i, (config.seed, offset + k, i), config.configurations) for k, c in enumerate(todo) for i in range(c.sets)
    ]
    if config.workers > 1:
        with ProcessPoolExecutor(max_workers=config.workers) as pool:
            outcomes = list(pool.map(capped, itertools.repeat(_task), jobs, chunksize=1))  # one BLAS thread each
    else:
        outcomes = [_task(job) for job in jobs]
    results = []
    for cell in todo:
        mine = [o for job, o in zip(jobs, outcomes, strict=True) if job[0] is cell]
        prediction = mine[0][2]
        results.append(
            CellResult(
                cell=cell,
                predicted_mean=prediction.mean,
                predicted_p95=prediction.p95,
                measured=np.array([o[0] for o in mine]),
                measured_p95=np.array([o[1] for o in mine]),
                condition=prediction.identifiability.condition_number,
                weak=prediction.weak,
            )
        )
    return results


@dataclass
class Analysis:
    """Everything the document shows."""

    results: list[CellResult]
    plan: object  # validation.plan.Plan
    config: AnalysisConfig
    seconds: dict[str, float] = field(default_factory=dict)
    cpu_seconds: float | None = None  # this process and its workers, user + system
    load: float | None = None  # the 1-minute load average at the end


def run_analysis(config: AnalysisConfig) -> Analysis:
    """Plan on the grid, then run every cell."""

    clock, cpu = time.perf_counter(), _cpu()
    result = plan(nominal_robot(), grid_candidates(config.grid), 3, np.random.default_rng(config.seed))
    seconds = {"plan": time.perf_counter() - clock}
    best = {s.candidate.name: tuple(float(x) for x in s.candidate.position)
            for s in result.surveys if result.best and s.candidate.name in result.best.names}
    clock = time.perf_counter()
    results = run_cells(cells(config, best or None), config)
    seconds["cells"] = time.perf_counter() - clock
    return Analysis(results, result, config, seconds, _cpu() - cpu, os.getloadavg()[0])


def _cpu() -> float:
    """User + system seconds of this process and of its finished children (the workers) [s]."""
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


# ------------------------------------------------------------------------------------- document
def _row(r: CellResult) -> str:
    c = r.cell
    m = r.measured
    ratio = f"{r.predicted_mean / m.mean():.2f}" if m.mean() > 1e-7 else "-"  # noise-free: both ~0
    dist = "yes" if c.distances and len(c.fixtures) > 1 else "no"
    joints = "all" if c.joint_range is None else ",".join(f"{x:g}" for x in c.joint_range)
    weak = ", ".join(r.weak) or "-"
    return (
        f"| {c.name} | {', '.join(n for n, _ in c.fixtures)} | {dist} | {joints} | {c.samples} | {c.noise * 1e3:.1f} "
        f"| {c.sets} | {r.predicted_mean * 1e3:.4g} | {r.predicted_p95 * 1e3:.4g} | {m.mean() * 1e3:.4g} "
        f"| {m.std() * 1e3:.3g} | {r.measured_p95.mean() * 1e3:.4g} | {ratio} | {r.condition:.3g} | {weak} |"
    )


HEADER = (
    "| case | fixtures | distances known | joint range (share) | samples / fixture | noise [mm] | sets "
    "| predicted mean [mm] | predicted p95 [mm] | measured mean [mm] | measured std [mm] | measured p95 [mm] "
    "| predicted / measured | condition number | weakly determined |\n"
    "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
)

TITLES = {
    "fixtures": "Number of fixtures, with and without the known distances",
    "joint range": "Joint range covered by the self-motion",
    "samples": "Samples per fixture",
    "noise": "Fixture noise",
    "plan": "The plan against the defaults and a P3-like set",
}


def markdown(analysis: Analysis, provenance: str) -> str:
    """The document."""

    cfg = analysis.config
    results = analysis.results
    by = {g: [r for r in results if r.cell.group == g] for g in TITLES}
    ratios = {r.cell.name: r.predicted_mean / r.measured.mean() for r in by["fixtures"] if r.cell.distances}
    lines = [
        f"<!--\n{provenance}\n-->",
        "",
        "# Experiment design: how many fixtures, how much self-motion, how many samples",
        "",
        f"Generated by `spherecal plan --analysis docs/experiment_design.md` (or `python -m {MODULE}`);"
        " do not edit by hand.",
        f"Wall time {sum(analysis.seconds.values()):.0f} s on {cfg.workers} workers "
        f"(plan {analysis.seconds.get('plan', 0):.0f} s, cells {analysis.seconds.get('cells', 0):.0f} s)"
        + ("." if analysis.cpu_seconds is None else
           f"; CPU {analysis.cpu_seconds:.0f} s in all, load average {analysis.load:.1f} at the end (the wall time "
           "depends on what else the machine runs, the CPU time much less)."),
        "",
        "**Protocol.** Each cell changes one thing from the base case (the three default fixtures of "
        "`spherecal simulate`, every centre-to-centre distance known, the whole self-motion manifold, 500 samples "
        "per fixture, 0.3 mm fixture noise per axis). *Measured*: `sets` motion sets, each a fresh seeded true "
        "robot (1 mm / 0.2 deg spread), kinematic self-motion samples (random configurations projected onto the "
        "fixture; with a joint range, inside a window of that share of every joint's range around a reach "
        "configuration), calibrated from the nominal model with `calibrate` (lm), and validated on "
        f"{cfg.configurations} random configurations against the exact tool point after the best rigid fit; "
        "the table gives the mean over the sets of each set's mean and 95th percentile error. *Predicted*: "
        "`identification.prediction.predict_accuracy` on the first set's data (covariance sigma^2 (J^T J)^-1 of "
        "the identified parameters with calibrate's gauge, scale and pruning, plus the bias of what is left at "
        "nominal, propagated to 1000 workspace configurations with the six rigid motions projected out).",
        "",
        f"Sets per cell: {cfg.key_sets} for the two- and three-fixture rows with distances and for the plan "
        f"rows (the acceptance cases), {cfg.sets} elsewhere, to keep the run to a few minutes on 2 cores; the "
        "measured std column says how far a mean of so few sets can be trusted.",
        "",
    ]
    lines += _findings(by)
    for group, title in TITLES.items():
        if not by[group]:
            continue
        lines += [f"## {title}", "", HEADER, *(_row(r) for r in by[group]), ""]
        if group == "fixtures":
            lines.append(
                "Predicted / measured mean with distances: "
                + ", ".join(f"{k} {v:.2f}" for k, v in ratios.items())
                + ". Without any known distance the scale comes from the nominal model: the error is the nominal "
                "model's scale error (about 1-2 mm here) whatever the number of fixtures; one measured distance "
                "removes it."
            )
            lines.append("")
        if group == "plan":
            lines += _plan_lines(by[group])
    lines += [
        "## The plan on the grid",
        "",
        f"`spherecal plan --robot panda --grid \"{cfg.grid}\" --fixtures 3 --seed {cfg.seed}` "
        "(kinematic self-motion survey; each candidate alone is scored without distances, so its scale error "
        "dominates the single-candidate column):",
        "",
        "```",
        format_plan(analysis.plan),
        "```",
        "",
    ]
    return "\n".join(lines)


def _findings(by: dict[str, list[CellResult]]) -> list[str]:
    """A few sentences with the figures of this run (measured means, mm)."""

    def pair(group: str) -> str:
        def label(c: Cell) -> str:
            if group != "fixtures" or len(c.fixtures) == 1:
                return c.name
            return f"{c.name} {'with' if c.distances else 'without'} distances"

        return ", ".join(f"{label(r.cell)} {r.measured.mean() * 1e3:.3g}" for r in by[group])

    lines = ["## Findings (measured mean error, mm)", ""]
    for group, what in (
        ("fixtures", "Fixtures"),
        ("joint range", "Joint range"),
        ("samples", "Samples per fixture (about 1/sqrt(samples))"),
        ("noise", "Noise (about linear)"),
    ):
        if by[group]:
            lines.append(f"- {what}: {pair(group)}.")
    ratios = [r.predicted_mean / r.measured.mean() for rs in by.values() for r in rs if r.measured.mean() > 1e-7]
    if ratios:
        lines.append(
            f"- Predicted / measured mean over all cells: median {np.median(ratios):.2f}, range "
            f"{min(ratios):.2f} to {max(ratios):.2f} (the prediction uses one data set, the measurement "
            "4 or 10 sets; strongly restricted self-motion is the least linear case)."
        )
    return [*lines, ""]


def _plan_lines(rows: list[CellResult]) -> list[str]:
    ranked = sorted(rows, key=lambda r: r.predicted_mean)
    order = " < ".join(f"{r.cell.name} ({r.predicted_mean * 1e3:.3f} mm)" for r in ranked)
    measured = " < ".join(f"{r.cell.name} ({r.measured.mean() * 1e3:.3f} mm)"
                          for r in sorted(rows, key=lambda r: r.measured.mean()))
    return [f"Ranked by predicted mean error: {order}.", "", f"Ranked by measured mean error: {measured}.", ""]


def write_analysis(path: str | Path, config: AnalysisConfig | None = None) -> Path:
    """Run the analysis and write the Markdown document (atomically; provenance in an HTML comment)."""

    config = config or AnalysisConfig()
    analysis = run_analysis(config)
    info = provenance(config.seed, {**config.__dict__, "wall_time_s": round(sum(analysis.seconds.values()), 1)})
    return atomic_write_text(Path(path), markdown(analysis, comment_block(info)))


def main(argv: list[str] | None = None) -> int:
    """``python -m spherecal.validation.planning.analysis [OUT] [--sets N] [--workers N]``."""

    parser = argparse.ArgumentParser(prog=f"python -m {MODULE}", description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", default="docs/experiment_design.md")
    parser.add_argument("--sets", type=int, default=AnalysisConfig.sets)
    parser.add_argument("--key-sets", type=int, default=AnalysisConfig.key_sets)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    config = replace(AnalysisConfig(), sets=args.sets, key_sets=args.key_sets, workers=args.workers, seed=args.seed)
    print(f"written: {write_analysis(args.out, config)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
