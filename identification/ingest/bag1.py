"""ROS 1 bags (``.bag``) read a chunk at a time: the message index in arrays, each chunk's messages sliced out together.

rosbags' own ROS 1 reader holds a Python object per message of the bag's index (300 MB and 3 s for 1.8 M messages
before the first is read) and parses every record's header in Python (8 s more). Here its reader opens the bag (the
same checks, errors and connections) but keeps the index in arrays (:class:`IndexedReader`), and :func:`blocks`
hands the messages in rosbags' order, a run of one chunk's at a time, as offsets into the decompressed chunk: the
records' headers are checked in arrays against the first one's of each connection, and the message bytes read at
their offsets. Anything else (a record that is not the message the index names, a chunk that does not decompress)
raises :class:`Unusual`: read the bag with rosbags' reader, which says what is wrong as it always did.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from rosbags.interfaces import MessageDefinitionFormat
from rosbags.rosbag1 import Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

_U32 = struct.Struct("<I")
#: One entry of an index data record: the message's receive time and its record's offset in the chunk.
_ENTRY = np.dtype([("sec", "<u4"), ("nsec", "<u4"), ("offset", "<u4")])
_MSGDATA, _CONNECTION, _IDXDATA = 2, 7, 4  # record ops


class Unusual(Exception):
    """What this reader does not read: the bag is read by rosbags' reader instead."""


def _fields(data: bytes) -> dict[bytes, bytes]:
    """The ``name=value`` fields of a record header's bytes."""
    fields, at = {}, 0
    while at < len(data):
        (size,) = _U32.unpack_from(data, at)
        name, equals, value = data[at + 4 : at + 4 + size].partition(b"=")
        if not equals or at + 4 + size > len(data):
            raise Unusual("a record header's field")
        fields[name] = value
        at += 4 + size
    return fields


class IndexedReader(Reader):
    """rosbags' ROS 1 reader that keeps each index data record as an array (:attr:`index`) instead of a Python object
    per message; its own ``messages`` then reads nothing (use :func:`blocks`)."""

    def __init__(self, path: str | Path):
        super().__init__(path)
        self.index: list[tuple[int, int, np.ndarray]] = []  # (connection id, chunk position, entries (_ENTRY))

    def read_index_data(self, pos: int, indexes) -> None:  # noqa: ARG002 (rosbags' lists are left empty)
        """Read the index data record at the file's position: the entries of one connection in the chunk at
        ``pos``."""
        assert self.bio
        head = self.bio.read(4)
        if len(head) < 4:
            raise Unusual("an index data record")
        header = self.bio.read(_U32.unpack(head)[0])
        fields = _fields(header)
        try:
            op, version = fields[b"op"], _U32.unpack(fields[b"ver"])[0]
            (conn,), (count,) = _U32.unpack(fields[b"conn"]), _U32.unpack(fields[b"count"])
            (size,) = _U32.unpack(self.bio.read(4))
        except (KeyError, struct.error):
            raise Unusual("an index data record") from None
        if op != bytes([_IDXDATA]) or version != 1 or size != 12 * count:
            raise Unusual("an index data record")
        data = self.bio.read(size)
        if len(data) != size:
            raise Unusual("an index data record")
        self.index.append((conn, pos, np.frombuffer(data, dtype=_ENTRY)))


def typestore(reader: IndexedReader):
    """The bag's own message types (its connections' definitions, checked against their MD5 sums), as rosbags'
    ``AnyReader`` builds them.

    Raises:
        Unusual: a connection without a definition, a definition that does not parse or match its sum.
    """
    types, digests = {}, {}
    try:
        for connection in reader.connections:
            if connection.msgdef.format != MessageDefinitionFormat.MSG:
                raise Unusual("a connection without a message definition")
            types.update(get_types_from_msg(connection.msgdef.data, connection.msgtype))
            if connection.digest:
                digests[connection.msgtype] = connection.digest
        store = get_typestore(Stores.EMPTY)
        store.register(types)
        if any(store.generate_msgdef(msgtype)[1] != digest for msgtype, digest in digests.items()):
            raise Unusual("a message definition that does not match its MD5 sum")
    except Unusual:
        raise
    except Exception as error:  # rosbags' parse errors have no common base
        raise Unusual(str(error)) from None
    return store


@dataclass
class Block:
    """Messages of one chunk, consecutive in the bag's order.

    Attributes:
        numbers: (K,) their 1-based numbers among the connections' messages.
        received: (K,) the bag's receive times [ns].
        chunk: the decompressed chunk (uint8).
        start, size: (K,) where each message's bytes start in ``chunk`` and their count.
    """

    numbers: np.ndarray
    received: np.ndarray
    chunk: np.ndarray
    start: np.ndarray
    size: np.ndarray


