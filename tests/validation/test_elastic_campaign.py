"""Campaign row with an elastic true robot: the elastic model removes the sag error dh cannot express."""

import numpy as np
import pytest

from spherecal.validation.experiments.campaign import CampaignConfig, run_task, tasks


@pytest.mark.slow
def test_elastic_row_dh_versus_elastic_noise_free():
    base = dict(sets=1, samples=150, configurations=300, source="synthetic", fixture_sets=("Pall",),
                noise_levels=(0.0,), stiffness=(0, 3e4, 3e4, 3e4, 0, 0, 0))
    errors = {}
    for model in ("dh", "elastic"):
        (task,) = tasks(CampaignConfig(model=model, **base))
        assert task.row == ("PallE" if model == "dh" else "PallE/elastic")
        result = run_task(task)
        assert not result.refused
        errors[model] = result.mean
    assert errors["elastic"] < 0.01e-3 < 0.1e-3 < errors["dh"]  # exact data: only the model's own error remains
    assert np.isfinite(errors["dh"])
