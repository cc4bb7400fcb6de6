"""Joint coverage as the kinematics sees it: the share of each joint's angles, one turn at most, visited.

Every joint spherecal models is revolute (the URDF reader refuses prismatic ones), so a joint's angle
enters the kinematics through its sine and cosine only: ``q_j`` and ``q_j + 2 pi`` put every link in the
same place. A joint limited to +-2 pi (a UR's) has two turns of range but one turn of distinct poses, and
a self-motion that sweeps one full turn of it has seen all of them. Its coverage is therefore measured
against ``min(upper - lower, 2 pi)``, and the visited extent is counted up to one turn:

    coverage_j = min(max q_j - min q_j, 2 pi) / min(upper_j - lower_j, 2 pi)

A joint whose range is one turn or less (a Panda's, a UR's elbow at +-pi) reads as
:func:`spherecal.controller.exploration.joint_coverage`, the share of its range (the paper's Fig. 5).
"""

from __future__ import annotations

import numpy as np

#: One turn [rad]: the most of a revolute joint's range the kinematics can tell apart.
TURN = 2 * np.pi


def visible_coverage(q: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Share of each joint's distinct angles visited by a continuous trajectory (module docstring).

    Args:
        q: (K, n) joint angles [rad], K >= 1 (a (n,) configuration reads as K = 1).
        lower, upper: (n,) joint limits [rad].

    Returns:
        (n,) shares, 1 for a full turn or the whole range (0 for a joint without range). Samples past the
        limits (the samples reader lets a reading through a little beyond them) can read a little above 1.
    """
    q = np.atleast_2d(np.asarray(q, float))
    span = np.minimum(np.asarray(upper, float) - np.asarray(lower, float), TURN)
    seen = np.minimum(np.ptp(q, axis=0), TURN)
    return np.divide(seen, span, out=np.zeros(span.shape), where=span > 0)
