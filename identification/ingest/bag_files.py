"""The storage files of a ROS 2 bag, for refusals that name the damaged file rather than its folder.

rosbags opens a bag folder's storage files (``relative_file_paths`` of its ``metadata.yaml``) and reports a damaged
one as ``File end magic is invalid.`` (a truncated MCAP file) or an overflow, naming neither the file nor what is
wrong with it. An MCAP file starts and ends with the 8-byte magic ``\\x89MCAP0\\r\\n`` (the specification,
mcap.dev/spec): a file without the first is not MCAP, one without the last was cut short (a recording killed before
``ros2 bag record`` closed it, a copy or download interrupted). Both are checked here, on a few bytes of each file,
before rosbags reads it.
"""

from __future__ import annotations

from pathlib import Path

from .importers import RecordingError

#: The first and last 8 bytes of an MCAP file (its "magic").
MCAP_MAGIC = b"\x89MCAP0\r\n"
#: The smallest MCAP file: magic, a header record, a footer record, magic [bytes] (a header with empty strings is
#: 17 bytes, the footer 29).
MCAP_LEAST = 8 + 17 + 29 + 8


def storage_files(path: Path, info: dict | None) -> list[Path]:
    """The storage files a bag reads: ``path`` itself when it is a file, else the ``relative_file_paths`` of the
    folder's metadata (``info``: its ``rosbag2_bagfile_information`` mapping) that exist. A file named otherwise
    (not a string, missing) is left to rosbags."""
    if path.is_file():
        return [path]
    names = (info or {}).get("relative_file_paths")
    if not isinstance(names, list):
        return []
    return [path / name for name in names if isinstance(name, str) and (path / name).is_file()]


def check_mcap(file: Path) -> None:
    """Refuse an MCAP storage file (named ``.mcap``) that is empty, not MCAP, or cut short, by its magic bytes.

    Raises:
        RecordingError: ``"<file>: cannot read the bag: <what is wrong> (<size>)"``, one line.
    """
    if file.suffix.lower() != ".mcap":
        return
    try:
        size = file.stat().st_size
        with open(file, "rb") as handle:
            head = handle.read(len(MCAP_MAGIC))
            handle.seek(max(size - len(MCAP_MAGIC), 0))
            tail = handle.read(len(MCAP_MAGIC))
    except OSError as error:
        raise RecordingError(f"{file}: cannot read the bag: {error.strerror or error}") from None
    if size == 0:
        why = "an empty MCAP file (0 bytes): the recording wrote nothing into it"
    elif head != MCAP_MAGIC:
        why = f"not an MCAP file: it does not start with MCAP's magic bytes (starts {head!r}, {size} bytes)"
    elif size < MCAP_LEAST or tail != MCAP_MAGIC:
        why = (f"a truncated MCAP file ({size} bytes, not ending with MCAP's closing magic bytes): a recording "
               "stopped before ros2 bag record closed it, or a copy cut short; copy it again, or try the mcap "
               "tool's `mcap recover` on it")
    else:
        return
    raise RecordingError(f"{file}: cannot read the bag: {why}")


def storage_module(error: BaseException) -> bool:
    """Whether rosbags' storage layer (``rosbags.rosbag2.storage_*``: the MCAP or SQLite file) raised ``error`` or
    the error it came from, rather than its metadata or message reading: then the storage file is what is damaged."""
    seen: set[int] = set()
    while error is not None and id(error) not in seen:
        seen.add(id(error))
        frame = error.__traceback__
        while frame is not None:
            if str(frame.tb_frame.f_globals.get("__name__", "")).startswith("rosbags.rosbag2.storage_"):
                return True
            frame = frame.tb_next
        error = error.__cause__ or error.__context__
    return False
