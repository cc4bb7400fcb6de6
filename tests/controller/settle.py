"""Let an elastic plant settle with its motors held (zero velocity commands), gravity on its link-side hinges."""

from __future__ import annotations

import mujoco


def settle(plant, steps: int = 3000) -> None:
    """``steps`` MuJoCo steps of ``plant`` (a :class:`spherecal.controller.plant.Plant`) with zero commands."""
    m, d = plant.mj_model, plant.mj_data
    for _ in range(steps):
        mujoco.mj_step1(m, d)
        plant.apply_joint_gravity()
        d.ctrl[:] = 0.0
        mujoco.mj_step2(m, d)
