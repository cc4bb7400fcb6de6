"""The calibration problem as an inspectable object: unknowns, residuals, Jacobian, gauge.

Residuals (metres)::

    r_k = p(q_k; params) - c_j          every sample k recorded at fixture j  (3 each)
    r_d = w (|c_a - c_b| - D_ab)         every known distance                  (1 each)
    r_i = sqrt(W) noise f(z_i)           every identified parameter i, when W > 0 (1 each),
                                         z_i = (x_i - x0_i) / s_i
    r_a = w (|c_f - o| - R)              the scale anchor, when there is one  (1, last)

The prior rows (MAP toward the nominal model ``x0``) weigh each identified parameter's deviation by
its prior spread ``s_i`` (:meth:`correction.layout.ParameterLayout.spread`: 1 mm, 0.2 deg, 3e-5 rad/Nm,
1e-3 per scale); ``W`` (``prior_weight``, ``calibrate --prior``) scales them: ``W = 1`` is the Gaussian
posterior when the spreads and the declared ``noise`` are right, ``W = 0`` plain least squares. With
``prior_noise`` set (no noise declared and residuals noisier than the default: :func:`.calibrate.prior_at_shown_noise`)
the rows are weighed at that noise instead, each joint's zero spread over its tolerance (:meth:`prior_spread`). Because
they are rows of the problem, the solvers, the stds, pruning, the self-check's leave-one-out and its
prediction all see them. What the data alone can see (the rank test of :func:`build_problem`) is
judged without them.

The prior is Gaussian in its core and heavy-tailed beyond ``k`` spreads (``prior_tail``, :data:`PRIOR_TAIL`)::

    f(z) = z                                  |z| <= k     (cost f^2 / 2 = z^2 / 2, the Gaussian's)
    f(z) = sign(z) k sqrt(1 + 2 ln(|z| / k))  |z| >  k     (cost grows as k^2 ln |z|: density ~ |z|^-(k^2))

A real arm has a few large errors (MUKCa's panda_2: ``theta4`` 6 spreads off; panda_4: ``theta5``, ``tool_x``
6); under a Gaussian prior they cost so much that a per-joint scale or a compliance, which over one placement's
narrow joint range acts as an offset, buys a cheaper explanation that is wrong elsewhere. In the tail an offset
costs little more than at the core's edge, so the offset explains itself. ``f`` is monotonic with an analytic
slope, so the solvers minimise the true cost. After the solve, :meth:`CalibrationProblem.reweighted` freezes the
rows at their IRLS weights ``w_i = min(1, k^2 / z_i^2)`` (rows ``sqrt(W w_i) noise z_i``: the same gradient,
so the solution stays one): the stds, effective unknowns, pruning and the self-check read that curvature.
``prior_tail = inf`` (the default, :data:`PRIOR_TAIL`) is the plain Gaussian prior.

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

from spherecal.correction import RobotModel, param_jacobian, tool_point
from spherecal.correction.errors import SpherecalError
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.samples import Dataset

from .identifiability import Identifiability, normal_inverse
from .selfcheck_result import CalibrationRefused

#: Joint-1 parameters that move every tool point rigidly (the gauge against unknown centres).
GAUGE: dict[str, tuple[str, ...]] = {"modified": ("a1", "alpha1", "d1", "theta1"), "standard": ("d1", "theta1")}
#: Default expected fixture noise [m] (the paper's motion-capture accuracy).
NOISE = 3e-4
#: Floor of the residual noise used to judge excitation [m] (noise-free data still has rounding).
SIGMA_FLOOR = 1e-6
#: Default weight ``W`` of the prior toward the nominal model (``calibrate --prior``; see the module
#: docstring). ``W = 1`` would be the Gaussian posterior if the samples were independent at the declared
#: noise; real self-motion samples are correlated (1500 samples, residual 0.1 mm per axis, far fewer
#: independent observations), so the weight was measured on real arms (MUKCa panda_2_clean, panda_4_clean,
#: geometric model): single placement, test MAE W 0 / 0.5 / 1 / 2 = 0.375 / 0.355 / 0.375 / 0.429 mm and
#: 0.275 / 0.267 / 0.273 / 0.285 mm; leave one placement out flat on panda_2 (0.282 for all), 0.240 / 0.230 /
#: 0.231 / 0.233 / 0.239 mm for W 0 / 0.25 / 0.5 / 1 / 2 on panda_4. 0.5 is inside the flat optimum of both.
PRIOR = 0.5
#: Where the prior's heavy tail starts by default, ``k`` [prior spreads] (module docstring); ``inf``: the Gaussian
#: prior. A tail at 3 spreads (the three-sigma rule: a parameter drawn from the Gaussian prior lies beyond it with
#: probability 0.27 %, so an arm within the spreads meets the Gaussian prior unchanged) helps simulated arms with a
#: joint zero or the tool 4-8 spreads off (``bench/prior_tail.py``: held-out error of ``auto`` 0.92x, worst 1.02x;
#: arms without them 1.00x) and the MUKCa placements (panda_2 front_center 0.99 -> 0.91x MUKCa, panda_4 front
#: 0.83 -> 0.82x), but not the real Pandas trained on each placement in turn (``bench/selection_real.py --tail 3``:
#: BIC's choice 0.371 -> 0.393 mm mean over 11, worst placement 0.64 -> 0.80 mm), so the default stays Gaussian.
PRIOR_TAIL = float("inf")
#: Default accuracy of a known distance [m].
DISTANCE_STD = 1e-6
#: Largest disagreement [m] between a known distance and the distance of two known positions.
CONSISTENCY_TOL = 1e-3
#: Fixtures closer than this are degenerate (one socket under two names, or a typo) [m].
MIN_SEPARATION = 0.02
#: With a robust loss, samples farther from their centre than this multiple of the median are outliers: the
#: samples the loss discounted, left out wherever the fit's noise is read (pruning, stds, the self-check).
OUTLIER = 4.0


class UnidentifiableError(SpherecalError):
    """The data cannot determine any parameter (or the problem is otherwise rank deficient)."""


class ImplausibleCalibrationError(CalibrationRefused):
    """The fit moved a parameter further from nominal than any real arm differs from its design."""


def prior_std(model: RobotModel) -> np.ndarray:
    """(P,) prior spread of every parameter: 1 mm on lengths and tool, 0.2 deg on angles."""
    return model.layout.spread()


#: How far a real arm's joint zero (``theta_i``: the angle its encoder counts from) may sit from its description
#: [rad]. Zeros are set by homing or by mounting an encoder, not machined as the lengths and twists are, and real
#: arms sit far beyond the 0.2 deg prior spread on them: MUKCa's Pandas up to 1.3 deg (panda_2 ``theta4`` -1.3,
#: panda_4 ``theta5`` 1.3, panda_1_with_sensor ``theta4`` -1.3, each within 0.06 deg on every placement), the Gen3
#: lites 1-3 deg (dinova_1 ``theta2`` 1.5 fitted on its four placements, dinova_2 ``theta2`` -1.9 on all of its,
#: -3.0 +- 0.3 on ``front_rotated`` alone). It is what pruning judges a zero's excitation against and what the
#: plausibility check counts as a real arm's error (:func:`tolerance`); the prior toward nominal keeps 0.2 deg on
#: them (a wide one lets a weakly seen zero wander with the lengths it trades against: panda_1_with_sensor
#: ``theta6`` against ``a7``, 0.26 -> 0.34 mm held out). The Gen3 lite's held-out error is the same for 0.6, 1 and
#: 2 deg (stop 10).
ZERO_TOLERANCE = float(np.deg2rad(1.0))


def tolerance(model: RobotModel) -> np.ndarray:
    """(P,) how far a real arm's parameter may sit from its design value: the prior spread (:func:`prior_std`),
    but :data:`ZERO_TOLERANCE` for every joint's zero ``theta_i``. What pruning fixes a parameter against (seen
    worse than that, it stays at its design value) and what :func:`.calibrate.check_plausible` counts as a real
    arm's error."""
    spread = prior_std(model)
    spread[zero_indices(model)] = ZERO_TOLERANCE
    return spread


