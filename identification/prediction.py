"""Predicted accuracy of a calibration from its data, before (or without) solving it.

The calibration problem of the data (:func:`identification.build.build_problem`: same unknowns,
gauge, scale fixing and excitation pruning as :func:`identification.calibrate.calibrate`) is
linearised at a generic point near the model (the rank test's point, so that accidental symmetries
of the nominal design do not count). With fixture noise ``sigma`` per coordinate::

    cov(x) = sigma^2 (J^T J)^-1                     x: identified parameters and centres

(sample rows scaled by ``sqrt(sample_weight)`` when one planning sample stands for several recorded
ones). Two biases are added, each drawn from its prior spread: parameters pruned as barely excited
stay at the nominal value and contribute ``(G_Q - G_F J_F^+ J_Q) dp_Q`` (what the fit cannot absorb
of their error); without a known distance or position the scale anchor's radius is the nominal
model's, off by its prior spread, and shifts the solution by ``J^+ (w dr e_anchor)``. Everything is
propagated to the tool point over random workspace configurations ``G = d p / d params`` (N, 3, P)
after removing the six rigid motions of the point set (the validation registers every model by a
best rigid fit), then sampled::

    e = Proj G_F (L z + shift),     L L^T = cov,  z ~ N(0, I)

Returns the expected mean and 95th percentile of ``|e|`` [m] and the identifiability summary.

At sockets a calibration did not see (:class:`HeldOut`, recorded by the self-check, read by ``validate``), the
spread of the recorded configurations (:func:`socket_spreads`): the parameter error above (its samples' part at the
socket's own noise, ``deviation_root(data_noise=...)``) through the parameter Jacobian there, the socket's own noise,
and the arm's unmodelled joint-angle error (:mod:`.joint_error`): the residual's smooth part over joint space
(:func:`.joint_error.split`, maximum likelihood) and any beyond the declared noise are that error's share the fit
could not absorb (:func:`joint_error_root` gives its std and the bias it bends the parameters by), and each
held-out socket gets a fresh draw of it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from spherecal.correction import RobotModel, joint_jacobian, param_jacobian, tool_point
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.samples import Dataset
from spherecal.correction.layout import ParameterLayout

from .build import build_problem
from .gauge import anchor_spread
from .identifiability import Identifiability, normal_inverse, symmetric_root
from .joint_error import LENGTH, draw, field_root, seen_fields, tool_fields
from .problem import NOISE, SIGMA_FLOOR, CalibrationProblem, prior_std, tolerance
from .pruning import generic_excitation, prune
from .synthetic import project_to_point

#: A parameter whose predicted std exceeds this share of its prior spread is "weakly determined".
WEAK_SHARE = 0.3
#: Default workspace configurations and Monte Carlo draws of the parameter error.
CONFIGURATIONS = 1000
DRAWS = 200
#: Radius of the region around the recorded tool points where a calibration is judged and used [m]: the plate
#: placed again on the same table (MUKCa's nearest placements are 0.12-0.27 m apart; :meth:`Workspace.near`).
NEAR_RADIUS = 0.3


@dataclass(frozen=True, eq=False)
class Workspace:
    """Random workspace configurations and the registered sensitivity of their tool points.

    Attributes:
        q: (N, n) configurations inside the joint limits [rad].
        sensitivity: (3 N, P) ``d p / d params`` with the six rigid motions of the point set
            projected out (what survives the best-rigid-fit registration of the validation).
    """

    q: np.ndarray
    sensitivity: np.ndarray

    @staticmethod
    def of(model: RobotModel, count: int = CONFIGURATIONS, rng: np.random.Generator | None = None) -> Workspace:
        """``count`` configurations uniform in the joint limits of ``model`` (seeded; default seed 0)."""
        rng = np.random.default_rng(0) if rng is None else rng
        q = model.random_configurations(count, rng)
        jac, points = param_jacobian(model, q, return_point=True)
        return Workspace(q=q, sensitivity=remove_rigid_motion(jac.reshape(3 * count, -1), points))

    @staticmethod
    def near(model: RobotModel, recorded: np.ndarray, count: int = CONFIGURATIONS, radius: float = NEAR_RADIUS,
             rng: np.random.Generator | None = None) -> Workspace:
        """Where the recording's calibration is used: tool points within ``radius`` [m] of recorded ones, reached
        with the recorded postures.

        Each of ``count`` configurations is a recorded one (``recorded`` (K, n) [rad], drawn at random) whose tool
        point is moved by a random displacement uniform in a ball of ``radius`` (damped Newton steps,
        :func:`.synthetic.project_to_point`: the nearest configuration there, inside the joint limits): a plate
        placed again on the same table, held as the person held it. Configurations that do not reach their point
        within 1 um in 25 steps (out of reach, or held at a joint limit) are dropped (seeded; default seed 0).
        """
        rng = np.random.default_rng(0) if rng is None else rng
        start = np.asarray(recorded, float)[rng.integers(0, len(recorded), count)]
        direction = rng.standard_normal((count, 3))
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        shift = direction * radius * rng.uniform(0.0, 1.0, (count, 1)) ** (1.0 / 3.0)
        q, ok = project_to_point(model, start, tool_point(model, start) + shift, iterations=25, tol=1e-6)
        q = q[ok]
        jac, points = param_jacobian(model, q, return_point=True)
        return Workspace(q=q, sensitivity=remove_rigid_motion(jac.reshape(3 * len(q), -1), points))


def remove_rigid_motion(field: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Project a displacement field onto the complement of the rigid motions of a point set.

    A small rigid motion moves point ``p`` by ``t + w x p``; registration (best rigid fit) removes
    exactly the least-squares part of a small error field in that 6-D space.

    Args:
        field: (3 N, C) displacement columns, points stacked ``x0 y0 z0 x1 ...`` [m per unit].
        points: (N, 3) the points [m].

    Returns:
        (3 N, C) the columns minus their rigid-motion part.
    """
    n = points.shape[0]
    centred = points - points.mean(axis=0)
    basis = np.zeros((n, 3, 6))
    basis[:, :, :3] = np.eye(3)
    for k in range(3):  # w_k e_k x p
        basis[:, :, 3 + k] = np.cross(np.eye(3)[k], centred)
    q, _ = np.linalg.qr(basis.reshape(3 * n, 6))
    return field - q @ (q.T @ field)


