"""The joint-angle error process: its root against the kernel, and its tool-point field against finite differences."""

from __future__ import annotations

import numpy as np

from spherecal.correction import load_robot, tool_point
from spherecal.identification.joint_error import EXACT, draw, field_root, kernel


def test_the_field_root_is_the_kernel_exactly_then_by_random_features() -> None:
    rng = np.random.default_rng(0)
    q = rng.uniform(-1.0, 1.0, (40, 6))
    root = field_root(q)
    np.testing.assert_allclose(root @ root.T, kernel(q, q), atol=1e-9)
    many = rng.uniform(-1.0, 1.0, (EXACT + 100, 6))
    features = field_root(many, rng=rng)
    assert features.shape[0] == len(many) and features.shape[1] < len(many)
    assert np.abs(features @ features.T - kernel(many, many)).mean() < 0.06  # ~1 / sqrt(features)


def test_a_drawn_joint_angle_error_moves_the_tool_point_as_the_kinematics_do() -> None:
    # one draw of the field at a few configurations: the tool point of the angles moved by that joint-angle error
    panda = load_robot("panda")
    rng = np.random.default_rng(1)
    q = panda.random_configurations(5, rng)
    std = 1e-6  # small: first order
    moved = draw(panda, q, std, 1, np.random.default_rng(2))[:, :, 0]
    again = np.random.default_rng(2)
    root = field_root(q)  # draw's joints in turn, each with its own normal draws
    eps = np.stack([root @ again.standard_normal((root.shape[1], 1))[:, 0] for _ in range(7)], axis=1) * std
    np.testing.assert_allclose(moved, tool_point(panda, q + eps) - tool_point(panda, q), rtol=1e-4, atol=1e-13)
