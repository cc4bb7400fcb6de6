"""The end-to-end demo: a seeded true Panda, self-motion at three fixtures, calibration, mocap
validation, the table, a Rerun recording and result files that say what made them."""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from spherecal.correction import RobotModel, save_robot, tool_point
from spherecal.correction.files.earlier_run import leading_comments, refuse_unless_own
from spherecal.correction.files.fixtures import format_fixtures
from spherecal.correction.files.outputs import OutputSet, check_folder
from spherecal.correction.files.provenance import comment_block, provenance
from spherecal.correction.files.samples_csv import format_samples
from spherecal.correction.files.text_input import read_text

from ..mocap import MARKER_NOISE, MocapMeasurement, write_mocap_csv
from ..pipeline import RANDOM_SET, ValidationReport, record_parameters, record_validation, validate_models
from ..progress import progress_bar
from ..viewer.recording import Recording
from .experiment import calibrate_from, default_fixtures, motion_set, nominal_robot, true_robot

#: Self-motion per fixture [s] and samples kept per fixture. The fixture compliance of the plant is
#: correlated in time (a new offset every 0.2 s), so the information grows with the duration, not with
#: the sample count alone: 20 s x 500 (the paper's) gives ~0.17 mm at 0.3 mm noise, 60 s x 1500 ~0.1 mm.
DEMO_SECONDS = 60.0
DEMO_SAMPLES = 1500


@dataclass(frozen=True)
class DemoConfig:
    """Options of ``spherecal demo``.

    Attributes:
        seed: seed of everything (true robot, motion, noise, mocap).
        samples: samples kept per fixture.
        noise: fixture noise in the calibration data [m].
        mocap_noise: per-marker mocap noise [m].
        seconds: simulated self-motion per fixture [s].
        configurations: random workspace validation configurations.
        source: ``"mujoco"`` or ``"synthetic"`` motion.
        out: output folder.
        rrd: write ``demo.rrd`` into ``out``.
        spawn: stream to a live viewer.
        quiet: no progress bars (they are off anyway when stderr is not a terminal).
    """

    seed: int = 0
    samples: int = DEMO_SAMPLES
    noise: float = 0.3e-3
    mocap_noise: float = MARKER_NOISE
    seconds: float = DEMO_SECONDS
    configurations: int = 5000
    source: str = "mujoco"
    out: Path = Path("spherecal-demo")
    rrd: bool = True
    spawn: bool = False
    quiet: bool = False


@dataclass
class DemoResult:
    """What the demo produced."""

    truth: RobotModel
    nominal: RobotModel
    calibrated: RobotModel
    report: ValidationReport
    calibration: object = None  # identification.calibrate.CalibrationResult
    files: dict[str, Path] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)


def run_demo(config: DemoConfig, say=print) -> DemoResult:
    """Run the demo; ``say`` prints progress lines. The output folder is checked first, the files
    appear together at the end (or none of them)."""
    outputs = demo_outputs(config)
    timings: dict[str, float] = {}
    clock = time.perf_counter()
    rng = np.random.default_rng(config.seed)
    nominal = nominal_robot()
    truth = true_robot(nominal, rng)
    fixtures = default_fixtures()
    say(
        f"[1/4] true robot: nominal Panda perturbed (seed {config.seed}); self-motion ({config.source}) at "
        f"{', '.join(fixtures)}, {config.samples} samples each, fixture noise {config.noise * 1e3:.2f} mm"
    )
    total = config.seconds * len(fixtures)
    with progress_bar(total, "self-motion", "s simulated", config.quiet or config.source != "mujoco", 1) as advance:
        data = motion_set(
            truth, nominal, fixtures, config.samples, config.noise, rng, config.source, config.seconds, advance
        )
    timings["motion"] = time.perf_counter() - clock

    say(f"[2/4] calibrating from {len(data.dataset.q)} samples, fixture distances known")
    clock = time.perf_counter()
    # the demo knows the truth: it goes on past a self-check refusal (printed in the summary) to show it
    calibration = calibrate_from(nominal, data, force=True)
    calibrated = calibration.model
    timings["calibration"] = time.perf_counter() - clock
    say(calibration.summary())

    say(
        f"[3/4] validating with simulated mocap ({config.mocap_noise * 1e3:.2f} mm per marker): "
        f"{config.configurations} random configurations and the self-motion sets"
    )
    clock = time.perf_counter()
    self_motion = {name: data.dataset.for_fixture(name) for name in data.dataset.fixture_names}
    total = config.configurations + len(data.dataset.q)
    with progress_bar(total, "validation", "configurations", config.quiet) as advance:
        report = validate_models(
            nominal,
            calibrated,
            rng,
            truth=truth,
            self_motion=self_motion,
            configurations=config.configurations,
            noise=config.mocap_noise,
            fixed=calibration.fixed,
            progress=advance,
        )
    timings["validation"] = time.perf_counter() - clock
    result = DemoResult(truth, nominal, calibrated, report, calibration, timings=timings)
    say(report.format())
    say(deviation_summary(report))
    say(summary(report))

    say(f"[4/4] writing results to {config.out}/")
    clock = time.perf_counter()
    result.files = write_results(config, result, data, fixtures, outputs)
    timings["writing"] = time.perf_counter() - clock
    return result