@dataclass(frozen=True, eq=False)
class Prediction:
    """Predicted calibration accuracy.

    Attributes:
        mean: expected mean tool-point error over the workspace after registration [m].
        p95: 95th percentile of the tool-point error (over configurations and draws) [m].
        rms: root-mean-square tool-point error [m].
        noise: fixture noise per coordinate assumed [m].
        samples: fixture name -> samples (as weighted: ``count x sample_weight``).
        identified: names of the identified parameters.
        std: name -> predicted standard deviation [m or rad] of every identified parameter.
        weak: identified parameters whose std exceeds :data:`WEAK_SHARE` of their prior spread.
        fixed: name -> reason, every parameter not identified (gauge, redundant, barely excited).
        identifiability: singular values and condition number of the column-scaled Jacobian.
        errors: (N, D) sampled error magnitudes [m] (configurations x draws), for plots.
        warnings: the calibration problem's warnings (scale from the nominal model, unused fixtures).
        layout: the model's parameter layout (kinds and display units of ``std``).
    """

    mean: float
    p95: float
    rms: float
    noise: float
    samples: dict[str, float]
    identified: tuple[str, ...]
    std: dict[str, float]
    weak: tuple[str, ...]
    fixed: dict[str, str]
    identifiability: Identifiability
    errors: np.ndarray
    warnings: tuple[str, ...] = ()
    layout: ParameterLayout | None = None

    def summary(self) -> str:
        """A few lines for humans (mm, deg)."""
        s = self.identifiability.singular_values
        counts = ", ".join(f"{k} {v:.0f}" for k, v in self.samples.items())
        lines = [
            f"predicted tool-point error after registration at {self.noise * 1e3:.3g} mm fixture noise "
            f"({counts} samples): mean {self.mean * 1e3:.4f} mm, 95th percentile {self.p95 * 1e3:.4f} mm",
            f"identified {len(self.identified)} parameters, "
            f"condition number {self.identifiability.condition_number:.3g}, "
            f"singular values {s[0]:.3g} .. {s[-1]:.3g}",
        ]
        lines.append("singular values (column-scaled): " + " ".join(f"{v:.3g}" for v in s))
        if self.weak:
            weak = ", ".join(f"{n} ({self.layout.format(n, self.std[n])})" for n in self.weak)
            lines.append(f"weakly determined (std > {WEAK_SHARE:.0%} of the prior spread): {weak}")
        pruned = [n for n, why in self.fixed.items() if why.startswith("barely excited")]
        if pruned:
            lines.append(f"not excited (left at nominal): {', '.join(pruned)}")
        lines.extend(f"warning: {w}" for w in self.warnings)
        return "\n".join(lines)


