"""Spherical-joint samples (``samples.csv``) and fixtures (``fixtures.yaml``): read, check, write.

``samples.csv``: header ``fixture,q1,...,qn`` (an optional ``t`` column in seconds right after
``fixture``), one row per recorded configuration, joint angles in radians. Blank lines and lines
starting with ``#`` are skipped (row numbers in messages are still the file's line numbers)::

    fixture,t,q1,q2,q3,q4,q5,q6,q7
    P1,0.000,0.01,-0.52,0.03,-2.11,0.02,1.63,0.79

``fixtures.yaml``: every fixture by name, with its centre in the base frame when it is known
(metres), and optional known centre-to-centre distances (metres)::

    fixtures:
      P1: {}
      P2: {position: [0.5, 0.1, 0.3]}
    distances:
      - [P1, P2, 0.5]

Errors are :class:`DatasetError`, one line naming the file, the row (1-based line number) and
the field. Writers are atomic (temporary file, rename).
"""

from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from spherecal.correction import RobotModel, atomic_write_text
from spherecal.correction.errors import SpherecalError

#: Default tolerance of :meth:`Dataset.deduplicated`: max |dq| [rad] under which two samples of one
#: fixture count as the same configuration (1e-4 rad ~ 0.1 mm at 1 m reach).
DEDUP_TOL = 1e-4
#: Joint angles this far outside a limit [rad] are still accepted (rounding in recorders).
LIMIT_TOL = 1e-6


class DatasetError(SpherecalError):
    """A samples or fixtures file that cannot be used; one line naming file, row and field."""


# --------------------------------------------------------------------------------------- dataset
@dataclass(frozen=True, eq=False)
class Dataset:
    """Joint angles recorded while the tool point sat in spherical joints (fixtures).

    Attributes:
        labels: (K,) fixture name of every sample (str).
        q: (K, n) joint angles [rad].
        t: (K,) time stamps [s], or None.
        fixture_names: fixture names in order of first appearance (computed when left empty).
        source: file the samples came from (for messages), or "".
        lines: (K,) line number of every sample in ``source`` (1-based), or None.
    """

    labels: np.ndarray
    q: np.ndarray
    t: np.ndarray | None = None
    fixture_names: tuple[str, ...] = ()
    source: str = ""
    lines: np.ndarray | None = None

    def __post_init__(self) -> None:
        labels = np.asarray(self.labels).astype(str).reshape(-1)
        q = np.asarray(self.q, dtype=float)
        if q.ndim != 2 or q.shape[0] != labels.shape[0]:
            raise ValueError(f"q must have shape ({labels.shape[0]}, n), got {q.shape}")
        object.__setattr__(self, "labels", labels)
        object.__setattr__(self, "q", q)
        if self.t is not None:
            t = np.asarray(self.t, dtype=float).reshape(-1)
            if t.shape != labels.shape:
                raise ValueError(f"t must have shape {labels.shape}, got {t.shape}")
            object.__setattr__(self, "t", t)
        if self.lines is not None:
            object.__setattr__(self, "lines", np.asarray(self.lines, dtype=int).reshape(labels.shape))
        if not self.fixture_names:
            _, first = np.unique(labels, return_index=True)
            object.__setattr__(self, "fixture_names", tuple(str(labels[i]) for i in np.sort(first)))
        else:
            object.__setattr__(self, "fixture_names", tuple(str(n) for n in self.fixture_names))

    # ------------------------------------------------------------------------------ views
    @property
    def n_samples(self) -> int:
        """Number of samples ``K``."""
        return int(self.q.shape[0])

    @property
    def n_joints(self) -> int:
        """Number of joints ``n``."""
        return int(self.q.shape[1])

    @property
    def fixture_index(self) -> np.ndarray:
        """(K,) int: index of every sample's fixture in :attr:`fixture_names`."""
        lookup = {name: i for i, name in enumerate(self.fixture_names)}
        return np.array([lookup[label] for label in self.labels], dtype=int)

    def counts(self) -> dict[str, int]:
        """Number of samples per fixture, in :attr:`fixture_names` order."""
        return {name: int(np.count_nonzero(self.labels == name)) for name in self.fixture_names}

    def for_fixture(self, name: str) -> np.ndarray:
        """(K_j, n) joint angles recorded at fixture ``name`` [rad]."""
        return self.q[self.labels == name]

    def select(self, index: np.ndarray) -> Dataset:
        """The samples at ``index`` (int array or boolean mask), fixtures that keep samples only."""
        index = np.asarray(index)
        labels = self.labels[index]
        names = tuple(name for name in self.fixture_names if np.any(labels == name))
        t = None if self.t is None else self.t[index]
        lines = None if self.lines is None else self.lines[index]
        return replace(self, labels=labels, q=self.q[index], t=t, fixture_names=names, lines=lines)

    def row_of(self, k: int) -> str:
        """``"row N"`` of sample ``k`` in its file (or ``"sample k"`` when lines are unknown)."""
        return f"row {self.lines[k]}" if self.lines is not None else f"sample {k + 1}"

    # ------------------------------------------------------------------------- reductions
    def deduplicated(self, tol: float = DEDUP_TOL) -> Dataset:
        """Drop exact and near duplicates within each fixture.

        A sample is dropped when an earlier kept sample of the same fixture lies within ``tol``
        on every joint (``max_i |q_i - q'_i| <= tol``); samples sharing one ``tol`` grid cell
        collapse onto the first of them first, so a dense cluster may lose a few more samples than
        the strict rule would. ``tol = 0`` drops exact duplicates only. About 0.5 s for 100 000
        samples of a 1 kHz recording.

        Args:
            tol: tolerance [rad], >= 0.
        """
        if not tol >= 0:
            raise ValueError(f"tol must be >= 0, got {tol}")
        keep = np.ones(self.n_samples, dtype=bool)
        for name in self.fixture_names:
            rows = np.flatnonzero(self.labels == name)
            keep[rows] = _first_of_clusters(self.q[rows], tol)
        return self if keep.all() else self.select(keep)

    def subsampled(self, max_per_fixture: int | None, rng: np.random.Generator) -> Dataset:
        """At most ``max_per_fixture`` samples per fixture, drawn at random (order kept).

        Args:
            max_per_fixture: samples to keep per fixture; None keeps all.
            rng: seeded generator (the only source of randomness).
        """
        if max_per_fixture is None:
            return self
        if max_per_fixture < 1:
            raise ValueError(f"max_per_fixture must be >= 1, got {max_per_fixture}")
        keep = np.zeros(self.n_samples, dtype=bool)
        for name in self.fixture_names:
            rows = np.flatnonzero(self.labels == name)
            if rows.size > max_per_fixture:
                rows = rng.choice(rows, size=max_per_fixture, replace=False)
            keep[rows] = True
        return self if keep.all() else self.select(keep)


