"""Build the calibration problem of a data set: input checks, unknowns, gauge, scale, rank.

:func:`build_problem` checks the samples against the fixtures file and the arm's reach, decides
which parameters and centres are unknowns (see :mod:`.problem` for the rules) and returns a
:class:`~.problem.CalibrationProblem` to solve.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from spherecal.correction import RobotModel, tool_point
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.samples import Dataset, DatasetError, configurations_digest

from .gauge import anchor_spread, gauge_left, scale_centre
from .identifiability import greedy_rank
from .problem import (
    CONSISTENCY_TOL,
    DISTANCE_STD,
    GAUGE,
    MIN_SEPARATION,
    NOISE,
    PRIOR_TAIL,
    CalibrationProblem,
    UnidentifiableError,
    mean_points,
    samples_location,
)


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
    """Refuse known positions and distances the arm cannot span (e.g. millimetres typed for metres), and known
    distances below :data:`.problem.MIN_SEPARATION` (MUKCa's plate imported with ``--distance 0.0005``: the fit
    pulled the sockets together for over 90 s before the self-check refused it).

    Reach bound: ``sum |a| + sum |d| + |tool|`` from the base origin.
    """
    reach = model.reach
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
                f"{where}: {spec.distance_field(k)}: {a}-{b} {value:.6g} m is more "
                f"than the arm can span ({2 * reach:.3g} m); distances are in metres"
            )
        if value < MIN_SEPARATION:  # the self-check's refusal, before a fit that pulls two sockets together
            raise DatasetError(
                f"{where}: {spec.distance_field(k)}: distance {a}-{b} is {value * 1e3:.4g} mm: fixtures closer than "
                f"{MIN_SEPARATION * 1e3:.0f} mm check nothing (the same socket under two names, or a typo)"
            )


def _drop_known_distances(spec: FixtureSpec, known: dict[str, np.ndarray]) -> FixtureSpec:
    """``spec`` without distances between two known positions (they add nothing but a constant residual).

    Raises:
        DatasetError: such a distance disagrees with its positions by more than :data:`CONSISTENCY_TOL`.
    """
    keep = []
    for k, (a, b, value) in enumerate(spec.distances):
        if a not in known or b not in known:
            keep.append(k)
            continue
        apart = float(np.linalg.norm(known[a] - known[b]))
        if abs(apart - value) > CONSISTENCY_TOL:
            raise DatasetError(
                f"{spec.source or 'fixtures'}: {spec.distance_field(k)}: "
                f"distance {a}-{b} is {value:.6g} m but their known positions are {apart:.6g} m apart"
            )
    return spec if len(keep) == len(spec.distances) else spec.keep_distances(keep)


#: Largest dense Jacobian a calibration builds [bytes]: 3 rows per sample (and a prior row per parameter) by the
#: parameters and 3 unknowns per fixture centre. 10 000 fixtures of 2 samples make 14 GB (the process was killed
#: after a minute); a 2 x 10^5-sample file of two sockets 0.23 GB (calibrated in 31 s at 1.1 GB resident: the fit
#: holds about 5 such arrays), a simulated campaign set under 0.01 GB.
MAX_JACOBIAN_BYTES = 500_000_000


def _check_size(dataset: Dataset, n_params: int) -> None:
    """Refuse a problem whose dense Jacobian exceeds :data:`MAX_JACOBIAN_BYTES` (before anything is built).

    Raises:
        DatasetError: one line naming the samples file, the fixture and sample counts and what to do.
    """
    fixtures = len(dataset.fixture_names)
    rows, unknowns = 3 * dataset.n_samples + n_params, n_params + 3 * fixtures
    size = 8.0 * rows * unknowns
    if size > MAX_JACOBIAN_BYTES:
        raise DatasetError(
            f"{samples_location(dataset)}, field 'fixture': {fixtures} fixtures and {dataset.n_samples} samples make "
            f"{unknowns} unknowns and {rows} equations, a {size / 1e9:.3g} GB Jacobian (at most "
            f"{MAX_JACOBIAN_BYTES / 1e9:g} GB): does the fixture column name each sample? Else fewer samples "
            "(--max-per-fixture) or fewer fixtures"
        )


def _check_copies(dataset: Dataset) -> None:
    """Refuse two fixtures holding the same configurations: one recording copied for two sockets (their centres
    coincide, and a known distance between them makes the fit's distance direction 0/0).

    Raises:
        DatasetError: one line naming the second fixture's rows and the first fixture.
    """
    index = dataset.fixture_index
    seen: dict[str, str] = {}
    for j, name in enumerate(dataset.fixture_names):
        rows = np.flatnonzero(index == j)
        digest = configurations_digest(dataset.q[rows])
        if digest in seen:
            raise DatasetError(
                f"{samples_location(dataset.select(rows))}, field 'fixture': fixture {name} holds the same "
                f"{len(rows)} configurations as fixture {seen[digest]} (one recording copied for two sockets?)"
            )
        seen[digest] = name


def build_problem(
    model: RobotModel,
    dataset: Dataset,
    spec: FixtureSpec | None = None,
    nominal: RobotModel | None = None,
    noise: float = NOISE,
    distance_std: float = DISTANCE_STD,
    rank_tol: float = 1e-7,
    pin: str = "radius",
    prior_weight: float = 0.0,
    prior_tail: float | None = None,
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
        prior_weight: ``W`` of the prior rows toward ``model`` (:mod:`.problem`; 0: plain least squares).
            The rank test judges the data alone: a parameter the samples cannot see is fixed, not left to
            the prior.
        prior_tail: where the prior's heavy tail starts [prior spreads] (default :data:`.problem.PRIOR_TAIL`;
            inf: a Gaussian prior).

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
    _check_size(dataset, len(names))
    _check_copies(dataset)
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
    for name in model.layout.held(model.convention):
        fixed[name] = "Hayati: held at zero beside a beta (nearly parallel axes)"
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
        for name in gauge_left(model, dataset, list(known.values())):
            fixed[name] = (
                f"gauge: with {len(known)} known fixture position(s) a rigid motion about them is still "
                f"indistinguishable"
            )
    spec = _drop_known_distances(spec, known)
    centres = mean_points(model, dataset)
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
    # compliances from the most loaded joint (the first) on, then the scales: geometry keeps what both could explain
    n = model.n_joints
    rank_of = {name: k for k, name in enumerate(("tool_x", "tool_y", "tool_z"))}
    for i in range(n, 0, -1):
        for f in ("a", "alpha", "beta", "d", "theta"):
            rank_of[f"{f}{i}"] = len(rank_of)
    for name in model.layout.names[model.layout.compliance] + model.layout.names[model.layout.scale]:
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
    if not np.isfinite(prior_weight) or prior_weight < 0:
        raise ValueError(f"prior_weight must be a finite number >= 0, got {prior_weight!r}")
    tail = PRIOR_TAIL if prior_tail is None else float(prior_tail)
    if not tail > 0:
        raise ValueError(f"prior_tail must be > 0 (inf: Gaussian), got {prior_tail!r}")
    return replace(problem, free=candidates[keep], fixed=ordered_fixed, prior_weight=float(prior_weight),
                   prior_centre=model.params if prior_weight > 0 else None, prior_tail=tail)


