"""The calibration problem as an inspectable object: unknowns, residuals, Jacobian, gauge.

Residuals (metres)::

    r_k = p(q_k; params) - c_j          every sample k recorded at fixture j  (3 each)
    r_d = w (|c_a - c_b| - D_ab)         every known distance                  (1 each)

Unknowns are the free DH/tool parameters and the centres of the fixtures whose position is not
known. ``w = noise / distance_std`` makes a known distance as stiff as its stated accuracy.

What the data cannot see is fixed at the start model's value, with the reason:

* the base placement (``base_*``), always;
* the gauge: the joint-1 parameters move the whole point set rigidly (modified DH: ``a1, alpha1,
  d1, theta1``; standard: ``d1, theta1``) and trade off against unknown centres: all are fixed
  when no centre is known; with known centres only as many as rigid motions keeping them in
  place remain (none for two or more known centres, generically);
* the scale: with unknown centres, no known distance and fewer than two known positions, a uniform
  scale of all lengths is unobservable (and noise pulls it smaller), so one fixture's distance from
  the joint-1 axis point is held at the nominal model's (``pin="radius"``, the default; ``"centre"``
  pins that centre at the mean of the nominal model's tool points) and a warning says so, with the
  scale error to expect (not part of the reported std);
* columns that add no rank to the column-scaled Jacobian, tested in a preference order
  (centres, tool point, joints from the last to the first), e.g. ``d7, theta7`` against the tool;
* (after a solve, :func:`prune`) parameters the data barely excites: predicted std at the residual
  noise above the prior spread.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from spherecal.correction import RobotModel, link_frames, param_jacobian, tool_point
from spherecal.correction.errors import SpherecalError
from spherecal.correction.fixtures import FixtureSpec
from spherecal.correction.samples import Dataset, DatasetError

from .identifiability import Identifiability, greedy_rank, predicted_std

#: Joint-1 parameters that move every tool point rigidly (the gauge against unknown centres).
GAUGE: dict[str, tuple[str, ...]] = {"modified": ("a1", "alpha1", "d1", "theta1"), "standard": ("d1", "theta1")}
#: Default expected fixture noise [m] (the paper's motion-capture accuracy).
NOISE = 3e-4
#: Default accuracy of a known distance [m].
DISTANCE_STD = 1e-6
#: Largest disagreement [m] between a known distance and the distance of two known positions.
CONSISTENCY_TOL = 1e-3


class UnidentifiableError(SpherecalError):
    """The data cannot determine any parameter (or the problem is otherwise rank deficient)."""


class ImplausibleCalibrationError(SpherecalError):
    """The fit moved a parameter further from nominal than any real arm differs from its design."""


def prior_std(model: RobotModel) -> np.ndarray:
    """(P,) prior spread of every parameter: 1 mm on lengths and tool, 0.2 deg on angles."""
    return model.layout.spread()


@dataclass(frozen=True, eq=False)
class CalibrationProblem:
    """Unknowns, residuals and Jacobian of one calibration; build with :func:`build_problem`.

    Attributes:
        model: start model; fixed parameters keep its values.
        dataset: the samples.
        spec: what is known about the fixtures.
        free: (Fp,) indices of the identified parameters in ``model.params``.
        fixed: name -> reason, for every parameter that is not identified.
        centres: (J, 3) start centres [m], in ``dataset.fixture_names`` order (known and pinned
            ones stay at these values).
        free_centres: fixtures whose centre is an unknown.
        pinned: the fixture that fixes the scale from the nominal model (see ``anchor``), or ().
        distance_weight: weight ``w`` of the distance residuals.
        noise: expected fixture noise [m].
        warnings: what the user must know about this problem.
        identifiability: singular values and condition number of the column-scaled Jacobian.
        anchor: ``(fixture, point, radius)``: the scale gauge ``|c_fixture - point| = radius`` [m]
            (one more residual, weighted like a distance), or None.
    """

    model: RobotModel
    dataset: Dataset
    spec: FixtureSpec
    free: np.ndarray
    fixed: dict[str, str]
    centres: np.ndarray
    free_centres: tuple[str, ...]
    pinned: tuple[str, ...]
    distance_weight: float
    noise: float
    warnings: tuple[str, ...] = ()
    identifiability: Identifiability | None = None
    anchor: tuple[str, np.ndarray, float] | None = None
    _cache: dict = field(default_factory=dict, repr=False)

    # ------------------------------------------------------------------------------ sizes
    @property
    def n_free_params(self) -> int:
        return int(self.free.size)

    @property
    def n_unknowns(self) -> int:
        return self.n_free_params + 3 * len(self.free_centres)

    @property
    def n_residuals(self) -> int:
        return 3 * self.dataset.n_samples + len(self.spec.distances) + (self.anchor is not None)

    @property
    def identified(self) -> tuple[str, ...]:
        """Names of the identified parameters."""
        names = self.model.param_names
        return tuple(names[i] for i in self.free)

    @property
    def unknown_names(self) -> tuple[str, ...]:
        """Names of the unknowns: identified parameters, then ``P1.x, P1.y, P1.z, ...``."""
        centres = tuple(f"{name}.{axis}" for name in self.free_centres for axis in "xyz")
        return self.identified + centres

    # ---------------------------------------------------------------------- vector views
    def _layout(self) -> tuple[np.ndarray, np.ndarray]:
        """(J,) unknown slot of every fixture centre (-1 if fixed) and (K,) fixture index."""
        if "layout" not in self._cache:
            names = self.dataset.fixture_names
            slot = np.full(len(names), -1)
            for k, name in enumerate(self.free_centres):
                slot[names.index(name)] = k
            self._cache["layout"] = (slot, self.dataset.fixture_index)
        return self._cache["layout"]

    @property
    def x0(self) -> np.ndarray:
        """(F,) start vector of the unknowns."""
        return self.pack(self.model.params, self.centres)

    def pack(self, params: np.ndarray, centres: np.ndarray) -> np.ndarray:
        """(F,) unknowns from full (P,) parameters and (J, 3) centres."""
        slot, _ = self._layout()
        return np.concatenate([np.asarray(params)[self.free], np.asarray(centres)[slot >= 0].ravel()])

    def unpack(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Full (P,) parameters and (J, 3) centres [m] of an unknown vector (F,)."""
        params = self.model.params.copy()
        params[self.free] = x[: self.n_free_params]
        centres = self.centres.copy()
        slot, _ = self._layout()
        centres[slot >= 0] = x[self.n_free_params :].reshape(-1, 3)
        return params, centres

    def start_from(self, model: RobotModel) -> np.ndarray:
        """(F,) unknowns starting at ``model``'s parameters, free centres at its mean tool points."""
        centres = self.centres.copy()
        slot, _ = self._layout()
        centres[slot >= 0] = _mean_points(model, self.dataset)[slot >= 0]
        return self.pack(model.params, centres)

    def generic_point(self) -> tuple[CalibrationProblem, np.ndarray]:
        """This problem re-based on a generic model near the start (seeded 0.1 x prior perturbation),
        and its unknown vector there.

        What the data can see is judged there, not at the nominal design (whose accidental symmetries,
        tool on the last axis and zero offsets, are not structural) nor at a solution (which a poorly
        excited data set lets wander far from any real arm).
        """
        model = self.model
        generic = model.params + np.random.default_rng(0).normal(0.0, 0.1, model.n_params) * prior_std(model)
        moved = replace(self, model=model.with_params(generic), _cache={})
        return moved, moved.pack(generic, self.centres)

    def generic_jacobian(self) -> np.ndarray:
        """(M, F) Jacobian at :meth:`generic_point`."""
        moved, x = self.generic_point()
        return moved.jacobian(x)

    def model_at(self, x: np.ndarray) -> RobotModel:
        """The robot of an unknown vector."""
        return self.model.with_params(self.unpack(x)[0])

    # ------------------------------------------------------------------ residuals, Jacobian
    def sample_errors(self, x: np.ndarray) -> np.ndarray:
        """(K, 3) ``p(q_k) - c_j`` [m]."""
        params, centres = self.unpack(x)
        _, fixture = self._layout()
        return tool_point(self.model.with_params(params), self.dataset.q) - centres[fixture]

    def _distances(self, centres: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        names = self.dataset.fixture_names
        a = np.array([names.index(d[0]) for d in self.spec.distances], dtype=int)
        b = np.array([names.index(d[1]) for d in self.spec.distances], dtype=int)
        target = np.array([d[2] for d in self.spec.distances], dtype=float)
        delta = centres[a] - centres[b]
        return a, b, target, delta

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """(M,) residual vector [m]: samples (3 K, x y z per sample), then distances."""
        sample = self.sample_errors(x).ravel()
        if not self.spec.distances and self.anchor is None:
            return sample
        _, centres = self.unpack(x)
        _, _, target, delta = self._distances(centres)
        parts = [sample, self.distance_weight * (np.linalg.norm(delta, axis=1) - target)]
        if self.anchor is not None:
            name, point, radius = self.anchor
            gap = np.linalg.norm(centres[self.dataset.fixture_names.index(name)] - point) - radius
            parts.append([self.distance_weight * gap])
        return np.concatenate(parts)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """(M, F) analytic Jacobian of :meth:`residuals` (``correction.param_jacobian`` columns)."""
        params, centres = self.unpack(x)
        count, fp = self.dataset.n_samples, self.n_free_params
        jac = np.zeros((self.n_residuals, self.n_unknowns))
        pj = param_jacobian(self.model.with_params(params), self.dataset.q)
        jac[: 3 * count, :fp] = pj[:, :, self.free].reshape(3 * count, fp)
        slot, fixture = self._layout()
        rows = np.flatnonzero(slot[fixture] >= 0)
        for axis in range(3):
            jac[3 * rows + axis, fp + 3 * slot[fixture[rows]] + axis] = -1.0
        if self.spec.distances:
            a, b, _, delta = self._distances(centres)
            unit = delta / np.linalg.norm(delta, axis=1, keepdims=True)
            for row, (ia, ib, u) in enumerate(zip(a, b, unit, strict=True)):
                for index, sign in ((ia, 1.0), (ib, -1.0)):
                    if slot[index] >= 0:
                        cols = slice(fp + 3 * slot[index], fp + 3 * slot[index] + 3)
                        jac[3 * count + row, cols] = sign * self.distance_weight * u
        if self.anchor is not None:
            name, point, _ = self.anchor
            j = self.dataset.fixture_names.index(name)
            if slot[j] >= 0:
                delta = centres[j] - point
                jac[-1, fp + 3 * slot[j] : fp + 3 * slot[j] + 3] = self.distance_weight * delta / np.linalg.norm(delta)
        return jac

    def centre_dict(self, centres: np.ndarray) -> dict[str, np.ndarray]:
        """Fixture name -> (3,) centre [m]."""
        return {name: centres[j] for j, name in enumerate(self.dataset.fixture_names)}


def scale_centre(model: RobotModel) -> np.ndarray:
    """(3,) the point on the joint-1 axis about which a uniform scale of the other lengths acts [m].

    With the joint-1 gauge parameters fixed, scaling every length from joint 2 on scales the tool
    points about this point: the frame-1 origin (modified DH) or the base origin moved ``d1``
    along the joint-1 axis (standard DH).
    """
    base = model.base_transform
    if model.convention == "modified":
        return link_frames(model, np.zeros(model.n_joints))[1, :3, 3]
    return base[:3, 3] + model.d[0] * base[:3, 2]


def anchor_spread(model: RobotModel, q: np.ndarray, point: np.ndarray) -> float:
    """Prior spread [m] of the distance between the mean tool point of ``q`` and ``point`` on ``model``.

    What a scale taken from the nominal model is off by: the radius's gradient with respect to the
    parameters times their prior spread (:func:`prior_std`; gauge and base parameters left out).

    Args:
        model: the robot.
        q: (K, n) configurations at one fixture [rad].
        point: (3,) the scale centre [m] (:func:`scale_centre`).
    """
    jac, points = param_jacobian(model, q, return_point=True)
    radial = points.mean(axis=0) - point
    grad = (radial / np.linalg.norm(radial)) @ jac.mean(axis=0)  # (P,)
    prior = prior_std(model)
    prior[[model.param_index(name) for name in GAUGE[model.convention]]] = 0.0
    prior[model.layout.base] = 0.0
    return max(float(np.linalg.norm(grad * prior)), 1e-9)


def _gauge_left(model: RobotModel, dataset: Dataset, known: list[np.ndarray]) -> list[str]:
    """Joint-1 parameters to fix so that no rigid motion keeping the ``known`` centres stays free.

    Each joint-1 gauge parameter moves every tool point by a twist ``dp = w x p + v`` (constant:
    it acts before every joint variable). Combinations of them that keep every known centre in
    place (``w x c + v = 0``) are invisible; one parameter per such direction is fixed (pivoted QR,
    preferring ``theta1, d1, alpha1, a1``).
    """
    from scipy.linalg import qr

    gauge = list(GAUGE[model.convention])[::-1]  # theta1, d1, alpha1, a1 (preference to fix)
    q = dataset.q[np.linspace(0, dataset.n_samples - 1, min(dataset.n_samples, 12)).astype(int)]
    jac, points = param_jacobian(model, q, return_point=True)
    # fit (w, v) of every gauge column from dp_k = -p_k x w + v (exact for a rigid motion)
    skew = np.zeros((points.shape[0], 3, 3))
    skew[:, 0, 1], skew[:, 0, 2], skew[:, 1, 2] = points[:, 2], -points[:, 1], points[:, 0]
    skew -= skew.transpose(0, 2, 1)
    design = np.concatenate([skew, np.broadcast_to(np.eye(3), skew.shape)], axis=2).reshape(-1, 6)
    cols = [model.param_index(name) for name in gauge]
    twists = np.linalg.lstsq(design, jac[:, :, cols].reshape(-1, len(cols)), rcond=None)[0]  # (6, g)
    moves = []
    for c in known:  # displacement of each known centre under each gauge twist: w x c + v
        moves.append(np.cross(twists[:3].T, c).T + twists[3:])
    a = np.concatenate(moves)  # (3 * known, g)
    s = np.linalg.svd(a, compute_uv=False)
    rank = int(np.sum(s > 1e-9 * max(1.0, s[0]))) if s.size else 0
    free_dims = len(cols) - rank
    if free_dims <= 0:
        return []
    _, _, vt = np.linalg.svd(a)
    null = vt[rank:]  # (free_dims, g)
    _, _, pivots = qr(null, pivoting=True)
    return sorted((gauge[i] for i in pivots[:free_dims]), key=GAUGE[model.convention].index)


def samples_location(dataset: Dataset) -> str:
    """``"samples.csv: rows 2-1501"``: where a dataset came from, for one-line errors
    (``"samples: all rows"`` when it was not read from a file)."""
    rows = (
        "all rows"
        if dataset.lines is None or dataset.n_samples == 0
        else f"rows {dataset.lines.min()}-{dataset.lines.max()}"
    )
    return f"{dataset.source or 'samples'}: {rows}"


def _mean_points(model: RobotModel, dataset: Dataset) -> np.ndarray:
    """(J, 3) mean tool point of every fixture's samples on ``model`` [m]."""
    points = tool_point(model, dataset.q)
    fixture = dataset.fixture_index
    return np.stack([points[fixture == j].mean(axis=0) for j in range(len(dataset.fixture_names))])


def _check_inputs(dataset: Dataset, spec: FixtureSpec) -> None:
    spec.check_against(dataset)
    listed = set(spec.names)
    for k, label in enumerate(dataset.labels):
        if label not in listed:
            raise DatasetError(
                f"{dataset.source or 'samples'}: {dataset.row_of(k)}, field 'fixture': fixture {str(label)!r} "
                f"is not listed in {spec.source or 'the fixtures'}"
            )


def _check_reach(model: RobotModel, spec: FixtureSpec) -> None:
    """Refuse known positions and distances the arm cannot span (e.g. millimetres typed for metres).

    Reach bound: ``sum |a| + sum |d| + |tool|`` from the base origin.
    """
    reach = float(np.abs(model.a).sum() + np.abs(model.d).sum() + np.linalg.norm(model.tool))
    where = spec.source or "fixtures"
    origin = model.base_transform[:3, 3]
    for name, position in spec.positions.items():
        gap = float(np.linalg.norm(np.asarray(position, float) - origin))
        if gap > reach:
            raise DatasetError(
                f"{where}: {spec._row('fixtures.' + name)}field 'fixtures.{name}.position': {gap:.6g} m from the "
                f"base, beyond the arm's reach ({reach:.3g} m); positions are in metres"
            )
    for k, (a, b, value) in enumerate(spec.distances):
        if value > 2 * reach:
            raise DatasetError(
                f"{where}: {spec._row(f'distances[{k}]')}field 'distances[{k}]': {a}-{b} {value:.6g} m is more "
                f"than the arm can span ({2 * reach:.3g} m); distances are in metres"
            )


def _drop_known_distances(spec: FixtureSpec, known: dict[str, np.ndarray]) -> FixtureSpec:
    """``spec`` without distances between two known positions (they add nothing but a constant residual).

    Raises:
        DatasetError: such a distance disagrees with its positions by more than :data:`CONSISTENCY_TOL`.
    """
    keep = []
    for k, (a, b, value) in enumerate(spec.distances):
        if a not in known or b not in known:
            keep.append((a, b, value))
            continue
        apart = float(np.linalg.norm(known[a] - known[b]))
        if abs(apart - value) > CONSISTENCY_TOL:
            raise DatasetError(
                f"{spec.source or 'fixtures'}: {spec._row(f'distances[{k}]')}field 'distances[{k}]': "
                f"distance {a}-{b} is {value:.6g} m but their known positions are {apart:.6g} m apart"
            )
    return spec if len(keep) == len(spec.distances) else replace(spec, distances=keep)


def build_problem(
    model: RobotModel,
    dataset: Dataset,
    spec: FixtureSpec | None = None,
    nominal: RobotModel | None = None,
    noise: float = NOISE,
    distance_std: float = DISTANCE_STD,
    rank_tol: float = 1e-7,
    pin: str = "radius",
) -> CalibrationProblem:
    """Set up the calibration: choose the unknowns, fix the gauge, test identifiability.

    Args:
        model: start model (usually the nominal one); fixed parameters keep its values.
        dataset: samples, (K, n) joint angles with a fixture label each.
        spec: known positions and distances; every fixture unknown when None.
        nominal: model whose mean tool point pins a centre when scale needs it (default ``model``).
        noise: expected fixture noise [m]: weights the distances, tests excitation.
        distance_std: accuracy of a known distance [m].
        rank_tol: relative tolerance of the rank test on unit-norm columns.
        pin: how scale is fixed when nothing else does: ``"radius"`` keeps the distance of one
            fixture's centre from the joint-1 axis point (frame-1 origin) at its nominal value (one
            equation: the scale gauge only); ``"centre"`` pins that centre at the mean nominal tool
            point (the paper's choice; three equations).

    Raises:
        DatasetError: a fixture used but not listed, a distance or position naming a fixture
            without samples, a position or distance beyond the arm's reach, a distance contradicting two
            known positions, fewer equations than unknowns.
        UnidentifiableError: nothing can be identified.
    """
    spec = FixtureSpec.unknown(dataset.fixture_names) if spec is None else spec
    _check_inputs(dataset, spec)
    _check_reach(model, spec)
    nominal = model if nominal is None else nominal
    if dataset.n_joints != model.n_joints:
        raise DatasetError(
            f"{dataset.source or 'samples'}: row 1, field 'q*': {dataset.n_joints} joints, "
            f"the robot has {model.n_joints}"
        )
    names = model.param_names
    names_fixtures = dataset.fixture_names
    if all(np.ptp(dataset.for_fixture(name), axis=0).max() == 0 for name in names_fixtures):
        raise UnidentifiableError(
            f"{samples_location(dataset)}, field 'q*': at every fixture all samples are "
            f"one configuration; the arm must move through its self-motion for any parameter to be identified"
        )
    fixed: dict[str, str] = {}
    warnings: list[str] = []
    unused = [name for name in spec.names if name not in names_fixtures]
    if unused:
        warnings.append(
            f"{spec.source or 'fixtures'} lists {', '.join(unused)} but {dataset.source or 'the samples'} has no "
            f"samples there; ignored"
        )
    for name in model.layout.names[model.layout.base]:
        fixed[name] = "base placement: not observable from spherical-joint data"
    known = {name: np.asarray(p, float) for name, p in spec.positions.items() if name in names_fixtures}
    if len(known) == 1 and not spec.distances:
        (lone,) = known
        warnings.append(
            f"fixture {lone}: one known position without a known distance fixes neither the scale nor the "
            f"joint-1 gauge; it is treated as unknown"
        )
        known = {}
    if not known:
        for name in GAUGE[model.convention]:
            fixed[name] = "gauge: moves every tool point rigidly, indistinguishable with unknown fixture centres"
    else:
        for name in _gauge_left(model, dataset, list(known.values())):
            fixed[name] = (
                f"gauge: with {len(known)} known fixture position(s) a rigid motion about them is still "
                f"indistinguishable"
            )
    spec = _drop_known_distances(spec, known)
    centres = _mean_points(model, dataset)
    for name, position in known.items():
        centres[names_fixtures.index(name)] = position
    pinned: tuple[str, ...] = ()
    anchor = None
    if not known and not spec.distances:
        counts = dataset.counts()
        pin_name = max(names_fixtures, key=lambda n: counts[n])  # first of the largest
        j = names_fixtures.index(pin_name)
        mean = tool_point(nominal, dataset.for_fixture(pin_name)).mean(axis=0)
        point = scale_centre(nominal)
        radius = float(np.linalg.norm(mean - point))
        spread = anchor_spread(nominal, dataset.for_fixture(pin_name), point)
        pinned = (pin_name,)
        if pin == "centre":
            centres[j] = mean
            how = f"fixture {pin_name}'s centre is pinned at the mean of the nominal model's tool points"
        else:
            anchor = (pin_name, point, radius)
            how = (
                f"fixture {pin_name}'s distance from the joint-1 axis point is held at the nominal model's "
                f"{radius:.4f} m"
            )
        warnings.append(
            f"scale: no known distance and at most one known fixture position, so {how} and absolute scale comes "
            f"from the nominal model; a real arm's errors (1 mm, 0.2 deg) make that distance wrong by about "
            f"{spread * 1e3:.2g} mm, a {spread / radius * 100:.2g} % scale error the reported std do not include"
        )
    free_centres = tuple(n for n in names_fixtures if n not in known and (n not in pinned or anchor is not None))
    candidates = np.array([i for i, n in enumerate(names) if n not in fixed], dtype=int)
    weight = max(noise, 1e-6) / distance_std
    problem = CalibrationProblem(
        model,
        dataset,
        spec,
        candidates,
        dict(fixed),
        centres,
        free_centres,
        pinned,
        weight,
        noise,
        tuple(warnings),
        anchor=anchor,
    )
    if problem.n_residuals < problem.n_unknowns:
        raise DatasetError(
            f"{samples_location(dataset)}, field 'fixture': {dataset.n_samples} samples give "
            f"{problem.n_residuals} equations, fewer than the {problem.n_unknowns} unknowns "
            f"({candidates.size} free parameters, {3 * len(free_centres)} centre coordinates)"
        )
    # rank test at a generic point near the start (seeded 0.1x prior perturbation), so that accidental
    # symmetries of the nominal design (tool on the last axis, zero offsets) do not count as structural
    jac = problem.generic_jacobian()
    fp = candidates.size
    # preference: centres, tool point, then joints from the last to the first, then (an elastic model) the
    # compliances from the most loaded joint (the first) on: geometry keeps what both could explain
    n = model.n_joints
    rank_of = {name: k for k, name in enumerate(("tool_x", "tool_y", "tool_z"))}
    for i in range(n, 0, -1):
        for f in ("a", "alpha", "d", "theta"):
            rank_of[f"{f}{i}"] = len(rank_of)
    for name in model.layout.names[model.layout.compliance]:
        rank_of[name] = len(rank_of)
    order = np.concatenate([np.arange(fp, jac.shape[1]), np.argsort([rank_of[names[i]] for i in candidates])])
    accepted, rejected = greedy_rank(jac, order, rank_tol)
    centre_cols = np.arange(fp, jac.shape[1])
    if np.any(~np.isin(centre_cols, accepted)):
        raise UnidentifiableError(
            f"{samples_location(dataset)}, field 'fixture': "
            f"the fixture centres are not determined by the samples"
        )
    for col, coef in rejected.items():
        weights = np.abs(coef) * np.linalg.norm(jac, axis=0)
        top = [problem.unknown_names[c] for c in np.argsort(-weights)[:3] if weights[c] > 1e-3 * weights.max()]
        fixed[names[candidates[col]]] = (
            f"redundant with {', '.join(top)}" if top else "no effect on the tool point for this data"
        )
    keep = accepted[accepted < fp]
    if keep.size == 0:
        raise UnidentifiableError(
            f"{samples_location(dataset)}, field 'q*': no parameter can be identified "
            f"from these samples (joint motion too small or too few distinct configurations)"
        )
    ordered_fixed = {name: fixed[name] for name in names if name in fixed}
    problem = replace(problem, free=candidates[keep], fixed=ordered_fixed)
    return replace(problem, identifiability=Identifiability.of(problem.jacobian(problem.x0)))


def prune(
    problem: CalibrationProblem, x: np.ndarray, sigma: float, jac: np.ndarray | None = None
) -> tuple[CalibrationProblem, np.ndarray]:
    """Fix, one at a time, the parameters whose predicted std exceeds their prior spread.

    Args:
        problem: a solved problem.
        x: (F,) its solution.
        sigma: residual noise [m] (estimated from the fit).
        jac: (M, F) Jacobian that judges the excitation (default: at ``x``;
            :meth:`CalibrationProblem.generic_jacobian` does not depend on how far a fit wandered).

    Returns:
        The problem without the barely excited parameters (they go back to the start model's value)
        and the matching unknown vector; the inputs when nothing is pruned.
    """
    prior = prior_std(problem.model)
    names = problem.model.param_names
    params, centres = problem.unpack(x)
    jac = problem.jacobian(x) if jac is None else jac
    fp = problem.n_free_params
    keep = np.arange(fp)
    fixed = dict(problem.fixed)
    while keep.size > 1:
        cols = np.concatenate([keep, np.arange(fp, jac.shape[1])])
        std = predicted_std(jac[:, cols], sigma)[: keep.size]
        ratio = std / prior[problem.free[keep]]
        worst = int(np.argmax(ratio))
        if ratio[worst] <= 1.0:
            break
        name = names[problem.free[keep[worst]]]
        fmt = problem.model.layout.format
        fixed[name] = (
            f"barely excited: predicted std {fmt(name, std[worst])} at {sigma * 1e3:.3g} mm residual noise "
            f"exceeds the prior spread {fmt(name, prior[problem.free[keep[worst]]])}"
        )
        keep = np.delete(keep, worst)
    if keep.size == fp:
        return problem, x
    dropped = np.setdiff1d(problem.free, problem.free[keep])
    params[dropped] = problem.model.params[dropped]
    fixed = {name: fixed[name] for name in names if name in fixed}
    pruned = replace(problem, free=problem.free[keep], fixed=fixed)
    x_new = pruned.pack(params, centres)
    return replace(pruned, identifiability=Identifiability.of(pruned.jacobian(x_new))), x_new
