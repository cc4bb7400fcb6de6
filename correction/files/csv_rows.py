"""Reading CSV files we are handed, one physical line per record, with one-line errors.

Our CSV files (``samples.csv``, mocap recordings, joint recordings) hold one record per line: a
quoted field never spans lines. Parsing each line on its own makes every error name the line it is
on: an unterminated quote is reported on the row where it opens (not at the end of the file, after
reading all of it), and a field longer than the csv module's limit is one line naming its row,
not a ``_csv.Error`` traceback. Files are read as a stream (:func:`iter_lines`), so a bad value on
row 2 is found without reading the rest of the file.
"""

from __future__ import annotations

import csv
import os
from collections.abc import Iterator, Sequence
from itertools import islice
from pathlib import Path

import numpy as np

from ..errors import SpherecalError
from .text_input import undecodable_hint

#: Longest physical line read [characters]: a row of joint angles is a few hundred; a file without line
#: ends (``/dev/zero``, a binary file) is refused here instead of being read whole into one line.
MAX_LINE = 1_000_000


def field_limit() -> int:
    """The csv module's field-size limit [characters] (131072 unless changed)."""
    return csv.field_size_limit()


def is_skipped(line: str) -> bool:
    """A blank (or whitespace-only) line or a ``#`` comment, both skipped by our readers."""
    stripped = line.strip()
    return not stripped or stripped.startswith("#")


def parse_line(line: str, where: str, error: type[SpherecalError] = SpherecalError) -> list[str]:
    """The fields of one CSV line.

    Args:
        line: one physical line (with or without its newline).
        where: ``"file: row N"`` for the message.
        error: the exception class to raise.

    Raises:
        error: an unterminated quote, a field over :func:`field_limit`, or another CSV syntax error.
    """
    try:
        return next(csv.reader([line.rstrip("\r\n")], strict=True), [])
    except csv.Error as problem:
        text = str(problem)
        if "field larger than field limit" in text:
            raise error(f"{where}: a field longer than the CSV limit of {field_limit()} characters") \
                from None
        if line.count('"') % 2 == 1 or "end of data" in text or "EOF" in text:
            raise error(f"{where}: unterminated quote (a quoted field must end on its own line)") from None
        raise error(f"{where}: CSV syntax: {text}") from None


def check_separator(header: list[str], where: str, error: type[SpherecalError] = SpherecalError) -> None:
    """Refuse a header of one field holding another separator (``;`` or a tab: a spreadsheet's export in a
    European locale, whose numbers then carry decimal commas), which no column name could match.

    Args:
        header: the header's fields, split at commas.
        where: ``"FILE: row N"`` for the message.
        error: the exception class to raise.
    """
    if len(header) != 1:
        return
    separator = next((sep for sep in (";", "\t", "|") if sep in header[0]), None)
    if separator is not None:
        first = header[0].split(separator)[0].strip()
        raise error(f"{where}, field {first!r}: the columns are separated by {separator!r}, not commas (a "
                    "spreadsheet's export in a European locale? the file must be comma-separated, with decimal points)")


def open_text(path: Path, error: type[SpherecalError]):
    """``path`` opened for reading as UTF-8 text (a byte-order mark dropped); one-line error."""
    try:
        return open(path, encoding="utf-8-sig", newline=None)  # noqa: SIM115 - the caller closes it
    except OSError as problem:
        raise error(f"{path}: cannot read: {problem.strerror or problem}") from None


def iter_lines(path: str | os.PathLike, error: type[SpherecalError], chunk: int = 50_000) -> Iterator[list[str]]:
    """The file's physical lines in blocks of ``chunk`` (a stream; memory stays small).

    Raises:
        error: the file cannot be opened or is not UTF-8 text (naming the file).
    """
    path = Path(path)
    with open_text(path, error) as handle:
        lines = _bounded_lines(handle, path, error)
        while True:
            try:
                block = list(islice(lines, chunk))
            except UnicodeDecodeError as problem:
                raise error(f"{path}: cannot read: not UTF-8 text ({_undecodable(path, problem)})") from None
            except OSError as problem:
                raise error(f"{path}: cannot read: {problem.strerror or problem}") from None
            if not block:
                return
            yield block


