"""What the stillness segmentation says when it cannot tell the sockets apart."""

from __future__ import annotations

import numpy as np
import pytest

from spherecal.correction import load_robot, tool_point
from spherecal.identification.ingest.segment import SegmentationError, segment


def _stream_parts():
    """The embedded Panda, a 200 Hz rate, a start posture, and two pieces of a recording: ``still(q)`` 3 s held at
    ``q`` with 1e-5 rad jitter (seeded), ``move(a, b)`` a 1 s straight transit [rad]."""
    panda, rng, rate = load_robot("panda"), np.random.default_rng(0), 200.0
    q_a = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])

    def still(q):
        return q + rng.normal(0.0, 1e-5, (int(3 * rate), 7))

    def move(a, b):
        return a + np.linspace(0.0, 1.0, int(rate))[:, None] * (b - a)

    return panda, rate, q_a, still, move


def test_one_socket_seen_twice_names_the_still_radius_beside_labelling() -> None:
    """Two still stretches 10 mm apart: one socket twice (the ball re-seated, or a self-motion whose nominal tool
    point wanders by the arm's own error) or two sockets too close. The refusal named only labelling; a user of a
    real Panda needed --still-radius (a review: 5 mm for its 8 mm nominal spread)."""
    panda, rate, q_a, still, move = _stream_parts()
    q_b = q_a + np.array([0.02, 0, 0, 0, 0, 0, 0])
    away = q_a + np.array([0.6, 0.3, 0, 0.3, 0, 0, 0])
    q = np.vstack([still(q_a), move(q_a, away), move(away, q_b), still(q_b)])
    gap = np.linalg.norm(tool_point(panda, q_a) - tool_point(panda, q_b))
    assert 5e-3 < gap < 30e-3
    with pytest.raises(SegmentationError, match="one socket twice or two sockets too close") as refused:
        segment(panda, q, np.arange(len(q)) / rate, where="rec.csv: ")
    assert "label the fixtures (--fixture NAME=START:END, or a CSV's 'fixture' column)" in str(refused.value)
    assert "--still-radius above 3 mm" in str(refused.value)


def test_a_refused_stretch_names_its_rows_beside_its_seconds() -> None:
    """A review (a ROS bag visiting one socket twice): the refusal gave the stretches in seconds from the start,
    no row or message of the file."""
    from spherecal.correction.files.csv_rows import RowNames

    panda, rate, q_a, still, move = _stream_parts()
    away = q_a + np.array([0.6, 0.3, 0, 0.3, 0, 0, 0])
    q_b = q_a + np.array([0.02, 0, 0, 0, 0, 0, 0])  # 10 mm on: one socket twice or two too close, ambiguous
    q = np.vstack([still(q_a), move(q_a, away), move(away, q_b), still(q_b)])
    rows = RowNames("rec.csv", np.arange(len(q)) + 2)  # the header is row 1
    with pytest.raises(SegmentationError) as refused:
        segment(panda, q, np.arange(len(q)) / rate, where="rec.csv", sources=rows)
    text = str(refused.value)
    found = [tuple(int(v) for v in m) for m in __import__("re").findall(r"\(rec\.csv: row (\d+)-(\d+)\)", text)]
    assert len(found) == 2, text
    (a0, a1), (b0, b1) = found
    assert 2 <= a0 < a1 < 2 + 600 and 2 + 1000 <= b0 < b1 <= 2 + len(q) - 1, found  # within each held stretch


