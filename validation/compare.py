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

from spherecal.correction import RobotModel, registered_errors, tool_point
from spherecal.correction.elastic import compliance_of, with_compliance
from spherecal.correction.layout import ANGLE, ParameterLayout, ParamKind
from spherecal.correction.scale import scale_of, with_scale

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


@dataclass(frozen=True)
class ValidationSet:
    """Configurations to validate on, with what is known about their tool points.

    Attributes:
        name: e.g. ``"random workspace"`` or ``"self-motion P1"``.
        q: (N, n) joint angles [rad].
        measured: (N, 3) mocap tool points in the mocap frame [m], or None.
        exact: (N, 3) the plant's exact tool points in the base frame [m] (simulation), or None.
    """

    name: str
    q: np.ndarray
    measured: np.ndarray | None = None
    exact: np.ndarray | None = None


def _split_errors(predicted: list[np.ndarray], reference: list[np.ndarray]) -> list[np.ndarray]:
    """Errors after ONE registration over all sets together, split back per set."""
    errors = registered_errors(np.concatenate(predicted), np.concatenate(reference))
    return np.split(errors, np.cumsum([len(p) for p in predicted])[:-1])


def compare(models: dict[str, RobotModel], sets: list[ValidationSet]) -> list[Comparison]:
    """Tool-point errors of each model on each set, after registration.

    Each model is registered once (best rigid fit of its predictions onto the reference) over all
    sets together, as a lab registers its mocap frame once; a self-motion set alone (all points at
    one fixture) could not fix the rotation. The mocap and exact columns are registered separately.

    Args:
        models: model name -> model (e.g. ``{"nominal": ..., "calibrated": ...}``).
        sets: validation sets; every set has ``measured`` or none has, likewise ``exact``.

    Returns:
        One :class:`Comparison` per set; ``floor`` is the error of the exact tool points against
        the measured ones when both are known.
    """
    predicted = {key: [tool_point(model, s.q) for s in sets] for key, model in models.items()}
    columns: dict[str, dict[str, list[np.ndarray]]] = {"measured": {}, "exact": {}}
    for column in columns:
        reference = [getattr(s, column) for s in sets]
        if any(r is None for r in reference):
            if any(r is not None for r in reference):
                raise ValueError(f"either every validation set has {column} tool points or none has")
            continue
        columns[column] = {key: _split_errors(p, reference) for key, p in predicted.items()}
    floors = None
    if columns["measured"] and columns["exact"]:
        floors = _split_errors([s.exact for s in sets], [s.measured for s in sets])
    return [
        Comparison(
            name=s.name,
            vs_mocap={k: ErrorStats.of(e[i]) for k, e in columns["measured"].items()},
            vs_exact={k: ErrorStats.of(e[i]) for k, e in columns["exact"].items()},
            floor=None if floors is None else ErrorStats.of(floors[i]),
            errors_mocap={k: e[i] for k, e in columns["measured"].items()},
            errors_exact={k: e[i] for k, e in columns["exact"].items()},
        )
        for i, s in enumerate(sets)
    ]


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
        layout: the parameter layout (names, kinds, display units).
        nominal: (P,) nominal minus truth [m, rad].
        calibrated: (P,) calibrated minus truth [m, rad].
    """

    layout: ParameterLayout
    nominal: np.ndarray
    calibrated: np.ndarray

    @property
    def names(self) -> tuple[str, ...]:
        """(P,) parameter names."""
        return self.layout.names

    def is_angle(self, name: str) -> bool:
        """True for angular parameters (shown in degrees), false for lengths (shown in mm)."""
        return self.layout.is_angle(name)

    def display(self, values: np.ndarray) -> np.ndarray:
        """(P,) values in display units: mm for lengths, degrees for angles."""
        return np.asarray(values) * self.layout.display_scale()

    def format(self) -> str:
        """One line per parameter: nominal and calibrated deviation from the truth (mm or deg)."""
        return _format_rows(self.names, [self.layout.kinds[self.layout.index(n)] for n in self.names],
                            self.display(self.nominal), self.display(self.calibrated))

    def identifiable(self, fixed: dict[str, str]) -> DeviationRows:
        """The rows a calibration can be judged on: parameters fixed at nominal (``fixed``: name ->
        reason, the calibrated file's ``calibration.fixed``) are left out and listed as held, and a
        length fixed as "redundant with" one other length is added to it (``d7 + tool_z``)."""
        groups = sum_groups(fixed, self.layout)
        names, rows = [], []
        for name in self.names:
            if name not in fixed:
                names.append(" + ".join(groups.get(name, [name])))
                rows.append([self.layout.index(m) for m in groups.get(name, [name])])
        return DeviationRows(
            names=tuple(names),
            kinds=tuple(self.layout.kinds[r[0]] for r in rows),
            nominal=np.array([self.nominal[r].sum() for r in rows]),
            calibrated=np.array([self.calibrated[r].sum() for r in rows]),
            held=tuple(n for n in self.names if n in fixed),
        )


@dataclass(frozen=True)
class DeviationRows:
    """Deviations from the truth of what a calibration determines (from :meth:`ParameterDeviations.identifiable`).

    Attributes:
        names: (R,) row names: a parameter, or a sum of lengths only identifiable together (``d7 + tool_z``).
        kinds: (R,) the rows' :class:`ParamKind` (length, angle).
        nominal, calibrated: (R,) nominal and calibrated minus truth [m, rad].
        held: parameters held at nominal, not compared.
    """

    names: tuple[str, ...]
    kinds: tuple[ParamKind, ...]
    nominal: np.ndarray
    calibrated: np.ndarray
    held: tuple[str, ...] = ()

    def is_angle(self, name: str) -> bool:
        """True for an angular row (shown in degrees), false for a length (mm)."""
        return self.kinds[self.names.index(name)] is ANGLE

    def display(self, values: np.ndarray) -> np.ndarray:
        """(R,) values in display units: mm for lengths, degrees for angles."""
        return np.asarray(values) * np.array([k.display_scale for k in self.kinds])

    def format(self) -> str:
        """One line per row (mm or deg), then the parameters held at nominal."""
        text = _format_rows(self.names, self.kinds, self.display(self.nominal), self.display(self.calibrated))
        if self.held:
            text += f"\nheld at nominal (not determined by the data, not compared): {', '.join(self.held)}"
        return text


def _format_rows(names, kinds, nominal, calibrated) -> str:
    lines = [f"{'parameter':<14} {'unit':<7} {'nominal-truth':>14} {'calibrated-truth':>17}"]
    for name, kind, a, b in zip(names, kinds, nominal, calibrated, strict=True):
        lines.append(f"{name:<14} {kind.display_unit:<7} {a:14.4f} {b:17.4f}")
    return "\n".join(lines)


def sum_groups(fixed: dict[str, str], layout: ParameterLayout) -> dict[str, list[str]]:
    """Identified length -> the lengths only identifiable in its sum, itself last (``{"tool_z": ["d7",
    "tool_z"]}``), from the reasons ``"redundant with <one length>"`` that calibration gives."""
    groups: dict[str, list[str]] = {}
    for name, reason in fixed.items():
        partner = reason.removeprefix("redundant with ").strip()
        if reason.startswith("redundant with ") and "," not in partner and partner in layout.names:
            if not (layout.is_angle(name) or layout.is_angle(partner)):
                groups.setdefault(partner, []).append(name)
    return {k: [*v, k] for k, v in groups.items()}


def parameter_deviations(nominal: RobotModel, calibrated: RobotModel, truth: RobotModel) -> ParameterDeviations:
    """Deviations of the nominal and calibrated parameters from the truth (same convention; when one of them
    has joint compliance or joint-angle scale, the others count as without: compliance or scale 0)."""
    models = (nominal, calibrated, truth)
    for key, value_of, lift in (("compliance", compliance_of, with_compliance), ("scale", scale_of, with_scale)):
        if any(key in m.extras for m in models):
            models = tuple(lift(m, value_of(m)) for m in models)
    nominal, calibrated, truth = models
    return ParameterDeviations(
        layout=truth.layout,
        nominal=nominal.params - truth.params,
        calibrated=calibrated.params - truth.params,
    )
