"""Shared fixtures: seeded generators, the embedded Panda, perturbed models."""

from __future__ import annotations

import os

import numpy as np
import pytest

os.environ.setdefault("RERUN_ANALYTICS", "0")
os.environ.setdefault("CI", "1")  # the Rerun viewer binary is quiet under CI

from spherecal.correction import RobotModel, load_robot, perturb  # noqa: E402


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261122)


@pytest.fixture(scope="session")
def panda() -> RobotModel:
    return load_robot("panda")


def perturbed(model: RobotModel, rng: np.random.Generator, scale: float = 1.0) -> RobotModel:
    """The model with every DH parameter, the tool and the base moved by ``scale`` x
    (1 mm on lengths, 0.2 deg on angles): a different, generic robot."""
    return perturb(model, rng, 1e-3 * scale, np.deg2rad(0.2) * scale, 1e-3 * scale, base=True)
