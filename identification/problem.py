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

from spherecal.correction import RobotModel, param_jacobian, tool_point
from spherecal.correction.errors import SpherecalError
from spherecal.correction.files.fixtures import FixtureSpec
from spherecal.correction.files.samples import Dataset

from .identifiability import Identifiability

#: Joint-1 parameters that move every tool point rigidly (the gauge against unknown centres).
GAUGE: dict[str, tuple[str, ...]] = {"modified": ("a1", "alpha1", "d1", "theta1"), "standard": ("d1", "theta1")}
#: Default expected fixture noise [m] (the paper's motion-capture accuracy).
NOISE = 3e-4
#: Floor of the residual noise used to judge excitation [m] (noise-free data still has rounding).
SIGMA_FLOOR = 1e-6
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
        moved = replace(self, model=model.with_params(generic), _cache={})
        return moved, moved.pack(generic, self.centres)

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


def samples_location(dataset: Dataset) -> str:
    """``"samples.csv: rows 2-1501"``: where a dataset came from, for one-line errors
    (``"samples: all rows"`` when it was not read from a file)."""
    rows = (
        "all rows"
        if dataset.lines is None or dataset.n_samples == 0
        else f"rows {dataset.lines.min()}-{dataset.lines.max()}"
    )
    return f"{dataset.source or 'samples'}: {rows}"


def mean_points(model: RobotModel, dataset: Dataset) -> np.ndarray:
    """(J, 3) mean tool point of every fixture's samples on ``model`` [m]."""
    points = tool_point(model, dataset.q)
    fixture = dataset.fixture_index
    return np.stack([points[fixture == j].mean(axis=0) for j in range(len(dataset.fixture_names))])
