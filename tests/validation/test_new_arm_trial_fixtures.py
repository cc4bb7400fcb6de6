"""simulate's default fixtures on arms that are not a Panda (a trial of a 0.45 m and a 1.3 m six-joint arm)."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.cli import main
from spherecal.correction import load_robot
from spherecal.validation.experiments.experiment import default_fixtures
from tests.validation.new_arm_urdfs import big_urdf, small_urdf


@pytest.fixture
def arms(tmp_path):
    (tmp_path / "big.urdf").write_text(big_urdf())
    (tmp_path / "small.urdf").write_text(small_urdf())
    return tmp_path


def test_a_small_arm_simulates_at_its_default_fixtures(arms, capsys):
    """The Panda's points are 0.24 m beyond a 0.45 m arm's reach: simulate refused its defaults ('default fixture
    P1 ... out of reach'); it now scales them to the arm's reach and says where they are."""
    out = arms / "sim"
    assert main(["simulate", "--robot", str(arms / "small.urdf"), "--tip-link", "ball", "--out", str(out),
                 "--seconds", "1", "--per-fixture", "50"]) == 0
    said = capsys.readouterr().out
    assert "the Panda's default fixtures are out of this arm's reach: scaled to its reach" in said
    assert "give your own with --fixtures" in said
    small = load_robot(arms / "small.urdf", tip_link="ball")
    points = default_fixtures(small)
    assert all(0.1 < np.linalg.norm(p[:2]) < 0.4 for p in points.values())  # in front of the base, inside 0.45 m


def test_arms_that_reach_the_pandas_points_keep_them(arms):
    """The Panda's defaults are unchanged for the Panda and for every arm that reaches them (its simulations too)."""
    panda = default_fixtures()
    for robot in (load_robot("panda"), load_robot("iiwa14"), load_robot(arms / "big.urdf", tip_link="ball")):
        points = default_fixtures(robot)
        assert all(np.array_equal(points[k], panda[k]) for k in panda)


def test_a_fixture_out_of_reach_says_what_to_do(arms, capsys):
    """'fixture P1 at [0.5, -0.25, 0.5] m is out of reach (IK ... misses it by 238.6 mm)' said what was wrong, not
    what to do."""
    fixtures = arms / "far.yaml"
    fixtures.write_text("fixtures:\n  P1: {position: [0.5, -0.25, 0.5]}\n")
    assert main(["simulate", "--robot", str(arms / "small.urdf"), "--tip-link", "ball", "--fixtures", str(fixtures),
                 "--out", str(arms / "sim"), "--seconds", "1", "--per-fixture", "50"]) == 1
    error = capsys.readouterr().err
    assert "out of reach" in error and "move it where the arm reaches" in error and "--grid auto" in error
    assert error.count("\n") == 1
