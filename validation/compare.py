"""Nominal against calibrated: tool-point errors after registration, and parameter deviations.

Two error columns are kept apart everywhere:

* ``vs mocap``: against the motion-capture measurement, what a real lab sees. It contains the
  mocap noise, so no model goes below the *floor* (the true robot's own error against the mocap).
* ``vs exact``: against the plant's exact tool point (simulation only): the model's own accuracy.

Each model is registered on its own (best rigid fit of its predicted points onto the reference),
since neither the mocap frame nor the robot base placement is known to the user.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from correction import RobotModel, registered_errors, tool_point

#: Validation configurations drawn uniformly inside the joint limits (the paper's "large random set").
RANDOM_CONFIGURATIONS = 5000


@dataclass(frozen=True)
class ErrorStats:
    """Mean, standard deviation and maximum of a set of tool-point errors.

    Attributes:
        mean, std, max: [m].
        count: number of configurations.
    """

    mean: float
    std: float
    max: float
    count: int

    @classmethod
    def of(cls, errors: np.ndarray) -> ErrorStats:
        """Statistics of (N,) errors [m]."""
        errors = np.asarray(errors, dtype=float)
        return cls(float(errors.mean()), float(errors.std()), float(errors.max()), int(errors.size))

    def mm(self) -> tuple[float, float, float]:
        """(mean, std, max) in millimetres."""
        return self.mean * 1e3, self.std * 1e3, self.max * 1e3


@dataclass(frozen=True)
class Comparison:
    """Errors of several models on one set of configurations.

    Attributes:
        name: the set (``"random workspace"``, ``"self-motion P1"``, ...).
        vs_mocap: model name -> errors against the mocap measurement (after registration).
        vs_exact: model name -> errors against the exact tool point (simulation only, else empty).
        floor: the true robot's errors against the mocap (the noise floor), or None if unknown.
        errors_mocap, errors_exact: model name -> (N,) errors [m], for plots and recordings.
    """

    name: str
    vs_mocap: dict[str, ErrorStats]
    vs_exact: dict[str, ErrorStats]
    floor: ErrorStats | None
    errors_mocap: dict[str, np.ndarray]
    errors_exact: dict[str, np.ndarray]


def compare(
    name: str,
    models: dict[str, RobotModel],
    q: np.ndarray,
    measured: np.ndarray | None = None,
    exact: np.ndarray | None = None,
) -> Comparison:
    """Tool-point errors of each model on configurations ``q``, after registration.

    Args:
        name: name of the configuration set.
        models: model name -> model (e.g. ``{"nominal": ..., "calibrated": ...}``).
        q: (N, n) joint angles [rad].
        measured: (N, 3) mocap tool points in the mocap frame [m], or None.
        exact: (N, 3) exact tool points (the plant's) in the base frame [m], or None.

    Returns:
        The comparison; ``floor`` is the error of ``exact`` against ``measured`` when both exist.
    """
    predicted = {key: tool_point(model, q) for key, model in models.items()}
    e_mocap = {} if measured is None else {k: registered_errors(p, measured) for k, p in predicted.items()}
    e_exact = {} if exact is None else {k: registered_errors(p, exact) for k, p in predicted.items()}
    floor = None
    if measured is not None and exact is not None:
        floor = ErrorStats.of(registered_errors(exact, measured))
    return Comparison(
        name=name,
        vs_mocap={k: ErrorStats.of(e) for k, e in e_mocap.items()},
        vs_exact={k: ErrorStats.of(e) for k, e in e_exact.items()},
        floor=floor,
        errors_mocap=e_mocap,
        errors_exact=e_exact,
    )


def format_comparisons(comparisons: list[Comparison]) -> str:
    """A fixed-width table in mm: one row per set and model, the two columns side by side."""

    def cell(stats: ErrorStats | None) -> str:
        return "      -        -        -" if stats is None else "{:8.3f} {:8.3f} {:8.3f}".format(*stats.mm())

    lines = [
        f"{'set':<22} {'model':<11} | {'vs mocap [mm]':^26} | {'vs exact tool point [mm]':^26}",
        f"{'':<22} {'':<11} | {'mean':>8} {'std':>8} {'max':>8} | {'mean':>8} {'std':>8} {'max':>8}",
    ]
    for c in comparisons:
        for key in list(dict.fromkeys([*c.vs_mocap, *c.vs_exact])):
            lines.append(f"{c.name:<22} {key:<11} | {cell(c.vs_mocap.get(key))} | {cell(c.vs_exact.get(key))}")
        if c.floor is not None:
            lines.append(f"{c.name:<22} {'mocap floor':<11} | {cell(c.floor)} | (true robot vs mocap noise)")
    return "\n".join(lines)


@dataclass(frozen=True)
class ParameterDeviations:
    """Identified minus true parameters (the paper's Fig. 3).

    Attributes:
        names: (P,) parameter names.
        nominal: (P,) nominal minus truth [m, rad].
        calibrated: (P,) calibrated minus truth [m, rad].
    """

    names: tuple[str, ...]
    nominal: np.ndarray
    calibrated: np.ndarray

    @staticmethod
    def is_angle(name: str) -> bool:
        """True for angular parameters (shown in degrees), false for lengths (shown in mm)."""
        return name.startswith(("alpha", "theta", "base_roll", "base_pitch", "base_yaw"))

    def display(self, values: np.ndarray) -> np.ndarray:
        """(P,) values in display units: mm for lengths, degrees for angles."""
        scale = np.array([np.rad2deg(1.0) if self.is_angle(n) else 1e3 for n in self.names])
        return np.asarray(values) * scale

    def format(self) -> str:
        """One line per parameter: nominal and calibrated deviation from the truth (mm or deg)."""
        nominal, calibrated = self.display(self.nominal), self.display(self.calibrated)
        lines = [f"{'parameter':<11} {'unit':<4} {'nominal-truth':>14} {'calibrated-truth':>17}"]
        for name, a, b in zip(self.names, nominal, calibrated, strict=True):
            lines.append(f"{name:<11} {'deg' if self.is_angle(name) else 'mm':<4} {a:14.4f} {b:17.4f}")
        return "\n".join(lines)


def parameter_deviations(nominal: RobotModel, calibrated: RobotModel, truth: RobotModel) -> ParameterDeviations:
    """Deviations of the nominal and calibrated parameters from the truth (same convention and size)."""
    return ParameterDeviations(
        names=truth.param_names,
        nominal=nominal.params - truth.params,
        calibrated=calibrated.params - truth.params,
    )