def _anchor_spread(problem: CalibrationProblem) -> float:
    """Prior spread [m] of the scale anchor's radius (taken from the nominal model, not measured)."""
    name, point, _ = problem.anchor
    return anchor_spread(problem.model, problem.dataset.for_fixture(name), point)


def _linearised(problem: CalibrationProblem, noise: float, sample_weight: float = 1.0,
                free: np.ndarray | None = None):
    """The pruned problem at its generic point: ``(lin, x_lin, pruned, x, rows, jac, inverse)`` (``rows``: the
    sample rows' weights, ``jac`` weighted by them, ``inverse`` of its normal matrix). ``free``: the parameters a
    calibration identified (indices into the model's), the others left at nominal as it left them; default: pruned
    at ``noise`` (:func:`.pruning.prune`). Kept in ``problem``'s cache: the self-check's record asks for the same
    one twice (:func:`joint_error_root`, :func:`deviation_root`); the arrays are shared, not to be written."""
    # problems made by dataclasses.replace share their cache (same model and samples): the key holds what else
    # the linearisation reads of ``problem``
    read = (problem.free.tobytes(), problem.free_centres, problem.pinned, problem.noise, problem.prior_weight,
            problem.prior_noise,
            None if problem.prior_curvature is None else problem.prior_curvature.tobytes())
    key = ("linearised", float(noise), float(sample_weight), None if free is None else np.asarray(free).tobytes(),
           *read)
    if key not in problem._cache:
        problem._cache[key] = _linearise(problem, noise, sample_weight, free, read)
    return problem._cache[key]


def _linearise(problem: CalibrationProblem, noise: float, sample_weight: float, free: np.ndarray | None,
               read: tuple):
    """:func:`_linearised`, computed (``read``: what its cache key holds of ``problem``)."""
    lin, x_lin = problem.generic_point()
    if free is None:  # lin's Jacobian at x_lin is problem's generic one: factorised once (the calibration's pruning)
        pruned, x = prune(lin, x_lin, max(noise, SIGMA_FLOOR) / np.sqrt(sample_weight),
                          excitation=generic_excitation(problem))
    else:
        params, centres = lin.unpack(x_lin)
        dropped = np.setdiff1d(lin.free, free)
        params[dropped] = lin.model.params[dropped]
        names = lin.model.param_names
        left = {names[i]: "left at nominal by the calibration" for i in dropped}
        pruned = replace(lin, free=np.intersect1d(lin.free, free), fixed={**lin.fixed, **left})
        x = pruned.pack(params, centres)
    rows = np.ones((pruned.n_residuals, 1))
    rows[: 3 * problem.dataset.n_samples] = np.sqrt(sample_weight)
    # the self-check asks for the calibration's own free parameters and for those pruned at its noise, most often the
    # same: the same unknowns at the same point, one Jacobian and one factorisation (a tall QR and SVD) for both
    key = ("linearised jacobian", float(sample_weight), pruned.free.tobytes(), x.tobytes(), *read)
    if key not in problem._cache:
        jac = pruned.jacobian(x) * rows
        problem._cache[key] = jac, normal_inverse(jac)
    jac, inverse = problem._cache[key]
    return lin, x_lin, pruned, x, rows, jac, inverse