def _undecodable(path: Path, problem: UnicodeDecodeError) -> str:
    """Where the first byte that is not UTF-8 is, as ``row N, field K: 0xe9; <what it likely is>`` (``problem``'s
    reason when the file cannot be read again): the decoder reads the file in chunks, so the row it failed in is
    found by reading the file again with each bad byte kept as an escape (only on this refusal's path)."""
    try:
        with open(path, "rb") as raw:
            head = raw.read(4)
        with open(path, encoding="utf-8-sig", errors="surrogateescape", newline=None) as handle:
            row = 0
            while line := handle.readline(MAX_LINE + 1):
                row += 1
                column = next((k for k, ch in enumerate(line) if "\udc80" <= ch <= "\udcff"), None)
                if column is not None:
                    return f"row {row}, field {line[:column].count(',') + 1}: " \
                           f"{undecodable_hint(ord(line[column]) - 0xDC00, head)}"
    except OSError:
        pass
    return problem.reason


def _bounded_lines(handle, path: Path, error: type[SpherecalError]) -> Iterator[str]:
    """The lines of ``handle``, each at most :data:`MAX_LINE` characters (else one line naming the row)."""
    row = 0
    while True:
        line = handle.readline(MAX_LINE + 1)
        if not line:
            return
        row += 1
        if len(line) > MAX_LINE:
            raise error(f"{path}: row {row}: a line longer than {MAX_LINE} characters (not a text "
                        "file of rows?)")
        yield line


def read_rows(path: str | os.PathLike, error: type[SpherecalError], comments: bool = True
              ) -> Iterator[tuple[int, list[str]]]:
    """``(line number, fields)`` of every record of a CSV file, blank lines (and ``#`` comments when
    ``comments``) skipped; line numbers are the file's (1-based).

    Raises:
        error: unreadable file, unterminated quote (on the row where it opens), a field over the
            limit, a record spanning lines (one line with the row).
    """
    first = 1
    for block in iter_lines(path, error):
        yield from block_rows(block, first, path, error, comments)
        first += len(block)


def block_rows(block: list[str], first: int, path: str | os.PathLike, error: type[SpherecalError],
               comments: bool = True) -> Iterator[tuple[int, list[str]]]:
    """:func:`read_rows` of one block of lines whose first is line ``first`` of ``path``."""
    reader = csv.reader(block, strict=True)
    done = 0  # lines of the block consumed so far
    while True:
        try:
            fields = next(reader)
        except StopIteration:
            return
        except csv.Error:
            parse_line(block[done], f"{path}: row {first + done}", error)  # raises, naming the problem
            raise error(f"{path}: row {first + done}: unterminated quote") from None
        if reader.line_num - done > 1:  # a quote opened on this line and closed on a later one
            raise error(f"{path}: row {first + done}: unterminated quote (a quoted field must end "
                        "on its own line)")
        number, done = first + done, reader.line_num
        if not fields or not "".join(fields).strip() or (comments and fields[0].lstrip().startswith("#")):
            continue
        yield number, fields


def plain_values(block: list[str], width: int, columns: Sequence[int]) -> np.ndarray | None:
    """(len(block), len(columns)) values of a block of plain CSV lines, converted by numpy's C reader,
    or None when the block is not plain: a quote, a ``#``, a line without exactly ``width`` fields (each line's
    count, not the block's total: numpy reads the ``columns`` of a ragged block without a word),
    a line over the field limit, or a value that is not a finite number. The caller then reads the
    block line by line (:func:`block_rows`), which names the row and field of the problem.
    """
    text = "".join(block)
    if '"' in text or "#" in text:
        return None
    # each line's count, not the block's total: one line short and another long make the same total, and numpy's
    # reader takes the columns asked of each line and ignores the rest
    if any(line.count(",") != width - 1 for line in block):
        return None
    if max(map(len, block)) > field_limit():
        return None
    try:
        data = np.loadtxt(block, delimiter=",", usecols=columns, dtype=float, ndmin=2)
    except ValueError:
        return None
    if data.shape[0] != len(block) or not np.isfinite(data).all():  # a blank line skipped, nan or inf
        return None
    return data


class RowNames(Sequence):
    """``"file: row N"`` of every record (``"bag: /topic message N"`` with ``what="/topic message"``), made when
    asked (2 M strings would take 200 MB)."""

    def __init__(self, path: str | os.PathLike, lines: np.ndarray, what: str = "row"):
        self.path, self.lines, self.what = str(path), np.asarray(lines), what

    def __len__(self) -> int:
        return int(self.lines.size)

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [self[i] for i in range(*k.indices(len(self)))]
        return f"{self.path}: {self.what} {int(self.lines[k])}"

    def select(self, keep: np.ndarray) -> RowNames:
        """The names of the records ``keep`` (a boolean mask or indices) selects."""
        return RowNames(self.path, self.lines[keep], self.what)
