"""Spherical-joint samples in ``samples.csv``: read, check, write.

``samples.csv``: header ``fixture,q1,...,qn`` (an optional ``t`` column in seconds right after
``fixture``), one row per recorded configuration, joint angles in radians. Blank lines and lines
starting with ``#`` are skipped (row numbers in messages are still the file's line numbers)::

    fixture,t,q1,q2,q3,q4,q5,q6,q7
    P1,0.000,0.01,-0.52,0.03,-2.11,0.02,1.63,0.79

Errors are :class:`~spherecal.correction.samples.DatasetError`, one line naming the file, the row
(1-based line number) and the field. The writer is atomic (temporary file, rename).
"""

from __future__ import annotations

import csv
import io
import math
import os
from pathlib import Path

import numpy as np

from spherecal.correction.atomic import atomic_write_text
from spherecal.correction.model import RobotModel
from spherecal.correction.samples import LIMIT_TOL, Dataset, DatasetError


# --------------------------------------------------------------------------------- samples.csv
def _number(text: str, where: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise DatasetError(f"{where}: expected a number, got {text.strip()!r}") from None
    if not math.isfinite(value):
        raise DatasetError(f"{where}: must be finite, got {text.strip()!r}")
    return value


def _parse_header(header: list[str], n: int, where: str) -> bool:
    """Check ``fixture[,t],q1..qn``; returns whether a ``t`` column is present."""
    names = [h.strip() for h in header]
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise DatasetError(f"{where}, field {name!r}: duplicate column")
        seen.add(name)
    if not names or names[0] != "fixture":
        raise DatasetError(f"{where}, field {names[0] if names else ''!r}: first column must be 'fixture'")
    has_t = len(names) > 1 and names[1] == "t"
    joints = names[2 if has_t else 1 :]
    for k, name in enumerate(joints):
        if name != f"q{k + 1}":
            if name == "t":
                raise DatasetError(f"{where}, field 't': the time column must come right after 'fixture'")
            if not (name.startswith("q") and name[1:].isdigit()):
                raise DatasetError(f"{where}, field {name!r}: unknown column (expected fixture[,t],q1..q{n})")
            raise DatasetError(f"{where}, field {name!r}: joint columns must be q1..q{n} in order")
    if len(joints) != n:
        raise DatasetError(f"{where}, field 'q*': {len(joints)} joint columns, the robot has {n} (expected q1..q{n})")
    return has_t


def read_samples(path: str | os.PathLike, model: RobotModel, limit_tol: float = LIMIT_TOL) -> Dataset:
    """Read and check ``samples.csv`` against a robot.

    Args:
        path: the CSV file.
        model: the robot (number of joints, joint limits).
        limit_tol: angles up to this far outside a joint limit are accepted [rad].

    Returns:
        The samples, in file order (no duplicates dropped: see :meth:`Dataset.deduplicated`).

    Raises:
        DatasetError: unreadable or empty file, bad header, wrong number of fields, a value that
            is not a finite number, an empty fixture name, an angle outside its joint limits.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")  # a spreadsheet's byte-order mark is not data
    except (OSError, UnicodeDecodeError) as error:
        raise DatasetError(f"{path}: cannot read: {getattr(error, 'strerror', None) or error}") from None
    n = model.n_joints
    rows = csv.reader(io.StringIO(text))
    header: list[str] | None = None
    has_t = False
    labels: list[str] = []
    values: list[list[float]] = []
    lines: list[int] = []
    for fields in rows:
        line = rows.line_num
        if not fields or not "".join(fields).strip() or fields[0].lstrip().startswith("#"):
            continue
        where = f"{path}: row {line}"
        if header is None:
            header = fields
            has_t = _parse_header(fields, n, where)
            columns = [h.strip() for h in header]
            continue
        if len(fields) != len(header):
            missing = columns[len(fields)] if len(fields) < len(columns) else f"column {len(columns) + 1}"
            raise DatasetError(f"{where}, field {missing!r}: {len(fields)} fields, the header has {len(header)}")
        label = fields[0].strip()
        if not label:
            raise DatasetError(f"{where}, field 'fixture': empty fixture name")
        labels.append(label)
        values.append([_number(v, f"{where}, field {c!r}") for v, c in zip(fields[1:], columns[1:], strict=True)])
        lines.append(line)
    if header is None:
        raise DatasetError(f"{path}: row 1, field 'fixture': empty file (expected header fixture[,t],q1..q{n})")
    if not labels:
        raise DatasetError(f"{path}: row 2, field 'fixture': no samples after the header")
    data = np.array(values, dtype=float)
    q = data[:, 1:] if has_t else data
    inside = (q >= model.lower - limit_tol) & (q <= model.upper + limit_tol)
    if not inside.all():
        k, i = np.argwhere(~inside)[0]
        raise DatasetError(
            f"{path}: row {lines[k]}, field 'q{i + 1}': {q[k, i]:.6g} rad outside the joint limits "
            f"[{model.lower[i]:.6g}, {model.upper[i]:.6g}]"
        )
    return Dataset(
        labels=np.array(labels), q=q, t=data[:, 0] if has_t else None, source=str(path), lines=np.array(lines)
    )


def format_samples(dataset: Dataset) -> str:
    """CSV text of a dataset (floats written with every digit, so they round-trip exactly)."""
    n = dataset.n_joints
    header = ["fixture"] + (["t"] if dataset.t is not None else []) + [f"q{i + 1}" for i in range(n)]
    out = [",".join(header)]
    for k in range(dataset.n_samples):
        row = [str(dataset.labels[k])]
        if dataset.t is not None:
            row.append(repr(float(dataset.t[k])))
        row.extend(repr(v) for v in dataset.q[k].tolist())
        out.append(",".join(row))
    return "\n".join(out) + "\n"


def write_samples(path: str | os.PathLike, dataset: Dataset) -> Path:
    """Write ``samples.csv`` atomically (temporary file, rename)."""
    for name in dataset.fixture_names:
        if not name or "," in name or '"' in name or "\n" in name or name != name.strip():
            raise DatasetError(f"{path}: field 'fixture': fixture name {name!r} cannot be written to CSV")
    return atomic_write_text(path, format_samples(dataset))