def summary(report: ValidationReport) -> str:
    """The headline: nominal and calibrated mean errors, both columns, the floor beside."""
    c = report.comparison(RANDOM_SET)
    return (
        f"random workspace, mean error: nominal {c.vs_exact['nominal'].mean * 1e3:.3f} mm -> calibrated "
        f"{c.vs_exact['calibrated'].mean * 1e3:.3f} mm against the exact tool point; "
        f"{c.vs_mocap['nominal'].mean * 1e3:.3f} -> {c.vs_mocap['calibrated'].mean * 1e3:.3f} mm against the mocap "
        f"(noise floor {c.floor.mean * 1e3:.3f} mm)"
    )


def deviation_summary(report: ValidationReport) -> str:
    """RMS deviation from the truth of the identified lengths [mm] and angles [deg] (the paper's Fig. 3).

    The rows are those of ``report.deviations``: parameters held at nominal are left out, and a
    length only identifiable in a sum counts as that sum (``d7 + tool_z``)."""
    d = report.deviations
    parts = []
    for kind in dict.fromkeys(d.kinds):  # lengths, angles (and compliances of an elastic model), in order
        mask = np.array([k is kind for k in d.kinds])
        nominal, calibrated = (np.sqrt(np.mean(d.display(v)[mask] ** 2)) for v in (d.nominal, d.calibrated))
        parts.append(f"{mask.sum()} {kind.name}s {nominal:.4f} -> {calibrated:.4f} {kind.display_unit}")
    return (
        f"identified parameters, RMS deviation from the truth (nominal -> calibrated; held at nominal left out, "
        f"{' and '.join(n for n in d.names if '+' in n) or 'no sums'} as sums): {'; '.join(parts)}"
    )


def _inputs(config: DemoConfig, data=None) -> dict:
    inputs = {
        "seed": config.seed,
        "samples_per_fixture": config.samples,
        "fixture_noise_m": config.noise,
        "mocap_noise_m": config.mocap_noise,
        "seconds_per_fixture": config.seconds,
        "configurations": config.configurations,
        "motion_source": config.source,
    }
    run = None if data is None else data.trajectory
    if run is not None:  # MuJoCo: the controller's rate over the 1 kHz physics shapes the samples
        inputs["control_rate_hz"] = run.settings.control_rate
    return inputs


#: Largest demo.json read to recognise an earlier demo's report [bytes].
MAX_REPORT_BYTES = 16_000_000

#: The files of a demo in its folder (``recording`` only with ``rrd``).
DEMO_FILES = {
    "samples": "samples.csv",
    "fixtures": "fixtures.yaml",
    "mocap": "mocap.csv",
    "truth": "truth.yaml",
    "calibrated": "calibrated.yaml",
    "report": "demo.json",
    "recording": "demo.rrd",
}


def demo_outputs(config: DemoConfig) -> OutputSet:
    """The demo's files, checked (before the run) and staged together (see :class:`correction.outputs.OutputSet`)."""
    check_folder(config.out, "--out")
    files = [Path(config.out) / name for key, name in DEMO_FILES.items() if key != "recording" or config.rrd]
    outputs = OutputSet({"--out": files})
    # a folder holding a recording (samples.csv, fixtures.yaml) keeps it: only an earlier demo's files are replaced
    refuse_unless_own(files, "--out", "spherecal demo", _demo_own)
    return outputs


