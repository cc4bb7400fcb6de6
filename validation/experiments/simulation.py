"""``spherecal simulate`` as a library call: self-motion at spherical-joint fixtures on a perturbed (true)
robot, written as ``samples.csv``, ``fixtures.yaml`` and ``truth.yaml`` (all three or none)."""

from __future__ import annotations

import os
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from spherecal.controller.reach import UnreachableFixtureError
from spherecal.correction import RobotModel, dump_robot, load_robot, perturb
from spherecal.correction.elastic import compliance_of, with_stiffness
from spherecal.correction.files.earlier_run import refuse_foreign_files
from spherecal.correction.files.fixtures import format_fixtures, read_fixtures
from spherecal.correction.files.outputs import OutputSet
from spherecal.correction.files.provenance import comment_block, provenance
from spherecal.correction.files.samples_csv import format_samples

from .experiment import ExperimentError, arm_reach, default_fixtures, fixture_spec, joint_stiffness, reach_scale

#: The files a simulation writes into its folder.
SIMULATION_FILES = ("samples.csv", "fixtures.yaml", "truth.yaml")


@dataclass(frozen=True)
class SimulationConfig:
    """What ``spherecal simulate`` simulates.

    Attributes:
        out: output folder (``samples.csv``, ``fixtures.yaml``, ``truth.yaml``).
        robot: nominal robot: a robot file, a URDF or an embedded arm's name (:func:`correction.load_robot`).
        tip_link, base_link, inertials: URDF robot: the chain and the inertials file (:func:`correction.load_robot`).
        seed: seed of the true robot, the motion and the noise.
        seconds: self-motion per fixture [s].
        samples: samples kept per fixture (at most ``seconds`` x 1 kHz).
        mode: null-space exploration, ``"coverage"`` or ``"random"`` (the paper's).
        noise: fixture compliance std per axis moving the physical point [m].
        fixtures: fixtures.yaml giving the true centre of every fixture [m] (None: the controller's defaults).
        length_std: true-robot a, d error std [m].
        angle_std_deg: true-robot alpha, theta error std [deg] (degrees: recorded in truth.yaml as given).
        tool_std: true-robot tool point error std [m].
        known_distances: write the true centre-to-centre distances [m] into fixtures.yaml.
        stiffness: elastic joints of the true robot as given: ``"K"`` (every joint) or ``"K,K,..."`` (one per
            joint) [Nm/rad], 0 = rigid; None: the robot file's compliance (rigid without one).
        solver: QP solver (a qpsolvers name).
    """

    out: Path
    robot: str = "panda"
    tip_link: str | None = None
    base_link: str | None = None
    inertials: str | None = None
    seed: int = 0
    seconds: float = 20.0
    samples: int = 500
    mode: str = "coverage"
    noise: float = 0.3e-3
    fixtures: str | None = None
    length_std: float = 1e-3
    angle_std_deg: float = 0.2
    tool_std: float = 1e-3
    known_distances: bool = False
    stiffness: str | None = None
    solver: str = "osqp"


@dataclass(frozen=True)
class SimulationResult:
    """What :func:`simulate_to_folder` wrote.

    Attributes:
        run: the controller's :class:`controller.self_motion.SelfMotionRun` (``coverage_table()``, ``q``: (N, n)).
        files: the written samples.csv, fixtures.yaml and truth.yaml.
    """

    run: object
    files: tuple[Path, ...]


def simulation_outputs(out: str | os.PathLike) -> list[Path]:
    """The files a simulation into ``out`` writes."""
    return [Path(out) / name for name in SIMULATION_FILES]


