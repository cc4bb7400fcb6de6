"""Motion capture as ground truth: a marker cluster on the tool, seen in a frame of its own.

A simulated system reads the markers from the MuJoCo plant of the *true* robot (not from our
forward kinematics), maps them into a motion-capture frame an unknown rigid transform away from the
robot base and adds Gaussian noise per marker. The tool point follows from the cluster by fitting
its known geometry to the measured markers (Kabsch). A real recording enters the same path through
:func:`read_mocap_csv`.
"""

from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from spherecal.correction import (
    RobotModel,
    SpherecalError,
    apply_transform,
    atomic_write_text,
    fit_rigid_transform,
    pose_matrix,
)
from spherecal.correction.files.csv_rows import read_rows
from spherecal.correction.files.samples import LIMIT_TOL
from spherecal.correction.files.text_input import plain_float

#: The paper's motion-capture accuracy: 0.3 mm per marker (std).
MARKER_NOISE = 0.3e-3


#: Smallest RMS distance of the recorded tool points from their best-fitting line [m]: below it the
#: registration's rotation about that line is fixed by noise alone (a column held constant or repeated).
MIN_SPREAD = 0.001
#: Fewest distinct configurations of a mocap recording that can validate a model.
MIN_CONFIGURATIONS = 10


class MocapError(SpherecalError):
    """A motion-capture recording that cannot be used (one line: file, row, field)."""


@dataclass(frozen=True)
class MarkerCluster:
    """A rigid set of markers on the tool, with the tool point, all in the last link frame.

    Attributes:
        markers: (M, 3) marker positions in the last link frame [m], M >= 3, not collinear.
        tool: (3,) tool point (centre of the ball) in the same frame [m].
    """

    markers: np.ndarray
    tool: np.ndarray

    def __post_init__(self) -> None:
        markers = np.array(self.markers, dtype=float)
        if markers.ndim != 2 or markers.shape[1] != 3 or len(markers) < 3:
            raise ValueError(f"a cluster needs (M >= 3, 3) markers, got {markers.shape}")
        centred = markers - markers.mean(axis=0)
        if np.linalg.matrix_rank(centred, tol=1e-6) < 2:
            raise ValueError("cluster markers are collinear: the cluster's orientation is not observable")
        object.__setattr__(self, "markers", markers)
        object.__setattr__(self, "tool", np.array(self.tool, dtype=float).reshape(3))

    @property
    def n_markers(self) -> int:
        """Number of markers ``M``."""
        return len(self.markers)

    def tool_from_markers(self, measured: np.ndarray) -> np.ndarray:
        """Tool points from measured markers: the cluster geometry fitted to each frame (Kabsch).

        Args:
            measured: (N, M, 3) marker positions in any frame [m].

        Returns:
            (N, 3) tool points in that frame [m].
        """
        measured = np.asarray(measured, dtype=float)
        out = np.empty((len(measured), 3))
        for k, frame in enumerate(measured):
            out[k] = apply_transform(fit_rigid_transform(self.markers, frame), self.tool[None])[0]
        return out


def default_cluster(tool: np.ndarray) -> MarkerCluster:
    """Four non-coplanar markers 5 to 8 cm around the tool point, as on the paper's tool.

    Args:
        tool: (3,) tool point in the last link frame [m].
    """
    tool = np.asarray(tool, dtype=float)
    offsets = np.array([[0.06, 0.0, -0.03], [-0.03, 0.05, -0.03], [-0.03, -0.05, -0.03], [0.0, 0.02, -0.08]])
    return MarkerCluster(markers=tool + offsets, tool=tool)


def random_mocap_transform(rng: np.random.Generator, distance: float = 2.0) -> np.ndarray:
    """(4, 4) a random rigid transform mocap <- base: any orientation, ``distance`` [m] away."""
    rpy = rng.uniform([-np.pi, -np.pi / 2, -np.pi], [np.pi, np.pi / 2, np.pi])
    direction = rng.normal(size=3)
    return pose_matrix(distance * direction / np.linalg.norm(direction), rpy)


@dataclass(frozen=True)
class MocapMeasurement:
    """What a motion-capture system reports for a set of robot configurations.

    Attributes:
        q: (N, n) joint angles [rad] recorded with each frame.
        tool: (N, 3) measured tool points in the mocap frame [m].
        markers: (N, M, 3) measured markers in the mocap frame [m], or None (tool given directly).
        exact_tool: (N, 3) the plant's exact tool points in the robot base frame [m] (simulation
            only, never used to register), or None.
        t: (N,) time stamps [s] or None.
        source: where it came from (file name or ``"simulated"``).
    """

    q: np.ndarray
    tool: np.ndarray
    markers: np.ndarray | None = None
    exact_tool: np.ndarray | None = None
    t: np.ndarray | None = None
    source: str = "simulated"
    lines: np.ndarray | None = None  # (N,) file line of every row (read from a file), for messages

    def __len__(self) -> int:
        return len(self.q)


