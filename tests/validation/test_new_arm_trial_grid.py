"""plan --grid auto: candidates over the arm's own reach (new-arm trial: a 0.45 m and a 1.3 m six-joint arm)."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.cli import main
from spherecal.correction import load_robot
from spherecal.validation.planning.candidates import auto_grid
from tests.validation.new_arm_urdfs import big_urdf, small_urdf


@pytest.fixture
def arms(tmp_path):
    (tmp_path / "big.urdf").write_text(big_urdf())
    (tmp_path / "small.urdf").write_text(small_urdf())
    return tmp_path


def test_the_auto_grid_follows_the_arms_size(arms):
    """A plan from scratch needed a box grid typed in metres, with nothing to say how large: for a new arm the
    engineer guessed (a 5x5x5 grid to 1.2 m left 13 of 125 candidates out of a 1.3 m arm's reach)."""
    spans = {}
    for name in ("small", "big"):
        model = load_robot(arms / f"{name}.urdf", tip_link="ball")
        grid = np.array([c.position for c in auto_grid(model, np.random.default_rng(0))])
        assert grid.shape == (125, 3) and (grid[:, 0] >= 0).all() and (grid[:, 2] >= 0).all()
        assert np.abs(grid).max() < model.reach  # each coordinate inside the reach (a corner may be beyond it)
        spans[name] = np.ptp(grid, axis=0)
    assert (spans["big"] > 2.5 * spans["small"]).all()  # 1.3 m against 0.45 m of reach


def test_plan_without_candidates_names_the_auto_grid(arms, capsys):
    assert main(["plan", "--robot", str(arms / "small.urdf"), "--tip-link", "ball"]) == 1
    assert "--grid auto" in capsys.readouterr().err
