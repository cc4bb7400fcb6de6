"""Fixtures (``fixtures.yaml``): what is known about the sockets besides the samples.

``fixtures.yaml``: every fixture by name, with its centre in the base frame when it is known
(metres), and optional known centre-to-centre distances (metres)::

    fixtures:
      P1: {}
      P2: {position: [0.5, 0.1, 0.3]}
    distances:
      - [P1, P2, 0.5]

Errors are :class:`~spherecal.correction.files.samples.DatasetError`, one line naming the file, the row
(1-based line number) and the field. The writer is atomic (temporary file, rename).
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from spherecal.correction.files.atomic import atomic_write_text
from spherecal.correction.files.robot_file import MAX_LENGTH
from spherecal.correction.files.samples import Dataset, DatasetError
from spherecal.correction.files.suggest import close_names
from spherecal.correction.files.text_input import read_text
from spherecal.correction.files.yaml_safe import MAX_FILE_BYTES, dump_yaml, load_yaml, node_line


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
        distance_index: the file's index of each of ``distances`` when some were left out (for messages;
            empty: the same order).
    """

    names: tuple[str, ...] = ()
    positions: dict[str, np.ndarray] = field(default_factory=dict)
    distances: list[tuple[str, str, float]] = field(default_factory=list)
    extras: dict = field(default_factory=dict)
    source: str = ""
    rows: dict[str, int] = field(default_factory=dict)
    distance_index: tuple[int, ...] = ()

    def _row(self, key: str) -> str:
        return f"row {self.rows[key]}, " if key in self.rows else ""

    def keep_distances(self, keep: list[int]) -> FixtureSpec:
        """This spec with only the distances at indices ``keep``, each still named as the file numbers it."""
        index = tuple(self.distance_index[k] if self.distance_index else k for k in keep)
        return replace(self, distances=[self.distances[k] for k in keep], distance_index=index)

    def distance_field(self, k: int) -> str:
        """``"row N, field 'distances[j]'"`` of distance ``k`` as the file numbers it (for messages)."""
        j = self.distance_index[k] if self.distance_index else k
        return f"{self._row(f'distances[{j}]')}field 'distances[{j}]'"

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
                        f"{where}: {self.distance_field(k)}: "
                        f"fixture {name!r} has no samples"
                        f"{' in ' + dataset.source if dataset.source else ''}"
                    )


def _written_name(node: Any) -> Any:
    """The fixture name as the file writes it, as a samples.csv label would be: a plain scalar YAML 1.1 would
    turn into another type (``01`` and ``0x1`` into 1, ``010`` into 8, ``1:30`` into 90, ``yes``/``no``/``on`` into
    True/False, ``null`` into None, ``2024-01-01`` into a date) keeps its text, so ``1`` and ``01`` stay two
    fixtures (they were one, the other silently dropped) and ``no`` stays ``no``. Other nodes: None."""
    return node.value if isinstance(node, yaml.ScalarNode) else None


def _name_problem(name: str) -> str | None:
    """Why ``name`` cannot be a fixture name a samples.csv label can match, or None."""
    if not name.strip() or "," in name:
        return "must be a non-empty name without commas"
    if name != name.strip():
        return "has spaces around it (samples.csv labels are read without them)"
    if not name.isprintable():
        return "holds a control character (a NUL byte, a tab or a line end)"
    if name.startswith("#"):
        return "starts with '#' (a samples.csv row starting with '#' is a comment)"
    return None


def nearest_name(name: Any, names: Iterable) -> str | None:
    """The fixture name of ``names`` nearest a misspelt ``name`` (difflib's ratio at least 0.6), or None: the
    did-you-mean of a refusal naming a fixture that is not there."""
    near = close_names(name, names, cutoff=0.6)
    return near[0] if near else None


def _value(mapping: yaml.MappingNode, key: str) -> Any:
    """The value node of ``key`` in a mapping node (the last, as the constructed mapping keeps)."""
    return [value for k, value in mapping.value if getattr(k, "value", None) == key][-1]


