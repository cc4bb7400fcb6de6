"""The self-check's chi-square tail probability, written without scipy (start-up), against scipy.special."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.special import gammaincc

from spherecal.identification.consistency import log10_chi2_sf


@pytest.mark.parametrize("dof", [1, 2, 3, 7, 30, 101, 999, 4471, 20000])
def test_log10_chi2_sf_matches_scipy(dof) -> None:
    statistics = np.concatenate([np.linspace(0.0, 3.0 * dof + 50.0, 60), [10.0 * dof, 30.0 * dof + 2000.0]])
    for statistic in statistics:
        reference = float(np.log10(max(gammaincc(dof / 2.0, statistic / 2.0), 1e-300)))
        assert log10_chi2_sf(float(statistic), dof) == pytest.approx(reference, rel=1e-10, abs=1e-12)
