"""Samples and distances the nominal model already shows in the wrong place: the cause a refusal names.

A refused calibration (the self-check's residual level, or a fit that moves the arm implausibly far) says what
failed, not always why. Some causes show before any fit, at the nominal model, because a real arm's errors
move its tool points by millimetres while these move them by centimetres:

* **two recordings under one name**: a fixture whose samples come in separate runs of the file (two imports
  joined, a placement recorded twice and named alike) that lie far apart (the calibration refused the 122
  samples of MUKCa panda_1's ``front`` and ``side_right`` joined under one name as 'the samples do not determine
  the parameters');
* **samples in the wrong socket**: a few samples far from the rest of their fixture (two presses swapped between
  MUKCa's ``hole_0.csv`` and ``hole_1.csv`` were refused as 'the socket or the ball moved');
* **a wrong known distance**: a known distance far from the one the nominal model puts between the two fixtures'
  samples (MUKCa's 50 mm plate imported with ``--distance 0.08`` was refused naming a fixture).

:func:`misplaced` returns the first it finds, as one line naming the file, rows and field, or None. It is asked
only when a calibration is refused, so good data's calibration is untouched.
"""

from __future__ import annotations

import numpy as np

from spherecal.correction import RobotModel, tool_point
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.samples import Dataset

from .problem import row_list

#: A sample lies in another fixture's socket when it is farther than this from its own fixture's middle point at the
#: nominal model [m] and nearer another's than half that; a run of samples is another socket's when its middle is
#: this far and :data:`GROSS_FACTOR` times the runs' spread from the first run's. MUKCa's real Pandas spread 8 mm on
#: average about a socket at the nominal model, a few good samples 26 mm (panda_6 right_h0); its sockets are 50 mm
#: apart.
GROSS = 0.030
GROSS_FACTOR = 4.0
#: Any sample farther than this from its fixture's middle point [m], and :data:`FAR_FACTOR` times the fixture's
#: median distance from it, is misplaced wherever it lies.
FAR = 0.060
FAR_FACTOR = 6.0
#: A known distance further than this (and than twice its fixtures' median spread) from the nominal model's
#: between the fixtures' middle points [m] (the real Pandas' nominal distance error: 2-8 mm).
DISTANCE_OFF = 0.020
#: Beyond this median distance of a fixture's samples from its middle point [m] the nominal model does not describe
#: the arm (another convention, another arm: hundreds of millimetres), and nothing is judged from it.
MAX_SCALE = 0.025


def misplaced(nominal: RobotModel, dataset: Dataset, spec: FixtureSpec | None = None,
              discounted: bool = False) -> str | None:
    """The first gross misplacement the nominal model shows (see the module), as one line, or None.

    Args:
        nominal: the robot (with the tool the samples show: :func:`.tool_fit.recentred_tool`).
        dataset: the samples calibrated.
        spec: known distances (None: none).
        discounted: the fit already used a robust loss (``soft_l1``, ``huber``): far samples are not advised to be
            discounted by one (a review: the advice repeated the loss the user had given).

    Returns:
        ``"samples.csv: rows 7-36 and 69-98, field 'fixture': ..."``, or None (also when the nominal model spreads
        a fixture's samples over more than :data:`MAX_SCALE`: it does not describe the arm).
    """
    points = tool_point(nominal, dataset.q)
    index = dataset.fixture_index
    middles, scales = {}, {}
    for j, name in enumerate(dataset.fixture_names):
        rows = np.flatnonzero(index == j)
        middles[name] = np.median(points[rows], axis=0)
        scales[name] = float(np.median(np.linalg.norm(points[rows] - middles[name], axis=1)))
    if max(scales.values()) > MAX_SCALE:
        return None
    for j, name in enumerate(dataset.fixture_names):
        found = _two_runs(dataset, points, np.flatnonzero(index == j), name)
        if found:
            return found
    found = _far_samples(dataset, points, middles, scales, discounted)
    if found:
        return found
    return _wrong_distance(spec, middles, scales) if spec is not None else None


def _span(dataset: Dataset, rows: np.ndarray) -> str:
    lines = dataset.lines[rows] if dataset.lines is not None else rows + 1
    return f"{lines.min()}-{lines.max()}" if len(lines) > 1 else f"{lines[0]}"


