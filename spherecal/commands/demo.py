"""`spherecal demo`: End-to-end demo on the embedded Panda: simulate, calibrate, validate, record."""

from __future__ import annotations

import argparse

from spherecal.options import check_per_fixture, start_viewer

HELP = "End-to-end demo on the embedded Panda: simulate, calibrate, validate, record."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal demo`."""
    from spherecal.options import add_per_fixture, add_seconds, add_seed, configurations, noise_mm

    add_seed(parser, "the true robot, motion and noise")
    add_per_fixture(parser, 1500)
    parser.add_argument(
        "--noise", type=noise_mm, default=0.3,
        help="fixture noise std per axis in the calibration data [mm] (default 0.3)",
    )
    parser.add_argument("--mocap-noise", type=noise_mm, default=0.3,
                        help="motion-capture marker noise std [mm] (default 0.3)")
    add_seconds(parser, 60.0, "simulated self-motion per fixture")
    parser.add_argument("--configurations", type=configurations, default=5000,
                        help="random validation configurations (default 5000)")
    parser.add_argument(
        "--source", choices=("mujoco", "synthetic"), default="mujoco",
        help="motion: MuJoCo self-motion through the QP controller (default) or kinematic self-motion samples "
        "(synthetic)",
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

    from spherecal.validation.experiments.demo import DemoConfig, run_demo

    check_per_fixture(args, 10, simulated=args.source == "mujoco")
    start_viewer(args, "or drop --spawn" + (" and --no-rrd" if args.no_rrd else "") + " and open the demo.rrd it "
                 "writes elsewhere")
    start = time.perf_counter()
    config = DemoConfig(
        seed=args.seed,
        samples=args.per_fixture,
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
