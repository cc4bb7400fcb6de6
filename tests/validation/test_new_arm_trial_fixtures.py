"""simulate's default fixtures on arms that are not a Panda (a trial of a 0.45 m and a 1.3 m six-joint arm)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from spherecal.cli import main
from spherecal.correction import load_robot
from spherecal.validation.experiments.experiment import arm_reach, column_top, default_fixtures, reach_scale
from tests.controller.test_generic_arm import UR5
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


def test_each_arm_is_measured_from_its_own_geometry_and_the_panda_from_the_embedded_one():
    """The Panda's reach (1.06 m) and column top (0.333 m) the defaults are scaled from were typed-in constants; they
    are measured on the embedded Panda now, and every arm by its own DH table (the hand sums below)."""
    panda = load_robot("panda")
    # the Panda's table: d1 0.333 (the column), then d3 0.316, a4 0.0825, a5 0.0825, d5 0.384, a7 0.088, flange 0.107
    assert column_top(panda) == pytest.approx([0.0, 0.0, 0.333], abs=1e-12)
    assert arm_reach(panda) == pytest.approx(0.316 + 0.0825 + 0.0825 + 0.384 + 0.088 + 0.107, abs=1e-12)
    assert reach_scale(panda) == 1.0
    iiwa = load_robot("iiwa14")  # d1 0.36 (the column), d3 0.42, d5 0.4, flange 0.126
    assert column_top(iiwa) == pytest.approx([0.0, 0.0, 0.36], abs=1e-12)
    assert reach_scale(iiwa) == pytest.approx((0.42 + 0.4 + 0.126) / 1.06, abs=1e-12)
    # standard DH: the column is d1 along the first axis; the tool [0, 0.05, 0.1] counts as its length
    assert column_top(UR5) == pytest.approx([0.0, 0.0, 0.089159], abs=1e-12)
    links = 0.425 + 0.39225 + 0.10915 + 0.09465 + 0.0823 + np.hypot(0.05, 0.1)
    assert arm_reach(UR5) == pytest.approx(links, abs=1e-12)


@pytest.mark.parametrize("k", [0.5, 0.7])
def test_a_panda_shrunk_by_k_gets_the_pandas_points_times_k(k):
    """Every length of the Panda times k (its column top at k x 0.333 m, its reach k x 1.06 m, the same joint limits):
    it reaches k x p exactly where the Panda reaches p, so its defaults are the Panda's times k (it misses some of
    the Panda's own: all three at 0.5, P1 at 0.7)."""
    panda = load_robot("panda")
    small = replace(panda, a=panda.a * k, d=panda.d * k, tool=panda.tool * k)
    points, reference = default_fixtures(small), default_fixtures()
    for name, point in reference.items():
        assert points[name] == pytest.approx(k * point, abs=1e-12)
