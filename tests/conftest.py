"""Shared fixtures: seeded generators, the embedded Panda, perturbed models."""

from __future__ import annotations

import os

import numpy as np
import pytest

os.environ.setdefault("RERUN_ANALYTICS", "0")

from correction import RobotModel, load_robot  # noqa: E402


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261122)


@pytest.fixture(scope="session")
def panda() -> RobotModel:
    return load_robot("panda")


def perturbed(model: RobotModel, rng: np.random.Generator, scale: float = 1.0) -> RobotModel:
    """The model with every DH parameter, the tool and the base moved by ``scale`` x
    (1 mm on lengths, 0.2 deg on angles): a different, generic robot."""
    params = model.params.copy()
    names = model.param_names
    for k, name in enumerate(names):
        is_angle = name.startswith(("alpha", "theta", "base_r", "base_p", "base_y"))
        params[k] += rng.normal(0.0, np.deg2rad(0.2) if is_angle else 1e-3) * scale
    return model.with_params(params)
