"""Rigid registration recovers a known transform."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from spherecal.correction.rigid import apply_transform, fit_rigid_transform, registered_errors


def test_recovers_a_known_transform_exactly(rng) -> None:
    points = rng.uniform(-0.8, 0.8, (500, 3))
    truth = np.eye(4)
    truth[:3, :3] = Rotation.from_rotvec(rng.normal(size=3)).as_matrix()
    truth[:3, 3] = rng.normal(0, 2.0, 3)
    moved = apply_transform(truth, points)
    np.testing.assert_allclose(fit_rigid_transform(points, moved), truth, atol=1e-12)
    assert registered_errors(points, moved).max() < 1e-12


def test_reflection_is_never_returned(rng) -> None:
    points = rng.normal(size=(50, 3))
    mirrored = points * [1, 1, -1]
    transform = fit_rigid_transform(points, mirrored)
    assert np.linalg.det(transform[:3, :3]) == pytest.approx(1.0)


def test_bad_shapes() -> None:
    with pytest.raises(ValueError, match="point sets"):
        fit_rigid_transform(np.zeros((2, 3)), np.zeros((2, 3)))
