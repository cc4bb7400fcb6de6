"""Reading untrusted text: a whole file as UTF-8 (an XML file in the encoding it declares), one number of a text
field; errors in one line."""

from __future__ import annotations

import codecs
import math
import os
import re
from pathlib import Path

#: Largest text file read whole [bytes] (robot files, URDFs, fixtures: kilobytes to a few megabytes). A
#: device such as ``/dev/zero`` or ``/dev/urandom`` never ends: it is refused at this size, not read forever.
MAX_TEXT_BYTES = 64_000_000


def read_text(path: str | os.PathLike, error: type[Exception], encoding: str = "utf-8",
              limit: int = MAX_TEXT_BYTES) -> str:
    """The UTF-8 text of ``path``, at most ``limit`` bytes.

    Args:
        encoding: ``"utf-8"``, or ``"utf-8-sig"`` to drop a byte-order mark.
        limit: the largest file accepted [bytes].

    Raises:
        error: ``"<path>: cannot read: <why>"`` (missing, unreadable, larger than ``limit``, not UTF-8
            with the byte offset).
    """
    path = Path(path)
    data = _read_bytes(path, error, limit)
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as why:
        start = why.start + (len(codecs.BOM_UTF8) if encoding == "utf-8-sig" and data.startswith(codecs.BOM_UTF8)
                             else 0)
        row = len(_LINE_BREAK.split(data[:start]))
        raise error(f"{path}: cannot read: not UTF-8 text (byte {start}, row {row}: "
                    f"{undecodable_hint(data[start], data)})") from None


#: A line break as Python's universal newlines and YAML read it.
_LINE_BREAK = re.compile(rb"\r\n|\r|\n")


def undecodable_hint(byte: int, head: bytes) -> str:
    """What a byte that is not UTF-8 likely is, for a refusal: ``head`` is the file's start (its byte-order mark)."""
    if head.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        return f"0x{byte:02x}; the file is UTF-16, as its byte-order mark says: save it as UTF-8"
    return f"0x{byte:02x}; a text file saved as Latin-1 or Windows-1252, or not a text file? save it as UTF-8"


def _read_bytes(path: Path, error: type[Exception], limit: int) -> bytes:
    try:
        with open(path, "rb") as handle:
            data = handle.read(limit + 1)
    except OSError as why:
        raise error(f"{path}: cannot read: {why.strerror or why}") from None
    if len(data) > limit:
        raise error(f"{path}: cannot read: larger than {limit} bytes (a device or a file of another kind?)")
    return data


#: The encoding named by an XML declaration at the start of a document (ASCII-compatible encodings).
_DECLARED = re.compile(rb"""<\?xml\s[^>]*?\bencoding\s*=\s*["']([A-Za-z][A-Za-z0-9._-]*)["']""")
#: Byte-order marks and the encoding each one sets (XML 1.0, appendix F): it takes precedence over a declaration.
_BOMS = ((codecs.BOM_UTF8, "utf-8-sig"), (codecs.BOM_UTF16_LE, "utf-16"), (codecs.BOM_UTF16_BE, "utf-16"))


def xml_encoding(data: bytes) -> str:
    """The encoding of an XML document's bytes, as the XML standard reads it: a byte-order mark, else the
    encoding its declaration (``<?xml version="1.0" encoding="ISO-8859-1"?>``) names, else UTF-8."""
    for bom, name in _BOMS:
        if data.startswith(bom):
            return name
    found = _DECLARED.match(data)
    return found.group(1).decode("ascii") if found else "utf-8"


def read_xml_text(path: str | os.PathLike, error: type[Exception], limit: int = MAX_TEXT_BYTES) -> str:
    """The text of the XML file ``path`` decoded in its own encoding (:func:`xml_encoding`), at most ``limit``
    bytes.

    Raises:
        error: ``"<path>: cannot read: <why>"``: missing, unreadable, too large, an encoding Python does not know,
            or bytes that are not text in the declared encoding (naming it and the byte offset).
    """
    path = Path(path)
    data = _read_bytes(path, error, limit)
    encoding = xml_encoding(data)
    try:
        codecs.lookup(encoding)
    except LookupError:
        raise error(f"{path}: cannot read: its XML declaration names an unknown encoding {encoding!r}") from None
    try:
        return data.decode(encoding)
    except UnicodeDecodeError as why:
        declared = "" if encoding == "utf-8" else ", the encoding its XML declaration names"
        name = "UTF-8" if encoding == "utf-8" else encoding
        raise error(f"{path}: cannot read: not {name} text (byte {why.start}){declared}") from None
    except UnicodeError as why:  # a codec that refuses the data as a whole (utf-16 of an odd length)
        raise error(f"{path}: cannot read: not {encoding} text ({why})") from None


def xml_bytes(text: str) -> bytes:
    """An XML document's text encoded as its declaration says (UTF-8 without one); a character that encoding
    cannot hold becomes a character reference (``&#8364;``), so a Latin-1 URDF stays a Latin-1 file."""
    encoding = xml_encoding(text.lstrip("\ufeff").encode("utf-8"))
    try:
        codecs.lookup(encoding)
    except LookupError:
        encoding = "utf-8"
    if encoding.lower().replace("_", "-") in ("utf-8", "utf8", "utf-8-sig"):
        return text.encode("utf-8")
    return text.encode(encoding, errors="xmlcharrefreplace")


def plain_float(text: str) -> float:
    """``float(text)`` for the numbers a file of ours holds: ASCII digits, sign, point, exponent, nan/inf.

    Python's ``float`` also takes other scripts' digits (``'\u0661'``, Arabic-Indic one, is 1.0; full-width
    ``'\uff15'`` is 5.0) and underscores (``'1_0'`` is 10.0): in a CSV cell these are a corrupted or
    foreign-locale value, not a number.

    Raises:
        ValueError: not such a number.
    """
    if not text.isascii() or "_" in text:
        raise ValueError(f"not a plain number: {text!r}")
    return float(text)


def finite_number(text: str, where: str, error: type[Exception]) -> float:
    """``text`` as a finite float.

    Raises:
        error: ``"<where>: expected a number, got '...'"`` or ``"<where>: must be finite, got 'nan'"``.
    """
    try:
        value = plain_float(text)
    except ValueError:
        raise error(f"{where}: expected a number, got {text.strip()!r}") from None
    if not math.isfinite(value):
        raise error(f"{where}: must be finite, got {text.strip()!r}")
    return value