def _first_of_clusters(q: np.ndarray, tol: float) -> np.ndarray:
    """(K,) bool: True for samples with no earlier kept sample within ``tol`` (Chebyshev).

    Samples in the same ``tol`` grid cell collapse onto the first of them (a robot standing still
    at 1 kHz gives thousands); the survivors are swept in order of their most spread joint, where
    only neighbours closer than ``tol`` on that joint can be duplicates. No KD-tree: importing
    scipy.spatial alone costs a third of a second of the command's start-up.
    """
    keep = np.zeros(q.shape[0], dtype=bool)
    if q.shape[0] < 2:
        keep[:] = True
        return keep
    cells = np.floor(q / tol) if tol > 0 else q  # floats: a tiny tol overflows int64 and merges distinct cells
    _, first = np.unique(cells, axis=0, return_index=True)
    first = np.sort(first)
    keep[first] = True
    if tol == 0.0 or first.size < 2:
        return keep
    sub = q[first]
    col = int(np.argmax(np.ptp(sub, axis=0)))
    order = np.argsort(sub[:, col], kind="stable")
    ordered = sub[order]
    pairs = []
    for offset in range(1, ordered.shape[0]):
        near = ordered[offset:, col] - ordered[:-offset, col] <= tol
        if not near.any():
            break
        i = np.flatnonzero(near)
        i = i[np.abs(ordered[i + offset] - ordered[i]).max(axis=1) <= tol]
        pairs.append(np.stack([first[order[i]], first[order[i + offset]]], axis=1))
    if not pairs:
        return keep
    pairs = np.sort(np.concatenate(pairs), axis=1)  # (earlier, later) in recording order
    pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
    starts = np.searchsorted(pairs[:, 0], np.arange(q.shape[0] + 1))
    for k in np.unique(pairs[:, 0]):  # greedy in recording order: a kept sample hides its later neighbours
        if keep[k]:
            keep[pairs[starts[k] : starts[k + 1], 1]] = False
    return keep


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