@dataclass
class SimulatedMocap:
    """A motion-capture system looking at the true robot's MuJoCo plant.

    Args:
        truth: the true robot (the plant is built from it, markers as sites on the last link).
        transform: (4, 4) mocap <- base transform, unknown to the user of the measurements.
        cluster: the marker cluster; default :func:`default_cluster` at the true tool point.
        noise: per-marker, per-axis Gaussian noise std [m].
    """

    truth: RobotModel
    transform: np.ndarray
    cluster: MarkerCluster | None = None
    noise: float = MARKER_NOISE
    _plant: object = field(default=None, init=False, repr=False)

    def __post_init__(self) -> None:
        if self.cluster is None:
            self.cluster = default_cluster(self.truth.tool)
        if self.noise < 0:
            raise ValueError(f"noise must be >= 0, got {self.noise}")

    def plant_points(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Exact marker and tool positions in the base frame, from MuJoCo's kinematics.

        Args:
            q: (N, n) joint angles [rad].

        Returns:
            markers (N, M, 3) and tool points (N, 3) [m], in the robot base (world) frame.
        """
        if self._plant is None:
            from spherecal.controller.plant import build_plant  # MuJoCo: only a simulation needs it (start-up)

            self._plant = build_plant(self.truth, markers=self.cluster.markers)
        sites = np.append(self._plant.marker_sites, self._plant.tool_site)
        points = self._plant.site_positions(np.atleast_2d(q), sites)
        return points[:, :-1], points[:, -1]

    def measure(self, q: np.ndarray, rng: np.random.Generator, t: np.ndarray | None = None) -> MocapMeasurement:
        """Noisy markers in the mocap frame, the tool point fitted from them, the exact tool point.

        Args:
            q: (N, n) joint angles [rad].
            rng: seeded generator for the marker noise.
            t: optional (N,) time stamps [s].
        """
        q = np.atleast_2d(np.asarray(q, dtype=float))
        markers, exact = self.plant_points(q)
        seen = apply_transform(self.transform, markers.reshape(-1, 3)).reshape(markers.shape)
        seen = seen + rng.normal(0.0, self.noise, seen.shape)
        return MocapMeasurement(
            q=q, tool=self.cluster.tool_from_markers(seen), markers=seen, exact_tool=exact, t=t, source="simulated"
        )


# ------------------------------------------------------------------------- CSV files
def _header(n_joints: int, n_markers: int | None, with_t: bool) -> list[str]:
    head = (["t"] if with_t else []) + [f"q{i + 1}" for i in range(n_joints)]
    if n_markers is None:
        return head + ["x", "y", "z"]
    return head + [f"m{k}_{axis}" for k in range(n_markers) for axis in "xyz"]


def write_mocap_csv(path: str | os.PathLike, measurement: MocapMeasurement, comment: str = "") -> Path:
    """Write a measurement as a mocap CSV (joint angles and markers, or the tool point), atomically.

    Columns: optional ``t`` [s], ``q1..qn`` [rad], then ``m0_x, m0_y, m0_z, ...`` [m] when markers
    are present, else ``x, y, z`` [m]. ``comment`` lines are written first, prefixed by ``#``.
    """
    m = measurement
    n_markers = None if m.markers is None else m.markers.shape[1]
    values = [m.q]
    if m.t is not None:
        values.insert(0, np.asarray(m.t)[:, None])
    values.append(m.tool if m.markers is None else m.markers.reshape(len(m.q), -1))
    buffer = io.StringIO()
    for line in comment.splitlines():
        buffer.write(f"# {line}\n")
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(_header(m.q.shape[1], n_markers, m.t is not None))
    writer.writerows([[repr(float(v)) for v in row] for row in np.hstack(values)])
    return atomic_write_text(path, buffer.getvalue())


def read_mocap_csv(path: str | os.PathLike, n_joints: int, cluster: MarkerCluster | None = None) -> MocapMeasurement:
    """Read a motion-capture recording: joint angles and measured tool (or marker) positions.

    The header is ``[t,] q1..qn, x, y, z`` (tool point in the mocap frame [m]) or ``[t,] q1..qn,
    m0_x, m0_y, m0_z, m1_x, ...`` (markers; then ``cluster`` gives their geometry and the tool point
    is fitted). Lines starting with ``#`` are comments.

    Raises:
        MocapError: missing file, unexpected header, wrong column count, missing or non-finite
            value: one line naming file, row and field (``header`` for the header, or the column given twice).
    """
    path = Path(path)
    rows = list(read_rows(path, MocapError))  # blank lines and comments skipped; one line per error
    if not rows:
        raise MocapError(f"{path}: empty mocap file, expected a header q1..q{n_joints}, x, y, z")
    header_line, header = rows[0]
    header = [h.strip() for h in header]
    with_t = bool(header) and header[0] == "t"
    n_markers = (len(header) - int(with_t) - n_joints) // 3 if len(header) > int(with_t) + n_joints + 3 else None
    expected = _header(n_joints, n_markers, with_t)
    if header != expected:
        twice = next((h for k, h in enumerate(header) if h in header[:k]), None)  # a column given twice: name it
        field, why = ("header", "") if twice is None else (twice, f" ({twice} given twice)")
        raise MocapError(
            f"{path}: row {header_line}: field {field}: header {','.join(header)!r} does not match a {n_joints}-joint "
            f"robot{why}, expected {','.join(_header(n_joints, None, with_t))!r} or marker columns m0_x, m0_y, m0_z, "
            "..."
        )
    if n_markers is not None and (cluster is None or cluster.n_markers != n_markers):
        raise MocapError(
            f"{path}: row {header_line}: field header: {n_markers} marker columns need a cluster geometry of "
            f"{n_markers} markers"
        )
    if len(rows) < 4:
        raise MocapError(f"{path}: {len(rows) - 1} data rows, need at least 3 to register the mocap frame")
    data = np.empty((len(rows) - 1, len(header)))
    for k, (line, row) in enumerate(rows[1:]):
        if len(row) != len(header):
            field = header[len(row)] if len(row) < len(header) else f"column {len(header) + 1}"  # first missing / extra
            raise MocapError(f"{path}: row {line}: field {field}: {len(row)} columns, expected {len(header)} "
                             f"({','.join(header)})")
        for j, cell in enumerate(row):
            try:
                value = plain_float(cell)
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                what = "missing value" if not cell.strip() else f"bad value {cell.strip()!r}"
                raise MocapError(f"{path}: row {line}: field {header[j]}: {what}")
            data[k, j] = value
    t = data[:, 0] if with_t else None
    q = data[:, int(with_t) : int(with_t) + n_joints]
    rest = data[:, int(with_t) + n_joints :]
    lines = np.array([line for line, _ in rows[1:]])
    if n_markers is None:
        return MocapMeasurement(q=q, tool=rest, t=t, source=str(path), lines=lines)
    markers = rest.reshape(len(rest), n_markers, 3)
    return MocapMeasurement(q=q, tool=cluster.tool_from_markers(markers), markers=markers, t=t, source=str(path),
                            lines=lines)


def check_mocap(measurement: MocapMeasurement, model: RobotModel, limit_tol: float = LIMIT_TOL) -> None:
    """Refuse a recording that cannot be of ``model``: angles outside its joint limits, tool points
    further apart than the arm reaches (millimetres in a metres file), or fewer than
    :data:`MIN_CONFIGURATIONS` distinct configurations (identical rows register perfectly and
    "validate" any model at 0.000 mm).

    Raises:
        MocapError: one line naming the file, row and field.
    """
    m = measurement
    source = m.source

    def row(k: int) -> str:
        return f"row {m.lines[k]}" if m.lines is not None else f"sample {k + 1}"

    outside = (m.q < model.lower - limit_tol) | (m.q > model.upper + limit_tol)
    if outside.any():
        k, i = np.argwhere(outside)[0]
        raise MocapError(f"{source}: {row(k)}: field q{i + 1}: {m.q[k, i]:.6g} rad outside the joint limits "
                         f"[{model.lower[i]:.6g}, {model.upper[i]:.6g}] of {model.name}")
    reach = float(np.sum(np.hypot(model.a, model.d)) + np.linalg.norm(model.tool))
    # the largest coordinate difference from the median point: no sum or square, so a 1e308 value cannot
    # overflow to "inf m"
    difference = np.abs(m.tool - np.median(m.tool, axis=0))
    offset = difference.max(axis=1)
    if offset.max() > 2 * reach:  # every tool point lies within `reach` of the base: any two within 2 reach
        k = int(np.argmax(offset))
        axis = "xyz"[int(np.argmax(difference[k]))]
        raise MocapError(
            f"{source}: {row(k)}: field {axis}: tool point {offset[k]:.4g} m from the recording's centre, but "
            f"{model.name} reaches at most {reach:.3g} m (the file is in metres: millimetres?)"
        )
    lines = f"rows {m.lines[0]}-{m.lines[-1]}" if m.lines is not None else f"samples 1-{len(m.tool)}"
    distinct = np.unique(m.q, axis=0).shape[0]
    if distinct < MIN_CONFIGURATIONS:
        raise MocapError(
            f"{source}: {lines}, field q1: {distinct} distinct configurations in {len(m.q)} rows, need at least "
            f"{MIN_CONFIGURATIONS} (a registration fits fewer exactly, and every model would look perfect)"
        )
    centred = m.tool - m.tool.mean(axis=0)
    off_line = np.linalg.svd(centred, compute_uv=False)[1] / np.sqrt(len(m.tool))  # RMS off the best line [m]
    if off_line < MIN_SPREAD:
        raise MocapError(
            f"{source}: {lines}: field x: the tool points lie on one line ({off_line * 1e3:.2f} mm RMS off it, at "
            f"least {MIN_SPREAD * 1e3:g} mm needed): the rotation about it, so the mocap frame, cannot be registered "
            "(a constant or repeated column?)"
        )
