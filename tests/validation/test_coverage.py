"""Joint coverage counted up to one turn: plan's table and the Rerun coverage bars."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from spherecal.controller.exploration import TURN, joint_coverage
from spherecal.validation.planning.candidates import Candidate
from spherecal.validation.planning.plan import survey_candidate

#: A UR5e's limits: +-2 pi everywhere, the elbow (q3) +-pi.
UR_LOWER = np.array([-2, -2, -1, -2, -2, -2]) * np.pi
UR_UPPER = -UR_LOWER


def test_a_full_turn_of_a_joint_limited_to_two_turns_reads_100_percent() -> None:
    """q1 on +-2 pi swept through one turn read 50 % (and a sweep of 0.5 rad 4 % in a UR trial); the kinematics
    cannot tell q from q + 2 pi, so one turn is all there is to see. One definition: the simulation's exploration,
    its printed table, plan and the Rerun bars (two read 50 % and 100 % for the same sweep)."""
    turn = np.linspace(-np.pi, np.pi, 50)
    q = np.zeros((50, 6))
    q[:, 0] = turn  # one full turn
    q[:, 1] = 2 * turn  # both turns: still all there is to see, not 200 %
    q[:, 2] = turn  # the elbow's whole +-pi range
    q[:, 3] = turn / 2  # half a turn of a +-2 pi joint
    q[:, 4] = np.linspace(0.0, 0.5, 50)
    np.testing.assert_allclose(joint_coverage(q, UR_LOWER, UR_UPPER), [1.0, 1.0, 1.0, 0.5, 0.5 / TURN, 0.0])


def test_a_joint_within_one_turn_reads_the_share_of_its_range(panda, rng) -> None:
    q = panda.random_configurations(30, rng)
    reference = (q.max(axis=0) - q.min(axis=0)) / (panda.upper - panda.lower)  # the paper's Fig. 5
    np.testing.assert_allclose(joint_coverage(q, panda.lower, panda.upper), reference)
    locked = panda.upper.copy()
    locked[2] = panda.lower[2]  # a joint without range: 0, no division by zero
    q[:, 2] = locked[2]
    assert joint_coverage(q, panda.lower, locked)[2] == 0.0


def test_plan_survey_counts_a_long_joint_against_one_turn(panda) -> None:
    lower, upper = panda.lower.copy(), panda.upper.copy()
    lower[0], upper[0] = -TURN, TURN  # q1 widened to +-2 pi (a UR's)
    wide = replace(panda, lower=lower, upper=upper)
    survey = survey_candidate(wide, Candidate("A", np.array([0.5, 0.0, 0.4])), seed=0, count=60)
    assert survey.reachable
    q1 = np.ptp(survey.q[:, 0])
    assert q1 > 0.1
    np.testing.assert_allclose(survey.coverage[0], min(q1, TURN) / TURN)  # not q1 / (4 pi)
    np.testing.assert_allclose(survey.coverage[1:], joint_coverage(survey.q, panda.lower, panda.upper)[1:])


def test_the_coverage_bars_count_a_long_joint_against_one_turn(tmp_path) -> None:
    from rerun.chunk import RrdReader

    from spherecal.validation.viewer.recording import Recording

    q = np.zeros((40, 6))
    q[:, 0] = np.linspace(-np.pi, np.pi, 40)
    q[:, 3] = np.linspace(0.0, np.pi, 40)
    recording = Recording(tmp_path / "c.rrd")
    recording.coverage({"P1": q}, UR_LOWER, UR_UPPER)
    recording.close()
    bars = None
    for chunk in RrdReader(str(tmp_path / "c.rrd")).stream().to_chunks():
        if chunk.entity_path.strip("/") == "coverage/P1":
            batch = chunk.to_record_batch()
            bars = [batch.column(n).to_pylist()[0] for n in batch.schema.names if n.endswith(":values")]
    assert bars, "no coverage/P1 values in the recording"
    values = bars[0][0] if isinstance(bars[0], list) else bars[0]  # a tensor: shape, names, buffer
    np.testing.assert_allclose(values["buffer"], [100, 0, 0, 50, 0, 0], atol=1e-9)