# ------------------------------------------------------------------------------ fixtures.yaml
@dataclass(frozen=True, eq=False)
class FixtureSpec:
    """What is known about the fixtures besides the samples.

    Attributes:
        names: every fixture, in file order.
        positions: known centres in the base frame, name -> (3,) [m].
        distances: known centre-to-centre distances ``(name_a, name_b, metres)``.
        extras: other top-level keys of the file, written back unchanged.
        source: file the spec came from (for messages), or "".
        rows: file line of ``"fixtures.P1"`` and ``"distances[k]"`` entries (for messages).
    """

    names: tuple[str, ...] = ()
    positions: dict[str, np.ndarray] = field(default_factory=dict)
    distances: list[tuple[str, str, float]] = field(default_factory=list)
    extras: dict = field(default_factory=dict)
    source: str = ""
    rows: dict[str, int] = field(default_factory=dict)

    def _row(self, key: str) -> str:
        return f"row {self.rows[key]}, " if key in self.rows else ""

    @staticmethod
    def unknown(names: tuple[str, ...] | list[str]) -> FixtureSpec:
        """A spec of fixtures with nothing known about them."""
        return FixtureSpec(names=tuple(names))

    def check_against(self, dataset: Dataset) -> None:
        """Raise :class:`DatasetError` if a known position or distance names a fixture without samples."""
        have = set(dataset.fixture_names)
        where = self.source or "fixtures"
        for name in self.positions:
            if name not in have:
                raise DatasetError(
                    f"{where}: {self._row('fixtures.' + name)}field 'fixtures.{name}.position': "
                    f"fixture {name!r} has no samples"
                    f"{' in ' + dataset.source if dataset.source else ''}"
                )
        for k, (a, b, _) in enumerate(self.distances):
            for name in (a, b):
                if name not in have:
                    raise DatasetError(
                        f"{where}: {self._row(f'distances[{k}]')}field 'distances[{k}]': "
                        f"fixture {name!r} has no samples"
                        f"{' in ' + dataset.source if dataset.source else ''}"
                    )


def _node_line(node: Any, *path: Any) -> int:
    """1-based line of the YAML node at ``path`` (keys and indices), or of the deepest node found."""
    import yaml

    for key in path:
        if isinstance(node, yaml.MappingNode):
            match = [v for k, v in node.value if getattr(k, "value", None) == key]
            if not match:
                break
            node = match[-1]
        elif isinstance(node, yaml.SequenceNode) and isinstance(key, int) and key < len(node.value):
            node = node.value[key]
        else:
            break
    return node.start_mark.line + 1


def _duplicate_keys(node: Any, where: str) -> None:
    import yaml

    if isinstance(node, yaml.MappingNode):
        seen: set[Any] = set()
        for key, value in node.value:
            if key.value in seen:
                raise DatasetError(f"{where}: row {key.start_mark.line + 1}, field {key.value!r}: duplicate key")
            seen.add(key.value)
            _duplicate_keys(value, where)
    elif isinstance(node, yaml.SequenceNode):
        for value in node.value:
            _duplicate_keys(value, where)


def _plain_name(name: Any) -> Any:
    """A fixture numbered in YAML (``1: {}``) is named ``"1"``, as in samples.csv; other keys unchanged."""
    return str(name) if isinstance(name, int) and not isinstance(name, bool) else name


