"""Candidate plate placements of recording guidance: groups of sockets with known distances.

A placement is where the user would put the plate next: its sockets' centres in the robot's base
frame [m] and the centre-to-centre distances known from the plate's drawing. From YAML::

    candidates:
      left:
        sockets: {left_h0: [0.42, 0.21, 0.02], left_h1: [0.42, 0.26, 0.02]}
        distances: [[left_h0, left_h1, 0.050]]
      C7: {position: [0.5, 0.0, 0.1]}        # a single socket (the older candidate form)

or generated: the user's plate (its socket layout, :func:`plate_layout`) placed at the points of a
box grid in several orientations about the vertical axis (:func:`plate_placements`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from spherecal.correction import RobotModel, tool_point
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.yaml_safe import node_line

from .candidates import MAX_CANDIDATES, Candidate, CandidateError, candidate_document, grid_candidates

#: Sockets of one candidate closer than this are one socket under two names (a copied line) [m]; the
#: calibration's self-check refuses such fixtures (``identification.selfcheck.MIN_SEPARATION``).
MIN_SOCKET_SEPARATION = 0.02
#: A known distance farther than this share of itself and :data:`DISTANCE_SLACK` from the distance of its two
#: sockets' positions is a typo: the positions are where the user will put the plate, the distance its drawing's.
DISTANCE_SHARE = 0.2
DISTANCE_SLACK = 0.005  # [m]


@dataclass(frozen=True)
class Placement:
    """One placement of a plate: a group of sockets.

    Attributes:
        name: candidate name.
        sockets: socket name -> (3,) centre in the base frame [m].
        distances: known centre-to-centre distances ``(socket_a, socket_b, metres)``.
        source: the candidates file it was read from ("" when generated), for refusals naming its field.
        located: socket name -> where that file gives its position (``"FILE: row N, field
            'candidates.NAME.sockets.SOCKET'"``, or ``'candidates.NAME.position'`` of a single socket), for the
            refusal of a socket the IK finds out of reach; empty when generated.
    """

    name: str
    sockets: dict[str, np.ndarray]
    distances: tuple[tuple[str, str, float], ...] = ()
    source: str = ""
    located: dict[str, str] = field(default_factory=dict)

    @property
    def centre(self) -> np.ndarray:
        """(3,) mean of the socket centres [m]."""
        return np.mean(list(self.sockets.values()), axis=0)

    @staticmethod
    def single(candidate: Candidate) -> Placement:
        """A one-socket placement from a :class:`Candidate` (its name is the socket's name)."""
        return Placement(candidate.name, {candidate.name: np.asarray(candidate.position, float)})


def read_placements(path: str | Path) -> list[Placement]:
    """Placements from YAML (see the module docstring).

    Raises:
        CandidateError: unreadable file, no candidates, a bad socket position, a distance naming a
            socket not in its placement or not positive, a socket name used twice (one line naming
            the file, the row of the field's key or list item, and the field).
    """
    path = Path(path)
    entries, root = candidate_document(path, "{sockets: {name: [x, y, z]}, distances: [[a, b, metres]]}")
    out, seen = [], set()
    for name, entry in entries.items():
        def at(*field, name=name) -> str:
            """``"FILE: row N, field 'candidates.NAME.FIELD'"``: the row of that key (or list item) in the file."""
            row = node_line(root, "candidates", str(name), *field, key_line=True)
            dotted = "".join(f"[{f}]" if isinstance(f, int) else f".{f}" for f in ("candidates", str(name), *field))
            return f"{path}: row {row}, field '{dotted[1:]}'"

        if not isinstance(entry, dict) or not ({"sockets", "position"} & set(entry)):
            raise CandidateError(f"{at()}: expected 'sockets: {{name: [x, y, z]}}' or 'position: [x, y, z]'")
        unknown = set(entry) - {"sockets", "distances", "position"}
        if unknown:
            raise CandidateError(f"{at(str(sorted(unknown)[0]))}: unknown field")
        if "position" in entry:
            located = {str(name): at("position")}
            sockets = {str(name): _point(entry["position"], located[str(name)])}
        elif not isinstance(entry["sockets"], dict) or not entry["sockets"]:
            raise CandidateError(f"{at('sockets')}: expected a non-empty mapping name -> [x, y, z] [m]")
        else:
            located = {str(k): at("sockets", str(k)) for k in entry["sockets"]}
            sockets = {str(k): _point(v, located[str(k)]) for k, v in entry["sockets"].items()}
        _separated(sockets, lambda socket: at("sockets", socket))
        for socket in sockets:
            if socket in seen:
                raise CandidateError(f"{at('sockets', socket)}: socket name used by another candidate")
            seen.add(socket)
        distances = []
        raw = entry.get("distances") or []
        if not isinstance(raw, list):
            raise CandidateError(f"{at('distances')}: expected a list of [socket_a, socket_b, metres]")
        for k, item in enumerate(raw):
            where = at("distances", k)
            if not isinstance(item, list) or len(item) != 3:
                raise CandidateError(f"{where}: expected [socket_a, socket_b, metres], got {item!r}")
            a, b, value = str(item[0]), str(item[1]), item[2]
            if a not in sockets or b not in sockets or a == b:
                raise CandidateError(f"{where}: {a!r} and {b!r} must be two sockets of this candidate")
            if not isinstance(value, (int, float)) or not 0.0 < float(value) <= 10.0:
                raise CandidateError(f"{where}: the distance must be in (0, 10] m, got {value!r}")
            apart = float(np.linalg.norm(sockets[a] - sockets[b]))
            if abs(apart - value) > max(DISTANCE_SHARE * min(apart, value), DISTANCE_SLACK):
                raise CandidateError(f"{where}: {a} - {b} is {value * 1e3:.4g} mm here, but their positions are "
                                     f"{apart * 1e3:.4g} mm apart (a typo in one of them?)")
            distances.append((a, b, float(value)))
        out.append(Placement(str(name), sockets, tuple(distances), str(path), located))
    return out


def _separated(sockets: dict[str, np.ndarray], where: Callable[[str], str]) -> None:
    """Refuse two sockets of one candidate closer than :data:`MIN_SOCKET_SEPARATION` (``where(socket)``: the file,
    row and field of a socket, for the message)."""
    names = list(sockets)
    for i, b in enumerate(names):
        for a in names[:i]:
            apart = float(np.linalg.norm(sockets[a] - sockets[b]))
            if apart < MIN_SOCKET_SEPARATION:
                raise CandidateError(f"{where(b)}: {apart * 1e3:.3g} mm from socket {a}: sockets closer "
                                     f"than {MIN_SOCKET_SEPARATION * 1e3:.0f} mm are one socket under two names")


def _point(value, where: str) -> np.ndarray:
    try:
        point = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise CandidateError(f"{where}: expected [x, y, z] [m], got {value!r}") from None
    if point.shape != (3,) or not np.all(np.isfinite(point)) or np.abs(point).max() > 10.0:
        unit = " (positions are in metres: millimetres given?)" if point.shape == (3,) and np.isfinite(point).all() \
            else ""
        raise CandidateError(f"{where}: expected 3 finite numbers within 10 m [m], got {value!r}{unit}")
    return point


def plate_layout(spec: FixtureSpec, centres: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The user's plate: socket suffix -> (3,) offset from the plate's centre [m], from the first
    recorded group of sockets joined by known distances (their calibrated centres).

    Args:
        spec: the recording's fixtures (its known distances define the groups).
        centres: fixture name -> (3,) calibrated centre [m].

    Raises:
        CandidateError: the recording has no known distance (no plate to copy).
    """
    if not spec.distances:
        raise CandidateError(f"{spec.source or 'fixtures'}: field 'distances': no known distance in the recording, "
                             "so no plate layout to place (give --candidates)")
    group = [spec.distances[0][0], spec.distances[0][1]]
    for a, b, _ in spec.distances[1:]:  # every socket joined to the first pair
        for x, y in ((a, b), (b, a)):
            if x in group and y not in group:
                group.append(y)
    points = np.array([centres[name] for name in group])
    return {f"h{k}": p - points.mean(axis=0) for k, p in enumerate(points)}


def reachable_grid(model: RobotModel, height: float, rng: np.random.Generator, count: int = 5,
                   toward: np.ndarray | None = None) -> list[Candidate]:
    """A ``count`` x ``count`` grid of plate centres at ``height`` [m] over where the tool point reaches at that
    height: the 10th to 90th percentile of random configurations' tool points within 3 cm of it, along x and y.
    With ``toward`` (the recorded plate's centre, (2,) or (3,) [m]), only the reach on its side of the base (the
    half-plane through the base's vertical axis facing it; the plate lies on the table the arm works over, not
    behind its base), the grid's axes along and across that direction. No collision check: points inside the
    robot's own column are refused later only if out of reach.

    Returns:
        Candidates ``C1`` ... (the along-axis outer, as :func:`.candidates.grid_candidates` orders x and y).

    Raises:
        CandidateError: the tool point rarely reaches that height (on that side).
    """
    points = tool_point(model, model.random_configurations(20_000, rng))
    near = points[np.abs(points[:, 2] - height) < 0.03, :2]
    axes, side = np.eye(2), ""
    if toward is not None and np.linalg.norm(np.asarray(toward, dtype=float)[:2]) > 1e-9:
        along = np.asarray(toward, dtype=float)[:2] / np.linalg.norm(np.asarray(toward, dtype=float)[:2])
        axes, side = np.array([along, [-along[1], along[0]]]), " on the recorded plate's side of the base"
        near = near[near @ along >= 0.0]
    if len(near) < 50:
        raise CandidateError(
            f"field '--plate-grid': auto: the tool point rarely reaches the plate's height {height:.3f} m{side}")
    low, high = np.percentile(near @ axes.T, [10, 90], axis=0)
    ticks = [np.linspace(low[k], high[k], count) for k in range(2)]
    grid = np.stack(np.meshgrid(*ticks, indexing="ij"), axis=-1).reshape(-1, 2) @ axes
    return [Candidate(f"C{k + 1}", np.array([x, y, height])) for k, (x, y) in enumerate(np.round(grid, 4))]


def plate_placements(layout: dict[str, np.ndarray], grid: str | list[Candidate],
                     orientations: int = 2) -> list[Placement]:
    """The plate at every point of a box grid, turned about the vertical (z) axis.

    Args:
        layout: socket suffix -> (3,) offset from the plate's centre [m] (:func:`plate_layout`).
        grid: ``"xmin,xmax,nx;ymin,ymax,ny;zmin,zmax,nz"`` [m], the plate centres, or the centres themselves
            (:func:`reachable_grid`).
        orientations: turns per point, evenly over half a turn (a plate's socket pattern is usually
            symmetric under a half turn), >= 1.

    Returns:
        Placements ``G<k>_<deg>`` with sockets ``G<k>_<deg>_<suffix>`` and every distance among them known.

    Raises:
        CandidateError: a bad grid or ``orientations`` < 1.
    """
    if orientations < 1:
        raise CandidateError(f"field '--plate-orientations': expected an integer >= 1, got {orientations}")
    suffixes = list(layout)
    offsets = np.array([layout[s] for s in suffixes])
    distances = [(i, j, float(np.linalg.norm(offsets[i] - offsets[j])))
                 for i in range(len(suffixes)) for j in range(i + 1, len(suffixes))]
    points = grid_candidates(grid, "--plate-grid") if isinstance(grid, str) else list(grid)
    if len(points) * orientations > MAX_CANDIDATES:
        raise CandidateError(f"field '--plate-grid': {grid!r}: {len(points)} points x {orientations} "
                             f"orientations make {len(points) * orientations} placements, at most {MAX_CANDIDATES}")
    out = []
    for point in points:
        for k in range(orientations):
            angle = math.pi * k / orientations
            c, s = math.cos(angle), math.sin(angle)
            turned = offsets @ np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
            name = f"G{point.name[1:]}_{round(math.degrees(angle))}"
            sockets = {f"{name}_{suffix}": point.position + turned[i] for i, suffix in enumerate(suffixes)}
            keys = list(sockets)
            out.append(Placement(name, sockets, tuple((keys[i], keys[j], d) for i, j, d in distances)))
    return out