def blocks(reader: IndexedReader, connections) -> Iterator[Block]:
    """The messages of ``connections`` in the order rosbags' reader yields them (by receive time; a tie by the order of
    ``connections``, then by the index's), a run of one chunk's messages at a time.

    Raises:
        Unusual: an index that does not count the messages the chunk infos do, a chunk that does not decompress, a
            record that is not a message of its connection at its receive time.
    """
    ids = [c.id for c in connections]
    expected = sum(info.connection_counts.get(conn, 0) for info in reader.chunk_infos for conn in ids)
    positions = [info.pos for info in reader.chunk_infos]
    place = {pos: k for k, pos in enumerate(positions)}
    parts = [(rank, place.get(pos, -1), entries) for rank, conn in enumerate(ids)
             for c, pos, entries in reader.index if c == conn]
    if sum(len(p[2]) for p in parts) != expected or any(p[1] < 0 for p in parts):
        raise Unusual("an index that does not count the messages of the chunk infos")
    if not parts:
        return
    entries = np.concatenate([p[2] for p in parts])
    chunk_of = np.concatenate([np.full(len(p[2]), p[1]) for p in parts])
    conn_of = np.concatenate([np.full(len(p[2]), p[0]) for p in parts])
    received = entries["sec"].astype(np.int64) * 1_000_000_000 + entries["nsec"]
    order = np.argsort(received, kind="stable")  # the entries are by connection, then in the index's order
    entries, chunk_of, conn_of, received = entries[order], chunk_of[order], conn_of[order], received[order]
    runs = np.concatenate([[0], np.flatnonzero(np.diff(chunk_of)) + 1, [len(order)]])
    templates: dict[int, tuple[np.ndarray, int]] = {}  # connection rank -> (header bytes, where its time is)
    for a, b in zip(runs[:-1], runs[1:], strict=True):
        chunk = _chunk(reader, positions[chunk_of[a]])
        start, size = _records(chunk, entries[a:b], conn_of[a:b], ids, templates)
        yield Block(np.arange(a + 1, b + 1), received[a:b], chunk, start, size)


def _chunk(reader: IndexedReader, pos: int) -> np.ndarray:
    """The decompressed bytes of the chunk at ``pos``."""
    info = reader.chunks[pos]
    reader.bio.seek(info.datapos)
    data = reader.bio.read(info.datasize)
    if len(data) != info.datasize:
        raise Unusual("a chunk cut short")
    try:
        return np.frombuffer(info.decompressor(data), dtype=np.uint8)
    except Exception as error:  # the decompressors' errors have no common base
        raise Unusual(str(error)) from None


def _u32(chunk: np.ndarray, at: np.ndarray) -> np.ndarray:
    """(K,) little-endian uint32 at offsets ``at`` of ``chunk`` (int64)."""
    if at.size and (at.min() < 0 or at.max() + 4 > chunk.size):
        raise Unusual("a record beyond its chunk")
    return np.ascontiguousarray(chunk[at[:, None] + np.arange(4)]).view("<u4")[:, 0].astype(np.int64)


def _records(chunk: np.ndarray, entries: np.ndarray, ranks: np.ndarray, ids: list[int],
             templates: dict[int, tuple[np.ndarray, int]]) -> tuple[np.ndarray, np.ndarray]:
    """``(start, size)``: (K,) where the message bytes of the records at ``entries['offset']`` start in ``chunk``, and
    their count. A record's header must be its connection's first one's (the one ``templates`` keeps, read by hand),
    but for the receive time it carries, which must be its index entry's."""
    offset = entries["offset"].astype(np.int64)
    length = _u32(chunk, offset)
    for rank in np.unique(ranks):
        mine = ranks == rank
        if rank not in templates:
            templates[rank] = _template(chunk, int(offset[mine][0]), ids[rank])
        header, at_time = templates[rank]
        if np.any(length[mine] != header.size):
            raise Unusual("a message record of another header")
        if offset[mine].max() + 4 + header.size > chunk.size:
            raise Unusual("a record beyond its chunk")
        got = chunk[offset[mine][:, None] + 4 + np.arange(header.size)]
        fixed = np.ones(header.size, dtype=bool)
        fixed[at_time : at_time + 8] = False
        times = np.ascontiguousarray(got[:, at_time : at_time + 8]).view("<u4")
        if (np.any(got[:, fixed] != header[fixed]) or np.any(times[:, 0] != entries["sec"][mine])
                or np.any(times[:, 1] != entries["nsec"][mine])):
            raise Unusual("a message record of another header")
    start = offset + 4 + length + 4
    size = _u32(chunk, start - 4)
    if size.size and (start + size).max() > chunk.size:
        raise Unusual("a message beyond its chunk")
    return start, size


def _template(chunk: np.ndarray, offset: int, conn: int) -> tuple[np.ndarray, int]:
    """The header of the message record at ``offset`` (uint8) and where its time's value starts in it.

    Raises:
        Unusual: not a message record of connection ``conn`` (rosbags' reader skips connection records before it:
            left to it).
    """
    (size,) = _U32.unpack(chunk[offset : offset + 4].tobytes())
    header = chunk[offset + 4 : offset + 4 + size]
    fields = _fields(header.tobytes())
    if (fields.get(b"op") != bytes([_MSGDATA]) or fields.get(b"conn") != _U32.pack(conn)
            or len(fields.get(b"time", b"")) != 8):
        raise Unusual("a record that is not a message of its connection")
    at_time = header.tobytes().find(b"time=") + 5
    if header.tobytes().count(b"time=") != 1:
        raise Unusual("a record header naming its time twice")
    return header.copy(), at_time
