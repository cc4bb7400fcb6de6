"""plan's kinematic survey on a six-joint arm: one branch of its self-motion, as a recording has (new-arm trial)."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.correction import load_robot
from spherecal.identification.synthetic import fixture_samples
from spherecal.validation.planning.candidates import Candidate
from spherecal.validation.planning.plan import candidate_rng, survey_candidate
from tests.validation.new_arm_urdfs import big_urdf


@pytest.fixture
def big(tmp_path):
    (tmp_path / "big.urdf").write_text(big_urdf())
    return load_robot(tmp_path / "big.urdf", tip_link="ball")


def test_a_six_joint_arm_is_surveyed_along_one_branch(big):
    """Random configurations projected onto a socket land on every IK branch of a six-joint arm (shoulder front or
    back, elbow up or down, wrist flipped): the survey read 53-100 % of joints 1-3 at (0.8, -0.6, 0.5) m and the
    plan predicted 0.036 mm for its set, where the simulated recording (one branch) covered 4-13 % and calibrated to
    0.27 mm. One walk stays in one branch."""
    survey = survey_candidate(big, Candidate("C53", np.array([0.8, -0.6, 0.5])), seed=0)
    assert survey.reachable and survey.q.shape == (120, 6)
    assert survey.coverage[:3].max() < 0.25  # the joints before the wrist follow it on its sphere: a few per cent
    assert survey.coverage[3:].min() > 0.3  # the wrist turns


def test_a_seven_joint_arm_keeps_the_whole_manifold():
    """The Panda's survey is the projection of random configurations, as before (same samples)."""
    panda = load_robot("panda")
    candidate = Candidate("P2", np.array([0.5, 0.0, 0.4]))
    survey = survey_candidate(panda, candidate, seed=0)
    assert np.array_equal(survey.q, fixture_samples(panda, candidate.position, 120, candidate_rng(0, candidate),
                                                    0.0, max_rounds=3))
