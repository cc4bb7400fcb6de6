"""A joint CSV read in blocks: the angles, stamps and rows are the file's whatever the block size (each block is
appended in place, :class:`importers._Growing`), and a bad row in a later block is still named."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from spherecal.correction import load_robot
from spherecal.correction.files import csv_rows
from spherecal.identification.ingest import importers
from spherecal.identification.ingest.importers import RecordingError, read_joint_csv

JOINTS = [f"panda_joint{i + 1}" for i in range(7)]


def _write(path, t: np.ndarray | None, q: np.ndarray, extra: dict[int, str] = ()) -> None:
    """A CSV of ``q`` (T, 7) [rad], with a ``time`` column when ``t`` (T,) [s] is given; ``extra``: line index ->
    a line put there instead (comments, bad rows)."""
    head = (["time"] if t is not None else []) + JOINTS + ["panda_finger_joint1"]
    lines = [",".join(head)]
    for k, row in enumerate(q):
        lines.append(",".join(([repr(float(t[k]))] if t is not None else []) + [repr(float(v)) for v in row]
                              + ["0.04"]))
    for k, line in dict(extra).items():
        lines[k] = line
    path.write_text("\n".join(lines) + "\n")


def _in_blocks(monkeypatch, chunk: int) -> None:
    monkeypatch.setattr(importers, "iter_lines", functools.partial(csv_rows.iter_lines, chunk=chunk))


@pytest.mark.parametrize("timed", [True, False])
def test_blocks_of_any_size_read_the_same_recording(tmp_path, monkeypatch, timed) -> None:
    panda, rng = load_robot("panda"), np.random.default_rng(0)
    q = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8]) + rng.normal(0.0, 1e-3, (23, 7))
    t = 1.7e9 + np.arange(23) * 1e-3 if timed else None
    path = tmp_path / "rec.csv"
    _write(path, t, q)
    whole = read_joint_csv(path, panda)
    np.testing.assert_array_equal(whole.q, q)
    for chunk in (1, 4, 7, 50):
        _in_blocks(monkeypatch, chunk)
        read = read_joint_csv(path, panda)
        assert read.q.flags.c_contiguous and read.q.dtype == float
        np.testing.assert_array_equal(read.q, q)
        if timed:
            np.testing.assert_array_equal(read.t, t)
        else:
            assert read.t is None
        assert list(read.rows) == [f"{path}: row {k}" for k in range(2, 25)]


def test_a_dropped_repeat_and_a_careful_block_keep_the_rows_numbered(tmp_path, monkeypatch) -> None:
    panda = load_robot("panda")
    q = np.tile([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8], (12, 1)) + np.arange(12)[:, None] * 1e-4
    t = 1.7e9 + np.arange(12) * 1e-3
    t[6] = t[5]
    q[6] = q[5]  # a logger's repeat: dropped, one note
    path = tmp_path / "rec.csv"
    _write(path, t, q, {9: "# a comment in the third block"})  # that block is read line by line
    _in_blocks(monkeypatch, 4)
    read = read_joint_csv(path, panda)
    kept = [k for k in range(12) if k not in (6, 8)]  # line 9 (sample 8) is the comment
    np.testing.assert_array_equal(read.q, q[kept])
    assert [r.split("row ")[1] for r in read.rows] == [str(k + 2) for k in kept]
    assert any("dropped 1 rows repeating" in note for note in read.notes)


def test_a_bad_value_in_a_later_block_names_its_row_and_field(tmp_path, monkeypatch) -> None:
    panda = load_robot("panda")
    q = np.tile([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8], (12, 1))
    path = tmp_path / "rec.csv"
    _write(path, 1.7e9 + np.arange(12) * 1e-3, q, {10: "1700000000.009,0.0,-0.3,x,-2.2,0.0,2.0,0.8,0.04"})
    _in_blocks(monkeypatch, 4)
    with pytest.raises(RecordingError) as error:
        read_joint_csv(path, panda)
    assert str(error.value).startswith(f"{path}: row 11, field 'panda_joint3'")
    assert "\n" not in str(error.value)


def _rows(q: np.ndarray) -> list[str]:
    """One line per row of ``q`` (T, 7) [rad], stamped 1 ms apart, with the finger column ``_write`` writes."""
    return [",".join([repr(1.7e9 + k * 1e-3)] + [repr(float(v)) for v in row] + ["0.04"]) for k, row in enumerate(q)]


def test_a_row_short_of_an_unread_column_is_refused_even_beside_a_long_one(tmp_path) -> None:
    """A block whose lines hold the header's commas in total, one short and one long, was read by numpy's reader
    (it takes the columns asked of each line): the short row is named, as it is alone."""
    panda = load_robot("panda")
    q = np.tile([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8], (6, 1)) + np.arange(6)[:, None] * 1e-4
    rows = _rows(q)
    rows[1] = rows[1].rsplit(",", 1)[0]  # no finger value
    rows[2] += ",0.04"  # a finger value too many
    path = tmp_path / "rec.csv"
    path.write_text("\n".join([",".join(["time", *JOINTS, "panda_finger_joint1"]), *rows]) + "\n")
    with pytest.raises(RecordingError) as error:
        read_joint_csv(path, panda)
    assert str(error.value).startswith(f"{path}: row 3, field 'panda_finger_joint1': 8 fields, the header has 9")


def test_a_value_past_the_last_named_column_is_refused_naming_its_row(tmp_path) -> None:
    panda = load_robot("panda")
    q = np.tile([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8], (6, 1)) + np.arange(6)[:, None] * 1e-4
    rows = _rows(q)
    rows[3] += ",0.5"
    path = tmp_path / "rec.csv"
    path.write_text("\n".join([",".join(["time", *JOINTS, "panda_finger_joint1"]), *rows]) + "\n")
    with pytest.raises(RecordingError) as error:
        read_joint_csv(path, panda)
    assert str(error.value).startswith(f"{path}: row 5, field 'column 10': 10 fields, the header has 9")
    assert "\n" not in str(error.value)


def test_a_trailing_comma_on_every_row_is_read_as_without_it(tmp_path) -> None:
    """A logger's trailing comma adds an empty field past the header's: nothing to misread, the rows are read."""
    panda = load_robot("panda")
    q = np.tile([0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8], (6, 1)) + np.arange(6)[:, None] * 1e-4
    head = ",".join(["time", *JOINTS, "panda_finger_joint1"])
    plain, trailing = tmp_path / "plain.csv", tmp_path / "trailing.csv"
    plain.write_text("\n".join([head, *_rows(q)]) + "\n")
    trailing.write_text("\n".join([head, *(row + "," for row in _rows(q))]) + "\n")
    np.testing.assert_array_equal(read_joint_csv(trailing, panda).q, read_joint_csv(plain, panda).q)
    np.testing.assert_array_equal(read_joint_csv(trailing, panda).q, q)


def test_plain_values_leaves_a_ragged_block_to_the_careful_reader() -> None:
    """Two lines with the header's commas in total but not each: not plain (None), whatever columns are asked."""
    assert csv_rows.plain_values(["1,2,3\n", "4,5,6\n"], 3, [0, 1]).tolist() == [[1.0, 2.0], [4.0, 5.0]]
    assert csv_rows.plain_values(["1,2\n", "4,5,6,7\n"], 3, [0, 1]) is None