def simulate_to_folder(config: SimulationConfig, outputs: OutputSet | None = None, report=None) -> SimulationResult:
    """Simulate self-motion on a seeded true robot and write the three files (all or none).

    Args:
        config: what to simulate.
        outputs: the staged outputs holding :func:`simulation_outputs` (checked by the caller against its
            inputs); None: made here.
        report: printer of :func:`correction.load_robot`'s one-line notes (where the inertials came from).

    Raises:
        OutputError: the folder holds a file an earlier simulation did not write (a recording keeps it).
        ExperimentError: a solver not installed, an arm without self-motion, a fixture without its centre, a
            fixture out of reach (naming the file and field that put it there), a bad stiffness.
    """
    import qpsolvers  # qpsolvers: only a simulation needs it (start-up)

    from spherecal.controller.plant import TIMESTEP  # MuJoCo: only a simulation needs it (start-up)
    from spherecal.controller.self_motion import (  # MuJoCo: only a simulation needs it (start-up)
        SelfMotionSettings,
        collect_self_motion,
    )

    files = simulation_outputs(config.out)
    outputs = OutputSet({"--out": files}) if outputs is None else outputs
    # a folder holding a recording keeps it: only an earlier simulation's own files are replaced
    refuse_foreign_files(files, "--out", "simulation", "spherecal simulate")
    if config.solver not in qpsolvers.available_solvers:
        raise ExperimentError(
            f"field '--solver': {config.solver!r} is not installed; have {', '.join(qpsolvers.available_solvers)}")
    nominal = load_robot(config.robot, tip_link=config.tip_link, base_link=config.base_link,
                         inertials=config.inertials, report=report)
    if nominal.n_joints < 4:  # the tool point pinned leaves n - 3 degrees of freedom
        raise ExperimentError(f"field '--robot': {config.robot}: {nominal.n_joints} joints have no self-motion at a "
                              "spherical joint (needs at least 4)")
    fixtures = true_centres(config.fixtures, nominal, report)
    rng = np.random.default_rng(config.seed)
    true = perturb(nominal, rng, config.length_std, np.deg2rad(config.angle_std_deg), config.tool_std)
    stiffness = joint_stiffness(config.stiffness, nominal.n_joints)
    if stiffness is not None:
        true = with_stiffness(true, stiffness)
    compliance_of(true)  # a compliance without inertials: one line naming the field, before simulating
    settings = SelfMotionSettings(seconds=config.seconds, samples=config.samples, mode=config.mode,
                                  noise=config.noise, solver=config.solver)
    try:
        result = collect_self_motion(true, nominal, fixtures, rng, settings)
    except UnreachableFixtureError as error:  # name the file and field that put the fixture there
        source = f"{config.fixtures}: field 'fixtures.{error.fixture}.position'" if config.fixtures else \
            f"field '--fixtures': default fixture {error.fixture}"
        remedy = "move it" if config.fixtures else "give --fixtures F.yaml with the positions"
        robot = config.robot + (f" --tip-link {config.tip_link}" if config.tip_link else "")
        raise ExperimentError(f"{source}: {error}; {remedy} where the arm reaches (spherecal plan --robot {robot} "
                              "--grid auto ranks candidates)") from None

    names = result.fixture_names
    record = _record(config, settings, result, TIMESTEP)
    made = record["provenance"]
    spec = fixture_spec(dict(zip(names, result.fixture_centres, strict=True)), config.known_distances)
    texts = (
        format_samples(result.dataset(), comment_block(made)),
        format_fixtures(replace(spec, extras={"simulation": {"truth": "truth.yaml", "provenance": made}})),
        dump_robot(_with_simulation(true, record), header=f"true robot of `spherecal simulate --seed {config.seed}`"),
    )
    with outputs:  # all three files or none
        for path, text in zip(files, texts, strict=True):
            outputs.write_text(path, text)
    return SimulationResult(result, tuple(files))


def true_centres(path: str | None, nominal: RobotModel | None = None, report=None) -> dict[str, np.ndarray]:
    """name -> (3,) true fixture centre [m], from the fixtures.yaml ``path`` or the defaults for ``nominal``
    (:func:`.experiment.default_fixtures`: the Panda's points, scaled to another arm's reach; ``report`` is
    given one line saying where they are when they are not the Panda's).

    Raises:
        ExperimentError: a fixture of the file without its position (one line naming the file and field).
    """
    if path is None:
        points = default_fixtures(nominal)
        panda = default_fixtures()
        if report is not None and any(not np.array_equal(points[k], panda[k]) for k in panda):
            where = ", ".join(f"{k} {np.round(v, 3).tolist()}" for k, v in points.items())
            report(f"the Panda's default fixtures are out of this arm's reach: scaled to its reach "
                   f"({arm_reach(nominal):.2f} m beyond its base column, {reach_scale(nominal):.2f}x the Panda's): "
                   f"{where} m; give your own with "
                   "--fixtures (spherecal plan ranks candidates)")
        return points
    spec = read_fixtures(path)
    missing = [name for name in spec.names if name not in spec.positions]
    if missing:
        raise ExperimentError(f"{path}: field 'fixtures.{missing[0]}.position': simulate needs the true centre "
                              "of every fixture")
    return {name: spec.positions[name] for name in spec.names}


def _with_simulation(model: RobotModel, record: dict) -> RobotModel:
    return replace(model, extras={**model.extras, "simulation": record})


def _record(config: SimulationConfig, settings, result, timestep: float) -> dict:
    """The ``simulation:`` block of truth.yaml: provenance (seed, versions, inputs), settings (``timestep``: the
    plant's physics step [s]), outcome."""
    inputs = {"robot": Path(config.robot), **({"fixtures": Path(config.fixtures)} if config.fixtures else {})}
    names = result.fixture_names
    return {
        "provenance": provenance(config.seed, inputs),
        "perturbation": {"length_std_m": config.length_std, "angle_std_deg": config.angle_std_deg,
                         "tool_std_m": config.tool_std, "stiffness_nm_per_rad": config.stiffness},
        "settings": {"seconds": settings.seconds, "samples": settings.samples, "mode": settings.mode,
                     "noise": settings.noise, "solver": settings.solver, "timestep": timestep},
        "fixtures": {name: [float(v) for v in c] for name, c in zip(names, result.fixture_centres, strict=True)},
        "coverage": {name: [round(float(v), 4) for v in cov] for name, cov in zip(names, result.coverage,
                                                                                 strict=True)},
        "max_violation_m": {name: float(v) for name, v in zip(names, result.max_violation, strict=True)},
        "qp_fallbacks": int(result.fallbacks),
    }
