"""Which elastic joints the MuJoCo plant simulates as springs, and how stiff (no MuJoCo import: the export reads it
to tell what an MJCF carries)."""

from __future__ import annotations

import numpy as np

from spherecal.correction.elastic import compliance_of
from spherecal.correction.model import RobotModel

#: Stiffest elastic joint the plant simulates [Nm/rad]; a stiffer one is a rigid hinge. At the 1 ms step a flex hinge
#: of 1e7 Nm/rad stays still under gravity, one of 1e8 diverges within 16 steps (the Panda's inertials, every other
#: joint 5e4 Nm/rad). Real arm joints are 1e4-1e5 Nm/rad; a calibration leaves a compliance the data does not see at
#: a few 1e-9 rad/Nm or at float noise (1e-24: 8.6e23 Nm/rad, which MuJoCo ran 3 steps; a review), and what such a
#: joint bends under 100 Nm (at most 10 urad) the rigid hinge leaves out.
MAX_FLEX_STIFFNESS = 1e7


def stiffness_of(model: RobotModel) -> np.ndarray:
    """(n,) joint stiffness [Nm/rad] of ``model``'s ``compliance`` (``1 / c``; 0 marks a rigid joint: a compliance
    at or below ``1 / MAX_FLEX_STIFFNESS`` is one)."""
    c = compliance_of(model)
    return np.divide(1.0, c, out=np.zeros_like(c), where=c > 1.0 / MAX_FLEX_STIFFNESS)
