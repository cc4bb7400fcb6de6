"""The fixtures' labels in the main 3D view stay apart at its default camera (a review by screenshot).

Centred on their wire spheres, the labels of a plate's two sockets 50 mm apart were drawn one over the other, at an
arm's default camera (MUKCa panda_2_clean: 'back_left_h0' over 'back_left_h1', 'mid_right_h0' over 'mid_right_h1';
plan --samples: 'front_center_h0' over 'front_center_h1'). Each label is now a point's under ``world/fixtures``, moved
up the screen by a label's height when it would cover another."""

from __future__ import annotations

import numpy as np

from spherecal.validation.viewer.blueprint import FIELD_OF_VIEW, view_axes
from spherecal.validation.viewer.recording import (
    LABEL_ROW,
    WORLD_VIEW_HEIGHT,
    Recording,
    read_entity_rows,
    read_eyes,
)

from .test_validation import _scene

PLATE = np.array([[0.25, -0.25, 0.016], [0.25, -0.20, 0.016], [0.0, 0.28, 0.016], [0.0, 0.33, 0.016]])
NAMES = ["mid_right_h0", "mid_right_h1", "back_left_h0", "back_left_h1"]


def _record(path, panda, rng, centres, names):
    recording = Recording(path, title="Calibrated robot and sockets")
    recording.fixtures(names, centres)
    q = panda.random_configurations(30, rng)
    recording.self_motion(panda, np.arange(30) * 0.01, q)
    recording.socket_spread(names[0], rng.normal(0, 1e-3, (20, 3)), rng.normal(0, 1e-4, (20, 3)))
    recording.close()
    return _scene(path, "world/fixtures")["world/fixtures"]


def _row(path) -> float:
    """A label's height [m] at the main view's default camera."""
    eye, target = read_eyes(path)["world"]
    return LABEL_ROW * 2 * np.linalg.norm(eye - target) * np.tan(FIELD_OF_VIEW / 2) / WORLD_VIEW_HEIGHT


def test_a_plate_s_socket_labels_stand_a_label_apart(tmp_path, panda, rng) -> None:
    fixtures = _record(tmp_path / "s.rrd", panda, rng, PLATE, NAMES)
    assert read_entity_rows(tmp_path / "s.rrd")["world/fixtures"] == 1
    assert fixtures["labels"] == NAMES and fixtures["show_labels"] == [True]  # the points' labels, shown
    places = np.array(fixtures["positions"])
    right, up, _ = view_axes()
    row = _row(tmp_path / "s.rrd")
    for a, b in ((0, 1), (2, 3)):  # the two sockets of each placement
        assert abs((places[a] - places[b]) @ up) >= 0.99 * row, (NAMES[a], NAMES[b])
    # moved only up the screen, never across it nor further than the labels need
    offsets = places - PLATE
    np.testing.assert_allclose(offsets @ right, 0.0, atol=1e-6)  # stored as float32
    assert np.all(offsets @ up >= -1e-6) and np.max(offsets @ up) <= 2.01 * row


def test_labels_of_fixtures_far_apart_stay_at_their_centres(tmp_path, panda, rng) -> None:
    centres = np.array([[0.5, -0.25, 0.5], [0.5, 0.0, 0.4], [0.45, 0.25, 0.45]])
    fixtures = _record(tmp_path / "d.rrd", panda, rng, centres, ["P1", "P2", "P3"])
    np.testing.assert_allclose(np.array(fixtures["positions"]), centres, atol=1e-6)


def test_the_spheres_carry_the_names_but_do_not_draw_them(tmp_path, panda, rng) -> None:
    """One label per fixture on the screen: the spheres' own, centred on them, would stand over the moved ones."""
    from rerun.chunk import RrdReader

    _record(tmp_path / "s.rrd", panda, rng, PLATE, NAMES)
    chunk = next(c for c in RrdReader(str(tmp_path / "s.rrd")).stream().to_chunks()
                 if c.entity_path.strip("/") == "world/fixtures")
    batch = chunk.to_record_batch()
    assert batch.column("Ellipsoids3D:labels").to_pylist()[0] == NAMES
    assert batch.column("Ellipsoids3D:show_labels").to_pylist()[0] == [False]
