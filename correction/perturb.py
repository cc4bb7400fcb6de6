"""Seeded perturbation of a model: the "true" robot of a simulation."""

from __future__ import annotations

import numpy as np

from .model import RobotModel

#: The issues' default true-robot spread: lengths 1 mm, angles 0.2 deg, tool 1 mm (std).
LENGTH_STD = 1e-3
ANGLE_STD = float(np.deg2rad(0.2))
TOOL_STD = 1e-3


def perturb(
    model: RobotModel,
    rng: np.random.Generator,
    length_std: float = LENGTH_STD,
    angle_std: float = ANGLE_STD,
    tool_std: float = TOOL_STD,
    base: bool = False,
) -> RobotModel:
    """A copy of ``model`` with Gaussian errors on its parameters.

    Args:
        model: the nominal model.
        rng: seeded generator (the only source of randomness).
        length_std: std of ``a`` and ``d`` errors [m].
        angle_std: std of ``alpha`` and ``theta`` errors [rad].
        tool_std: std of each tool-point coordinate error [m].
        base: also perturb the base placement (lengths and angles as above).

    Returns:
        The perturbed model, same convention and joint limits.
    """
    n = model.n_joints
    std = np.empty(model.n_params)
    std[: 4 * n] = np.tile([length_std, angle_std, length_std, angle_std], n)
    std[4 * n : 4 * n + 3] = tool_std
    std[4 * n + 3 : 4 * n + 6] = length_std if base else 0.0
    std[4 * n + 6 :] = angle_std if base else 0.0
    return model.with_params(model.params + rng.normal(0.0, 1.0, model.n_params) * std)
