"""`spherecal simulate`: self-motion at spherical-joint fixtures on a perturbed (true) robot."""

from __future__ import annotations

import argparse

from spherecal.options import fail, stiffness_values, urdf_links

FILES = ("samples.csv", "fixtures.yaml", "truth.yaml")
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
                        help="fixtures.yaml giving the true centre (position) of every fixture [m]")
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
                             "one per joint separated by commas, 0 = rigid (e.g. 0,3e4,3e4,3e4,0,0,0); links sag "
                             "under gravity from the robot's inertials (default: the robot file's compliance, rigid "
                             "without one)")
    parser.add_argument("--solver", default="osqp", help="QP solver (qpsolvers name; osqp is persistent)")


def _fixtures(path: str | None) -> dict:
    """name -> (3,) true centres, from ``path`` or the defaults."""
    import numpy as np

    if path is None:
        from spherecal.controller.self_motion import DEFAULT_FIXTURES  # MuJoCo: only when simulating

        return {k: np.array(v, dtype=float) for k, v in DEFAULT_FIXTURES.items()}
    from spherecal.correction.files.fixtures import read_fixtures

    spec = read_fixtures(path)
    missing = [name for name in spec.names if name not in spec.positions]
    if missing:
        raise fail(f"{path}: field 'fixtures.{missing[0]}.position': simulate needs the true centre of every "
                    "fixture")
    return {name: spec.positions[name] for name in spec.names}


def _check_args(args: argparse.Namespace):
    """Check the options and the output folder; returns the checked :class:`OutputSet`."""
    from pathlib import Path

    from spherecal.options import check_folder, planned_outputs

    if not args.seconds >= 0.001:
        raise fail(f"--seconds must be >= 0.001 (one 1 kHz step), got {args.seconds}")
    if not 1 <= args.per_fixture <= int(round(args.seconds * 1000)):
        raise fail(
            f"--per-fixture must be in 1..{int(round(args.seconds * 1000))} (1 kHz x seconds), got {args.per_fixture}"
        )
    out = Path(args.out)
    check_folder(args.out)
    # found before the simulation runs, not when the files are written; --fixtures may be out/fixtures.yaml
    outputs = planned_outputs(args, {"--out": [out / name for name in FILES]})
    from spherecal.correction.files.earlier_run import refuse_foreign_files

    # a folder holding a recording keeps it: only an earlier simulation's own files are replaced
    refuse_foreign_files([out / name for name in FILES], "--out", "simulation", "spherecal simulate")
    return outputs


def run(args: argparse.Namespace) -> int:
    """Simulate, then write the three files (nothing is written unless everything succeeded)."""
    import sys
    from pathlib import Path

    import numpy as np
    import qpsolvers

    from spherecal.controller.self_motion import SelfMotionSettings, collect_self_motion
    from spherecal.correction import dump_robot, load_robot, perturb
    from spherecal.correction.files.fixtures import FixtureSpec, format_fixtures
    from spherecal.correction.files.provenance import comment_block
    from spherecal.correction.files.samples_csv import format_samples

    outputs = _check_args(args)
    if args.solver not in qpsolvers.available_solvers:
        raise fail(f"--solver {args.solver!r} is not installed; have {', '.join(qpsolvers.available_solvers)}")
    nominal = load_robot(args.robot, **urdf_links(args))
    if nominal.n_joints < 4:  # the tool point pinned leaves n - 3 degrees of freedom
        raise fail(f"--robot {args.robot}: {nominal.n_joints} joints have no self-motion at a spherical joint "
                    "(needs at least 4)")
    fixtures = _fixtures(args.fixtures)
    rng = np.random.default_rng(args.seed)
    true = perturb(nominal, rng, args.length_std * 1e-3, np.deg2rad(args.angle_std_deg), args.tool_std * 1e-3)
    stiffness = stiffness_values(args.stiffness, nominal.n_joints)
    if stiffness is not None:
        from spherecal.correction.elastic import with_compliance

        compliance = np.divide(1.0, stiffness, out=np.zeros(nominal.n_joints), where=np.array(stiffness) > 0)
        true = with_compliance(true, compliance if np.any(compliance) else None)
    from spherecal.correction.elastic import compliance_of

    compliance_of(true)  # a compliance without inertials: one line naming the field, before simulating
    settings = SelfMotionSettings(seconds=args.seconds, samples=args.per_fixture, mode=args.mode,
                                  noise=args.noise * 1e-3, solver=args.solver)
    from spherecal.controller.self_motion import UnreachableFixtureError

    try:
        result = collect_self_motion(true, nominal, fixtures, rng, settings)
    except UnreachableFixtureError as error:  # name the file and field that put the fixture there
        source = f"{args.fixtures}: field 'fixtures.{error.fixture}.position'" if args.fixtures else \
            f"--fixtures (default fixture {error.fixture})"
        raise fail(f"{source}: {error}") from None

    names = result.fixture_names
    distances = []
    if args.known_distances:
        centres = result.fixture_centres
        distances = [(names[i], names[j], float(np.linalg.norm(centres[i] - centres[j])))
                     for i in range(len(names)) for j in range(i + 1, len(names))]
    provenance = _provenance(args, settings, result)
    made = provenance["provenance"]
    samples_text = format_samples(result.dataset(), comment_block(made))
    fixtures_text = format_fixtures(FixtureSpec(names=names, distances=distances,
                                                extras={"simulation": {"truth": "truth.yaml", "provenance": made}}))
    truth = _with_simulation(true, provenance)
    truth_text = dump_robot(truth, header=f"true robot of `spherecal simulate --seed {args.seed}`")

    out = Path(args.out)
    with outputs:  # all three files or none
        for name, text in zip(FILES, (samples_text, fixtures_text, truth_text), strict=True):
            outputs.write_text(out / name, text)
    print(result.coverage_table(), file=sys.stderr)
    print(f"wrote {out / 'samples.csv'} ({result.q.shape[0]} samples), {out / 'fixtures.yaml'}, {out / 'truth.yaml'}")
    return 0


def _with_simulation(model, provenance: dict):
    from dataclasses import replace

    return replace(model, extras={**model.extras, "simulation": provenance})


def _provenance(args: argparse.Namespace, settings, result) -> dict:
    """The ``simulation:`` block of truth.yaml: provenance (seed, versions, inputs), settings, outcome."""
    from pathlib import Path

    from spherecal.correction.files.provenance import provenance

    inputs = {"robot": Path(args.robot), **({"fixtures": Path(args.fixtures)} if args.fixtures else {})}
    return {
        "provenance": provenance(args.seed, inputs),
        "perturbation": {"length_std_m": args.length_std * 1e-3, "angle_std_deg": args.angle_std_deg,
                         "tool_std_m": args.tool_std * 1e-3, "stiffness_nm_per_rad": args.stiffness},
        "settings": {"seconds": settings.seconds, "samples": settings.samples, "mode": settings.mode,
                     "noise": settings.noise, "solver": settings.solver, "timestep": 0.001},
        "fixtures": {name: [float(v) for v in c] for name, c in zip(result.fixture_names, result.fixture_centres,
                                                                     strict=True)},
        "coverage": {name: [round(float(v), 4) for v in cov] for name, cov in zip(result.fixture_names,
                                                                                 result.coverage, strict=True)},
        "max_violation_m": {name: float(v) for name, v in zip(result.fixture_names, result.max_violation,
                                                                strict=True)},
        "qp_fallbacks": int(result.fallbacks),
    }
