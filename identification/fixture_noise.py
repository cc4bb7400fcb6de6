"""Each fixture's own noise, and the weights that make a fit read every fixture at it.

Sockets of one recording are not equally good: a ball that sits loosely, a plate that gives a little, a socket
recorded while the base rocked. A real iiwa14 placement shows 0.19 and 0.12 mm per axis at its two sockets, a real
Gen3 lite 3.2 and 1.4 mm (MUKCa's ``kuka_14 raised_left``, ``dinova_1 front``). Least squares weighs every sample
alike, so the noisier socket pulls the parameters as hard as the quieter one. Weighing each fixture's rows by the
inverse of the noise it shows is the maximum-likelihood fit when the noise differs by fixture (feasible generalised
least squares; the noise is read from a first fit).

* **A fixture's noise** ``s_j``: 1.4826 x the median absolute residual coordinate of its samples (robust: a few
  presses taken before the ball sat do not move it), pulled toward the noise of all samples ``s`` by
  :data:`PRIOR_COORDINATES` coordinates' worth (``s_j^2 = (d_j m_j^2 + n0 s^2) / (d_j + n0)``, ``d_j`` its
  coordinates less the three of its centre): a socket with a few presses keeps about the common noise. Kept within
  :data:`RATIO` of ``s`` either way: a few dozen correlated presses do not tell one socket's noise better than that.
* **The weights** ``w_j = c / s_j``, with ``c`` such that ``sum_j n_j w_j^2 = sum_j n_j`` (``n_j`` samples): the
  fixtures share the data's weight by their noise, and the data's weight against the prior toward nominal is the
  unweighted fit's. ``c`` is the noise every weighted row then shows (the robust loss's scale).

Only the solves weigh (``calibrate --loss auto``): pruning, the stds and the self-check read the samples as least
squares does, at the weighted solution (a socket recorded in two places is refused by its disagreement, not hidden by
its weight).

Measured (``bench/fixture_weights.py``, MUKCa recordings, trained on each placement, held-out test MAE):
see ``docs/figures.md``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .problem import SIGMA_FLOOR, CalibrationProblem

#: Coordinates' worth ``n0`` of the pull of a fixture's noise toward the noise of all samples: three presses.
PRIOR_COORDINATES = 9.0
#: A fixture's noise is kept within this factor of the noise of all samples, either way.
RATIO = 3.0
#: The median absolute deviation's factor to a normal distribution's std.
MAD_TO_STD = 1.4826


@dataclass(frozen=True)
class FixtureNoise:
    """The noise each fixture's samples show, and the weights of a fit that reads each at its own.

    Attributes:
        noise: fixture -> its noise per coordinate [m] (pulled toward ``common`` and bounded, module docstring).
        weights: fixture -> the weight of its sample rows (``level / noise``).
        common: the noise per coordinate of all samples together [m] (robust).
        level: the noise per coordinate every weighted row shows [m] (``c``).
    """

    noise: dict[str, float]
    weights: dict[str, float]
    common: float
    level: float

    def uneven(self, by: float = 1.25) -> bool:
        """Does some fixture's weight differ from 1 by more than the factor ``by``?"""
        return any(w > by or w < 1.0 / by for w in self.weights.values())

    def text(self) -> str:
        """``"front_h0 3.19 mm (weight 0.45), front_h1 1.43 mm (1.01)"``."""
        return ", ".join(f"{name} {self.noise[name] * 1e3:.3g} mm (weight {w:.2g})" for name, w in self.weights.items())

    def block(self) -> dict:
        """The calibration block's record (mm, and plain weights)."""
        return {"noise_mm": {k: v * 1e3 for k, v in self.noise.items()}, "weights": dict(self.weights),
                "level_mm": self.level * 1e3}


def _mad(errors: np.ndarray) -> float:
    return MAD_TO_STD * float(np.median(np.abs(errors))) if errors.size else 0.0


def fixture_noise(problem: CalibrationProblem, x: np.ndarray) -> FixtureNoise:
    """Each fixture's noise at the solution ``x`` (F,) of ``problem`` (unweighted), and the weights (module
    docstring). One fixture: its weight is 1 and every noise the common one."""
    dataset = problem.dataset
    errors = problem.sample_errors(x)
    common = max(_mad(errors), SIGMA_FLOOR)
    names = dataset.fixture_names
    counts = np.array([np.count_nonzero(dataset.fixture_index == j) for j in range(len(names))], dtype=float)
    if len(names) < 2:
        return FixtureNoise({n: common for n in names}, {n: 1.0 for n in names}, common, common)
    noise = {}
    for j, name in enumerate(names):
        own = _mad(errors[dataset.fixture_index == j])
        dof = max(3.0 * counts[j] - 3.0, 0.0)
        pulled = np.sqrt((dof * own**2 + PRIOR_COORDINATES * common**2) / (dof + PRIOR_COORDINATES))
        noise[name] = float(np.clip(pulled, common / RATIO, common * RATIO))
    s = np.array([noise[n] for n in names])
    level = float(np.sqrt(counts.sum() / np.sum(counts / s**2)))
    return FixtureNoise(noise, {n: level / noise[n] for n in names}, common, level)