def deviation_root(
    model: RobotModel, problem: CalibrationProblem, noise: float, sample_weight: float = 1.0,
    bias_scale: float = 1.0, data_noise: float | None = None, free: np.ndarray | None = None,
    unseen_scale: float | None = None,
) -> tuple[np.ndarray, CalibrationProblem, np.ndarray, np.ndarray]:
    """The calibrated parameters' error ``dp = R z``, ``z ~ N(0, I)`` (see the module docstring).

    Args:
        model: the nominal robot (prior spreads of the parameters left at nominal).
        problem: ``build_problem(model, dataset, spec)``.
        noise: fixture noise std per coordinate [m].
        sample_weight: each sample stands for this many recorded ones.
        bias_scale: the arm's parameter deviations as a share of the prior spread (1: the generic arm);
            scales the biases of what the data cannot see (parameters left at nominal, the scale anchor),
            which are the nominal model's own errors in those directions.
        data_noise: the samples' own noise, std per coordinate [m], when known apart from ``noise`` (which then
            only sets the pruning): the error of the MAP estimate ``x = A^-1 J_d^T y`` (``A = J_d^T J_d + J_p^T J_p``)
            of an arm ``bias_scale`` prior spreads off is ``A^-1 J_d^T n - A^-1 J_p^T J_p dp``, whose covariance is
            ``A^-1 (data_noise^2 J_s^T J_s + noise_p^2 J_r^T J_r + bias_scale^2 W noise_p^2 J_p^T J_p) A^-1``: the
            prior rows weigh ``sqrt(W) noise_p / s`` (``W`` the prior weight, ``noise_p`` the problem's noise), the
            distance rows ``J_r`` are at ``noise_p`` by their weight. None: every row at ``noise``,
            ``noise^2 A^-1 (J_d^T J_d + bias_scale^2 J_p^T J_p) A^-1`` (the beat-nominal judgement's, which counts the
            prior's penalty in the residual as noise, and is exact only when ``noise^2 = W noise_p^2``).
        free: the parameters the calibration identified (indices into ``model``'s), when known: the others are
            what it left at nominal (default: ``problem`` pruned at ``noise``, which may leave at nominal a
            parameter the calibration, pruning at its own residual, identified).
        unseen_scale: ``bias_scale`` of what the data cannot see at all (parameters left at nominal, the scale
            anchor) where it differs (default ``bias_scale``): a forecast charges them at the arm's measured scale.

    Returns:
        ``(R, pruned, x, std)``: (P, k) root of the error covariance of every parameter of ``model``
        (zero rows for the gauge), the pruned problem and its linearisation point, (F,) predicted std
        of its identified parameters.
    """
    lin, x_lin, pruned, x, rows, jac, inverse = _linearised(problem, noise, sample_weight, free)
    unseen_scale = bias_scale if unseen_scale is None else unseen_scale
    fp = pruned.n_free_params
    if data_noise is not None:  # the samples at their noise; distances, anchor and prior rows at the problem's
        samples, prior = slice(0, 3 * pruned.dataset.n_samples), pruned.prior_rows()
        rest = ~prior
        rest[samples] = False
        stated = max(pruned.noise, SIGMA_FLOOR) ** 2  # (w distance_std)^2
        held = pruned.prior_sigma() ** 2  # (sqrt(W) noise_p / s)^2 s^2 over W
        middle = (data_noise**2 * (jac[samples].T @ jac[samples]) + stated * (jac[rest].T @ jac[rest])
                  + bias_scale**2 * pruned.prior_weight * held * (jac[prior].T @ jac[prior]))
        cov = (inverse @ middle @ inverse)[:fp, :fp]
        cov = 0.5 * (cov + cov.T)
    elif bias_scale == 1.0 or not pruned.n_prior:
        cov = noise**2 * inverse[:fp, :fp]
    else:  # the prior rows regularise at the generic spread, the arm's deviations are bias_scale times it:
        # cov = A^-1 (J_d^T J_d + s^2 J_p^T J_p) A^-1 sigma^2 (= sigma^2 A^-1 at s = 1)
        prior = pruned.prior_rows()
        middle = jac[~prior].T @ jac[~prior] + bias_scale**2 * (jac[prior].T @ jac[prior])
        cov = noise**2 * (inverse @ middle @ inverse)[:fp, :fp]
        cov = 0.5 * (cov + cov.T)
    free = pruned.free
    std = np.sqrt(np.maximum(np.diag(cov), 0.0))  # a variance a little below 0 by rounding (a noise-free fit) is 0
    columns = [np.zeros((model.n_params, fp))]
    columns[0][free] = symmetric_root(cov)
    # biases, one column per standard-normal source
    dropped = np.setdiff1d(lin.free, free)
    if dropped.size:  # barely excited parameters left at nominal: the fit absorbs what it can
        cols = [int(np.flatnonzero(lin.free == i)[0]) for i in dropped]
        spread = unseen_scale * tolerance(model)[dropped]  # pruned against it: a zero may be 1 deg off
        bias = np.zeros((model.n_params, dropped.size))
        moved = np.zeros((pruned.n_residuals, len(cols)))  # their data columns in the pruned problem's rows
        moved[~pruned.prior_rows()] = lin.jacobian(x_lin)[~lin.prior_rows()][:, cols]
        bias[free] = (-inverse @ (jac.T @ (moved * rows * spread)))[:fp]
        bias[dropped, np.arange(dropped.size)] = spread
        columns.append(bias)
    if pruned.anchor is not None:  # the scale anchor's radius is the nominal model's, not measured
        kick = np.zeros((pruned.n_residuals, 1))
        kick[-1] = unseen_scale * pruned.distance_weight * _anchor_spread(pruned)
        bias = np.zeros((model.n_params, 1))
        bias[free] = (inverse @ (jac.T @ kick))[:fp]
        columns.append(bias)
    return np.hstack(columns), pruned, x, std


