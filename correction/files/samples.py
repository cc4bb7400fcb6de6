"""Spherical-joint samples: the :class:`Dataset` type (joint angles per fixture) and its selections.

The files are :mod:`spherecal.correction.files.samples_csv` (``samples.csv``) and
:mod:`spherecal.correction.files.fixtures` (``fixtures.yaml``). Errors are :class:`DatasetError`, one line
naming the file, the row (1-based line number) and the field.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace

import numpy as np

from spherecal.correction.errors import SpherecalError

#: Default tolerance of :meth:`Dataset.deduplicated`: max ``|dq|`` [rad] under which two samples of one
#: fixture count as the same configuration (1e-4 rad ~ 0.1 mm at 1 m reach).
DEDUP_TOL = 1e-4
#: Joint angles this far outside a limit [rad] are still accepted (rounding in recorders).
LIMIT_TOL = 1e-6


#: An angle further than this beyond a joint limit [rad] (a quarter turn) cannot be an angle of that joint
#: as the robot file describes it (another arm's file, degrees in a radians file, a wrapped encoder):
#: refused. Closer, it is the arm's own range exceeding its file's, as real arms do (MUKCa's Gen3 lite
#: recordings pass ``gen3lite.urdf``'s q6 limit of 2.09 rad by 0.65 rad): used, with one warning.
HARD_MARGIN = float(np.pi / 2)


class DatasetError(SpherecalError):
    """A samples or fixtures file that cannot be used; one line naming file, row and field."""


def configurations_digest(q: np.ndarray) -> str:
    """SHA-256 (hex) of a set of configurations: (K, n) joint angles [rad] as little-endian float64,
    rows sorted (the file order and the fixture's name do not matter; every bit of every angle does).

    A calibrated file records it per fixture trained on (``calibration.trained_on``), so that
    ``validate`` recognises training samples by their content, whatever they are called.
    """
    import hashlib  # standard library; only digests need it

    rows = np.ascontiguousarray(np.asarray(q, dtype="<f8"))
    if rows.ndim != 2:
        raise ValueError("q must be (K, n)")
    order = np.lexsort(rows.T[::-1]) if len(rows) else np.arange(0)
    return hashlib.sha256(rows[order].tobytes()).hexdigest()


def configuration_hashes(q: np.ndarray) -> np.ndarray:
    """(K,) uint64: each configuration's own hash, the first 8 bytes of the SHA-256 of its joint angles [rad]
    as little-endian float64 (every bit of every angle counts). A calibrated file records the smallest few of
    its fixtures' (``calibration.trained_on``), so that ``validate`` recognises samples it shares with the
    training ones: a subset or a superset of them (a recording imported again with another subsample)."""
    import hashlib  # standard library; only digests need it

    rows = np.ascontiguousarray(np.asarray(q, dtype="<f8"))
    if rows.ndim != 2:
        raise ValueError("q must be (K, n)")
    return np.array([int.from_bytes(hashlib.sha256(row.tobytes()).digest()[:8], "big") for row in rows],
                    dtype=np.uint64)


#: Rows checked at a time on a long recording (:meth:`LimitExcess.add`, the importers' jump check): their
#: temporaries stay small.
LIMIT_BLOCK = 100_000


class JointLimitWarning(UserWarning):
    """Recorded angles beyond the robot file's joint limits (within :data:`HARD_MARGIN`): used as recorded."""


@dataclass
class LimitExcess:
    """How far recorded angles pass the joint limits, gathered over a file read in blocks.

    Attributes:
        model_name: the robot (for messages).
        lower, upper: (n,) joint limits [rad].
        names: (n,) joint names for messages (``q1..qn``).
        tol: accepted without a word [rad].
        worst: (joint index, 0 below / 1 above) -> (excess [rad], the angle [rad], where it was found).
    """

    model_name: str
    lower: np.ndarray
    upper: np.ndarray
    names: list[str]
    tol: float = 1e-6
    worst: dict[tuple[int, int], tuple[float, float, str]] = field(default_factory=dict)

    @staticmethod
    def of(model, names: list[str] | None = None, tol: float = 1e-6) -> LimitExcess:
        """For a :class:`~spherecal.correction.model.RobotModel` ``model``."""
        names = list(names) if names else [f"q{i + 1}" for i in range(model.n_joints)]
        return LimitExcess(model.name, np.asarray(model.lower), np.asarray(model.upper), names, tol)

    def add(self, q: np.ndarray, where, error: type[Exception]) -> None:
        """Check (K, n) angles; ``where(k)`` names row ``k`` ("file: row N").

        Checked :data:`LIMIT_BLOCK` rows at a time (the first row refused and the worst excess of each joint are
        the same as at once; the temporaries stay small: three of (K, n) floats were 300 MB of a 1.8 M-sample bag).

        Raises:
            error: an angle more than :data:`HARD_MARGIN` beyond a limit of a joint whose range is less
                than a turn (one line: row, field, angle, limits).
        """
        for start in range(0, len(q), LIMIT_BLOCK):
            self._add(q[start:start + LIMIT_BLOCK], lambda k, start=start: where(start + k), error)

    def _add(self, q: np.ndarray, where, error: type[Exception]) -> None:
        below, above = self.lower - q, q - self.upper
        excess = np.maximum(below, above)
        if not np.any(excess > self.tol):
            return
        bounded = (self.upper - self.lower) < 2 * np.pi - 1e-9
        hard = (excess > HARD_MARGIN) & bounded
        if hard.any():
            k, i = np.argwhere(hard)[0]
            raise error(
                f"{where(k)}, field {self.names[i]!r}: {q[k, i]:.6g} rad is {excess[k, i]:.3g} rad outside the joint "
                f"limits [{self.lower[i]:.6g}, {self.upper[i]:.6g}] of {self.model_name}, more than a quarter turn "
                f"({HARD_MARGIN:.3g} rad): not an angle of this joint (another arm's file, or degrees?)"
            )
        for side, past in ((0, below), (1, above)):  # each side of a joint: an arm may pass both
            # a joint of a full turn (URDF "continuous": no limits stated) has no side to pass: its angles wrap
            for i in np.flatnonzero((past > self.tol).any(axis=0) & bounded):
                k = int(np.argmax(past[:, i]))
                if past[k, i] > self.worst.get((int(i), side), (0.0,))[0]:
                    self.worst[(int(i), side)] = (float(past[k, i]), float(q[k, i]), where(k))

    def warn(self, source: str) -> str | None:
        """Issue ONE :class:`JointLimitWarning` naming every joint past its limits (None, nothing to say)."""
        if not self.worst:
            return None
        parts = []
        for (i, past), (excess, _, where) in sorted(self.worst.items()):
            side = f"above {self.upper[i]:.4g}" if past else f"below {self.lower[i]:.4g}"
            place = where[len(source):].lstrip("/\\: ") if where.startswith(source) else where
            parts.append(f"{self.names[i]} by up to {excess:.3g} rad ({np.rad2deg(excess):.3g} deg) {side} ({place})")
        text = (
            f"{source}: recorded angles beyond the joint limits of {self.model_name}, used as recorded: "
            f"{'; '.join(parts)} (the arm's range is wider than its robot file says, or the file is another arm's)"
        )
        warnings.warn(text, JointLimitWarning, stacklevel=3)
        return text


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
        index = np.full(self.labels.shape, -1, dtype=int)
        for i, name in enumerate(self.fixture_names):  # one comparison per fixture, not a Python loop per sample
            index[self.labels == name] = i
        if np.any(index < 0):
            raise KeyError(str(self.labels[np.argmax(index < 0)]))
        return index

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
    first = first_of_rows(cells)
    keep[first] = True
    if tol == 0.0 or first.size < 2:
        return keep
    sub = q[first]
    spread = np.ptp(sub, axis=0)
    col = int(np.argmax(spread))
    order = np.argsort(sub[:, col], kind="stable")
    joints = [col] + [int(j) for j in np.argsort(-spread, kind="stable") if j != col]
    key, *others = (np.ascontiguousarray(sub[order, j]) for j in joints)
    pairs = []
    near = np.arange(key.size - 1)  # samples whose neighbour ``offset`` places on may be within tol
    for offset in range(1, key.size):
        # sorted on the joint: a sample not within tol of the one offset places on is not of any further one
        near = near[near + offset < key.size]
        near = near[key[near + offset] - key[near] <= tol]
        if not near.size:
            break
        i = near
        for values in others:  # within tol on every joint, the most spread first (it rules out the most)
            i = i[np.abs(values[i + offset] - values[i]) <= tol]
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


def first_of_rows(cells: np.ndarray) -> np.ndarray:
    """Sorted indices of the first of every distinct row of ``cells`` (K, n) (rows equal as floats: 0.0 is -0.0):
    ``np.unique(cells, axis=0, return_index=True)[1]``, sorted, in one sort of a 64-bit hash of each row instead
    of a sort of the rows (a tenth of the time on a million rows); rows of equal hash that differ, or values that
    are not finite, take ``np.unique``."""
    if not np.isfinite(cells).all():
        return np.sort(np.unique(cells, axis=0, return_index=True)[1])
    bits = np.ascontiguousarray(cells + 0.0).view(np.uint64)  # + 0.0: -0.0 is 0.0, as float comparison has it
    hashes = np.zeros(len(cells), dtype=np.uint64)
    for j in range(cells.shape[1]):  # splitmix64's mixing of each value's bits (a grid cell's have few set)
        x = bits[:, j] ^ (bits[:, j] >> np.uint64(30))
        x *= np.uint64(0xBF58476D1CE4E5B9)  # wraps around, as a hash does
        x ^= x >> np.uint64(27)
        x *= np.uint64(0x94D049BB133111EB)
        x ^= x >> np.uint64(31)
        hashes *= np.uint64(0x9E3779B97F4A7C15)
        hashes ^= x
    order = np.argsort(hashes, kind="stable")  # stable: the first of equal rows comes first
    ordered = cells[order]
    same_hash = hashes[order][1:] == hashes[order][:-1]
    differ = (ordered[1:] != ordered[:-1]).any(axis=1)
    if np.any(same_hash & differ):  # two distinct rows of one hash (never seen): sort the rows themselves
        return np.sort(np.unique(cells, axis=0, return_index=True)[1])
    return np.sort(order[np.concatenate([[True], differ])])