def zero_indices(model: RobotModel) -> np.ndarray:
    """Indices of the joints' zeros ``theta1..thetan`` in ``model.params``."""
    return model.layout.field("theta")


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
        anchor: ``(fixture, point, radius)``: the scale gauge ``|c_fixture - point| = radius`` [m]
            (one more residual, weighted like a distance), or None.
        prior_weight: ``W`` of the prior rows (0: none; see the module docstring).
        prior_centre: (P,) parameters the prior pulls toward (the nominal model's), or None (``model``'s).
        prior_tail: where the prior's tail starts [prior spreads] (inf: Gaussian; :data:`PRIOR_TAIL`).
        prior_curvature: (P,) frozen IRLS weights of the prior rows (:meth:`reweighted`), or None.
        prior_noise: the noise [m] the prior rows are weighed at when it is not ``noise``: the noise per axis the
            residuals show, where it is above the default (:func:`.calibrate.calibrate` without a declared noise;
            the module docstring); the joints' zeros then spread over their tolerance (:meth:`prior_spread`).
            None: ``noise``, every spread :func:`prior_std`'s.
        fixture_weights: ``(fixture, w)`` pairs: that fixture's sample rows are multiplied by ``w`` (the solves of
            ``--loss auto`` weigh each fixture by the noise it shows, :mod:`.fixture_noise`); a fixture not named,
            and every one when empty, weighs 1.
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
    anchor: tuple[str, np.ndarray, float] | None = None
    prior_weight: float = 0.0
    prior_centre: np.ndarray | None = None
    prior_tail: float = np.inf
    prior_curvature: np.ndarray | None = None
    fixture_weights: tuple[tuple[str, float], ...] = ()
    prior_noise: float | None = None
    _cache: dict = field(default_factory=dict, repr=False)

    # ------------------------------------------------------------------------------ sizes
    @property
    def n_free_params(self) -> int:
        return int(self.free.size)

    @property
    def n_unknowns(self) -> int:
        return self.n_free_params + 3 * len(self.free_centres)

    @property
    def n_prior(self) -> int:
        """Number of prior rows (one per identified parameter when ``prior_weight > 0``)."""
        return self.n_free_params if self.prior_weight > 0 else 0

    @property
    def n_data(self) -> int:
        """Number of data rows (samples, distances, anchor): the residuals without the prior."""
        return 3 * self.dataset.n_samples + len(self.spec.distances) + (self.anchor is not None)

    @property
    def n_residuals(self) -> int:
        return self.n_data + self.n_prior

    def prior_rows(self) -> np.ndarray:
        """(M,) True on the prior rows of :meth:`residuals` (between the distances and the anchor)."""
        rows = np.zeros(self.n_residuals, dtype=bool)
        start = 3 * self.dataset.n_samples + len(self.spec.distances)
        rows[start : start + self.n_prior] = True
        return rows

    def data_sigma(self, x: np.ndarray, unknowns: float | None = None) -> float:
        """Residual standard deviation per coordinate [m] of the data rows at ``x``: ``sqrt(|r|^2 / (M - F))``
        without the prior rows (their penalty is not noise), with the effective number of unknowns ``F`` of a
        regularised fit when given (:meth:`effective_unknowns`), else the count of unknowns."""
        r = self.residuals(x)[~self.prior_rows()]
        dof = max(self.n_data - (self.n_unknowns if unknowns is None else unknowns), 1.0)
        return float(np.sqrt(r @ r / dof))

    def effective_unknowns(self, jac: np.ndarray, inverse: np.ndarray | None = None) -> float:
        """Effective number of unknowns of the regularised fit: ``trace`` of the hat matrix of the data rows,
        ``F - trace(J_p (J^T J)^-1 J_p^T)`` for the prior rows ``J_p`` of ``jac`` (M, F); ``F`` without a prior
        (``inverse``: ``(J^T J)^-1``, :func:`.identifiability.normal_inverse`, when already computed)."""
        if not self.n_prior:
            return float(self.n_unknowns)
        jp = jac[self.prior_rows()]
        inverse = normal_inverse(jac) if inverse is None else inverse
        return float(self.n_unknowns - np.einsum("ij,jk,ik->", jp, inverse, jp))

    def data_share(self, jac: np.ndarray, inverse: np.ndarray | None = None) -> np.ndarray:
        """(Fp,) share of each identified parameter's estimate that comes from the data, between 0 and 1: its
        diagonal term of the data rows' hat matrix, ``1 - (J_p^T J_p (J^T J)^-1)_ii`` for the prior rows ``J_p`` of
        ``jac`` (M, F) (``inverse``: ``(J^T J)^-1`` when already computed). 1 where the data alone determines it, 0
        where the prior alone holds it (a compliance of a joint gravity does not load); the shares and the centres'
        one each sum to :meth:`effective_unknowns`. All ones without a prior."""
        fp = self.n_free_params
        if not self.n_prior:
            return np.ones(fp)
        inverse = normal_inverse(jac) if inverse is None else inverse
        prior = np.sum(jac[self.prior_rows()][:, :fp] ** 2, axis=0)  # one prior row per parameter: its square
        return np.clip(1.0 - prior * np.diag(inverse)[:fp], 0.0, 1.0)

    def prior_spread(self) -> np.ndarray:
        """(P,) the prior's spread ``s`` of every parameter: :func:`prior_std`, or, with :attr:`prior_noise` (the
        prior at the noise the residuals show), :func:`tolerance` (each joint's zero at :data:`ZERO_TOLERANCE`)."""
        return prior_std(self.model) if self.prior_noise is None else tolerance(self.model)

    def prior_sigma(self) -> float:
        """The noise [m] the prior rows are weighed at: :attr:`prior_noise`, else ``noise`` (at least the floor)."""
        return max(self.noise if self.prior_noise is None else self.prior_noise, SIGMA_FLOOR)

    def _prior_scale(self) -> np.ndarray:
        """(Fp,) ``sqrt(W) noise / s_i`` of the identified parameters [m per unit of the parameter]."""
        spread = self.prior_spread()[self.free]
        return np.sqrt(self.prior_weight) * self.prior_sigma() / spread

    def _prior_z(self, params: np.ndarray) -> np.ndarray:
        """(Fp,) deviations ``z = (p - p0) / s`` of the identified parameters from the prior's centre [spreads]."""
        centre = self.model.params if self.prior_centre is None else self.prior_centre
        return (params[self.free] - centre[self.free]) / self.prior_spread()[self.free]

    def _prior_shape(self, params: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(Fp,) prior rows over ``sqrt(W) noise``, ``f(z)``, and their slope ``df/dz`` at the identified parameters'
        deviations ``z`` (:meth:`_prior_z`; ``f`` in the module docstring, or the frozen ``sqrt(w) z``)."""
        z = self._prior_z(params)
        if self.prior_curvature is not None:
            root = np.sqrt(self.prior_curvature[self.free])
            return root * z, root
        k = self.prior_tail
        if not np.isfinite(k):
            return z, np.ones_like(z)
        size = np.maximum(np.abs(z), k)
        root = k * np.sqrt(1.0 + 2.0 * np.log(size / k))  # sqrt of the tail's cost, k at |z| = k
        inside = np.abs(z) <= k
        return np.where(inside, z, np.sign(z) * root), np.where(inside, 1.0, k**2 / (size * root))

    def prior_weights(self, x: np.ndarray) -> np.ndarray:
        """(P,) IRLS weight of every parameter's prior row at the unknowns ``x`` (F,): ``min(1, k^2 / z^2)``, the
        tail's gradient over the Gaussian's (1 within the core, for a Gaussian prior and for parameters that are not
        identified)."""
        if self.prior_curvature is not None:
            return self.prior_curvature.copy()
        weights = np.ones(self.model.n_params)
        if self.n_prior and np.isfinite(self.prior_tail):
            z = self._prior_z(self.unpack(x)[0])
            weights[self.free] = np.minimum(1.0, self.prior_tail**2 / np.maximum(z**2, self.prior_tail**2))
        return weights

    def reweighted(self, x: np.ndarray) -> CalibrationProblem:
        """This problem with the prior rows frozen at their IRLS weights at ``x`` (F,): Gaussian rows
        ``sqrt(W w_i) noise z_i``, whose gradient at ``x`` is the tailed rows' (``x`` stays a solution) and whose
        curvature is the tail's IRLS curvature there. The stds, effective unknowns, pruning and self-check of a
        solved problem read this one; itself when the prior is Gaussian or absent."""
        if not self.n_prior or not np.isfinite(self.prior_tail) or self.prior_curvature is not None:
            return self
        return replace(self, prior_curvature=self.prior_weights(x), _cache={})

    @property
    def identifiability(self) -> Identifiability:
        """Singular values and condition number of the column-scaled Jacobian at the start :attr:`x0`
        (computed on each access: a calibration reports its own at the solution)."""
        return Identifiability.of(self.jacobian(self.x0))

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
        centres[slot >= 0] = mean_points(model, self.dataset)[slot >= 0]
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
        centre = model.params if self.prior_centre is None else self.prior_centre
        moved = replace(self, model=model.with_params(generic), prior_centre=centre, _cache={})
        x = moved.pack(generic, self.centres)
        # its parameter Jacobian depends on the model and the samples alone (not on which parameters are free,
        # nor on the prior): computed once for every problem sharing this one's cache (build_problem's rank
        # test, prune after the solve, the self-check's prediction), handed to the moved problem
        if "generic_param_jacobian" not in self._cache:
            self._cache["generic_param_jacobian"] = _read_only(param_jacobian(moved.model, self.dataset.q))
        moved._cache["param_jacobian"] = (moved.unpack(x)[0].tobytes(), self._cache["generic_param_jacobian"])
        return moved, x

    def generic_jacobian(self) -> np.ndarray:
        """(M, F) Jacobian at :meth:`generic_point`."""
        moved, x = self.generic_point()
        return moved.jacobian(x)

    # ------------------------------------------------------------------ residuals, Jacobian
    def sample_errors(self, x: np.ndarray) -> np.ndarray:
        """(K, 3) ``p(q_k) - c_j`` [m]."""
        params, centres = self.unpack(x)
        _, fixture = self._layout()
        return tool_point(self.model.with_params(params), self.dataset.q) - centres[fixture]

    def start_distances(self) -> np.ndarray:
        """(K,) distance [m] of each sample's tool point from its fixture's start centre at the start model (known
        positions, else the samples' mean point): a calibration's 'residual before'."""
        return np.linalg.norm(self.sample_errors(self.x0), axis=1)

    def inliers(self, x: np.ndarray) -> np.ndarray:
        """(K,) False on the samples a robust loss discounts at ``x``: farther from their centre than :data:`OUTLIER`
        x the median distance; all True when there are none or when a fixture would lose every sample."""
        distance = np.linalg.norm(self.sample_errors(x), axis=1)
        kept = distance <= OUTLIER * np.median(distance)
        index = self.dataset.fixture_index
        if kept.all() or not all(np.any(kept[index == j]) for j in range(len(self.dataset.fixture_names))):
            return np.ones(len(kept), dtype=bool)
        return kept

    def weighted(self, weights: dict[str, float]) -> CalibrationProblem:
        """This problem with each fixture's sample rows multiplied by ``weights[fixture]`` (fixture -> w; one not
        named weighs 1, ``{}`` is unweighted): the same unknowns, another cost."""
        return replace(self, fixture_weights=tuple((str(k), float(v)) for k, v in weights.items()))

    def sample_weights(self) -> np.ndarray | None:
        """(K,) the weight of every sample's rows (:attr:`fixture_weights`), or None when unweighted."""
        if not self.fixture_weights:
            return None
        table = dict(self.fixture_weights)
        return np.array([table.get(name, 1.0) for name in self.dataset.fixture_names])[self.dataset.fixture_index]

    def with_samples(self, kept: np.ndarray) -> CalibrationProblem:
        """The problem on the samples ``kept`` (K,) bool (itself when every one is kept)."""
        return self if kept.all() else replace(self, dataset=self.dataset.select(kept), _cache={})

    def _distances(self, centres: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        names = self.dataset.fixture_names
        a = np.array([names.index(d[0]) for d in self.spec.distances], dtype=int)
        b = np.array([names.index(d[1]) for d in self.spec.distances], dtype=int)
        target = np.array([d[2] for d in self.spec.distances], dtype=float)
        delta = centres[a] - centres[b]
        return a, b, target, delta

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """(M,) residual vector [m]: samples (3 K, x y z per sample; times their fixture's weight, if any), distances,
        prior rows, anchor."""
        sample = self.sample_errors(x)
        weights = self.sample_weights()
        sample = (sample if weights is None else sample * weights[:, None]).ravel()
        if not self.spec.distances and self.anchor is None and not self.n_prior:
            return sample
        params, centres = self.unpack(x)
        _, _, target, delta = self._distances(centres)
        parts = [sample, self.distance_weight * (np.linalg.norm(delta, axis=1) - target)]
        if self.n_prior:
            parts.append(np.sqrt(self.prior_weight) * self.prior_sigma() * self._prior_shape(params)[0])
        if self.anchor is not None:
            name, point, radius = self.anchor
            gap = np.linalg.norm(centres[self.dataset.fixture_names.index(name)] - point) - radius
            parts.append([self.distance_weight * gap])
        return np.concatenate(parts)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """(M, F) analytic Jacobian of :meth:`residuals` (``correction.param_jacobian`` columns).

        The last parameter Jacobian is kept with the parameters it was taken at, for every problem sharing
        this one's cache: asked again at the same parameters (a fit's covariance, then its self-check) it is
        not recomputed."""
        params, centres = self.unpack(x)
        count, fp = self.dataset.n_samples, self.n_free_params
        jac = np.zeros((self.n_residuals, self.n_unknowns))
        key = params.tobytes()
        known = self._cache.get("param_jacobian")
        if known is not None and known[0] == key:
            pj = known[1]
        else:
            pj = _read_only(param_jacobian(self.model.with_params(params), self.dataset.q))
            self._cache["param_jacobian"] = (key, pj)
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
        if self.n_prior:
            start = 3 * count + len(self.spec.distances)
            jac[start + np.arange(fp), np.arange(fp)] = self._prior_scale() * self._prior_shape(params)[1]
        if self.anchor is not None:
            name, point, _ = self.anchor
            j = self.dataset.fixture_names.index(name)
            if slot[j] >= 0:
                delta = centres[j] - point
                jac[-1, fp + 3 * slot[j] : fp + 3 * slot[j] + 3] = self.distance_weight * delta / np.linalg.norm(delta)
        weights = self.sample_weights()
        if weights is not None:
            jac[: 3 * count] *= np.repeat(weights, 3)[:, None]
        return jac

    def centre_dict(self, centres: np.ndarray) -> dict[str, np.ndarray]:
        """Fixture name -> (3,) centre [m]."""
        return {name: centres[j] for j, name in enumerate(self.dataset.fixture_names)}


def _read_only(array: np.ndarray) -> np.ndarray:
    """``array``, no longer writable (it is shared through a problem's cache)."""
    array.setflags(write=False)
    return array


#: Rows a one-line message lists at most (:func:`row_list`).
SHOWN_ROWS = 6


def row_list(dataset: Dataset, rows: np.ndarray) -> str:
    """``"rows 12, 19, 48"`` or ``"row 37"``: the samples ``rows`` (indices) as file lines when read from a file, else
    sample numbers; at most :data:`SHOWN_ROWS`, then ``", ..."``."""
    lines = dataset.lines[rows] if dataset.lines is not None else np.asarray(rows) + 1
    if len(lines) == 1:
        return f"row {int(lines[0])}"
    return f"rows {', '.join(str(int(k)) for k in lines[:SHOWN_ROWS])}{', ...' * (len(lines) > SHOWN_ROWS)}"


def samples_location(dataset: Dataset) -> str:
    """``"samples.csv: rows 2-1501"``: where a dataset came from, for one-line errors
    (``"samples: all rows"`` when it was not read from a file); the rows part is :func:`samples_rows`."""
    return f"{dataset.source or 'samples'}: {samples_rows(dataset)}"


def samples_rows(dataset: Dataset) -> str:
    """``"rows 2-1501"``, ``"row 37"`` or ``"all rows"`` (not read from a file): the rows part of
    :func:`samples_location`, which names the file before them (every message names both since stop 19)."""
    if dataset.lines is None or dataset.n_samples == 0:
        return "all rows"
    if dataset.lines.min() == dataset.lines.max():  # 'row 37', not 'rows 37-37'
        return f"row {dataset.lines.min()}"
    return f"rows {dataset.lines.min()}-{dataset.lines.max()}"


def mean_points(model: RobotModel, dataset: Dataset) -> np.ndarray:
    """(J, 3) mean tool point of every fixture's samples on ``model`` [m]."""
    points = tool_point(model, dataset.q)
    fixture = dataset.fixture_index
    return np.stack([points[fixture == j].mean(axis=0) for j in range(len(dataset.fixture_names))])