def seen_part(model: RobotModel, root: np.ndarray, count: int = 300) -> np.ndarray:
    """``root`` (P, k) less its part that moves no tool point of ``model``: the parameter combinations no
    configuration sees (the null space of the parameter Jacobian over ``count`` random configurations, seed 0; a
    UR-like arm's d2, d3 and d4 count only by their sum across its parallel axes).

    No tool point of ``model`` changes, but a covariance charging such a combination at the prior's spread (what a
    calibration left at nominal) is read by ``validate`` through the calibrated model's Jacobian, where it is no
    longer exactly unseen: a noise-free UR-like arm's held-out spread was predicted at 9 um where 0.7 um was measured.
    """
    q = model.random_configurations(count, np.random.default_rng(0))
    jac = param_jacobian(model, q).reshape(3 * count, -1)
    # the (P, P) right vectors; a full U (3 count, 3 count) is formed only when it is needed to have P of them
    _, values, rows = np.linalg.svd(jac, full_matrices=jac.shape[0] < jac.shape[1])
    unseen = rows[np.concatenate([values, np.zeros(rows.shape[0] - len(values))]) <= 1e-10 * values[0]]
    return root - unseen.T @ (unseen @ root)


def excess_energy(shown: float, declared: float, dof: float) -> float:
    """``excess`` of :func:`joint_error_root`: sqrt of the residual energy beyond the declared noise [m],
    ``sqrt((shown^2 - declared^2) x dof)`` for a residual std ``shown`` per coordinate over ``dof`` degrees of
    freedom (0 when the residual is within the declared noise)."""
    return float(np.sqrt(max(shown**2 - declared**2, 0.0) * max(dof, 0.0)))