def _demo_own(path: Path) -> bool:
    """Whether an existing file is an earlier demo's: text files start with the ``# spherecal demo`` line, the
    report is the demo's JSON, the recording lies beside such a report."""
    if path.name == DEMO_FILES["recording"]:
        return (path.parent / DEMO_FILES["report"]).is_file() and _demo_own(path.parent / DEMO_FILES["report"])
    if path.name == DEMO_FILES["report"]:
        try:
            report = json.loads(read_text(path, OSError, limit=MAX_REPORT_BYTES))
        except (OSError, ValueError):
            return False
        return isinstance(report, dict) and {"provenance", "fixtures_true_centres_m"} <= set(report)
    return leading_comments(path)[:1] == ["spherecal demo"]


def write_results(config: DemoConfig, result: DemoResult, data, fixtures: dict[str, np.ndarray],
                  outputs: OutputSet | None = None) -> dict[str, Path]:
    """Samples, fixtures, truth, calibrated model, report JSON and the recording, each with provenance:
    staged in ``outputs`` and renamed into place together."""

    out = Path(config.out)
    outputs = demo_outputs(config) if outputs is None else outputs
    info = provenance(config.seed, _inputs(config, data))
    header = "spherecal demo\n" + comment_block(info)
    comment = "".join(f"# {line}\n" for line in header.splitlines())
    first = result.report.sets[0]
    measured = MocapMeasurement(q=first.q, tool=first.measured)
    files = {key: out / name for key, name in DEMO_FILES.items()}
    with outputs:
        outputs.write_text(files["samples"], comment + format_samples(data.dataset))
        outputs.write_text(files["fixtures"], comment + format_fixtures(data.spec))
        write_mocap_csv(outputs.stage(files["mocap"]), measured, comment=header + "\nsimulated mocap, random set")
        save_robot(result.truth, outputs.stage(files["truth"]), header=header + "\nthe TRUE robot of this simulation")
        save_robot(_with_block(result, info), outputs.stage(files["calibrated"]), header=header)
        report = {
            "provenance": info,
            "fixtures_true_centres_m": {k: v.tolist() for k, v in fixtures.items()},
            "timings_s": result.timings,
            "validation": result.report.to_dict(),
        }
        outputs.write_text(files["report"], json.dumps(report, indent=2) + "\n")
        if config.rrd or config.spawn:
            write_recording(config, result, data, fixtures, outputs.stage(files["recording"]) if config.rrd else None,
                            info)
    return {k: v for k, v in files.items() if k != "recording" or config.rrd}


def write_recording(config: DemoConfig, result: DemoResult, data, fixtures: dict[str, np.ndarray],
                    path: Path | None = None, info: dict | None = None) -> Path | None:
    """The demo's Rerun recording (entity paths and layout in :mod:`validation.recording`), into ``path``
    (the staged ``demo.rrd``), or a live viewer only; ``info``: the provenance block the demo's other files hold."""

    recording = Recording(path, spawn=config.spawn, title="True robot (simulated) and fixtures, self-motion on 'time'",
                          run=info)
    try:
        if info is not None:
            recording.provenance(info)
        recording.fixtures(list(fixtures), np.array(list(fixtures.values())))
        trajectory = data.trajectory
        if trajectory is not None:
            recording.self_motion(result.truth, trajectory.trajectory_t, trajectory.trajectory_q)
        dataset = data.dataset
        recording.samples(tool_point(result.truth, dataset.q), dataset.labels)
        record_validation(recording, result.report, {"nominal": result.nominal, "calibrated": result.calibrated})
        calibration = result.calibration
        recording.residuals(calibration.residual_before, calibration.residual_after)
        record_parameters(recording, result.nominal, result.calibrated, calibration.identified, calibration.std,
                          calibration.fixed, result.truth)
        per_fixture = {name: dataset.for_fixture(name) for name in dataset.fixture_names}
        recording.coverage(per_fixture, result.truth.lower, result.truth.upper)
        recording.text("calibration", calibration.summary(), "Calibration table (mm, deg)")
        recording.text("deviations", deviation_summary(result.report) + "\n\n" + result.report.deviations.format(),
                       "Parameter deviations from the truth (mm, deg)")
    except BaseException:
        recording.abort()
        raise
    return recording.close()


def _with_block(result: DemoResult, info: dict) -> RobotModel:
    """The calibrated model with identification's ``calibration:`` block and the demo's provenance."""
    block = {**result.calibration.block(), "provenance": info}
    extras = {k: v for k, v in result.nominal.extras.items() if k != "calibration"}
    return replace(result.calibrated, extras={**extras, "calibration": block})
