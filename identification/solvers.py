"""Solvers of a :class:`CalibrationProblem`: least squares (``lm``) and particle swarm (``pso``).

``lm`` is our own column-scaled trust-region Levenberg-Marquardt (:mod:`.levenberg`) on the
analytic Jacobian: it reaches :func:`scipy.optimize.least_squares`' minimum (cost to 1e-9
relative, unknowns within std / 100) in 4-5 Jacobian evaluations where scipy's MINPACK takes 6-9,
without importing scipy.optimize. The robust losses ``soft_l1`` / ``huber`` (scale ``f``: the expected
noise) apply to the samples' rows (not to the known distances, the prior or the scale anchor: a stated
accuracy is no outlier): scipy's robust cost ``f^2 / 2 sum rho(r_i^2 / f^2)`` written as plain least squares
on the residuals ``f sign(r) sqrt(rho(r^2 / f^2))`` (:func:`robust_residuals`), which ours solves. scipy's
MINPACK (``least_squares``, imported only then) continues on the same residuals from where ours stops when
ours used up its budget (:data:`MAX_OURS`).

``pso`` is the paper's method: pyswarms' ``GlobalBestPSO`` over bounded deviations of the
identified parameters from the start, minimising eq. 5, the mean distance between each sample's
tool point and its fixture centre (free centres are the per-fixture mean tool point; known
distances add a penalty). pyswarms is imported only here, with its logging kept off the root
logger and no ``report.log`` written.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import time
from dataclasses import dataclass, replace

import numpy as np

from spherecal.correction import tool_point

from .levenberg import levenberg_marquardt
from .problem import CalibrationProblem, prior_std

LOSSES: tuple[str, ...] = ("linear", "soft_l1", "huber")
#: Jacobian evaluations of ours before scipy's MINPACK continues from where it is (a well-posed
#: calibration needs 4-6; a flat valley, e.g. Hayati betas beside non-parallel axes, can take ~100).
MAX_OURS = 20


@dataclass(frozen=True)
class Solution:
    """Where a solver ended.

    Attributes:
        x: (F,) unknowns at the end.
        evaluations: residual (or swarm objective) evaluations.
        seconds: wall time [s].
        message: the solver's own words.
        jacobians: Jacobian evaluations (0 for PSO).
        converged: a stopping test was met (not the evaluation budget).
    """

    x: np.ndarray
    evaluations: int
    seconds: float
    message: str
    jacobians: int = 0
    converged: bool = True


def solve_lm(
    problem: CalibrationProblem,
    x0: np.ndarray | None = None,
    loss: str = "linear",
    f_scale: float | None = None,
    tol: float = 1e-12,
    max_nfev: int | None = None,
) -> Solution:
    """Least squares with the analytic Jacobian.

    Args:
        problem: the problem.
        x0: (F,) start (default ``problem.x0``).
        loss: ``linear``, ``soft_l1`` or ``huber``.
        f_scale: residual scale of the robust loss [m] (default ``problem.noise``).
        tol: ``ftol``, ``xtol`` and ``gtol``.
        max_nfev: Jacobian evaluation budget of ours, residual budget of scipy's (default :data:`MAX_OURS` /
            scipy's default).
    """
    if loss not in LOSSES:
        raise ValueError(f"unknown loss {loss!r}, expected one of {LOSSES}")
    x0 = problem.x0 if x0 is None else np.asarray(x0, float)
    start = time.perf_counter()
    residuals, jacobian = _objective(problem, loss, f_scale)
    ours = levenberg_marquardt(residuals, jacobian, x0, tol, tol, tol, max_nfev or MAX_OURS)
    if ours.converged:
        return Solution(ours.x, ours.evaluations, time.perf_counter() - start, ours.message, ours.jacobians)
    rescue = solve_scipy(problem, ours.x, loss, f_scale, tol, max_nfev, start)
    return replace(
        rescue,
        evaluations=rescue.evaluations + ours.evaluations,
        jacobians=rescue.jacobians + ours.jacobians,
        message=f"{ours.message}; scipy continued: {rescue.message}",
    )


def _objective(problem: CalibrationProblem, loss: str, f_scale: float | None):
    """The residual and Jacobian functions of ``problem`` under ``loss``: the sample rows through
    :func:`robust_residuals` (scale ``f_scale``, default the problem's noise); the known distances, the prior and
    the scale anchor stay plain (a stated accuracy and a prior are not outliers)."""
    if loss == "linear":
        return problem.residuals, problem.jacobian
    scale, rows, last = f_scale or problem.noise, 3 * problem.dataset.n_samples, {}

    def robust(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # the Jacobian comes at the last residual's x
        key = x.tobytes()
        if key not in last:
            r = problem.residuals(x).copy()
            slope = np.ones_like(r)
            r[:rows], slope[:rows] = robust_residuals(r[:rows], loss, scale)
            last.clear()
            last[key] = r, slope
        return last[key]

    def residuals(x: np.ndarray) -> np.ndarray:
        return robust(x)[0]

    def jacobian(x: np.ndarray) -> np.ndarray:
        return robust(x)[1][:, None] * problem.jacobian(x)

    return residuals, jacobian


def robust_residuals(r: np.ndarray, loss: str, f_scale: float) -> tuple[np.ndarray, np.ndarray]:
    """Residuals whose plain sum of squares is scipy's robust cost, and their slope.

    ``t = f sign(r) sqrt(rho(z))``, ``z = r^2 / f^2``, so ``sum t^2 = f^2 sum rho(z)`` (twice
    :func:`scipy.optimize.least_squares`' cost with ``loss``, ``f_scale = f``); ``dt/dr = rho'(z) |r| / (f
    sqrt(rho(z)))``, 1 at ``r = 0`` (``rho(z) ~ z`` there).

    Args:
        r: (M,) residuals.
        loss: ``soft_l1`` (``rho = 2 (sqrt(1 + z) - 1)``) or ``huber`` (``z`` up to 1, ``2 sqrt(z) - 1`` beyond).
        f_scale: ``f``, in the residuals' unit.

    Returns:
        (M,) ``t`` and (M,) ``dt/dr``.
    """
    z = (r / f_scale) ** 2
    if loss == "soft_l1":
        rho, slope = 2.0 * (np.sqrt(1.0 + z) - 1.0), 1.0 / np.sqrt(1.0 + z)
    elif loss == "huber":
        root = np.sqrt(np.maximum(z, 1.0))
        rho, slope = np.where(z <= 1.0, z, 2.0 * root - 1.0), np.where(z <= 1.0, 1.0, 1.0 / root)
    else:
        raise ValueError(f"unknown robust loss {loss!r}")
    size = np.sqrt(rho)
    tiny = size <= 1e-8  # rho ~ z: t ~ r, slope 1
    gain = np.where(tiny, 1.0, slope * np.abs(r) / (f_scale * np.where(tiny, 1.0, size)))
    return f_scale * np.sign(r) * size, gain


def solve_scipy(
    problem: CalibrationProblem,
    x0: np.ndarray,
    loss: str = "linear",
    f_scale: float | None = None,
    tol: float = 1e-12,
    max_nfev: int | None = None,
    start: float | None = None,
) -> Solution:
    """:func:`scipy.optimize.least_squares` from ``x0`` (MINPACK's LM, ``x_scale='jac'``, on the residuals of
    ``loss``: :func:`_objective`): the rescue of ours, and the reference ours is measured against.

    Args:
        problem, x0, loss, f_scale, tol, max_nfev: as :func:`solve_lm` (``max_nfev``: residual budget).
        start: ``time.perf_counter()`` the wall time counts from (default: now).
    """
    start = time.perf_counter() if start is None else start
    from scipy.optimize import least_squares  # scipy.optimize: heavy, only for the rescue and the reference

    residuals, jacobian = _objective(problem, loss, f_scale)
    result = least_squares(
        residuals,
        x0,
        jac=jacobian,
        method="lm",
        x_scale="jac",
        ftol=tol,
        xtol=tol,
        gtol=tol,
        max_nfev=max_nfev,
    )
    return Solution(
        result.x, int(result.nfev), time.perf_counter() - start, str(result.message), int(result.njev or 0),
        bool(result.status > 0),
    )


@contextlib.contextmanager
def _quiet_pyswarms():
    """Import/construct pyswarms without it configuring the root logger or writing report.log.

    pyswarms' Reporter loads the logging config named by ``LOG_CFG`` when that file exists; an
    incremental, empty config changes nothing (a non-incremental one would close every handler).
    """
    fd, path = tempfile.mkstemp(suffix=".yaml", prefix="spherecal-pyswarms-")
    with os.fdopen(fd, "w") as handle:
        handle.write("version: 1\nincremental: true\n")
    old = os.environ.get("LOG_CFG")
    os.environ["LOG_CFG"] = path
    try:
        yield
    finally:
        if old is None:
            os.environ.pop("LOG_CFG", None)
        else:
            os.environ["LOG_CFG"] = old
        os.unlink(path)


def solve_pso(
    problem: CalibrationProblem,
    seed: int = 0,
    x0: np.ndarray | None = None,
    particles: int = 60,
    iterations: int = 300,
    bound: float = 20.0,
    samples_per_fixture: int | None = 150,
    options: dict | None = None,
) -> Solution:
    """Particle swarm over the identified parameters (the paper's eq. 5).

    Args:
        problem: the problem.
        seed: seeds pyswarms (which draws from numpy's global generator: seeded here, restored after).
        x0: (F,) centre of the search box (default ``problem.x0``); its centres are ignored.
        particles: swarm size.
        iterations: swarm iterations.
        bound: half-width of the search box in prior spreads (1 mm, 0.2 deg per unit).
        samples_per_fixture: samples per fixture the objective uses (a seeded subset; None: all).
        options: pyswarms ``c1, c2, w`` (default 0.5, 0.3, 0.9).

    Returns:
        The best parameters found, with each free centre at the mean tool point of its samples.
    """
    x0 = problem.x0 if x0 is None else np.asarray(x0, float)
    start = time.perf_counter()
    params0, centres0 = problem.unpack(x0)
    rng = np.random.default_rng(seed)
    dataset = problem.dataset
    subset = dataset.subsampled(samples_per_fixture, rng) if samples_per_fixture else dataset
    fixture = np.array([dataset.fixture_names.index(name) for name in subset.labels])
    free_slots = [dataset.fixture_names.index(name) for name in problem.free_centres]
    half = bound * prior_std(problem.model)[problem.free]
    distances = [
        (dataset.fixture_names.index(a), dataset.fixture_names.index(b), target)
        for a, b, target in problem.spec.distances
    ]
    counts = np.bincount(fixture, minlength=len(dataset.fixture_names))

    def centres_of(points: np.ndarray) -> np.ndarray:
        centres = centres0.copy()
        if free_slots:
            sums = np.zeros_like(centres)
            np.add.at(sums, fixture, points)
            centres[free_slots] = sums[free_slots] / counts[free_slots, None]
        return centres

    def cost(deviation: np.ndarray) -> float:
        params = params0.copy()
        params[problem.free] += deviation
        points = tool_point(problem.model.with_params(params), subset.q)
        centres = centres_of(points)
        value = np.mean(np.linalg.norm(points - centres[fixture], axis=1))
        for a, b, target in distances:
            value += abs(np.linalg.norm(centres[a] - centres[b]) - target)
        return float(value)

    evaluations = 0

    def swarm_cost(swarm: np.ndarray) -> np.ndarray:
        nonlocal evaluations
        evaluations += swarm.shape[0]
        return np.array([cost(row) for row in swarm])

    with _quiet_pyswarms():
        import pyswarms  # pyswarms: heavy and optional, only for method 'pso'

        state = np.random.get_state()  # noqa: NPY002 (pyswarms draws from the global state)
        np.random.seed(seed)  # noqa: NPY002
        try:
            init = rng.uniform(-half, half, (particles, half.size))
            init[0] = 0.0  # the start itself is a particle
            optimiser = pyswarms.single.GlobalBestPSO(
                n_particles=particles,
                dimensions=half.size,
                options=options or {"c1": 0.5, "c2": 0.3, "w": 0.9},
                bounds=(-half, half),
                init_pos=init,
            )
            _, best = optimiser.optimize(swarm_cost, iters=iterations, verbose=False)
        finally:
            np.random.set_state(state)  # noqa: NPY002
    params = params0.copy()
    params[problem.free] += best
    points = tool_point(problem.model.with_params(params), dataset.q)
    full = dataset.fixture_index
    centres = centres0.copy()
    for j in free_slots:
        centres[j] = points[full == j].mean(axis=0)
    message = f"{iterations} iterations of {particles} particles"
    return Solution(problem.pack(params, centres), evaluations, time.perf_counter() - start, message)
