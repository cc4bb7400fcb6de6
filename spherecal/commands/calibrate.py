"""`spherecal calibrate`: Identify DH parameters from spherical-joint samples and write a calibrated robot file."""

from __future__ import annotations

import argparse
import math

from spherecal.options import urdf_links

HELP = "Identify DH parameters from spherical-joint samples and write a calibrated robot file."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal calibrate`."""
    from spherecal.options import add_deprecated, add_robot, add_seed, at_most, count, non_negative, positive_noise_mm

    add_robot(parser, default=None)
    parser.add_argument("--samples", required=True, help="samples.csv: fixture[,t],q1..qn [rad]")
    parser.add_argument("--fixtures", help="fixtures.yaml: known positions and distances [m]")
    parser.add_argument("--method", choices=("lm", "pso", "pso+lm"), default="lm", help="solver (default lm)")
    parser.add_argument("--max-per-fixture", type=count(1), default=None, metavar="N",
                        help="keep at most N samples per fixture (random; default all)")
    add_deprecated(parser, "--max-samples", "--max-per-fixture", count(1))
    add_seed(parser, "subsampling and PSO")
    parser.add_argument("--loss", choices=("linear", "soft_l1", "huber"), default="linear", help="lm loss")
    parser.add_argument(
        "--noise", type=positive_noise_mm, default=0.3,
        help="expected fixture noise std per axis [mm] (robust-loss scale, residual check; default 0.3)",
    )
    parser.add_argument(
        "--dedup-deg", type=at_most(10.0, "deg", allow_zero=True), default=None,
        help="drop samples within this of an earlier one, every joint [deg] (default 0.00573 = 1e-4 rad)",
    )
    add_deprecated(parser, "--dedup-tol", "--dedup-deg", non_negative, convert=math.degrees)
    parser.add_argument(
        "--max-change",
        type=at_most(1000.0, "(a factor)"),
        default=4.0,
        help="refuse a fit that moves the tool point more than this many times what a real arm's errors "
        "(1 mm, 0.2 deg) typically do (a factor; 4: about 24 mm on the Panda)",
    )
    parser.add_argument(
        "--force",
        action="store_true",
        help="write the result even when the self-check finds the data inconsistent (every failed check is "
        "recorded in the file's calibration.self_check block)",
    )
    parser.add_argument(
        "--model",
        choices=("dh", "elastic", "auto"),
        default="auto",
        help="dh: geometry only; elastic: geometry plus joint compliance under gravity (rad/Nm; needs the robot "
        "file's inertials); auto (default): elastic only when it predicts held-out fixtures (or placements "
        "<placement>_h<k>) better than dh by more than the fold-to-fold spread",
    )
    parser.add_argument(
        "--exclude-fixture", action="append", default=[], metavar="NAME",
        help="leave the fixture NAME out (its samples and every known distance naming it); repeatable "
        "(a socket the self-check finds drifting, a fixture that moved)",
    )
    parser.add_argument("--out", required=True, help="calibrated robot file to write (YAML)")


def run(args: argparse.Namespace) -> int:
    """Read, check, calibrate, then write ``--out`` atomically and print the summary."""
    import os

    # The problem is small (a few thousand rows, ~35 columns): threaded BLAS only adds start-up
    # and, on a busy machine, stalls (a 4500 x 34 SVD: 3 ms on one thread, 50-700 ms on two
    # contended ones). Set before numpy is first imported; a user's own setting wins.
    for variable in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(variable, "1")
    import datetime
    import time
    from dataclasses import replace

    import numpy as np

    from spherecal.correction import load_robot, save_robot
    from spherecal.correction.files.fixtures import read_fixtures
    from spherecal.correction.files.provenance import PACKAGES, input_record, versions
    from spherecal.correction.files.samples import DEDUP_TOL
    from spherecal.correction.files.samples_csv import read_samples
    from spherecal.identification.calibrate import calibrate
    from spherecal.identification.selection import elastic_start, rigid, select_model
    from spherecal.identification.training import exclude_fixtures, training_record
    from spherecal.options import planned_outputs

    outputs = planned_outputs(args, {"--out": args.out})  # before any work: never over an input
    clock = time.perf_counter()
    noise = args.noise * 1e-3  # [m] from here on
    dedup_tol = DEDUP_TOL if args.dedup_deg is None else float(np.deg2rad(args.dedup_deg))  # [rad]
    nominal = load_robot(args.robot, **urdf_links(args))
    dataset = read_samples(args.samples, nominal)
    spec = read_fixtures(args.fixtures) if args.fixtures else None
    dataset, spec = exclude_fixtures(dataset, spec, args.exclude_fixture)
    as_read = dataset
    read = len(dataset.labels)
    dataset = dataset.deduplicated(dedup_tol)
    dropped = read - dataset.n_samples
    dataset = dataset.subsampled(args.max_per_fixture, np.random.default_rng(args.seed))

    def fit(start, data, fixtures):  # a cross-validation fold: lm, the user's loss and noise; no self-check
        # (it judges the chosen calibration below, not each fold's)
        return calibrate(
            start, data, fixtures, loss=args.loss, noise=noise, max_change=args.max_change, check=False
        ).model

    selection = select_model(args.model, fit, nominal, dataset, spec, seed=args.seed)
    start = elastic_start(nominal) if selection.chosen == "elastic" else rigid(nominal)
    result = calibrate(
        start,
        dataset,
        spec,
        method=args.method,
        seed=args.seed,
        loss=args.loss,
        noise=noise,
        max_change=args.max_change,
        force=args.force,
    )
    block = result.block()
    block["model_selection"] = selection.block()
    if selection.seconds:
        block["timings_s"]["cross_validation"] = selection.seconds
    block["duplicates_dropped"] = dropped
    block["trained_on"] = training_record(as_read, dataset)  # validate recognises these samples by content
    block["inputs"] = {
        "robot": input_record(args.robot),
        "samples": input_record(args.samples),
    }
    if args.fixtures:
        block["inputs"]["fixtures"] = input_record(args.fixtures)
    block["options"] = {
        "loss": args.loss,
        "noise_m": noise,
        "max_per_fixture": args.max_per_fixture,
        "dedup_tol_rad": float(dedup_tol),
        "max_change": args.max_change,
        "model": args.model,
        "force": args.force,
        "exclude_fixture": list(args.exclude_fixture),
    }
    block["seed"] = args.seed
    block["versions"] = versions(PACKAGES[:4] + (("pyswarms",) if "pso" in args.method else ()))
    block["time"] = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    extras = {k: v for k, v in result.model.extras.items() if k != "calibration"}  # compliance when elastic
    extras["calibration"] = block
    model = replace(result.model, extras=extras)
    header = f"calibrated by spherecal calibrate ({args.method}) from {args.samples}"
    with outputs:
        save_robot(model, outputs.stage(args.out), header=header)
    print(result.summary())
    print(selection.summary())
    if dropped:
        print(f"dropped {dropped} duplicate samples (within {np.rad2deg(dedup_tol):.3g} deg)")
    print(f"wrote {args.out} in {time.perf_counter() - clock:.2f} s")
    return 0
