"""The plain geometry behind the recordings: link capsules, colour ramp, histograms, parameter bars."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.correction.layout import ANGLE, LENGTH, layout_for
from spherecal.validation.viewer.recording_shapes import (
    BAR_HEIGHT,
    capsules,
    colour_ramp,
    covered_axis_height,
    histogram,
    parameter_bars,
)


def _rotate(quaternion: np.ndarray, vector: np.ndarray) -> np.ndarray:
    """Rotate ``vector`` by the unit quaternion (x, y, z, w) through its rotation matrix."""
    x, y, z, w = quaternion
    matrix = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])
    return matrix @ vector


def test_capsules_run_from_each_point_to_the_next(rng) -> None:
    strips = rng.normal(size=(5, 6, 3))
    strips[0, 2] = strips[0, 1]  # a zero-length link (coincident DH origins)
    strips[1, 3] = strips[1, 2] - np.array([0.0, 0.0, 0.4])  # straight down: the half-way formula degenerates
    lengths, starts, quats = capsules(strips)
    assert lengths.shape == (5, 5) and starts.shape == (5, 5, 3) and quats.shape == (5, 5, 4)
    assert np.allclose(np.linalg.norm(quats, axis=-1), 1.0)
    for t in range(5):
        for k in range(5):
            end = starts[t, k] + lengths[t, k] * _rotate(quats[t, k], np.array([0.0, 0.0, 1.0]))
            assert np.allclose(end, strips[t, k + 1], atol=1e-12), (t, k)
    assert lengths[0, 1] == 0.0 and np.allclose(lengths[1, 2], 0.4)


def test_colour_ramp_and_histogram() -> None:
    colours = colour_ramp(np.array([-1.0, 0.0, 0.5, 1.0, 7.0]))
    assert colours.dtype == np.uint8 and colours.shape == (5, 3)
    assert np.array_equal(colours[0], colours[1]) and np.array_equal(colours[3], colours[4])  # clipped
    assert colours[1][2] > colours[1][0] and colours[3][0] > colours[3][2]  # blue small, red large
    counts, left, width = histogram(np.array([0.0, 0.1, 0.2, 2.9, 3.0]), bins=3)
    assert counts.tolist() == [3, 0, 2] and np.allclose(left, [0, 1, 2]) and width == 1.0


def test_parameter_bars_scale_each_group_to_its_largest_value() -> None:
    names = ["a2", "alpha2", "d7 + tool_z"]
    change, std = np.array([1e-3, np.deg2rad(0.1), -2e-3]), np.array([1e-5, np.deg2rad(0.01), 1e-4])
    truth = np.array([1.1e-3, np.deg2rad(0.1), -2e-3])
    bars = parameter_bars(names, [LENGTH, ANGLE, LENGTH], change, std, truth)
    lengths, angles = bars["lengths"], bars["angles"]
    assert lengths["labels"] == ["a2", "d7 + tool_z"] and angles["labels"] == ["alpha2"]
    # y points down in Rerun's 2D view: a positive change is a bar above zero (negative y)
    assert lengths["mins"][0, 1] < 0 and np.isclose(lengths["mins"][1, 1], 0.0)
    reach = 2.1  # mm: |d7 + tool_z| + its std
    assert np.allclose(lengths["sizes"][:, 1], np.array([1.0, 2.0]) * BAR_HEIGHT / reach)
    assert lengths["scale_label"] == "2.100 mm" and angles["scale_label"] == "0.110 deg"
    assert np.allclose(lengths["truth"][:, 1], -np.array([1.1, -2.0]) * BAR_HEIGHT / reach)
    assert np.allclose(np.abs(np.diff(lengths["whiskers"][:, :, 1], axis=1)).ravel(),
                       2 * np.array([0.01, 0.1]) * BAR_HEIGHT / reach)


def test_parameter_bars_take_each_unit_from_the_layout_not_the_name() -> None:
    """A Hayati ``beta`` is an angle (deg) and a compliance ``c`` its own kind (urad/Nm), though
    neither name says so: the layout's kinds decide the panel, its unit and its scale."""
    layout = layout_for(7, hayati=(2,), elastic=True)
    names = ["a2", "beta3", "c2"]
    kinds = [layout.kinds[layout.index(n)] for n in names]
    change = np.array([1e-3, np.deg2rad(0.05), 2e-6])  # 1 mm, 0.05 deg, 2 urad/Nm
    bars = parameter_bars(names, kinds, change, np.zeros(3))
    assert set(bars) == {"lengths", "angles", "compliances"}
    assert bars["angles"]["labels"] == ["beta3"] and bars["angles"]["scale_label"] == "0.050 deg"
    assert bars["compliances"]["labels"] == ["c2"] and bars["compliances"]["scale_label"] == "2.000 urad/Nm"
    assert bars["lengths"]["scale_label"] == "1.000 mm" and bars["compliances"]["unit"] == "urad/Nm"
    with pytest.raises(ValueError, match="kinds"):
        parameter_bars(names, kinds[:2], change, np.zeros(3))


