"""Candidate fixture positions of a plan: from a box grid or a YAML file."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from spherecal.correction import RobotModel, tool_point
from spherecal.correction.errors import SpherecalError
from spherecal.correction.files.text_input import read_text
from spherecal.correction.files.yaml_safe import MAX_FILE_BYTES, load_yaml, node_line

#: Most candidates of one plan, from a grid or a file (each one is surveyed and scored: 1000 single sockets take
#: 70 s on one core, 1000 plate placements of guidance about 50 s; 10^4 from a file ran for 12 minutes).
MAX_CANDIDATES = 1000
MAX_GRID = MAX_CANDIDATES


class CandidateError(SpherecalError):
    """A candidate list that is empty or malformed (message names the file or option and field)."""


@dataclass(frozen=True)
class Candidate:
    """A candidate fixture position.

    Attributes:
        name: label (``C1`` ... or from the file).
        position: (3,) centre in the base frame [m].
        joint_range: (n,) share of each joint's range the self-motion may use there (None: all).
        source: the candidates file or the command-line option that gave it (``""`` when placed by the program,
            ``--grid auto``): a given one farther than the arm reaches in any posture is named so, with the unit of
            positions (:func:`controller.reach.check_fixture_distance`), before any IK is tried.
        located: where a candidates file gives its position (``"FILE: row N, field 'candidates.NAME.position'"``),
            for the survey's line when the IK finds it out of reach; ``""`` for one from a grid.
    """

    name: str
    position: np.ndarray
    joint_range: np.ndarray | None = None
    source: str = ""
    located: str = ""


def grid_candidates(text: str, option: str = "--grid") -> list[Candidate]:
    """Candidates on a box grid ``"xmin,xmax,nx;ymin,ymax,ny;zmin,zmax,nz"`` [m], named ``C1`` ...

    Raises:
        CandidateError: not three ``min,max,count`` triples, a count < 1, more than :data:`MAX_GRID` points (one
            line naming ``option``, the command-line option that gave ``text``).
    """
    axes = []
    parts = text.split(";")
    if len(parts) != 3:
        raise CandidateError(f"field '{option}': {text!r}: expected 'xmin,xmax,nx;ymin,ymax,ny;zmin,zmax,nz'")
    for axis, part in zip("xyz", parts, strict=True):
        fields = part.split(",")
        try:
            lo, hi, count = float(fields[0]), float(fields[1]), int(fields[2])
        except (ValueError, IndexError):
            raise CandidateError(
                f"field '{option}': {text!r}: {axis}: expected 'min,max,count', got {part!r}") from None
        if len(fields) != 3 or count < 1 or not (abs(lo) <= 10.0 and abs(hi) <= 10.0):  # finite, metres
            unit = "; positions are in metres: millimetres given?" if max(abs(lo), abs(hi)) > 10.0 else ""
            raise CandidateError(f"field '{option}': {text!r}: {axis}: expected 'min,max,count', count >= 1, |min|, "
                                 f"|max| <= 10 m{unit}")
        axes.append(np.linspace(lo, hi, count) if count > 1 else np.array([(lo + hi) / 2]))
    total = math.prod(a.size for a in axes)
    if total > MAX_GRID:
        raise CandidateError(f"field '{option}': {text!r}: {total} points, at most {MAX_GRID}")
    points = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return [Candidate(f"C{k + 1}", p, source=option) for k, p in enumerate(points)]


#: Points per axis of ``--grid auto`` (:func:`auto_grid`): 5 x 5 x 5 candidates.
AUTO_COUNT = 5


def auto_grid(model: RobotModel, rng: np.random.Generator, count: int = AUTO_COUNT) -> list[Candidate]:
    """``--grid auto``: a ``count`` x ``count`` x ``count`` box grid over where the arm's tool point reaches in
    front of its base and above it (x >= 0 and z >= 0 in the base frame: a socket stands on the table the arm is
    mounted on, not below it): the 10th to 90th percentile of random configurations' tool points
    along x, y and z, so that its spacing follows the arm's size (a 0.45 m arm and a 1.3 m one alike), named
    ``C1`` ... as :func:`grid_candidates` names them. Points the arm does not reach there, or inside its base column,
    are surveyed and named unreachable, as any candidate.

    Raises:
        CandidateError: the tool point rarely reaches the front of the base.
    """
    points = tool_point(model, model.random_configurations(20_000, rng))
    front = points[(points[:, 0] >= 0.0) & (points[:, 2] >= 0.0)]
    if len(front) < 50:
        raise CandidateError("field '--grid': auto: the tool point rarely reaches in front of and above the base (x, "
                             "z >= 0); give the box 'xmin,xmax,nx;ymin,ymax,ny;zmin,zmax,nz' [m]")
    low, high = np.percentile(front, [10, 90], axis=0)
    ticks = [np.round(np.linspace(low[k], high[k], count), 3) for k in range(3)]
    grid = np.stack(np.meshgrid(*ticks, indexing="ij"), axis=-1).reshape(-1, 3)
    return [Candidate(f"C{k + 1}", p) for k, p in enumerate(grid)]


def read_candidates(path: str | Path, n_joints: int) -> list[Candidate]:
    """Candidates from YAML: ``candidates: {C1: {position: [x, y, z], joint_range: [...]}, ...}``.

    ``joint_range`` (optional) gives, per joint, the share of its range the self-motion may use.

    Raises:
        CandidateError: unreadable file, no candidates, a bad position or joint range (one line naming the file, the
            row of the field's key and the field, as :mod:`correction.files` readers name a YAML node).
    """

    path = Path(path)
    entries, root = candidate_document(path, "{position: [x, y, z]}")

    def where(name, *field: str) -> str:
        """``"FILE: row N, field 'candidates.NAME.FIELD'"``, the row of that key in the file."""
        row = node_line(root, "candidates", str(name), *field, key_line=True)
        return f"{path}: row {row}, field '{'.'.join(['candidates', str(name), *field])}'"

    out = []
    for name, entry in entries.items():
        if not isinstance(entry, dict) or "position" not in entry:
            raise CandidateError(f"{where(name)}: expected a mapping with 'position: [x, y, z]'")
        located = where(name, "position")  # checked below, and carried to the IK's refusal (Candidate.located)
        position = _vector(entry["position"], 3, located)
        if np.abs(position).max() > 10.0:
            raise CandidateError(f"{located}: {position.tolist()} m is not physical (at most 10 m; "
                                 "positions are in metres: millimetres given?)")
        joint_range = None
        if entry.get("joint_range") is not None:
            joint_range = _vector(entry["joint_range"], n_joints, where(name, "joint_range"))
            if np.any(joint_range <= 0) or np.any(joint_range > 1):
                raise CandidateError(f"{where(name, 'joint_range')}: every share must be in (0, 1]")
        unknown = set(entry) - {"position", "joint_range"}
        if unknown:
            raise CandidateError(f"{where(name, str(sorted(unknown)[0]))}: unknown field")
        out.append(Candidate(str(name), position, joint_range, str(path), located))
    return out


def candidate_document(path: Path, expected: str) -> tuple[dict, object]:
    """The ``candidates:`` mapping of a YAML file (bounded reader: size, depth, aliases, no duplicate keys) and the
    document's YAML node tree (for the rows of its fields).

    Raises:
        CandidateError: unreadable file, or no non-empty mapping (``expected`` names an entry's form).
    """
    text = read_text(path, CandidateError, limit=MAX_FILE_BYTES)
    data, root = load_yaml(text, str(path), CandidateError)
    entries = data.get("candidates") if isinstance(data, dict) else None
    if not isinstance(entries, dict) or not entries:
        raise CandidateError(f"{path}: field 'candidates': expected a non-empty mapping name -> {expected}")
    if len(entries) > MAX_CANDIDATES:
        raise CandidateError(f"{path}: field 'candidates': {len(entries)} candidates, at most {MAX_CANDIDATES} (each "
                             "is surveyed and scored: about a minute per 1000 on one core)")
    return entries, root


def _vector(value, size: int, where: str) -> np.ndarray:
    try:
        vector = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise CandidateError(f"{where}: expected {size} numbers, got {value!r}") from None
    if vector.shape != (size,) or not np.all(np.isfinite(vector)):
        raise CandidateError(f"{where}: expected {size} finite numbers, got {value!r}")
    return vector
