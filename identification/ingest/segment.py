"""Split a continuous recording into fixtures: where the nominal tool point stays put, the ball is in a socket.

While the ball sits in a socket, hand guiding moves the arm through its null space: the joints move
and the (true) tool point does not. The NOMINAL tool point then moves only as slowly as the model
error changes along the self-motion (a few mm/s on a real Panda), while carrying the ball from one
socket to the next moves it by centimetres within a second. So:

1. the tool point is averaged into ``bin`` intervals (10 ms) and a bin is *still* when every bin
   within ``window / 2`` of it lies within ``still_radius`` of it;
2. a run of still bins, less half a window at each end (the ball entering and leaving the socket),
   lasting at least ``min_duration`` with at least ``min_configurations`` distinct configurations
   is one fixture; everything between them (transport, pauses in the air) is dropped;
3. a fixture whose points lie further than ``max_spread`` from their mean (a drift) or two fixtures
   whose mean points are closer than ``min_separation`` (one socket visited twice, or two sockets
   that cannot be told apart) is refused: label such a recording by hand (``--fixture NAME=START:END``,
   :func:`labelled_spans`, or a CSV's ``fixture`` column).

Thresholds measured on MUKCa's real Panda with its ball (nominal model): within one socket the
nominal tool point lies on average 8 mm and at most 19 mm from its mean; the sockets are 50 mm apart.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from spherecal.correction.files.samples import DatasetError, first_of_rows
from spherecal.correction.kinematics import tool_point, tool_pose
from spherecal.correction.model import RobotModel

#: Bin of the stillness test [s].
BIN = 0.01
#: Samples whose tool points are computed at a time: the chain's temporaries of 1.8 M samples at once peaked at 410 MB
#: (each sample's point is computed on its own, elementwise: the same numbers in blocks).
POINT_BLOCK = 100_000


class SegmentationError(DatasetError):
    """A recording that cannot be split into fixtures unambiguously (one line)."""


class NoFixtureError(SegmentationError):
    """No stretch of a recording where the tool point stays still (one line)."""


@dataclass(frozen=True)
class SegmentSettings:
    """Thresholds of :func:`segment` (metres, seconds).

    Attributes:
        window: stillness window [s] (0.5).
        still_radius: the tool point stays within this of itself over the window [m] (0.003).
        min_duration: shortest fixture [s] (2.0).
        min_configurations: fewest distinct configurations (joints 1e-3 rad apart) of a fixture (20).
        max_spread: largest distance of a fixture's tool points from their mean [m] (0.020).
        min_separation: smallest distance between two fixtures' mean tool points [m] (0.030).
    """

    window: float = 0.5
    still_radius: float = 0.003
    min_duration: float = 2.0
    min_configurations: int = 20
    max_spread: float = 0.020
    min_separation: float = 0.030


@dataclass(frozen=True)
class Segment:
    """One fixture found in a recording.

    Attributes:
        name: fixture name (``S1``, ``S2``, ...).
        rows: (K,) sample indices in the recording.
        start, end: time span [s] since the first sample of the recording.
        centre: (3,) mean nominal tool point [m].
        spread_mean, spread_max: mean and largest distance of the nominal tool points from ``centre`` [m].
        visit: 1, or the how-manyth visit of a socket the recording came back to (:func:`_revisits`): its samples
            are that socket's fixture too.
    """

    name: str
    rows: np.ndarray
    start: float
    end: float
    centre: np.ndarray
    spread_mean: float
    spread_max: float
    visit: int = 1
    labelled: bool = False  # a span given by hand (:func:`labelled_spans`), not found by stillness

    @property
    def label(self) -> str:
        """``S1``, or ``S1 visit 2`` for a later visit of the same socket (tables, the provenance block)."""
        return self.name if self.visit == 1 else f"{self.name} visit {self.visit}"


def _distinct(q: np.ndarray, tol: float = 1e-3) -> int:
    return int(first_of_rows(np.floor(q / tol)).size)  # np.unique(axis=0)'s count, a tenth of its time


def _tool_points(model: RobotModel, q: np.ndarray) -> np.ndarray:
    """(T, 3) nominal tool points [m] of ``q`` (T, n) [rad], :data:`POINT_BLOCK` samples at a time."""
    if len(q) <= POINT_BLOCK:
        return tool_point(model, q)
    points = np.empty((len(q), 3))
    for first in range(0, len(q), POINT_BLOCK):
        points[first : first + POINT_BLOCK] = tool_point(model, q[first : first + POINT_BLOCK])
    return points


def _still_bins(points: np.ndarray, half: int, radius: float) -> np.ndarray:
    """(B,) bool: bin ``b`` is still when bins ``b-half .. b+half`` all lie within ``radius`` of it."""
    still = np.ones(points.shape[0], dtype=bool)
    for offset in range(1, half + 1):
        gap = np.linalg.norm(points[offset:] - points[:-offset], axis=1) > radius
        still[offset:] &= ~gap
        still[:-offset] &= ~gap
    still[:half] = False  # a window cut by the start or the end is not known to be still
    still[points.shape[0] - half :] = False
    return still


def segment(
    model: RobotModel, q: np.ndarray, t: np.ndarray, settings: SegmentSettings = SegmentSettings(), where: str = "",
    sources=None,
) -> list[Segment]:
    """Find the fixtures of a continuous recording.

    Args:
        model: the NOMINAL robot (its tool point is the one tested for stillness).
        q: (T, n) joint angles [rad], in time order.
        t: (T,) time stamps [s], non-decreasing.
        settings: thresholds.
        where: the source, for messages.
        sources: (T,) where each sample came from (``"file: row N"``, a bag's message), for messages: a refused
            stretch names its rows beside its seconds (a review: seconds alone named no row of the file).

    Returns:
        The fixtures in time order, named ``S1, S2, ...``.

    Raises:
        SegmentationError: no fixture found, a fixture that drifts, two fixtures too close together.
    """
    where = f"{where}: " if where else ""
    s = settings
    points = _tool_points(model, q)
    bins = np.floor((t - t[0]) / BIN).astype(np.int64)
    edges = np.flatnonzero(np.diff(bins)) + 1
    starts = np.concatenate([[0], edges])
    counts = np.diff(np.concatenate([starts, [len(t)]]))
    centres = np.add.reduceat(points, starts, axis=0) / counts[:, None]
    times = bins[starts] * BIN
    # bins are indexed by time: a gap in the recording leaves no bin, so the window is counted in bins, at the
    # recording's own spacing of its bins where that is wider than BIN (a 30 Hz /joint_states that
    # joint_state_publisher republishes: every bin 33 ms on, a window counted in 10 ms bins was 3.3x --window)
    step = float(np.median(np.diff(times))) if len(times) > 1 else BIN
    half = max(1, int(round(s.window / 2 / max(BIN, step))))
    still = _still_bins(centres, half, s.still_radius)
    runs = np.flatnonzero(np.diff(np.concatenate([[0], still.astype(np.int8), [0]])))
    found: list[Segment] = []
    for a, b in zip(runs[0::2], runs[1::2], strict=True):
        a, b = a + half, b - half  # entering and leaving the socket
        if b <= a:
            continue
        if times[b - 1] + BIN - times[a] < s.min_duration:
            continue
        lo, hi = starts[a], starts[b] if b < len(starts) else len(t)
        rows = np.arange(lo, hi)
        if _distinct(q[rows]) < s.min_configurations:
            continue
        p = points[rows]
        centre = p.mean(axis=0)
        spread = np.linalg.norm(p - centre, axis=1)
        found.append(
            Segment(
                f"S{len(found) + 1}",
                rows,
                float(t[lo] - t[0]),
                float(t[hi - 1] - t[0]),
                centre,
                float(spread.mean()),
                float(spread.max()),
            )
        )
    if not found:
        raise NoFixtureError(
            f"{where}field 'q': no fixture found (no stretch of {s.min_duration:g} s and {s.min_configurations} "
            f"configurations where the nominal tool point stays within {s.still_radius * 1e3:g} mm over "
            f"{s.window:g} s)"
        )
    found = _revisits(found)
    for seg in found:
        if seg.spread_max > s.max_spread:
            raise SegmentationError(
                f"{where}field 'q': ambiguous: the still stretch {seg.start:.2f}-{seg.end:.2f} s{_span(sources, seg)} "
                f"drifts "
                f"{seg.spread_max * 1e3:.1f} mm from its mean (max spread {s.max_spread * 1e3:g} mm); "
                "label the fixtures (--fixture NAME=START:END, or a CSV's 'fixture' column)"
            )
    for i, first in enumerate(found):
        for second in found[i + 1 :]:
            gap = float(np.linalg.norm(first.centre - second.centre))
            if gap < s.min_separation and first.name != second.name:
                raise SegmentationError(
                    f"{where}field 'q': ambiguous: still stretches {first.start:.2f}-{first.end:.2f} s"
                    f"{_span(sources, first)} and {second.start:.2f}-{second.end:.2f} s{_span(sources, second)} are "
                    f"{gap * 1e3:.1f} mm apart (less than "
                    f"{s.min_separation * 1e3:g} mm): one socket twice or two sockets too close; label the "
                    "fixtures (--fixture NAME=START:END, or a CSV's 'fixture' column), or, where the arm moved on in "
                    "one socket without leaving it, let "
                    f"the stillness take the nominal model's own error (a real arm's several mm over a self-motion): "
                    f"--still-radius above {s.still_radius * 1e3:g} mm"
                )
    return found


#: Spacing of the samples :func:`still_point` fits [s] (50 Hz: a 2 s stretch gives 100 poses).
PIVOT_STEP = 0.02


def last_frames(model: RobotModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The last joint frame at configurations ``q`` (K, n) [rad]: its rotations (K, 3, 3) and origins (K, 3) [m] (the
    tool pose less the tool offset), for a pivot fit of a point ``x`` of that frame, ``origin + frame @ x``
    (:func:`still_point`, :func:`.tool_fit.pivot_tool`)."""
    pose = tool_pose(model, q).reshape(-1, 4, 4)
    frame = pose[:, :3, :3]
    return frame, pose[:, :3, 3] - frame @ np.asarray(model.tool, dtype=float)


def still_point(model: RobotModel, q: np.ndarray, t: np.ndarray,
                settings: SegmentSettings = SegmentSettings()) -> tuple[np.ndarray, int] | None:
    """The point of the last link that stays still where the robot file's tool point does not: the ball's centre
    when the robot file ends at the flange or another link than the ball's (the embedded arms, a ``--tip-link``
    naming the hand). Its stillness cannot be tested as :func:`segment` tests the tool point's, so each
    ``settings.min_duration`` of the recording gets a pivot fit of its own (the point ``x`` of the last joint frame
    whose ``p_k + R_k x`` lie closest to their mean, the nominal model's frames at :data:`PIVOT_STEP`): a stretch is
    held in a socket when that point stays within ``settings.still_radius`` rms of its mean and the rotations
    recorded pin it within ``still_radius`` (transport rotates about a line at most: its point is not pinned).

    Args:
        model: the nominal robot.
        q: (T, n) joint angles [rad], in time order.
        t: (T,) time stamps [s], non-decreasing.
        settings: thresholds (``min_duration``, ``still_radius``).

    Returns:
        ``(tool, stretches)``: (3,) the point [m] in the last joint frame, one pivot fit over every stretch held, and
        how many stretches were; None when no stretch is held.
    """
    if len(t) < 2:
        return None
    keep = np.flatnonzero(np.diff(np.floor((t - t[0]) / PIVOT_STEP), prepend=-1) > 0)
    frame, origin = last_frames(model, q[keep])
    chunk = np.floor((t[keep] - t[0]) / settings.min_duration).astype(np.int64)
    lhs, rhs = [], []
    for c in np.unique(chunk):
        rows = chunk == c
        if np.count_nonzero(rows) < 3:
            continue
        a = (frame[rows] - frame[rows].mean(axis=0)).reshape(-1, 3)
        b = -(origin[rows] - origin[rows].mean(axis=0)).reshape(-1)
        x, *_ = np.linalg.lstsq(a, b, rcond=None)
        residual = (a @ x - b).reshape(-1, 3)
        rms = float(np.sqrt(np.mean(np.sum(residual**2, axis=1))))
        smallest = float(np.linalg.svd(a, compute_uv=False)[-1])
        if rms <= settings.still_radius and smallest > 0 and rms / smallest <= settings.still_radius:
            lhs.append(a)
            rhs.append(b)
    if not lhs:
        return None
    tool, *_ = np.linalg.lstsq(np.concatenate(lhs), np.concatenate(rhs), rcond=None)
    return tool, len(lhs)


#: Two visits whose mean nominal tool points are this close [m] are one socket whatever their spread (a socket is
#: wider than a ball's play; the default ``still_radius``).
SAME_SOCKET = 0.003


def _revisits(found: list[Segment]) -> list[Segment]:
    """The stretches, each later visit of a socket named as its first: a stretch whose mean tool point lies within
    the larger of :data:`SAME_SOCKET` and the two visits' own spread (the nominal model's error moves the point that
    much within one visit) of an earlier socket's is the same socket again (the ball re-seated, the socket visited
    twice; a review: a ROS bag that came back to a socket was refused, 'one socket twice', with no remedy a bag
    allows). Not ``--still-radius``: raised as a refusal advises, it merged two sockets 20 mm apart (a review).
    Farther and nearer than ``min_separation`` stays ambiguous (refused by :func:`segment`)."""
    out: list[Segment] = []
    for seg in found:
        same = next((o for o in out if o.visit == 1 and np.linalg.norm(o.centre - seg.centre)
                     <= max(SAME_SOCKET, min(o.spread_mean, seg.spread_mean))), None)
        if same is None:
            out.append(replace(seg, name=f"S{sum(o.visit == 1 for o in out) + 1}"))
        else:
            out.append(replace(seg, name=same.name, visit=1 + sum(o.name == same.name for o in out)))
    return out


def labelled_spans(model: RobotModel, q: np.ndarray, t: np.ndarray, spans, where: str = "",
                   sources=None) -> list[Segment]:
    """The fixtures of a recording labelled by hand in time: ``spans`` ``(name, start, end)``, seconds since its first
    sample (the clock of the import's table), ends included; a name given twice is one socket visited twice. The
    nominal tool points' mean and spread are reported as :func:`segment`'s, never refused: the user said where the
    ball was.

    Args:
        model: the nominal robot.
        q: (T, n) joint angles [rad], in time order.
        t: (T,) time stamps [s], non-decreasing.
        spans: ``(name, start, end)`` [s] each.
        where: the source, for messages.
        sources: (T,) where each sample came from, for messages.

    Returns:
        The fixtures in time order.

    Raises:
        SegmentationError: a span holding no sample, two spans overlapping (one line naming them, field
            ``--fixture``).
    """
    where = f"{where}: " if where else ""
    since = t - t[0]
    found: list[Segment] = []
    for name, start, end in sorted(spans, key=lambda span: span[1]):
        given = f"{name}={start:g}:{end:g}"
        if found and start <= found[-1].end:
            last = found[-1]
            raise SegmentationError(f"{where}field '--fixture': {given} overlaps {last.name}="
                                    f"{last.start:g}:{last.end:g} (seconds since the first sample): give each sample "
                                    "one socket")
        rows = np.flatnonzero((since >= start) & (since <= end))
        if not rows.size:
            raise SegmentationError(f"{where}field '--fixture': {given} holds no sample: the recording spans "
                                    f"0-{since[-1]:.2f} s since its first sample{_first(sources)}")
        p = tool_point(model, q[rows]) if rows.size <= POINT_BLOCK else _tool_points(model, q[rows])
        centre = p.mean(axis=0)
        spread = np.linalg.norm(p - centre, axis=1)
        visit = 1 + sum(seg.name == name for seg in found)
        found.append(Segment(name, rows, float(start), float(end), centre, float(spread.mean()), float(spread.max()),
                             visit, labelled=True))
    return found


def _first(sources) -> str:
    """`` (data.csv: row 2)``: where the first sample came from; "" without ``sources``."""
    return "" if sources is None or not len(sources) else f" ({sources[0]})"


def revisit_notes(segments: list[Segment]) -> tuple[str, ...]:
    """One line per socket the recording visited more than once: its visits are one fixture (found by stillness;
    spans labelled by hand say so themselves)."""
    notes = []
    for first in (seg for seg in segments if seg.visit == 1 and not seg.labelled):
        later = [seg for seg in segments if seg.name == first.name and seg.visit > 1]
        if later:
            gaps = ", ".join(f"{np.linalg.norm(seg.centre - first.centre) * 1e3:.1f}" for seg in later)
            notes.append(f"{first.name} visited {len(later) + 1} times (later visits' mean tool points {gaps} mm from "
                         f"the first, within {SAME_SOCKET * 1e3:g} mm or the visits' own spread): one fixture")
    return tuple(notes)


def _span(sources, seg: Segment) -> str:
    """`` (data.csv: row 4301-63721)``: where a stretch's first and last samples came from; "" without ``sources``."""
    if sources is None or not len(seg.rows):
        return ""
    first, last = sources[int(seg.rows[0])], sources[int(seg.rows[-1])]
    head, _, number = last.rpartition(" ")
    return f" ({first}-{number})" if first.rpartition(" ")[0] == head else f" ({first} to {last})"


def labels_of(segments: list[Segment], count: int) -> np.ndarray:
    """(count,) fixture name of every sample, ``""`` for samples in no fixture (dropped)."""
    labels = np.full(count, "", dtype=object)
    for seg in segments:
        labels[seg.rows] = seg.name
    return labels.astype(str)


def format_segments(segments: list[Segment], kept: dict[str, int] | None = None) -> str:
    """One line per fixture (per visit of a socket visited again; its kept samples on its first line): samples, kept
    samples, time span [s], spread [mm]."""
    width = max([8, *(len(seg.label) for seg in segments)])
    lines = [
        f"{'fixture':<{width}} {'samples':>8} {'kept':>6} {'from [s]':>9} {'to [s]':>9} "
        f"{'spread mean [mm]':>17} {'max [mm]':>9}"
    ]
    for seg in segments:
        k = "-" if kept is None else str(kept.get(seg.name, 0)) if seg.visit == 1 else "\""
        lines.append(
            f"{seg.label:<{width}} {len(seg.rows):>8} {k:>6} {seg.start:>9.2f} {seg.end:>9.2f} "
            f"{seg.spread_mean * 1e3:>17.2f} {seg.spread_max * 1e3:>9.2f}"
        )
    return "\n".join(lines)
