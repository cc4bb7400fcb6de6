"""`spherecal demo`: End-to-end demo on the embedded Panda: simulate, calibrate, validate, record."""

from __future__ import annotations

import argparse

HELP = "End-to-end demo on the embedded Panda: simulate, calibrate, validate, record."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal demo`."""
    from spherecal.identification.options import non_negative, positive, seed

    parser.add_argument("--seed", type=seed, default=0, help="seed of the true robot, motion and noise (0)")
    parser.add_argument("--samples", type=int, default=1500, help="samples kept per fixture (1500)")
    parser.add_argument(
        "--noise", type=non_negative, default=0.3, help="fixture noise in the calibration data, mm std (0.3)"
    )
    parser.add_argument("--mocap-noise", type=non_negative, default=0.3, help="mocap noise per marker, mm std (0.3)")
    parser.add_argument("--seconds", type=positive, default=60.0, help="simulated self-motion per fixture, s (60)")
    parser.add_argument("--configurations", type=int, default=5000, help="random validation configurations (5000)")
    parser.add_argument(
        "--source", choices=("mujoco", "synthetic"), default="mujoco", help="motion: MuJoCo self-motion (default)"
    )
    parser.add_argument("--out", default="spherecal-demo", help="output folder (spherecal-demo)")
    parser.add_argument("--no-rrd", action="store_true", help="do not write demo.rrd")
    parser.add_argument("--spawn", action="store_true", help="also stream to a live Rerun viewer")
    parser.add_argument(
        "--quiet", action="store_true", help="no progress bars (they are off anyway when stderr is not a terminal)"
    )


def run(args: argparse.Namespace) -> int:
    """Check the options, run the demo, print where the results are."""
    import time
    from pathlib import Path

    from spherecal.validation.demo import DemoConfig, run_demo

    if (
        args.samples < 10
        or not args.seconds > 0
        or args.configurations < 3
        or not (args.noise >= 0 and args.mocap_noise >= 0)
    ):
        raise SystemExit(
            "spherecal demo: error: need --samples >= 10, --seconds > 0, --configurations >= 3, noises >= 0"
        )
    if args.samples > round(args.seconds * 1000) and args.source == "mujoco":
        raise SystemExit(f"spherecal demo: error: --samples {args.samples} > {args.seconds} s of 1 kHz readings")
    from spherecal.validation.inputs import check_out_folder

    check_out_folder(args.out)
    start = time.perf_counter()
    config = DemoConfig(
        seed=args.seed,
        samples=args.samples,
        noise=args.noise * 1e-3,
        mocap_noise=args.mocap_noise * 1e-3,
        seconds=args.seconds,
        configurations=args.configurations,
        source=args.source,
        out=Path(args.out),
        rrd=not args.no_rrd,
        spawn=args.spawn,
        quiet=args.quiet,
    )
    result = run_demo(config, say=lambda line: print(line, flush=True))
    for key, path in result.files.items():
        print(f"  {key:<11} {path}")
    if "recording" in result.files:
        print(f"recording: {result.files['recording']}  (view: rerun {result.files['recording']})")
    print(f"done in {time.perf_counter() - start:.1f} s")
    return 0
