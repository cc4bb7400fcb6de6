"""The parameter layout: one owner of names, kinds, units, prior spread and slices."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.correction import load_robot
from spherecal.correction.layout import ANGLE, LENGTH, layout_for


@pytest.mark.parametrize("n", [4, 6, 7])
def test_slices_names_and_kinds_agree(n: int) -> None:
    lay = layout_for(n)
    assert lay.size == len(lay.names) == len(lay.kinds)
    assert lay.names[lay.tool] == ("tool_x", "tool_y", "tool_z")
    assert lay.names[lay.base] == ("base_x", "base_y", "base_z", "base_roll", "base_pitch", "base_yaw")
    for field, kind in (("a", LENGTH), ("alpha", ANGLE), ("d", LENGTH), ("theta", ANGLE)):
        idx = lay.field(field)
        assert [lay.names[i] for i in idx] == [f"{field}{j + 1}" for j in range(n)]
        assert all(lay.kinds[i] is kind for i in idx)
    assert len(set(lay.names)) == lay.size
    with pytest.raises(KeyError, match="no parameter named 'beta9'"):
        lay.index("beta9")


def test_model_vector_round_trips_through_the_layout(rng) -> None:
    panda = load_robot("panda")
    lay = panda.layout
    values = rng.normal(size=lay.size)
    model = panda.with_params(values)
    np.testing.assert_array_equal(model.params, values)
    np.testing.assert_array_equal(model.alpha, values[lay.field("alpha")])
    np.testing.assert_array_equal(model.tool, values[lay.tool])
    np.testing.assert_array_equal(model.base_rpy, values[lay.base_rpy])


def test_spread_and_display_units() -> None:
    lay = layout_for(7)
    std = lay.spread(length=2e-3, angle=1e-3, tool=5e-3, base=False)
    assert np.all(std[lay.field("a")] == 2e-3) and np.all(std[lay.field("theta")] == 1e-3)
    assert np.all(std[lay.tool] == 5e-3) and np.all(std[lay.base] == 0.0)
    assert lay.format("d3", 1e-4) == "0.1 mm"
    assert lay.format("alpha2", np.deg2rad(0.5)) == "0.5 deg"
    np.testing.assert_allclose(lay.display_scale()[lay.field("theta")], np.rad2deg(1.0))