def joint_error_root(
    model: RobotModel, problem: CalibrationProblem, noise: float, excess: float, length: float = LENGTH,
    std: float = 0.0, free: np.ndarray | None = None, bound: float | None = None,
) -> tuple[float, np.ndarray]:
    """The unmodelled joint-angle error (:mod:`.joint_error`) that leaves ``excess`` in the residuals, and the bias
    it bends the fitted parameters by.

    A unit-std error ``f`` at the training configurations moves the fit by ``dx = -(J^T J)^-1 J^T f`` and leaves
    ``f + J dx`` in the residuals; its std ``s`` is the one whose expected left-over energy ``s^2 |f + J dx|^2``
    (summed over the process's root columns) equals the residual energy beyond the declared noise,
    ``excess^2 = (sigma_data^2 - noise_declared^2) x dof``.

    Args:
        model: the nominal robot.
        problem: ``build_problem(model, dataset, spec)``.
        noise: the noise of the linearisation (as :func:`deviation_root`) [m].
        excess: sqrt of the residual energy beyond the declared noise [m] (0: none).
        length: the process's correlation length [rad].
        std: the error's std [rad] as estimated otherwise (:func:`.joint_error.split`); the larger of it and the
            excess's is taken.
        free: the parameters the calibration identified, as :func:`deviation_root`'s.
        bound: the largest std [rad]: default :func:`joint_error_bound` of ``problem``'s samples (a caller that has
            it already passes it); ``inf``: none, the std linear in ``excess`` for a caller that scales it.

    Returns:
        ``(s, B)``: the std of each joint's angle error [rad] and (P, c) the root of the bias's covariance
        over every parameter of ``model`` (already times ``s``; add its columns to :func:`deviation_root`'s).
    """
    if excess <= 0 and std <= 0:
        return 0.0, np.zeros((model.n_params, 0))
    _, _, pruned, _, _, jac, inverse = _linearised(problem, noise, free=free)
    count, fp = pruned.dataset.n_samples, pruned.n_free_params
    data = jac[: 3 * count]
    normal = data.T @ data
    shifts, kept = [], 0.0
    for seen, energy, _ in seen_fields(model, pruned.dataset.q, data, length):
        shift = -inverse @ seen  # (U, r): every unknown
        # |F + J dx|^2 = |F|^2 + 2 <J^T F, dx> + <dx, J^T J dx>
        kept += energy + 2.0 * float(np.sum(seen * shift)) + float(np.sum(shift * (normal @ shift)))
        shifts.append(shift[:fp])
    if kept <= 0:
        return 0.0, np.zeros((model.n_params, 0))
    bound = joint_error_bound(model, pruned.dataset, length) if bound is None else bound
    std = min(max(excess / np.sqrt(kept), std), bound)
    bias = np.zeros((model.n_params, sum(s.shape[1] for s in shifts)))
    bias[pruned.free] = std * np.hstack(shifts)
    return float(std), bias


def joint_error_bound(model: RobotModel, dataset: Dataset, length: float = LENGTH) -> float:
    """The largest joint-angle error std [rad] the nominal model's own spread at the sockets allows.

    Before calibration, each socket's samples spread about their mean by the whole joint-angle error (only its mean
    there goes into the centre) plus everything else: ``s^2 |F_c|^2 <= |p - mean|^2`` summed over the sockets, with
    ``F_c`` the unit process's tool-point field less its mean per socket. The fit may absorb nearly all of a smooth
    error over a short recording, and the std that leaves the residual's excess then grows without bound (86 mrad
    per joint from 2 s of self-motion whose nominal spread was 0.6 mm); the nominal's spread bounds it. Infinite
    when the field has no energy (a socket of one sample).
    """
    index = dataset.fixture_index
    points = tool_point(model, dataset.q)
    spread = sum(float(((points[index == j] - points[index == j].mean(axis=0)) ** 2).sum())
                 for j in range(len(dataset.fixture_names)))
    # |F_c|^2 per joint i without forming the (K, 3, r) field: sum_k |g_k|^2 |L_k|^2 - sum_j |sum_k g_k L_k^T|^2 / K_j
    # (g_k = dp/dq_i at sample k, L_k its row of the process's root; the second sum per socket j)
    root = field_root(dataset.q, length)
    gains = joint_jacobian(model, dataset.q)  # (K, 3, n)
    weight = np.einsum("kr,kr->k", root, root)
    energy = float(np.einsum("kin,kin,k->", gains, gains, weight))
    for j in range(len(dataset.fixture_names)):
        mine = index == j
        energy -= float((np.einsum("kin,kr->inr", gains[mine], root[mine]) ** 2).sum()) / max(int(mine.sum()), 1)
    return float(np.sqrt(spread / energy)) if energy > 0 else float("inf")


