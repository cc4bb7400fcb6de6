"""`spherecal campaign`: Run the paper's simulated protocol (fixture sets x noise levels) and print its error table."""

from __future__ import annotations

import argparse

from spherecal.options import check_per_fixture, fail, recorded_options

HELP = "Run the paper's simulated protocol (fixture sets x noise levels) and print its error table."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal campaign`."""
    from spherecal.options import (
        add_per_fixture,
        add_seconds,
        add_seed,
        add_workers,
        configurations,
        count,
        noise_mm,
    )

    parser.add_argument("--sets", type=count(1, 1000), default=10, help="motion sets per row (default 10)")
    add_per_fixture(parser, 500, "samples per fixture in each set")
    parser.add_argument("--configurations", type=configurations, default=5000,
                        help="random validation configurations (default 5000)")
    parser.add_argument("--noise", type=noise_mm, default=0.3,
                        help="fixture noise std per axis of the noisy rows [mm] (default 0.3)")
    parser.add_argument(
        "--source",
        choices=("synthetic", "mujoco"),
        default="synthetic",
        help="motion: kinematic self-motion samples (default) or MuJoCo self-motion through the QP controller",
    )
    parser.add_argument(
        "--protocol",
        choices=("realistic", "paper"),
        default="realistic",
        help="realistic: perturbed true robot, calibrated from nominal (default); paper: true = nominal, "
        "started from a perturbed model, as the paper's simulation",
    )
    add_seconds(parser, 20.0, "MuJoCo self-motion per fixture")
    parser.add_argument("--rows", default="P1,P2,P3,Pall", help="fixture sets (P1,P2,P3,Pall)")
    add_seed(parser, "the campaign (every set is seeded from it)")
    parser.add_argument("--stiffness", default=None, metavar="K[,K...]",
                        help="elastic true robot: joint stiffness [Nm/rad], one value or one per joint, 0 = rigid "
                             "(e.g. 0,3e4,3e4,3e4,0,0,0); rows get an E")
    parser.add_argument("--model", choices=("dh", "elastic", "auto"), default="dh",
                        help="model calibrated (dh: default, the paper's; elastic; auto: cross-validated choice)")
    add_workers(parser, "motion sets")
    parser.add_argument("--out", default="spherecal-campaign",
                        help="folder for table2.csv and table2.md (default spherecal-campaign). A set that fails "
                        "(raises) is left out of the statistics and counted in its row's 'failed' column, named in "
                        "a 'failed:' comment line of both files; the other sets are written and the exit status is 1")


def run(args: argparse.Namespace) -> int:
    """Check the options, run the campaign, print Table 2 and where it was written (CSV and Markdown)."""
    import sys
    from pathlib import Path

    from spherecal.options import check_folder, planned_outputs
    from spherecal.validation.experiments.campaign import (
        FIXTURE_SETS,
        TABLE_FILES,
        CampaignConfig,
        format_table,
        refuse_foreign_tables,
        run_and_write,
    )
    from spherecal.validation.experiments.experiment import joint_stiffness

    rows = tuple(r.strip() for r in args.rows.split(",") if r.strip())
    unknown = [r for r in rows if r not in FIXTURE_SETS]
    if unknown or not rows:
        raise fail(f"field '--rows': unknown {unknown}, choose from {list(FIXTURE_SETS)}")
    if len(set(rows)) < len(rows):  # the same seeded sets twice: the table counted them as independent
        twice = next(r for r in rows if rows.count(r) > 1)
        raise fail(f"field '--rows': {twice} is given twice (its sets would be counted twice, the same seeds each "
                   "time)")
    check_per_fixture(args, 10, simulated=args.source == "mujoco")
    check_folder(args.out, writes=TABLE_FILES)
    outputs = planned_outputs(args, {"--out": [Path(args.out) / name for name in TABLE_FILES]})
    refuse_foreign_tables(args.out)
    config = CampaignConfig(
        stiffness=tuple(joint_stiffness(args.stiffness, 7) or ()),  # the campaign's arm is the embedded Panda
        model=args.model,
        sets=args.sets,
        samples=args.per_fixture,
        configurations=args.configurations,
        seconds=args.seconds,
        source=args.source,
        protocol=args.protocol,
        seed=args.seed,
        fixture_sets=rows,
        noise_levels=(0.0, args.noise * 1e-3) if args.noise > 0 else (0.0,),  # --noise 0: no noisy rows
    )

    def show(results, rows) -> None:  # before the files are written: a failed write after hours still shows it
        print(f"Table 2 ({args.protocol} protocol, {args.source} motion): calibrated tool-point error against the "
              "exact tool point on random workspace configurations, after registration")
        print(format_table(rows))
        for result in results:
            if result.refused:
                print(f"refused: {result.row} set {result.index}: {result.refused}")

    done = run_and_write(config, args.out, recorded_options(args), outputs, args.workers, args.scheduler, show)
    results = done.run.results
    print(f"written: {done.files[0]}, {done.files[1]}")
    where = f"Dask scheduler {args.scheduler}" if args.scheduler else "process pool"
    print(f"wall time {done.wall:.1f} s ({len(results)} sets, {len(done.run.workers)} worker processes, {where})")
    failures = done.run.failures
    if failures:  # each also reported as it happened (TaskFailedWarning); the table holds the others
        rerun = ",".join(dict.fromkeys(done.run.failed_sets))
        print(f"spherecal campaign: error: {len(failures)} of {len(failures) + len(results)} sets failed "
              f"({', '.join(f.name for f in failures)}): written as incomplete rows (the 'failed' column of "
              f"{done.files[0].name} and {done.files[1].name}); --rows {rerun} runs them again", file=sys.stderr)
        return 1
    return 0
