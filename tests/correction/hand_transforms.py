"""Elementary homogeneous transforms written out by hand: the independent reference the kinematics tests
build their frames from (no code of ours)."""

from __future__ import annotations

import numpy as np


def rot(axis: int, angle: float) -> np.ndarray:
    """(4, 4) rotation about x, y or z (axis 0, 1, 2) [rad]."""
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    t = np.eye(4)
    t[i, i], t[i, j], t[j, i], t[j, j] = c, -s, s, c
    return t


def shift(axis: int, length: float) -> np.ndarray:
    """(4, 4) translation along x, y or z [m]."""
    t = np.eye(4)
    t[axis, 3] = length
    return t