def test_a_socket_visited_again_is_one_fixture() -> None:
    """A review: a ROS bag that came back to a socket (the ball re-seated) was refused as 'one socket twice', with
    remedies a bag cannot take (a 'fixture' column) or that cannot help (--still-radius). A later stretch whose mean
    tool point is within the visits' own spread of an earlier socket's is that socket again: one fixture."""
    from spherecal.identification.ingest.segment import format_segments, labels_of, revisit_notes

    panda, rate, q_a, still, move = _stream_parts()
    other = q_a + np.array([0.3, 0.2, 0, 0.2, 0, 0, 0])  # another socket, decimetres away
    q = np.vstack([still(q_a), move(q_a, other), still(other), move(other, q_a), still(q_a)])
    found = segment(panda, q, np.arange(len(q)) / rate)
    assert [(seg.name, seg.visit) for seg in found] == [("S1", 1), ("S2", 1), ("S1", 2)]
    labels = labels_of(found, len(q))
    assert set(labels[:600]) <= {"S1", ""} and set(labels[-600:]) <= {"S1", ""} and "S2" in set(labels[800:1400])
    assert np.sum(labels == "S1") == len(found[0].rows) + len(found[2].rows)
    (note,) = revisit_notes(found)
    assert note.startswith("S1 visited 2 times") and note.endswith("one fixture")
    assert "S1 visit 2" in format_segments(found)


def test_a_csv_timed_by_rate_says_so_when_segmentation_fails(tmp_path, capsys) -> None:
    """A review: '--rate 100' on a 1 kHz CSV without a time column was refused as a drifting stretch, with no word of
    the rate that timed the rows."""
    from tests.refusal import refused

    rng = np.random.default_rng(0)
    q_a = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8])
    q = q_a + rng.normal(0.0, 1e-5, (600, 7))  # 3 s held at 200 Hz: 0.3 s at 2 kHz, shorter than --min-duration
    lines = [",".join(f"panda_joint{i}" for i in range(1, 8))] + [",".join(f"{v:.9f}" for v in row) for row in q]
    (tmp_path / "rec.csv").write_text("\n".join(lines) + "\n")
    refused(["import", tmp_path / "rec.csv", "--format", "csv", "--robot", "panda", "--rate", "2000", "--out",
             tmp_path / "out"], tmp_path, capsys, "no fixture found", "timed by --rate 2000 Hz (no time column)")


def test_a_raised_still_radius_does_not_merge_two_sockets() -> None:
    """A review: following a refusal's '--still-radius above 6 mm' with 21 mm merged two sockets 20 mm apart into one
    fixture ('S1 visit 2'); a revisit is judged by the visits' own spread, not by the stillness radius."""
    from spherecal.identification.ingest.segment import SegmentSettings

    panda, rate, q_a, still, move = _stream_parts()
    q_b = q_a + np.array([0.04, 0, 0, 0, 0, 0, 0])
    away = q_a + np.array([0.6, 0.3, 0, 0.3, 0, 0, 0])
    q = np.vstack([still(q_a), move(q_a, away), move(away, q_b), still(q_b)])
    gap = np.linalg.norm(tool_point(panda, q_a) - tool_point(panda, q_b))
    assert 0.01 < gap < 0.025
    with pytest.raises(SegmentationError, match="one socket twice or two sockets too close"):
        segment(panda, q, np.arange(len(q)) / rate, SegmentSettings(still_radius=0.025))


def test_tool_points_in_blocks_are_the_points_of_all_samples_at_once(monkeypatch) -> None:
    """The stillness test's tool points are computed a block of samples at a time (the chain's temporaries of 1.8 M
    samples at once peaked at 410 MB): the same numbers, bit for bit, and the same fixtures."""
    from spherecal.identification.ingest import segment as segment_module

    panda, rate, q_a, still, move = _stream_parts()
    other = q_a + np.array([0.3, 0.2, 0, 0.2, 0, 0, 0])
    q = np.vstack([still(q_a), move(q_a, other), still(other)])
    whole = segment(panda, q, np.arange(len(q)) / rate)
    monkeypatch.setattr(segment_module, "POINT_BLOCK", 97)  # blocks that do not divide the samples
    np.testing.assert_array_equal(segment_module._tool_points(panda, q), tool_point(panda, q))
    blocked = segment(panda, q, np.arange(len(q)) / rate)
    assert [(s.name, s.start, s.end, s.spread_max) for s in blocked] == [(s.name, s.start, s.end, s.spread_max)
                                                                         for s in whole]
    assert len(whole) == 2 and all(np.array_equal(a.centre, b.centre) and np.array_equal(a.rows, b.rows)
                                   for a, b in zip(blocked, whole, strict=True))
