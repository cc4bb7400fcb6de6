"""Self-motion at a fixture: the closed chain holds the true tool point, limits hold, coverage."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.controller import exploration
from spherecal.controller.exploration import CoverageExploration, Ramp, RunningExtent, joint_coverage
from spherecal.controller.nullspace import NullSpaceController
from spherecal.controller.reach import FixtureInsideRobotError, UnreachableFixtureError
from spherecal.controller.self_motion import (
    DEFAULT_FIXTURES,
    SelfMotionRun,
    SelfMotionSettings,
    collect_self_motion,
    home,
    reach_fixture,
)
from spherecal.correction import perturb, tool_point
from spherecal.correction.errors import ShapeError


@pytest.fixture(scope="module")
def short_run():
    from spherecal.correction import load_robot

    panda = load_robot("panda")
    rng = np.random.default_rng(11)
    true = perturb(panda, rng)
    fixtures = {"P2": DEFAULT_FIXTURES["P2"]}
    return collect_self_motion(true, panda, fixtures, rng, SelfMotionSettings(seconds=2.0, samples=200))


def test_short_run_holds_the_fixture(short_run):
    run = short_run
    assert run.q.shape == (200, 7) and run.labels.tolist() == ["P2"] * 200
    assert np.all(np.diff(run.t) > 0) and run.t.max() < 2.0
    assert run.max_violation[0] < 5e-5  # 0.05 mm
    assert run.max_deviation[0] < 5e-5
    assert run.limit_excess[0] == 0.0 and run.fallbacks == 0
    # the recorded true tool point is the TRUE model's FK of the joint readings, on the fixture
    assert np.abs(run.tool - tool_point(run.true_model, run.q)).max() < 1e-9
    assert np.linalg.norm(run.tool - np.array(DEFAULT_FIXTURES["P2"]), axis=1).max() < 5e-5
    # while the nominal model's idea of the tool point drifts (it is not fed back)
    nominal = tool_point(run.nominal_model, run.q)
    assert np.ptp(nominal, axis=0).max() > 1e-4
    # it moved: self-motion, not standing still
    assert run.coverage[0].max() > 0.05
    assert run.trajectory_q.shape == (200, 7) and np.allclose(np.diff(run.trajectory_t), 0.01)


def test_dataset_view(short_run):
    data = short_run.dataset()
    assert data.fixture_names == ("P2",) and data.q.shape == (200, 7) and data.t is not None


def test_progress_reports_every_simulated_second_and_changes_nothing(panda):
    # the long motion stage was silent; the callback gets simulated seconds, summing to the total
    true = perturb(panda, np.random.default_rng(7))
    fixtures = {"P1": DEFAULT_FIXTURES["P1"], "P2": DEFAULT_FIXTURES["P2"]}
    settings = SelfMotionSettings(seconds=0.35, samples=50)
    calls: list[float] = []
    run = collect_self_motion(true, panda, fixtures, np.random.default_rng(8), settings, progress=calls.append)
    quiet = collect_self_motion(true, panda, fixtures, np.random.default_rng(8), settings)
    assert len(calls) == 2 * 4  # 0.1, 0.1, 0.1, 0.05 per fixture
    assert np.isclose(sum(calls), 0.7) and max(calls) <= 0.1 + 1e-12
    assert np.array_equal(run.q, quiet.q)


def test_compliance_moves_the_point_not_the_readings(panda):
    rng = np.random.default_rng(5)
    true = perturb(panda, rng)
    run = collect_self_motion(true, panda, {"P": DEFAULT_FIXTURES["P2"]}, rng,
                              SelfMotionSettings(seconds=1.0, samples=100, noise=3e-4))
    assert 1e-4 < run.rms_deviation[0] < 1e-3
    # the readings are exact joint angles of the true robot, whose tool point sits off the centre
    assert np.abs(run.tool - tool_point(true, run.q)).max() < 1e-9
    assert run.limit_excess[0] == 0.0


def test_bad_fixtures_are_refused(panda, rng):
    with pytest.raises(UnreachableFixtureError, match="fixture far .* out of reach"):
        reach_fixture(panda, "far", np.array([1.5, 0.0, 0.3]), rng)
    with pytest.raises(FixtureInsideRobotError, match="fixture in .* inside the robot"):
        reach_fixture(panda, "in", np.array([0.02, 0.03, 0.2]), rng)
    # two numbers: our ShapeError naming the fixture before anything runs (was numpy's 'cannot reshape array of
    # size 2 into shape (3,)')
    with pytest.raises(ShapeError, match=r"^fixture P: expected a position \(3,\) \[m\], got shape \(2,\)$"):
        collect_self_motion(panda, panda, {"P": [0.5, 0.0]}, rng)


def test_ramp_is_smooth():
    ramp = Ramp(2, duration=0.3)
    ramp.retarget(0.0)
    values = np.array([ramp(t, np.array([1.0, -1.0])) for t in np.arange(0.0, 0.5, 1e-3)])
    assert values[0] == pytest.approx([0.0, 0.0]) and values[-1] == pytest.approx([1.0, -1.0])
    assert np.abs(np.diff(values, axis=0)).max() < 1e-2


def test_joint_coverage():
    q = np.array([[0.0, 0.0], [1.0, -0.5], [0.5, 0.5]])
    assert np.allclose(joint_coverage(q, np.array([-1.0, -1.0]), np.array([1.0, 1.0])), [0.5, 0.5])


def test_running_extent_reads_only_new_rows_and_equals_a_full_scan():
    # the coverage exploration rescanned the whole history at every decision: quadratic in --seconds
    rng = np.random.default_rng(3)
    history = np.cumsum(rng.normal(size=(400, 3)), axis=0)
    extent = RunningExtent(3)
    for end in (1, 2, 2, 57, 58, 300, 400):
        lo, hi = extent.update(history[:end])
        assert np.array_equal(lo, history[:end].min(axis=0)) and np.array_equal(hi, history[:end].max(axis=0))
    assert extent.count == 399  # the last row is read again next time (its caller may still be writing it)
    live = history[:10].copy()
    extent = RunningExtent(3)
    extent.update(live)
    live[9] = 1e3  # the row being filled changes before the next call: not kept from the first
    assert np.array_equal(extent.update(live)[1], live.max(axis=0))
    lo, hi = extent.update(history[:5])  # a shorter history: starts over
    assert np.array_equal(lo, history[:5].min(axis=0)) and np.array_equal(hi, history[:5].max(axis=0))


def test_a_goal_not_found_is_not_sought_again_from_the_same_place(panda, monkeypatch):
    # at a saturated fixture the same goals were sought (and missed) at every check, 50 ms apart: most of a
    # long simulation's time; now a goal missed at GOAL_MISSES decisions from one place is not sought from there
    kinematics = NullSpaceController(panda).kinematics  # MuJoCo's: 42 searches a decision
    misses_default = exploration.GOAL_MISSES
    searches: list[int] = []
    real_ik = exploration.ik
    monkeypatch.setattr(exploration, "ik", lambda *a, **k: searches.append(1) or real_ik(*a, **k))
    q = home(panda)
    far = np.array([2.0, 0.0, 0.5])  # out of reach: no goal is ever found

    def decisions(misses: int, count: int, moved: float = 0.0):
        monkeypatch.setattr(exploration, "GOAL_MISSES", misses)
        searches.clear()
        rng = np.random.default_rng(4)
        explore = CoverageExploration(panda, far, rng, kinematics=kinematics)
        history = np.vstack([q - 0.1, q + 0.1])  # the visited range: the goals stay where they are
        per_decision = []
        for k in range(count):
            start = len(searches)
            here = q + (moved if k == count - 1 else 0.0)
            explore.decide(0.05 * k, np.vstack([history, here]), None)
            assert explore.goal is None
            per_decision.append(len(searches) - start)
        return per_decision, rng.random()

    every, after_every = decisions(10**9, 4)  # sought at every decision, as before
    assert every[0] > 0 and every == [every[0]] * 4
    kept, after_kept = decisions(misses_default, 4)
    assert kept == every[:3] + [0]  # missed at 3 decisions from here: not sought again from here
    assert after_kept == after_every  # the restarts are drawn all the same: the random stream is unchanged
    moved, _ = decisions(misses_default, 4, moved=2 * exploration.GOAL_SAME_START)
    assert moved == every  # the arm moved (inside the visited range: the same goals): sought again


def test_coverage_table_labels_every_column_with_its_unit():
    # was: "q1 ... q7" without the % that "min%" had
    from types import SimpleNamespace

    run = SimpleNamespace(coverage=np.array([[0.5, 0.25]]), fixture_names=["P1"], max_violation=np.array([2e-6]),
                          limit_excess=np.array([0.0]))
    head, row = SelfMotionRun.coverage_table(run).splitlines()
    assert head.split() == ["fixture", "q1%", "q2%", "min%", "viol_mm", "limit_rad"]
    assert row.split()[:4] == ["P1", "50.0", "25.0", "25.0"]


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1])
def test_default_fixtures_cover_thirty_percent(panda, seed):
    rng = np.random.default_rng(seed)
    true = perturb(panda, rng)
    fixtures = {k: np.array(v) for k, v in DEFAULT_FIXTURES.items()}
    run = collect_self_motion(true, panda, fixtures, rng, SelfMotionSettings(seconds=20.0))
    print(run.coverage_table())
    assert np.all(run.coverage >= 0.30)
    assert np.all(run.max_violation < 5e-5)
    assert np.all(run.limit_excess == 0.0)
    assert run.fallbacks == 0