def test_parameter_bars_wear_no_model_s_colour() -> None:
    """Negative changes were red bars and positive ones blue: the colours of the nominal and the calibrated model in
    the Errors, Residuals and Socket spread views of the same recording. The sign is the bar's direction."""
    from spherecal.validation.viewer.recording import COLOURS

    bars = parameter_bars(["a2", "d3"], [LENGTH, LENGTH], np.array([1e-3, -1e-3]), np.full(2, 1e-5))["lengths"]
    assert np.all(bars["sizes"][:, 1] > 0) and bars["mins"][0, 1] < 0 <= bars["mins"][1, 1]  # up, down
    used = {tuple(int(v) for v in c) for c in bars["colours"]}
    assert used.isdisjoint({COLOURS["nominal"], COLOURS["calibrated"]})


def test_round_up_gives_one_two_or_five_times_a_power_of_ten() -> None:
    from spherecal.validation.viewer.recording_shapes import round_up

    assert [round_up(v) for v in (0.7e-3, 1e-3, 1.3e-3, 3e-3, 6e-3, 0.04)] == pytest.approx(
        [1e-3, 1e-3, 2e-3, 5e-3, 1e-2, 0.05])


def test_magnification_fills_the_sphere_with_the_scatter_and_names_a_round_radius(rng) -> None:
    """The samples' 95th percentile offset fits the sphere once magnified, and the sphere's radius stands for a
    round figure; a scatter as wide as the sphere is drawn as it is."""
    from spherecal.validation.viewer.recording_shapes import magnification

    offsets = rng.normal(0.0, 0.25e-3, (1500, 3))  # a calibrated socket: 0.25 mm per axis
    gain, reach = magnification(offsets, 0.05)
    far = np.quantile(np.linalg.norm(offsets, axis=1), 0.95)
    assert reach == pytest.approx(1e-3) and gain == pytest.approx(50.0)  # 0.7 mm -> the sphere stands for 1 mm
    assert far * gain <= 0.05 < 2.5 * far * gain
    assert magnification(rng.normal(0.0, 0.05, (100, 3)), 0.05) == (1.0, 0.05)
    assert magnification(np.zeros((3, 3)), 0.02) == (1.0, 0.02)


def test_scale_labels_label_every_fifth_sphere_from_bottom_to_top() -> None:
    from spherecal.validation.viewer.recording_shapes import SCALE_STEPS, scale_labels

    labels = scale_labels(1.0, 3.0, lambda v: f"{v:.1f} mm")
    assert len(labels) == SCALE_STEPS
    assert [label for label in labels if label] == ["1.0 mm", "1.5 mm", "2.0 mm", "2.5 mm", "3.0 mm"]


def test_covered_axis_height_is_where_the_capsules_leave_the_axis() -> None:
    """How high the link capsules (radius r) cover the base's z axis, against geometry worked by hand: an upright
    column capped by a level link covers it to the cap's height plus r; a link leaning at theta from the vertical, from
    height h, to h + r / sin(theta) (where the axis leaves the capsule's cylinder: the highest point of the axis within
    r of the link's line), here at a point the function samples (t = 1/4 of a 0.2771 m link, 41 points); a step that
    stands higher wins; an arm whose base is off the axis covers none of it."""
    r, h, theta = 0.04, 0.333, np.radians(30.0)
    upright = np.array([[0, 0, 0], [0, 0, h], [0, 0, 0.649], [0.3, 0, 0.649], [0.3, 0, 0.4]], dtype=float)
    assert covered_axis_height(upright[None], r) == pytest.approx(0.649 + r, abs=1e-12)
    length = 40 * np.sqrt(3) * r / 10  # the highest point at t = cos r / (L sin) = 10/40
    tip = np.array([length * np.sin(theta), 0.0, h + length * np.cos(theta)])
    leaning = np.array([[0, 0, 0], [0, 0, h], tip, tip + [0.3, 0, 0]], dtype=float)
    assert covered_axis_height(leaning[None], r) == pytest.approx(h + r / np.sin(theta), abs=1e-12)
    assert covered_axis_height(np.stack([leaning[:4], upright[:4]]), r) == pytest.approx(0.649 + r, abs=1e-12)
    assert covered_axis_height(upright[None] + [0.5, 0.0, 0.0], r) == 0.0