def held_out_joint_error(
    model: RobotModel, problem: CalibrationProblem, noise: float, std: float, q: np.ndarray, labels: np.ndarray,
    length: float = LENGTH, rng: np.random.Generator | None = None,
) -> np.ndarray:
    """Expected squared spread [m^2] at sockets the calibration of ``problem`` did not see, of the arm's unmodelled
    joint-angle error (:mod:`.joint_error`, std ``std`` [rad]): one realisation of it over the training and the
    held-out configurations together.

    The fit absorbs the error at its training configurations (``dx = -(J^T J)^-1 J^T f``, as
    :func:`joint_error_root`); at a held-out configuration the calibrated model is off by ``f + G dx``, less its
    mean over the socket (MUKCa's spread). Where the held-out configurations lie close to the training ones in
    joint space the two errors are correlated and the absorbed bias cancels part of the held-out one; far away it
    adds to a fresh draw (what :func:`socket_spreads` assumes for an unseen socket).

    Args:
        model: the robot (joint and parameter Jacobians).
        problem: ``build_problem(model, dataset, spec)`` of the training data.
        noise: the noise of the linearisation (as :func:`deviation_root`) [m].
        std: std of each joint's angle error [rad] (0: zeros).
        q: (M, n) held-out configurations [rad].
        labels: (M,) socket of each (the spread is about each socket's mean).
        length: correlation length over joint space [rad].
        rng: seeds the random features of a large configuration set (:func:`.joint_error.field_root`).

    Returns:
        (M,) expected ``|e - mean over the socket|^2`` at each held-out configuration [m^2] (summed over the axes).
    """
    out = np.zeros(len(q))
    if std <= 0 or not len(q):
        return out
    _, _, pruned, _, _, jac, inverse = _linearised(problem, noise)
    count, fp = pruned.dataset.n_samples, pruned.n_free_params
    absorb = -(inverse @ jac[: 3 * count].T)[:fp]  # (fp, 3K): training error -> identified parameters' shift
    gains = param_jacobian(model, q)[:, :, pruned.free]  # (M, 3, fp)
    names, index = np.unique(labels, return_inverse=True)
    size = np.bincount(index, minlength=len(names))
    for field in tool_fields(model, np.concatenate([pruned.dataset.q, q]), length, rng):  # (K + M, 3, r)
        shift = absorb @ field[:count].reshape(3 * count, -1)  # (fp, r)
        error = field[count:] + np.einsum("mip,pr->mir", gains, shift)
        mean = np.zeros((len(names), *error.shape[1:]))
        np.add.at(mean, index, error)
        error -= (mean / size[:, None, None])[index]
        out += std**2 * np.einsum("mir,mir->m", error, error)
    return out


def error_field(
    model: RobotModel,
    problem: CalibrationProblem,
    noise: float,
    gains: np.ndarray,
    sample_weight: float = 1.0,
    draws: int = DRAWS,
    rng: np.random.Generator | None = None,
) -> tuple[np.ndarray, CalibrationProblem, np.ndarray, np.ndarray]:
    """Sampled tool-point errors of the calibration of ``problem``'s data: ``gains @ R @ z``.

    Args:
        model, problem, noise, sample_weight: see :func:`deviation_root`.
        gains: (3 N, P) ``d p / d params`` at the configurations where the error is wanted, with what
            the comparison removes projected out (rigid motions for :class:`Workspace`).
        draws: Monte Carlo draws.
        rng: seeds the draws (default seed 0).

    Returns:
        ``(field, pruned, x, std)``: (3 N, draws) error vectors [m], then as :func:`deviation_root`.
    """
    rng = np.random.default_rng(0) if rng is None else rng
    root, pruned, x, std = deviation_root(model, problem, noise, sample_weight)
    return gains @ root @ rng.standard_normal((root.shape[1], draws)), pruned, x, std


def socket_spreads(
    model: RobotModel, root: np.ndarray, sockets: list[np.ndarray], noise: float, draws: int = DRAWS,
    rng: np.random.Generator | None = None, gains: list[np.ndarray] | None = None, joint_error: float = 0.0,
    length: float = LENGTH,
) -> np.ndarray:
    """Predicted spread of each socket: the mean distance of a calibrated model's tool points from their
    mean (MUKCa's MAE, :mod:`spherecal.validation.sockets`), for the configurations recorded there.

    The calibrated model's error ``G(q) R z`` (``R`` from :func:`deviation_root`) plus the socket's noise
    ``n ~ N(0, noise^2)`` per axis and sample plus, for a socket the calibration did not see, a fresh draw of the
    arm's unmodelled joint-angle error (:func:`.joint_error.draw`, std ``joint_error``), less their mean over the
    socket; averaged over draws.

    Args:
        model: the model whose parameter Jacobian is used (nominal or calibrated: the same to first order).
        root: (P, k) from :func:`deviation_root` (or as recorded in a calibrated file).
        sockets: per socket, (K, n) joint angles [rad].
        noise: std per axis of where the ball sits in its socket [m] (0: the model's part alone).
        draws: Monte Carlo draws.
        rng: seeds the draws (default seed 0).
        gains: per socket, (K, 3, P) ``param_jacobian(model, q)`` if already computed.
        joint_error: std of each joint's unmodelled angle error [rad] (0: none).
        length: its correlation length over joint space [rad].

    Returns:
        (S,) predicted mean spread of each socket [m] (NaN for a socket with fewer than 2 samples).
    """
    rng = np.random.default_rng(0) if rng is None else rng
    out = np.full(len(sockets), np.nan)
    for s, q in enumerate(sockets):
        if len(q) < 2:
            continue
        jac = param_jacobian(model, q) if gains is None else gains[s]  # (K, 3, P)
        error = np.einsum("kip,pd->kid", jac, root @ rng.standard_normal((root.shape[1], draws)))
        error += noise * rng.standard_normal(error.shape)
        if joint_error > 0:
            error += draw(model, q, joint_error, draws, rng, length)
        error -= error.mean(axis=0)
        out[s] = float(np.linalg.norm(error, axis=1).mean())
    return out


