"""`spherecal calibrate`: Identify DH parameters from spherical-joint samples and write a calibrated robot file."""

from __future__ import annotations

import argparse
import math

from spherecal.options import check_robot_names, refuse_given, urdf_links

HELP = "Identify DH parameters from spherical-joint samples and write a calibrated robot file."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal calibrate`."""
    from spherecal.options import add_deprecated, add_robot, add_seed, at_most, count, non_negative, positive_noise_mm

    add_robot(parser, default=None)
    parser.add_argument("--samples", required=True, help="samples.csv: fixture[,t],q1..qn [rad]")
    parser.add_argument("--fixtures", help="fixtures.yaml: known positions and distances [m] (import writes it; "
                        "without one, no distance is known and the scale comes from the nominal model, with a warning)")
    parser.add_argument("--method", choices=("lm", "pso", "pso+lm"), default="lm", help="solver (default lm)")
    parser.add_argument("--max-per-fixture", type=count(1), default=None, metavar="N",
                        help="keep at most N samples per fixture (random; default all)")
    add_deprecated(parser, "--max-samples", "--max-per-fixture", count(1))
    add_seed(parser, "--max-per-fixture's subsampling, --model auto's cross-validation folds and PSO")
    parser.add_argument(
        "--loss", choices=("auto", "linear", "soft_l1", "huber"), default="auto",
        help="lm loss (default auto: least squares, then each fixture weighed by the noise its residuals show and "
             "Huber at 2.5x that noise, so a noisier socket pulls less and a press taken before the ball sat in its "
             "socket pulls with a bounded weight; soft_l1 / huber: at --noise, every fixture alike)")
    parser.add_argument(
        "--noise", type=positive_noise_mm, default=None,
        help="fixture noise std per axis you know of this recording [mm] (soft_l1 / huber scale, residual check, "
             "and a floor of the accuracy judgement); default: the fit weighs samples at 0.3 and the accuracy "
             "is judged at the noise the residuals show",
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
        "(1 mm, 0.2 deg, a joint's zero 1 deg) typically do (a factor; default 4: about 62 mm on the Panda)",
    )
    parser.add_argument(
        "--force",
        action="store_true",
        help="write the result even when the self-check finds the data inconsistent (every failed check is "
        "recorded in the file's calibration.self_check block)",
    )
    parser.add_argument(
        "--model",
        choices=("dh", "elastic", "scale", "elastic+scale", "auto"),
        default="auto",
        help="dh: geometry only; elastic: plus joint compliance under gravity (rad/Nm; needs the robot file's "
        "inertials); scale: plus a per-joint angle scale (q -> (1 + s) q); elastic+scale: both; auto (default): "
        "the candidate that predicts held-out fixture groups best by cross-validation (>= 3 groups: placements "
        "<placement>_h<k> or fixtures), else the lowest BIC with the fit's effective number of unknowns among dh, "
        "scale and elastic",
    )
    parser.add_argument(
        "--prior", type=at_most(1e6, "(a weight)", allow_zero=True), default=0.5,  # identification.problem.PRIOR
        help="weight of the prior toward the nominal model: each parameter's change over its typical spread "
        "(1 mm, 0.2 deg, 3e-5 rad/Nm, 1e-3 scale) at the declared --noise; with none declared, at the noise the "
        "residuals show where above 0.3 mm, the joints' zeros then at 1 deg "
        "(a weight; default 0.5, measured on real arms; 0: plain least squares)",
    )
    parser.add_argument(
        "--exclude-fixture", action="append", default=[], metavar="NAME",
        help="leave the fixture NAME out (its samples and every known distance naming it); repeatable "
        "(a socket the self-check finds drifting, a fixture that moved)",
    )
    parser.add_argument("--out", required=True, help="calibrated robot file to write (YAML)")


def run(args: argparse.Namespace) -> int:
    """Read, check, calibrate, then write ``--out`` atomically and print the summary."""
    import time

    from spherecal.correction.files.samples import DEDUP_TOL
    from spherecal.identification.workflow import WorkflowOptions, calibrate_files
    from spherecal.options import planned_outputs

    if args.method == "lm" and args.model != "auto" and args.max_per_fixture is None:  # nothing random is drawn
        refuse_given(args, ("seed",), f"with --method lm, --model {args.model} and every sample kept nothing random "
                     "is drawn (it seeds --max-per-fixture's subsampling, --model auto's cross-validation and PSO)")
    check_robot_names(args)  # an unknown robot name, by its option
    outputs = planned_outputs(args, {"--out": args.out})  # before any work: never over an input, named as YAML
    clock = time.perf_counter()
    options = WorkflowOptions(
        method=args.method,
        model=args.model,
        loss=args.loss,
        noise=None if args.noise is None else args.noise * 1e-3,  # [m]
        max_per_fixture=args.max_per_fixture,
        dedup_tol=DEDUP_TOL if args.dedup_deg is None else math.radians(args.dedup_deg),  # [rad]
        max_change=args.max_change,
        force=args.force,
        seed=args.seed,
        prior=args.prior,
        exclude_fixtures=tuple(args.exclude_fixture),
    )
    done = calibrate_files(args.robot, args.samples, args.fixtures, args.out, options, outputs, **urdf_links(args))
    print(done.summary())
    print(f"wrote {args.out} in {time.perf_counter() - clock:.2f} s")
    return 0
