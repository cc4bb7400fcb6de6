"""One validation: nominal and calibrated models against motion capture (simulated or recorded).

Build the validation sets (random workspace configurations and the recorded self-motion sets, each
measured by the mocap), then compare; the report prints the two error columns and the noise floor.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from spherecal.correction import RobotModel, tool_point

from .compare import (
    RANDOM_CONFIGURATIONS,
    Comparison,
    ParameterDeviations,
    ValidationSet,
    compare,
    format_comparisons,
    parameter_deviations,
)
from .mocap import MARKER_NOISE, MocapMeasurement, SimulatedMocap, random_mocap_transform

RANDOM_SET = "random workspace"


@dataclass
class ValidationReport:
    """The outcome of a validation.

    Attributes:
        comparisons: one per validation set (the random workspace set first).
        deviations: parameter deviations from the truth, when the truth is known.
        sets: the validation sets themselves (for recordings).
        noise: per-marker noise of the simulated mocap [m], or None for a recording.
        source: ``"simulated"`` or the mocap file.
    """

    comparisons: list[Comparison]
    deviations: ParameterDeviations | None
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

    Returns:
        The report; ``deviations`` is set when ``truth`` is.
    """
    models = {"nominal": nominal, "calibrated": calibrated}
    deviations = None if truth is None else parameter_deviations(nominal, calibrated, truth)
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
    return ValidationReport(compare(models, sets), deviations, sets, noise, "simulated")


def record_validation(recording, report: ValidationReport, models: dict[str, RobotModel]) -> None:
    """Log a validation into a :class:`validation.recording.Recording`: the first set's measured and
    predicted points with error vectors (Fig. 8), and its per-configuration errors per model [mm]
    under ``plots/error/<model>`` (against the mocap, else against the exact tool point)."""
    first, comparison = report.sets[0], report.comparisons[0]
    reference = first.measured if first.measured is not None else first.exact
    recording.validation(reference, {key: tool_point(model, first.q) for key, model in models.items()})
    errors = comparison.errors_mocap or comparison.errors_exact
    for key, values in errors.items():
        recording.series(f"plots/error/{key}", values * 1e3)
