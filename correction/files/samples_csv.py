"""Spherical-joint samples in ``samples.csv``: read, check, write.

``samples.csv``: header ``fixture,q1,...,qn`` (an optional ``t`` column in seconds right after
``fixture``), one row per recorded configuration, joint angles in radians. Blank lines and lines
starting with ``#`` are skipped (row numbers in messages are still the file's line numbers)::

    fixture,t,q1,q2,q3,q4,q5,q6,q7
    P1,0.000,0.01,-0.52,0.03,-2.11,0.02,1.63,0.79

Errors are :class:`~spherecal.correction.files.samples.DatasetError`, one line naming the file, the row
(1-based line number) and the field. The writer is atomic (temporary file, rename).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from spherecal.correction.files.atomic import atomic_write_text
from spherecal.correction.files.csv_rows import check_separator, is_skipped, iter_lines, parse_line, plain_values
from spherecal.correction.files.samples import LIMIT_TOL, Dataset, DatasetError, LimitExcess
from spherecal.correction.files.text_input import finite_number
from spherecal.correction.model import RobotModel


# --------------------------------------------------------------------------------- samples.csv
def _number(text: str, where: str) -> float:
    return finite_number(text, where, DatasetError)


def _parse_header(header: list[str], n: int, where: str) -> bool:
    """Check ``fixture[,t],q1..qn``; returns whether a ``t`` column is present."""
    names = [h.strip() for h in header]
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise DatasetError(f"{where}, field {name!r}: duplicate column")
        seen.add(name)
    check_separator(names, where, DatasetError)
    if "" in names[1:]:
        raise DatasetError(f"{where}, field 'column {names.index('', 1) + 1}': a column without a name (a comma at "
                           "the end of each line?)")
    if not names or names[0] != "fixture":
        hint = ""
        if names and "fixture" not in names:  # a recording, a MUKCa hole file: not samples yet
            hint = (" (a recording without fixture labels? spherecal import makes samples.csv of it: --format csv for "
                    "joint CSVs, mukca for a folder of hole_<k>.csv)")
        raise DatasetError(f"{where}, field {names[0] if names else ''!r}: first column must be 'fixture'{hint}")
    has_t = len(names) > 1 and names[1] == "t"
    joints = names[2 if has_t else 1 :]
    for k, name in enumerate(joints):
        if name != f"q{k + 1}":
            if name == "t":
                raise DatasetError(f"{where}, field 't': the time column must come right after 'fixture'")
            if name.lower() == f"q{k + 1}":
                raise DatasetError(f"{where}, field {name!r}: joint columns are named in lower case, q1..q{n}")
            if not (name.startswith("q") and name[1:].isdigit()):
                raise DatasetError(f"{where}, field {name!r}: unknown column (expected fixture[,t],q1..q{n})")
            raise DatasetError(f"{where}, field {name!r}: joint columns must be q1..q{n} in order")
    if len(joints) != n:
        raise DatasetError(f"{where}, field 'q*': {len(joints)} joint columns, the robot has {n} (expected q1..q{n})")
    return has_t


def read_samples(path: str | os.PathLike, model: RobotModel, limit_tol: float = LIMIT_TOL) -> Dataset:
    """Read and check ``samples.csv`` against a robot, as a stream of blocks of lines.

    A block of plain rows (no quotes, no comments, the header's number of commas on every line, no
    line over the CSV field limit) is converted at once by numpy's C reader; any other block is parsed line by
    line with the csv module, which names the row and field of the first bad value. Either way the
    file is read block by block and an error stops the reading (a bad value on row 2 is reported
    without reading the rest). 2 M rows: about 10 s and 0.5 GB (``bench/large_samples.py``).

    Args:
        path: the CSV file.
        model: the robot (number of joints, joint limits).
        limit_tol: angles up to this far outside a joint limit are accepted without a word [rad]; further,
            up to :data:`~spherecal.correction.files.samples.HARD_MARGIN`, with one
            :class:`~spherecal.correction.files.samples.JointLimitWarning` listing every joint.

    Returns:
        The samples, in file order (no duplicates dropped: see :meth:`Dataset.deduplicated`).

    Raises:
        DatasetError: unreadable or empty file, bad header, wrong number of fields, a value that
            is not a finite number, an empty fixture name, an angle that cannot be of its joint, an
            unterminated quote or an over-long field.
    """
    path = Path(path)
    n = model.n_joints
    reader = _Reader(path, model, limit_tol)
    number = 0
    for block in iter_lines(path, DatasetError):
        start = number + 1
        number += len(block)
        if reader.columns is None:
            block, start = reader.header(block, start)
            if reader.columns is None:
                continue
        if block:
            reader.block(block, start)
    if reader.columns is None:
        raise DatasetError(f"{path}: row 1, field 'fixture': empty file (expected header fixture[,t],q1..q{n})")
    return reader.dataset()


class _Reader:
    """The state of one :func:`read_samples`: the header, then the blocks of values read so far."""

    def __init__(self, path: Path, model: RobotModel, limit_tol: float):
        self.path, self.model, self.limit_tol = path, model, limit_tol
        self.excess = LimitExcess.of(model, tol=limit_tol)
        self.columns: list[str] | None = None
        self.has_t = False
        self.labels: list[np.ndarray] = []
        self.names: dict[str, None] = {}
        self.values: list[np.ndarray] = []
        self.lines: list[np.ndarray] = []

    def header(self, block: list[str], start: int) -> tuple[list[str], int]:
        """Find the header in ``block``; returns the lines after it and the line number of the first."""
        for k, line in enumerate(block):
            if is_skipped(line):
                continue
            where = f"{self.path}: row {start + k}"
            fields = parse_line(line, where, DatasetError)
            self.has_t = _parse_header(fields, self.model.n_joints, where)
            self.columns = [h.strip() for h in fields]
            return block[k + 1 :], start + k + 1
        return [], start + len(block)

    def block(self, block: list[str], start: int) -> None:
        """Convert a block of lines (first at file line ``start``) and check it."""
        width = len(self.columns)
        data = plain_values(block, width, range(1, width))
        plain = data is not None
        if plain:
            labels = [line[: line.find(",")].strip() for line in block]
            rows = np.arange(start, start + len(block))
            plain = "" not in labels
        if not plain:
            labels, data, rows = self._careful(block, start)
        if len(labels) == 0:
            return
        self._check_limits(data, rows)
        self.names.update(dict.fromkeys(labels))  # first appearance, in order
        self.labels.append(np.array(labels))
        self.values.append(data)
        self.lines.append(rows)

    def _careful(self, block: list[str], start: int) -> tuple[list[str], np.ndarray, np.ndarray]:
        """Line by line with the csv module: the first error names its row and field."""
        columns = self.columns
        labels: list[str] = []
        values: list[list[float]] = []
        rows: list[int] = []
        for k, line in enumerate(block):
            if is_skipped(line):
                continue
            where = f"{self.path}: row {start + k}"
            fields = parse_line(line, where, DatasetError)
            if len(fields) != len(columns):
                missing = columns[len(fields)] if len(fields) < len(columns) else f"column {len(columns) + 1}"
                raise DatasetError(f"{where}, field {missing!r}: {len(fields)} fields, the header has {len(columns)}")
            label = fields[0].strip()
            if not label:
                raise DatasetError(f"{where}, field 'fixture': empty fixture name")
            if [f.strip() for f in fields] == columns:
                raise DatasetError(f"{where}, field 'fixture': the header again (two files concatenated? a samples "
                                   "file has one header; merge the rows without it)")
            labels.append(label)
            values.append([_number(v, f"{where}, field {c!r}") for v, c in zip(fields[1:], columns[1:], strict=True)])
            rows.append(start + k)
        return labels, np.array(values, dtype=float).reshape(len(rows), len(columns) - 1), np.array(rows)

    def _check_limits(self, data: np.ndarray, rows: np.ndarray) -> None:
        q = data[:, 1:] if self.has_t else data
        self.excess.add(q, lambda k: f"{self.path}: row {rows[k]}", DatasetError)

    def dataset(self) -> Dataset:
        if not self.values:
            raise DatasetError(f"{self.path}: row 2, field 'fixture': no samples after the header")
        for name in self.names:  # a NUL byte or a control character: no fixtures.yaml name can match it
            if not name.isprintable():
                labels = np.concatenate(self.labels)
                row = np.concatenate(self.lines)[int(np.argmax(labels == name))]
                raise DatasetError(f"{self.path}: row {row}, field 'fixture': the fixture name {name!r} holds a "
                                   "control character (a NUL byte? a file of another kind or a damaged copy)")
        self.excess.warn(str(self.path))  # one warning for the whole file, every joint past its limits
        data = np.concatenate(self.values) if len(self.values) > 1 else self.values[0]
        self.values.clear()  # the chunks are not kept beside the whole (peak memory)
        q = np.ascontiguousarray(data[:, 1:]) if self.has_t else data
        return Dataset(
            labels=np.concatenate(self.labels), q=q, t=data[:, 0].copy() if self.has_t else None,
            fixture_names=tuple(self.names), source=str(self.path), lines=np.concatenate(self.lines),
        )


def format_samples(dataset: Dataset, comment: str = "") -> str:
    """CSV text of a dataset (floats written with every digit, so they round-trip exactly).

    Args:
        dataset: the samples.
        comment: text written first as ``#`` lines (the provenance block's
            :func:`~spherecal.correction.files.provenance.comment_block`), skipped by the reader.
    """
    n = dataset.n_joints
    header = ["fixture"] + (["t"] if dataset.t is not None else []) + [f"q{i + 1}" for i in range(n)]
    out = [f"# {line}".rstrip() for line in comment.splitlines()] + [",".join(header)]
    for k in range(dataset.n_samples):
        row = [str(dataset.labels[k])]
        if dataset.t is not None:
            row.append(repr(float(dataset.t[k])))
        row.extend(repr(v) for v in dataset.q[k].tolist())
        out.append(",".join(row))
    return "\n".join(out) + "\n"


def write_samples(path: str | os.PathLike, dataset: Dataset, comment: str = "") -> Path:
    """Write ``samples.csv`` atomically (temporary file, rename), ``comment`` first as ``#`` lines."""
    for name in dataset.fixture_names:
        if not name or "," in name or '"' in name or "\n" in name or name != name.strip():
            raise DatasetError(f"{path}: field 'fixture': fixture name {name!r} cannot be written to CSV")
    return atomic_write_text(path, format_samples(dataset, comment))


