"""The one reach search behind the simulations' default fixtures and the plan's restricted candidates."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.controller.reach import UnreachableFixtureError
from spherecal.correction import tool_point
from spherecal.identification.synthetic import project_to_point
from spherecal.validation.planning.postures import reach_configuration, reaches


def test_the_reach_configuration_is_on_the_point_and_the_least_cramped_of_its_seeds(panda):
    """On the point, inside the limits, and no farther from them than any converged seed (against a brute force over
    the seeds' own projections, each landed by a long projection from the same draw)."""
    centre = np.array([0.5, -0.1, 0.4])
    q = reach_configuration(panda, centre, np.random.default_rng(3), seeds=40)
    assert np.linalg.norm(tool_point(panda, q) - centre) < 1e-9
    assert panda.within_limits(q[None])[0]
    share = np.minimum(q - panda.lower, panda.upper - q) / (panda.upper - panda.lower)
    seeds = panda.random_configurations(40, np.random.default_rng(3))
    others = []
    for start in seeds:  # one at a time (in a batch, a converged row steps on until every row has)
        landed, ok = project_to_point(panda, start[None], centre, iterations=60)
        if ok[0]:
            others.append(np.min(np.minimum(landed[0] - panda.lower, panda.upper - landed[0]) /
                                 (panda.upper - panda.lower)))
    assert others and share.min() >= max(others) - 1e-6


def test_no_reach_configuration_beyond_the_reach(panda):
    with pytest.raises(UnreachableFixtureError, match=r"no configuration inside the joint limits reaches \[2.0"):
        reach_configuration(panda, np.array([2.0, 0.0, 0.3]), np.random.default_rng(0), seeds=20)


def test_reaches_says_no_inside_the_column_and_beyond_the_reach_and_yes_at_the_defaults(panda):
    assert not reaches(panda, np.array([0.0, 0.05, 0.2]))  # inside the base column (0.12 m around it)
    assert not reaches(panda, np.array([1.2, 0.0, 0.9]))  # 1.5 m from the base, beyond 1.393 m
    assert reaches(panda, np.array([0.5, -0.25, 0.5]))  # the simulations' P1
    # the same answer every run (its own seeded draws, none from a caller's generator)
    point = np.array([0.3, 0.6, 0.7])
    assert len({reaches(panda, point) for _ in range(3)}) == 1
