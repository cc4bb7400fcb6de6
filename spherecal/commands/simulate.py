"""`spherecal simulate`: self-motion at spherical-joint fixtures on a perturbed (true) robot."""

from __future__ import annotations

import argparse

from spherecal.options import check_per_fixture, check_robot_names, urdf_links

HELP = "Simulate self-motion at spherical-joint fixtures on a perturbed (true) robot and write samples."

def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal simulate`."""
    from spherecal.options import add_per_fixture, add_robot, add_seed, at_most, duration, noise_mm, spread_mm

    parser.add_argument("--out", required=True, help="output folder (samples.csv, fixtures.yaml, truth.yaml)")
    add_seed(parser)
    parser.add_argument("--seconds", type=duration, default=20.0,
                        help="self-motion per fixture [s], at most 3600 (default 20)")
    add_per_fixture(parser, 500)
    parser.add_argument("--mode", choices=("coverage", "random"), default="coverage",
                        help="exploration of the null space (default coverage; random is the paper's)")
    parser.add_argument("--noise", type=noise_mm, default=0.3,
                        help="fixture compliance std per axis moving the physical point [mm] (default 0.3)")
    parser.add_argument("--fixtures", default=None,
                        help="fixtures.yaml giving the true centre (position) of every fixture [m] (default: the "
                             "Panda's P1, P2, P3 at (0.5, -0.25, 0.5), (0.5, 0, 0.4), (0.45, 0.25, 0.45) m, scaled "
                             "to the reach of an arm that does not reach them; spherecal plan --grid auto ranks "
                             "positions for yours)")
    add_robot(parser)
    parser.add_argument("--length-std", type=spread_mm, default=1.0, help="true-robot a, d error std [mm] (default 1)")
    parser.add_argument("--angle-std-deg", type=at_most(10.0, "deg", allow_zero=True), default=0.2,
                        help="true-robot alpha, theta error std [deg] (default 0.2)")
    parser.add_argument("--tool-std", type=spread_mm, default=1.0,
                        help="true-robot tool point error std [mm] (default 1)")
    parser.add_argument("--known-distances", action="store_true",
                        help="write the true centre-to-centre distances into fixtures.yaml")
    parser.add_argument("--stiffness", default=None, metavar="K[,K...]",
                        help="elastic joints of the true robot: stiffness [Nm/rad], one value for every joint or "
                             "one per joint separated by commas, 0 = rigid (e.g. 0,3e4,3e4,3e4,0,0,0 on a 7-joint "
                             "arm); links sag "
                             "under gravity from the robot's inertials (default: the robot file's compliance, rigid "
                             "without one)")
    parser.add_argument("--solver", default="osqp", help="QP solver (qpsolvers name; osqp is persistent)")


def run(args: argparse.Namespace) -> int:
    """Check the options, simulate and write the three files (nothing is written unless everything succeeded)."""
    from pathlib import Path

    from spherecal.options import check_folder, planned_outputs
    from spherecal.validation.experiments.simulation import SimulationConfig, simulate_to_folder, simulation_outputs

    check_per_fixture(args, 1)
    check_robot_names(args)  # an unknown robot name, by its option
    check_folder(args.out, writes=("samples.csv", "fixtures.yaml", "truth.yaml"))
    # found before the simulation runs, not when the files are written; --fixtures may be out/fixtures.yaml
    outputs = planned_outputs(args, {"--out": simulation_outputs(args.out)})
    links = urdf_links(args)
    config = SimulationConfig(
        out=Path(args.out), robot=args.robot, tip_link=links["tip_link"], base_link=links["base_link"],
        inertials=links["inertials"], seed=args.seed, seconds=args.seconds, samples=args.per_fixture,
        mode=args.mode, noise=args.noise * 1e-3, fixtures=args.fixtures, length_std=args.length_std * 1e-3,
        angle_std_deg=args.angle_std_deg, tool_std=args.tool_std * 1e-3, known_distances=args.known_distances,
        stiffness=args.stiffness, solver=args.solver,
    )
    result = simulate_to_folder(config, outputs, report=links["report"])
    samples, fixtures, truth = result.files
    print(result.run.coverage_table())  # a table: stdout (stderr holds warnings and errors)
    print(f"wrote {samples} ({result.run.q.shape[0]} samples), {fixtures}, {truth}")
    return 0
