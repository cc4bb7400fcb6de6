"""Seeded perturbation of a model: the "true" robot of a simulation."""

from __future__ import annotations

import numpy as np

from .layout import ANGLE, LENGTH
from .model import RobotModel

#: The issues' default true-robot spread: lengths 1 mm, angles 0.2 deg, tool 1 mm (std): the layout's prior.
LENGTH_STD = LENGTH.prior_std
ANGLE_STD = ANGLE.prior_std
TOOL_STD = LENGTH.prior_std


def perturb(
    model: RobotModel,
    rng: np.random.Generator,
    length_std: float = LENGTH_STD,
    angle_std: float = ANGLE_STD,
    tool_std: float = TOOL_STD,
    base: bool = False,
) -> RobotModel:
    """A copy of ``model`` with zero-mean Gaussian errors on its parameters.

    Every parameter of :attr:`RobotModel.params` gets an independent error, except: the base (unless ``base``),
    the compliances of an elastic model (kept as stated), and each ``d`` a Hayati ``beta`` holds at zero
    (:meth:`.layout.ParameterLayout.held`). The scales ``s1..sn`` of a scaled model *are* perturbed, with the
    layout's prior spread (:data:`.layout.SCALE`, 1e-3).

    Args:
        model: the nominal model.
        rng: seeded generator (the only source of randomness).
        length_std: std of ``a`` and ``d`` errors (and of the base translation) [m].
        angle_std: std of ``alpha``, ``theta`` and Hayati ``beta`` errors (and of the base rotation) [rad].
        tool_std: std of each tool-point coordinate error [m].
        base: also perturb the base placement (lengths and angles as above).

    Returns:
        The perturbed model, same convention, joint limits and other ``extras``.

    Example::

        true = perturb(load_robot("panda"), np.random.default_rng(0))   # 1 mm, 0.2 deg, 1 mm tool
    """
    std = model.layout.spread(length_std, angle_std, tool_std, base=base)
    std[model.layout.compliance] = 0.0  # geometric errors only: an elastic truth states its compliance
    for name in model.layout.held(model.convention):  # Hayati: this d stays at zero
        std[model.layout.index(name)] = 0.0
    return model.with_params(model.params + rng.normal(0.0, 1.0, model.n_params) * std)
