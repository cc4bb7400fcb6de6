"""Let an elastic plant settle with its motors held (zero velocity commands): plain ``mj_step``, its MJCF puts
gravity on the link-side hinges."""

from __future__ import annotations

import mujoco


def settle(plant, steps: int = 3000) -> None:
    """``steps`` MuJoCo steps of ``plant`` (a :class:`spherecal.controller.plant.Plant`) with zero commands."""
    m, d = plant.mj_model, plant.mj_data
    d.ctrl[:] = 0.0
    for _ in range(steps):
        mujoco.mj_step(m, d)
