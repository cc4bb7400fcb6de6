"""One validation: nominal and calibrated models against motion capture (simulated or recorded).

Build the validation sets (random workspace configurations and the recorded self-motion sets, each
measured by the mocap), then compare; the report prints the two error columns and the noise floor.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from spherecal.correction import RobotModel, tool_point

from .compare import (
    RANDOM_CONFIGURATIONS,
    Comparison,
    DeviationRows,
    ValidationSet,
    compare,
    format_comparisons,
    parameter_deviations,
    sum_groups,
)
from .mocap import MARKER_NOISE, MocapMeasurement, SimulatedMocap, random_mocap_transform

RANDOM_SET = "random workspace"


@dataclass
class ValidationReport:
    """The outcome of a validation.

    Attributes:
        comparisons: one per validation set (the random workspace set first).
        deviations: deviations from the truth of what the calibration determines, when the truth is known.
        sets: the validation sets themselves (for recordings).
        noise: per-marker noise of the simulated mocap [m], or None for a recording.
        source: ``"simulated"`` or the mocap file.
    """

    comparisons: list[Comparison]
    deviations: DeviationRows | None
    sets: list[ValidationSet] = field(repr=False)
    noise: float | None
    source: str

    def comparison(self, name: str) -> Comparison:
        """The comparison of the set called ``name``."""
        return next(c for c in self.comparisons if c.name == name)

    def format(self) -> str:
        """The printed table (mm), with the noise floor and its meaning."""
        head = f"tool-point error after registration, {self.source} mocap"
        if self.noise is not None:
            head += f" (marker noise {self.noise * 1e3:.2f} mm std)"
        return head + "\n" + format_comparisons(self.comparisons)

    def to_dict(self) -> dict:
        """Plain data (metres) for a JSON result file."""

        def stats(s):
            return None if s is None else {"mean": s.mean, "std": s.std, "max": s.max, "count": s.count}

        out = {
            "source": self.source,
            "marker_noise": self.noise,
            "units": "m",
            "sets": {
                c.name: {
                    "vs_mocap": {k: stats(v) for k, v in c.vs_mocap.items()},
                    "vs_exact": {k: stats(v) for k, v in c.vs_exact.items()},
                    "mocap_floor": stats(c.floor),
                }
                for c in self.comparisons
            },
        }
        if self.deviations is not None:
            d = self.deviations
            out["parameter_deviations"] = {
                "units": "m, rad",
                "names": list(d.names),
                "nominal_minus_truth": d.nominal.tolist(),
                "calibrated_minus_truth": d.calibrated.tolist(),
                "held_at_nominal": list(d.held),
            }
        return out


def validate_models(
    nominal: RobotModel,
    calibrated: RobotModel,
    rng: np.random.Generator,
    truth: RobotModel | None = None,
    measurement: MocapMeasurement | None = None,
    self_motion: dict[str, np.ndarray] | None = None,
    configurations: int = RANDOM_CONFIGURATIONS,
    noise: float = MARKER_NOISE,
    fixed: dict[str, str] | None = None,
    progress=None,
) -> ValidationReport:
    """Validate a calibration against motion capture.

    Simulated (no ``measurement``): a mocap at a random unknown pose looks at the true robot's
    plant; it measures ``configurations`` random configurations (uniform in the limits) and every
    self-motion set. Recorded (``measurement`` given): its configurations and tool points are used;
    if ``truth`` is given too, the plant's exact tool points are added as the second column.

    Args:
        nominal, calibrated: the models compared (same joint count and convention).
        rng: seeded generator (mocap pose, configurations, noise).
        truth: the true robot (simulation), or None.
        measurement: a recorded mocap measurement, or None to simulate one.
        self_motion: fixture name -> (K, n) recorded self-motion configurations [rad].
        configurations: number of random workspace configurations (simulation).
        noise: per-marker noise std of the simulated mocap [m].
        fixed: parameters the calibration held at nominal (name -> reason); default: the calibrated
            file's ``calibration.fixed``. They are left out of ``deviations``, and a length only
            identifiable in a sum is compared as that sum (``d7 + tool_z``).
        progress: called with the number of configurations measured after each set, or None.

    Returns:
        The report; ``deviations`` is set when ``truth`` is.
    """
    models = {"nominal": nominal, "calibrated": calibrated}
    if fixed is None:
        fixed = dict((calibrated.extras.get("calibration") or {}).get("fixed") or {})
    deviations = None if truth is None else parameter_deviations(nominal, calibrated, truth).identifiable(fixed)
    if measurement is not None:
        exact = None
        if truth is not None:
            exact = SimulatedMocap(truth, np.eye(4), noise=0.0).plant_points(measurement.q)[1]
        sets = [ValidationSet(f"recorded ({len(measurement)})", measurement.q, measurement.tool, exact)]
        return ValidationReport(compare(models, sets), deviations, sets, None, measurement.source)
    if truth is None:
        raise ValueError("a simulated validation needs the true robot")
    mocap = SimulatedMocap(truth, random_mocap_transform(rng), noise=noise)
    named = {RANDOM_SET: truth.random_configurations(configurations, rng)}
    named.update({f"self-motion {k}": np.atleast_2d(v) for k, v in (self_motion or {}).items()})
    sets = []
    for name, q in named.items():
        measured = mocap.measure(q, rng)
        sets.append(ValidationSet(name, q, measured.tool, measured.exact_tool))
        if progress is not None:
            progress(len(q))
    return ValidationReport(compare(models, sets), deviations, sets, noise, "simulated")


def record_validation(recording, report: ValidationReport, models: dict[str, RobotModel]) -> None:
    """Log a validation into a :class:`validation.recording.Recording`: each model's tool points on the
    first set coloured by their error (against the exact tool point in a simulation, else the mocap),
    with histograms, and the printed table."""
    first, comparison = report.sets[0], report.comparisons[0]
    errors = comparison.errors_exact or comparison.errors_mocap
    against = "the true tool point" if comparison.errors_exact else "the mocap"
    top = max(float(np.quantile(e, 0.99)) for e in errors.values()) * 1e3  # one colour scale for all models
    for key, model in models.items():
        # the set's name less its count ('recorded (5000)'): the heading counts the points ('the mocap (recorded
        # (5000)), 5000 points' read double, h6's review)
        name = re.sub(r" \(\d+\)$", "", first.name)
        recording.workspace_errors(key, tool_point(model, first.q), errors[key], f"{against} ({name})", top)
    text = report.format()
    if report.deviations is not None:
        text += "\n\nparameter deviations from the truth:\n" + report.deviations.format()
    recording.text("validation", text, "Validation table (mm)")


def record_validate_run(recording, report: ValidationReport, models: dict[str, RobotModel], drawn: str) -> None:
    """What ``spherecal validate`` records: the robot ``models[drawn]`` through the self-motion sets
    (else the first 300 configurations of the first set, 0.5 s each) on ``time``, the fixture centres
    and parameter changes of the calibrated file's ``calibration:`` block when it has one, the errors,
    and the joint coverage per self-motion set."""
    calibrated = models["calibrated"]
    block = calibrated.extras.get("calibration") or {}
    centres = block.get("fixture_centres") or {}
    if centres:
        recording.fixtures(list(centres), np.array(list(centres.values()), dtype=float))
    motion = [s for s in report.sets if s.name.startswith("self-motion ")]
    if motion:
        q = np.concatenate([s.q for s in motion])
        recording.self_motion(models[drawn], np.arange(len(q)) * 0.02, q)
    else:
        q = report.sets[0].q[:300]
        recording.self_motion(models[drawn], np.arange(len(q)) * 0.5, q)
    record_validation(recording, report, {"nominal": models["nominal"], "calibrated": calibrated})
    if block.get("identified"):
        truth = models.get("truth")
        record_parameters(recording, models["nominal"], calibrated, block["identified"], block.get("std") or {},
                          block.get("fixed") or {}, truth)
    if motion:
        per_fixture = {s.name.removeprefix("self-motion "): s.q for s in motion}
        recording.coverage(per_fixture, calibrated.lower, calibrated.upper)


def record_parameters(
    recording,
    nominal: RobotModel,
    calibrated: RobotModel,
    identified: list[str],
    std: dict[str, float],
    fixed: dict[str, str],
    truth: RobotModel | None = None,
) -> None:
    """Log the identified parameters' changes (calibrated minus nominal) with their std, and the true
    changes in a simulation; a length only identifiable in a sum is shown as that sum (``d7 + tool_z``).

    Args:
        recording: a :class:`validation.recording.Recording`.
        nominal, calibrated: the models.
        identified: names of the identified parameters.
        std: name -> predicted std [m, rad].
        fixed: name -> reason, the parameters held at nominal.
        truth: the true robot, or None.
    """
    groups = sum_groups(fixed, nominal.layout)
    index = {n: i for i, n in enumerate(nominal.param_names)}
    names, kinds, change, spread, true = [], [], [], [], []
    for name in identified:
        members = groups.get(name, [name])
        names.append(" + ".join(members))
        kinds.append(nominal.layout.kinds[index[name]])
        change.append(sum(calibrated.params[index[m]] - nominal.params[index[m]] for m in members))
        spread.append(float(std.get(name, np.nan)))
        if truth is not None:
            true.append(sum(truth.params[index[m]] - nominal.params[index[m]] for m in members))
    truths = None if truth is None else np.array(true)
    recording.parameter_changes(names, kinds, np.array(change), np.array(spread), truths)