def _two_runs(dataset: Dataset, points: np.ndarray, rows: np.ndarray, name: str) -> str | None:
    """A fixture whose runs of consecutive rows lie far apart (each run's middle against the first's)."""
    runs = np.split(rows, np.flatnonzero(np.diff(rows) > 1) + 1)
    if len(runs) < 2:
        return None
    middles = [np.median(points[run], axis=0) for run in runs]
    within = float(np.median(np.concatenate([np.linalg.norm(points[run] - m, axis=1)
                                             for run, m in zip(runs, middles, strict=True)])))
    for k in range(1, len(runs)):
        gap = float(np.linalg.norm(middles[k] - middles[0]))
        if gap > max(GROSS, GROSS_FACTOR * within):
            return (f"{dataset.source or 'samples'}: rows {_span(dataset, runs[0])} and {_span(dataset, runs[k])}, "
                    f"field 'fixture': fixture {name}'s samples come in separate runs of the file that the nominal "
                    f"model puts {gap * 1e3:.0f} mm apart (each within {within * 1e3:.2g} mm of its middle): two "
                    "sockets under one name (a placement recorded twice, or two imports joined?); give each its own "
                    "fixture name")
    return None


def _far_samples(dataset: Dataset, points: np.ndarray, middles: dict, scales: dict,
                 discounted: bool = False) -> str | None:
    """Samples far from their fixture's middle point; when one lies near another fixture's, says so."""
    names = dataset.fixture_names
    far: list[int] = []
    for j, name in enumerate(names):
        rows = np.flatnonzero(dataset.fixture_index == j)
        own = np.linalg.norm(points[rows] - middles[name], axis=1)
        other = np.min([np.linalg.norm(points[rows] - middles[n], axis=1) for n in names if n != name]
                       or [np.full(len(rows), np.inf)], axis=0)
        far += list(rows[((own > GROSS) & (other < own / 2)) | (own > max(FAR, FAR_FACTOR * scales[name]))])
    if not far:
        return None
    far_rows = np.array(sorted(far))
    gaps = [np.linalg.norm(points[k] - middles[names[dataset.fixture_index[k]]]) for k in far_rows]
    elsewhere = []
    for k, gap in zip(far_rows, gaps, strict=True):
        own = names[dataset.fixture_index[k]]
        other = min((n for n in names if n != own), key=lambda n: np.linalg.norm(points[k] - middles[n]), default=None)
        if other is not None and np.linalg.norm(points[k] - middles[other]) < gap / 2:
            elsewhere.append(other)
    where = (f"; {len(elsewhere)} of them among another fixture's samples ({', '.join(dict.fromkeys(elsewhere))}): "
             "pressed into the wrong socket?" if elsewhere else "")
    typical = max(scales.values())
    span = f"{min(gaps) * 1e3:.0f}" if len(gaps) == 1 else f"{min(gaps) * 1e3:.0f}-{max(gaps) * 1e3:.0f}"
    counted = "1 sample lies" if len(far_rows) == 1 else f"{len(far_rows)} samples lie"
    return (f"{dataset.source or 'samples'}: {row_list(dataset, far_rows)}, field 'fixture': {counted} "
            f"{span} mm from the rest of their fixture at the nominal model (the "
            f"rest within {typical * 1e3:.2g} mm of its middle, as a real arm's errors put them){where}; remove them"
            + ("" if discounted else ", or calibrate --loss soft_l1 to discount them"))


def _wrong_distance(spec: FixtureSpec, middles: dict, scales: dict) -> str | None:
    """A known distance far from the nominal model's between its fixtures' middle points."""
    for k, (a, b, value) in enumerate(spec.distances):
        if a not in middles or b not in middles:
            continue
        shown = float(np.linalg.norm(middles[a] - middles[b]))
        if abs(shown - value) > max(DISTANCE_OFF, 2.0 * max(scales[a], scales[b])):
            return (f"{spec.source or 'fixtures'}: {spec.distance_field(k)}: known distance {a}-{b} "
                    f"{value * 1e3:.4g} mm, the nominal model puts their samples {shown * 1e3:.4g} mm apart (a real "
                    "arm's errors change that by millimetres): is the distance right (import --distance, in metres)?")
    return None