def read_fixtures(path: str | os.PathLike) -> FixtureSpec:
    """Read and check ``fixtures.yaml``.

    Raises:
        DatasetError: unreadable file, invalid YAML, duplicate keys, a fixture entry that is not
            a mapping or has an unknown key, a position that is not 3 finite numbers, a distance
            that is not ``[name, name, metres > 0]`` or names an unlisted fixture.
    """
    import yaml

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")  # a spreadsheet's byte-order mark is not data
    except (OSError, UnicodeDecodeError) as error:
        raise DatasetError(f"{path}: cannot read: {getattr(error, 'strerror', None) or error}") from None
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
        data = yaml.safe_load(text)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        row = f"row {mark.line + 1}" if mark is not None else "row ?"
        raise DatasetError(f"{path}: {row}, field '': invalid YAML: {getattr(error, 'problem', error)}") from None
    if data is None:
        raise DatasetError(f"{path}: row 1, field 'fixtures': empty file")
    _duplicate_keys(root, str(path))

    def fail(message: str, *where: Any) -> DatasetError:
        field_name = ".".join(str(w) if not isinstance(w, int) else f"[{w}]" for w in where).replace(".[", "[")
        return DatasetError(f"{path}: row {_node_line(root, *where)}, field '{field_name}': {message}")

    if not isinstance(data, dict):
        raise fail(f"expected a mapping at the top level, got {type(data).__name__}")
    fixtures = data.get("fixtures")
    if not isinstance(fixtures, dict) or not fixtures:
        raise fail("expected a non-empty mapping of fixture names", "fixtures")
    fixtures = {_plain_name(name): entry for name, entry in fixtures.items()}
    names: list[str] = []
    positions: dict[str, np.ndarray] = {}
    for name, entry in fixtures.items():
        if not isinstance(name, str) or not name.strip() or "," in name:
            raise fail(f"fixture name must be a non-empty string without commas, got {name!r}", "fixtures", name)
        names.append(name)
        entry = {} if entry is None else entry
        if not isinstance(entry, dict):
            raise fail(f"expected a mapping ({{}} or {{position: [x, y, z]}}), got {entry!r}", "fixtures", name)
        for key in entry:
            if key != "position":
                raise fail(f"unknown key {key!r} (expected 'position')", "fixtures", name, key)
        if "position" in entry:
            value = entry["position"]
            ok = isinstance(value, list) and len(value) == 3
            ok = ok and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
            if not ok or not all(math.isfinite(v) for v in value):
                raise fail(f"expected 3 finite numbers [m], got {value!r}", "fixtures", name, "position")
            positions[name] = np.array(value, dtype=float)
    distances: list[tuple[str, str, float]] = []
    raw = data.get("distances") or []
    if not isinstance(raw, list):
        raise fail("expected a list of [name, name, metres]", "distances")
    seen_pairs: set[frozenset[str]] = set()
    for k, item in enumerate(raw):
        if not isinstance(item, list) or len(item) != 3:
            raise fail(f"expected [name, name, metres], got {item!r}", "distances", k)
        a, b, value = _plain_name(item[0]), _plain_name(item[1]), item[2]
        for j, name in enumerate((a, b)):
            if name not in fixtures:
                raise fail(f"fixture {name!r} is not listed under 'fixtures'", "distances", k, j)
        if a == b:
            raise fail(f"a distance needs two different fixtures, got {a!r} twice", "distances", k)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise fail(f"expected a finite distance [m], got {value!r}", "distances", k, 2)
        if value <= 0:
            raise fail(f"distance must be > 0 m, got {value!r}", "distances", k, 2)
        pair = frozenset((a, b))
        if pair in seen_pairs:
            raise fail(f"distance between {a!r} and {b!r} given twice", "distances", k)
        seen_pairs.add(pair)
        distances.append((a, b, float(value)))
    extras = {k: v for k, v in data.items() if k not in ("fixtures", "distances")}
    rows = {f"fixtures.{name}": _node_line(root, "fixtures", name) for name in names}
    rows.update({f"distances[{k}]": _node_line(root, "distances", k) for k in range(len(distances))})
    return FixtureSpec(tuple(names), positions, distances, extras, source=str(path), rows=rows)


def format_fixtures(spec: FixtureSpec) -> str:
    """YAML text of a fixture spec (floats exact)."""
    import yaml

    fixtures: dict[str, Any] = {}
    for name in spec.names:
        fixtures[name] = {"position": [float(v) for v in spec.positions[name]]} if name in spec.positions else {}
    data: dict[str, Any] = {"fixtures": fixtures}
    if spec.distances:
        data["distances"] = [[a, b, float(v)] for a, b, v in spec.distances]
    data.update(spec.extras)
    body = yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=1000)
    return "# spherecal fixtures: centres in the base frame and distances, metres\n" + body


def write_fixtures(path: str | os.PathLike, spec: FixtureSpec) -> Path:
    """Write ``fixtures.yaml`` atomically (temporary file, rename)."""
    for name in list(spec.positions) + [n for a, b, _ in spec.distances for n in (a, b)]:
        if name not in spec.names:
            raise DatasetError(f"{path}: field 'fixtures': {name!r} is used but not listed in names")
    return atomic_write_text(path, format_fixtures(spec))