@dataclass(frozen=True, eq=False)
class HeldOut:
    """What a calibration predicts at sockets it did not see (recorded in its file's self-check).

    Attributes:
        root: (P, k) root of the calibrated parameters' error covariance (:func:`deviation_root` plus
            :func:`joint_error_root`'s bias), over every parameter of the model.
        noise: the socket's own noise, std per axis [m].
        joint_error: std of each joint's unmodelled angle error [rad] (0: none).
        length: its correlation length over joint space [rad].
    """

    root: np.ndarray
    noise: float
    joint_error: float = 0.0
    length: float = LENGTH

    def spreads(self, model: RobotModel, sockets: list[np.ndarray]) -> np.ndarray:
        """(S,) predicted mean spread [m] of each socket's configurations (K, n) [rad] (:func:`socket_spreads`)."""
        return socket_spreads(model, self.root, sockets, self.noise, joint_error=self.joint_error,
                              length=self.length)


def predict_accuracy(
    model: RobotModel,
    dataset: Dataset,
    spec: FixtureSpec | None = None,
    noise: float = NOISE,
    workspace: Workspace | None = None,
    sample_weight: float = 1.0,
    draws: int = DRAWS,
    rng: np.random.Generator | None = None,
    problem: CalibrationProblem | None = None,
) -> Prediction:
    """Predict the accuracy a calibration from ``dataset`` will reach.

    Args:
        model: the nominal robot (the calibration's start).
        dataset: the samples (recorded or simulated), (K, n) joint angles with fixture labels.
        spec: known fixture positions and distances (all unknown when None).
        noise: fixture noise std per coordinate [m] (0 allowed: only the pruning bias remains).
        workspace: where the error is evaluated (default :meth:`Workspace.of` ``model``, seed 0).
        sample_weight: each sample stands for this many recorded ones (planning with few samples).
        draws: Monte Carlo draws of the parameter error.
        rng: seeds the draws (default seed 0).
        problem: a prebuilt ``build_problem(model, dataset, spec, noise=noise)`` (saves its cost).

    Returns:
        The :class:`Prediction`.

    Raises:
        DatasetError, UnidentifiableError: as :func:`identification.build.build_problem`.
    """
    rng = np.random.default_rng(0) if rng is None else rng
    workspace = Workspace.of(model) if workspace is None else workspace
    problem = build_problem(model, dataset, spec, noise=max(noise, SIGMA_FLOOR)) if problem is None else problem
    field, pruned, x, std = error_field(model, problem, noise, workspace.sensitivity, sample_weight, draws, rng)
    free = pruned.free
    errors = np.linalg.norm(field.reshape(-1, 3, draws), axis=1)
    prior = prior_std(model)[free]
    names = pruned.identified
    return Prediction(
        mean=float(errors.mean()),
        p95=float(np.percentile(errors, 95)),
        rms=float(np.sqrt(np.mean(errors**2))),
        noise=noise,
        samples={k: v * sample_weight for k, v in dataset.counts().items()},
        identified=names,
        std=dict(zip(names, (float(s) for s in std), strict=True)),
        weak=tuple(n for n, s, p in zip(names, std, prior, strict=True) if s > WEAK_SHARE * p),
        fixed=pruned.fixed,
        identifiability=Identifiability.of(pruned.jacobian(x)),
        errors=errors,
        warnings=pruned.warnings,
        layout=model.layout,
    )