def read_fixtures(path: str | os.PathLike) -> FixtureSpec:
    """Read and check ``fixtures.yaml``.

    Raises:
        DatasetError: unreadable file, invalid YAML, duplicate keys, a fixture entry that is not
            a mapping or has an unknown key, a position that is not 3 finite numbers, a distance
            that is not ``[name, name, metres > 0]`` or names an unlisted fixture.
    """

    path = Path(path)
    # a spreadsheet's byte-order mark is not data; bounded: /dev/zero is refused, not read forever
    text = read_text(path, DatasetError, encoding="utf-8-sig", limit=MAX_FILE_BYTES)
    data, root = load_yaml(text, str(path), DatasetError)  # bounded: size, depth, aliases; no duplicate keys
    if data is None:
        raise DatasetError(f"{path}: row 1, field 'fixtures': empty file")

    def fail(message: str, *where: Any) -> DatasetError:
        field_name = ".".join(str(w) if not isinstance(w, int) else f"[{w}]" for w in where).replace(".[", "[")
        return DatasetError(f"{path}: row {node_line(root, *where)}, field '{field_name}': {message}")

    if not isinstance(data, dict):
        raise fail(f"expected a mapping at the top level, got {type(data).__name__}")
    fixtures = data.get("fixtures")
    if not isinstance(fixtures, dict) or not fixtures:
        raise fail("expected a non-empty mapping of fixture names", "fixtures")
    # the names as written (the constructed keys may have merged 1 and 01 into one), the entries from their nodes
    constructor = yaml.constructor.SafeConstructor()
    fixtures = {}
    for key, value in _value(root, "fixtures").value:
        name = _written_name(key)
        problem = "is not a name" if not isinstance(name, str) else _name_problem(name)
        if problem is None and name in fixtures:  # only a '<<' merge gives a name twice (duplicate keys are refused)
            problem = "is given twice (a '<<' merge?)"
        if problem:
            shown = repr(name)[1:-1] if isinstance(name, str) else key.tag.rsplit(":", 1)[-1]
            raise DatasetError(f"{path}: row {key.start_mark.line + 1}, field 'fixtures.{shown}': fixture name "
                               f"{repr(name) if isinstance(name, str) else 'of type ' + shown} {problem}")
        fixtures[name] = constructor.construct_object(value, deep=True)
    names: list[str] = []
    positions: dict[str, np.ndarray] = {}
    for name, entry in fixtures.items():
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
            if max(abs(v) for v in value) > MAX_LENGTH:
                raise fail(f"{value!r} m is not physical (at most {MAX_LENGTH:g} m from the base; the file is in "
                           "metres)", "fixtures", name, "position")
            positions[name] = np.array(value, dtype=float)
    distances: list[tuple[str, str, float]] = []
    raw = data.get("distances") or []
    if not isinstance(raw, list):
        raise fail("expected a list of [name, name, metres]", "distances")
    seen_pairs: set[frozenset[str]] = set()
    for k, item in enumerate(raw):
        if not isinstance(item, list) or len(item) != 3:
            raise fail(f"expected [name, name, metres], got {item!r}", "distances", k)
        item_node = _value(root, "distances").value[k]
        a, b, value = _written_name(item_node.value[0]), _written_name(item_node.value[1]), item[2]
        for j, name in enumerate((a, b)):
            if name not in fixtures:
                near = nearest_name(name, fixtures)
                hint = f" (did you mean {near!r}?)" if near else f" (listed: {', '.join(map(str, fixtures))})"
                raise fail(f"fixture {name!r} is not listed under 'fixtures'{hint}", "distances", k, j)
        if a == b:
            raise fail(f"a distance needs two different fixtures, got {a!r} twice", "distances", k)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise fail(f"expected a finite distance [m], got {value!r}", "distances", k, 2)
        if value <= 0:
            raise fail(f"distance must be > 0 m, got {value!r}", "distances", k, 2)
        if value > 2 * MAX_LENGTH:
            raise fail(f"{value!r} m is not physical (at most {2 * MAX_LENGTH:g} m; the file is in metres)",
                       "distances", k)
        pair = frozenset((a, b))
        if pair in seen_pairs:
            raise fail(f"distance between {a!r} and {b!r} given twice", "distances", k)
        seen_pairs.add(pair)
        distances.append((a, b, float(value)))
    extras = {k: v for k, v in data.items() if k not in ("fixtures", "distances")}
    for key in extras:  # kept unread (provenance blocks, notes), unless it is a misspelt key we read
        near = close_names(str(key).lower(), ["fixtures", "distances"], cutoff=0.75)
        if near:
            raise fail(f"unknown key {key!r} (did you mean {near[0]!r}? as written, it would be ignored)", key)
        value = extras[key]  # known centres go under their fixture, not beside the fixtures (an anchor is no centre)
        if str(key).lower() in CENTRE_KEYS and isinstance(value, dict) and set(map(str, value)) & set(fixtures):
            raise fail(f"unknown key {key!r}: a fixture's known centre is given under its name, 'fixtures: {{P1: "
                       "{position: [x, y, z]}}' [m] (as written, it would be ignored)", key)
    rows = {f"fixtures.{name}": node_line(root, "fixtures", name) for name in names}
    rows.update({f"distances[{k}]": node_line(root, "distances", k) for k in range(len(distances))})
    return FixtureSpec(tuple(names), positions, distances, extras, source=str(path), rows=rows)


#: Top-level keys that mean known fixture centres when they map fixture names, given in the wrong place (a user
#: trial's 'positions: {P1: [...]}' beside 'fixtures:' was kept unread, and the calibration ran without the centres).
CENTRE_KEYS = ("position", "positions", "centre", "centres", "center", "centers")


def format_fixtures(spec: FixtureSpec) -> str:
    """YAML text of a fixture spec (floats exact)."""

    fixtures: dict[str, Any] = {}
    for name in spec.names:
        fixtures[name] = {"position": [float(v) for v in spec.positions[name]]} if name in spec.positions else {}
    data: dict[str, Any] = {"fixtures": fixtures}
    if spec.distances:
        data["distances"] = [[a, b, float(v)] for a, b, v in spec.distances]
    data.update(spec.extras)
    body = dump_yaml(data, sort_keys=False, default_flow_style=None, width=1000)
    return "# spherecal fixtures: centres in the base frame and distances, metres\n" + body


def write_fixtures(path: str | os.PathLike, spec: FixtureSpec) -> Path:
    """Write ``fixtures.yaml`` atomically (temporary file, rename)."""
    for name in list(spec.positions) + [n for a, b, _ in spec.distances for n in (a, b)]:
        if name not in spec.names:
            raise DatasetError(f"{path}: field 'fixtures': {name!r} is used but not listed in names")
    return atomic_write_text(path, format_fixtures(spec))
