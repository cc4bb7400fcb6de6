"""A file that is not UTF-8 is refused on one line naming the row (and, in a CSV, the field) of its first bad byte and
what it likely is; a UTF-8 file with a byte-order mark or CRLF line ends is read as without them."""

from __future__ import annotations

import codecs

import numpy as np
import pytest

from spherecal.correction import load_robot
from spherecal.correction.files import csv_rows, samples_csv
from spherecal.correction.files.fixtures import read_fixtures
from spherecal.correction.files.samples import DatasetError
from spherecal.correction.files.samples_csv import read_samples
from tests.refusal import refused

HEADER = "fixture,q1,q2,q3,q4,q5,q6,q7"
ROWS = [f"P{k % 2 + 1},0.1,-0.3,0.0,-2.2,0.0,2.0,{0.8 + 1e-3 * k!r}" for k in range(8)]


def _samples(path, rows=ROWS, encoding="utf-8", newline="\n") -> None:
    path.write_bytes(newline.join(["# a comment", HEADER, *rows]).encode(encoding) + newline.encode())


@pytest.mark.parametrize("chunk_rows", [2, 50_000])
def test_a_latin1_byte_in_a_samples_file_names_its_row_and_field(tmp_path, monkeypatch, chunk_rows) -> None:
    """The decoder fails on the chunk it reads, not the line: the row is found again (it said only 'invalid
    continuation byte', no row). A later block too."""
    monkeypatch.setattr(samples_csv, "iter_lines", lambda p, e: csv_rows.iter_lines(p, e, chunk=chunk_rows))
    rows = list(ROWS)
    rows[5] = rows[5].replace("P2", "P\xe92", 1)  # row 8 of the file: comment, header, rows 3..10
    path = tmp_path / "s.csv"
    _samples(path, rows, encoding="latin-1")
    with pytest.raises(DatasetError) as error:
        read_samples(path, load_robot("panda"))
    message = str(error.value)
    assert message.startswith(f"{path}: cannot read: not UTF-8 text (row 8, field 1: 0xe9; a text file saved as "
                              "Latin-1"), message
    assert "\n" not in message


def test_a_utf16_csv_is_named_for_what_it_is_and_nothing_is_written(tmp_path, capsys) -> None:
    path = tmp_path / "s.csv"
    _samples(path, encoding="utf-16")
    assert path.read_bytes().startswith(codecs.BOM_UTF16_LE)
    refused(["calibrate", "--robot", "panda", "--samples", path, "--out", tmp_path / "cal.yaml"], tmp_path, capsys,
            "s.csv: cannot read: not UTF-8 text (row 1, field 1: 0xff; the file is UTF-16")


def test_a_latin1_byte_in_a_yaml_file_names_its_row(tmp_path) -> None:
    path = tmp_path / "fixtures.yaml"
    path.write_bytes("fixtures:\n  P1: {}\n  # caf\xe9\n  P2: {}\n".encode("latin-1"))
    with pytest.raises(DatasetError, match=r"fixtures.yaml: cannot read: not UTF-8 text \(byte 26, row 3: 0xe9; "):
        read_fixtures(path)
    bom = tmp_path / "bom.yaml"  # the mark is not counted: the byte is the file's
    bom.write_bytes(codecs.BOM_UTF8 + "fixtures:\n  P1: {}\n  # caf\xe9\n".encode("latin-1"))
    with pytest.raises(DatasetError, match=r"bom.yaml: cannot read: not UTF-8 text \(byte 29, row 3: 0xe9; "):
        read_fixtures(bom)


@pytest.mark.parametrize("bom, newline", [(True, "\n"), (False, "\r\n"), (True, "\r\n"), (False, "\r")])
def test_a_bom_or_crlf_samples_file_is_read_as_the_plain_one(tmp_path, bom, newline) -> None:
    panda = load_robot("panda")
    plain, other = tmp_path / "plain.csv", tmp_path / "other.csv"
    _samples(plain)
    _samples(other, newline=newline)
    if bom:
        other.write_bytes(codecs.BOM_UTF8 + other.read_bytes())
    a, b = read_samples(plain, panda), read_samples(other, panda)
    np.testing.assert_array_equal(a.q, b.q)
    assert list(a.labels) == list(b.labels) and list(a.lines) == list(b.lines)
