"""A set of output files that appear together or not at all, and never over an input.

Every command that writes files builds one :class:`OutputSet` before any work: it checks each
planned file (no folder in the way, a writable folder, not an input, not planned twice) and
refuses with one line naming the option and the file. The files are then staged as temporary
files beside their destination and renamed into place together at the end; on any failure the
staged files (and the folders the set created) are removed::

    outputs = OutputSet({"--out": [out / "samples.csv", out / "truth.yaml"]}, {"--fixtures": fixtures})
    ...                                           # the long computation
    with outputs:
        outputs.write_text(out / "samples.csv", text)
        write_anything(outputs.stage(out / "truth.yaml"), ...)   # a writer that takes a path
    # here both files exist, or (an exception) neither was touched

Inputs are compared as files (links resolved, ``os.path.samefile``), never as strings.
"""

from __future__ import annotations

import os
import signal
import sys
import tempfile
import threading
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path

from .atomic import OutputError, _umask, refuse_special_file

PathLike = str | os.PathLike


def _names(value: PathLike | Iterable[PathLike] | None) -> list[PathLike]:
    if value is None:
        return []
    if isinstance(value, (str, os.PathLike)):
        return [value]
    return [v for v in value if v is not None]


def _paths(value: PathLike | Iterable[PathLike] | None) -> list[Path]:
    return [Path(v) for v in _names(value)]


def same_file(a: Path, b: Path) -> bool:
    """True when ``a`` and ``b`` name the same file (links resolved; hard links by inode)."""
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    except OSError:
        pass
    return a.resolve() == b.resolve()


def _refuse_link_loop(path: Path, option: str) -> None:
    """Refuse an output whose path runs into a symbolic link loop (``Path.resolve`` raises RuntimeError on
    one in Python 3.11-3.12, OSError ELOOP later: a traceback before this check).

    Raises:
        OutputError: one line naming the option and the file.
    """
    try:
        path.resolve()
    except (RuntimeError, OSError):
        raise OutputError(f"{path}: field '{option}': runs into a symbolic link loop (expected a file name to "
                          "write)") from None


def _inside(path: Path, folder: Path) -> bool:
    try:
        return folder.is_dir() and path.resolve().is_relative_to(folder.resolve())
    except OSError:
        return False


#: The packages whose folders hold spherecal's code (looked up in ``sys.modules``, never imported from here).
_PACKAGES = ("spherecal", "spherecal.identification", "spherecal.controller", "spherecal.validation")


def _refuse_package_folder(path: Path, option: str, shown: Path | None = None) -> None:
    """Refuse an output inside the installed package's code (``--out`` given as a folder of the package, or a
    path relative to it): a file written there is mixed into the code and goes with the next upgrade."""
    folders = [Path(__file__).resolve().parents[1]]  # spherecal.correction
    for name in _PACKAGES:
        folders += [Path(p) for p in getattr(sys.modules.get(name), "__path__", None) or ()]
    for folder in folders:
        if _inside(path, folder):
            raise OutputError(f"{shown or path}: field '{option}': is inside the installed spherecal package "
                              f"({folder}); write outputs to a folder of your own")


def check_output(path: Path, option: str) -> None:
    """Refuse an output file that is a folder, lies under a file or inside the installed package, or whose folder
    cannot be written.

    Raises:
        OutputError: one line naming the option and the file.
    """
    if path.is_dir():
        raise OutputError(f"{path}: field '{option}': is a folder, expected a file name")
    refuse_special_file(path, option)
    _refuse_package_folder(path, option)
    _check_parents(path, option)


def check_folder(path: PathLike, option: str) -> None:
    """Refuse an output folder that is an existing file or lies under one (before a long run).

    Raises:
        OutputError: one line naming the option and the folder.
    """
    path = Path(path)
    _refuse_link_loop(path, option)
    if path.exists() and not path.is_dir():
        raise OutputError(f"{path}: field '{option}': exists and is not a folder")
    _refuse_package_folder(path / "_", option, shown=path)
    _check_parents(path / "_", option, shown=path)


def _check_parents(path: Path, option: str, shown: Path | None = None) -> None:
    """The nearest existing parent of ``path`` is a folder we may write into."""
    shown = path if shown is None else shown
    for parent in path.absolute().parents:
        if parent.exists():
            if not parent.is_dir():
                raise OutputError(f"{shown}: field '{option}': {parent} is not a folder")
            if not os.access(parent, os.W_OK | os.X_OK):
                raise OutputError(f"{shown}: field '{option}': cannot write into {parent}: permission denied")
            return


def _utf8_name(name: str) -> str:
    """``name`` with each byte that is not UTF-8 (``\\udcff`` in Python's ``surrogateescape``) as ``_``: a staged file's
    name that a writer taking UTF-8 paths can open (Rerun refused ``--rrd $'v\\xff.rrd'``: 'cannot write the
    recording'); the rename gives the file its own name."""
    return "".join("_" if "\udc80" <= char <= "\udcff" else char for char in name)


class OutputSet:
    """Planned output files, checked now, staged while written and renamed into place together.

    Args:
        outputs: option -> the file (or files) it writes, e.g. ``{"--out": [dir/"a.csv", dir/"b.yaml"]}``.
        inputs: option -> the file (or folder) it reads; an output that is one of them, or lies in
            an input folder, is refused. ``None`` values (options not given) are skipped.
        file_inputs: the options of ``inputs`` that name a file: one given a folder that an output lies in is
            refused as a folder given for a file (the mistake), not as an output inside an input.

    Raises:
        OutputError: a collision or an unwritable location (one line naming the option and file).
    """

    def __init__(
        self,
        outputs: Mapping[str, PathLike | Iterable[PathLike] | None],
        inputs: Mapping[str, PathLike | Iterable[PathLike] | None] | None = None,
        file_inputs: Iterable[str] = (),
    ):
        self.planned: dict[Path, str] = {}
        file_inputs = set(file_inputs)
        self._staged: dict[Path, Path] = {}
        self._created: list[Path] = []
        input_paths = [(option, p) for option, value in (inputs or {}).items() for p in _paths(value) if p.exists()]
        for option, value in outputs.items():
            for name in _names(value):
                path = Path(name)
                if isinstance(name, str) and name.endswith(("/", os.sep)):  # Path() drops the slash
                    raise OutputError(f"{name}: field '{option}': ends with '/', a folder name (expected a file name)")
                _refuse_link_loop(path, option)
                for other, known in self.planned.items():
                    if same_file(path, other):
                        raise OutputError(f"{path}: field '{option}': is also the output of {known}; "
                                          "give two different files")
                for source, item in input_paths:
                    if same_file(path, item) or _inside(path, item):
                        if source in file_inputs and item.is_dir():
                            raise OutputError(f"{item}: field '{source}': is a folder, not a file; give the file "
                                              "itself")
                        what = f"is the {source} file" if same_file(path, item) else f"is inside the {source} folder"
                        raise OutputError(f"{path}: field '{option}': {what} {item}; an output never overwrites "
                                          "an input")
                check_output(path, option)
                self.planned[path] = option

    # ------------------------------------------------------------------ staging
    def stage(self, path: PathLike) -> Path:
        """A temporary file beside ``path`` to write it to (renamed to ``path`` by :meth:`commit`)."""
        path = self._planned(path)
        if path in self._staged:
            return self._staged[path]
        self._make_folder(path.parent, self.planned[path])
        try:
            fd, tmp = tempfile.mkstemp(prefix=f".{_utf8_name(path.name)}.", suffix=".staged", dir=path.parent)
            os.close(fd)
            os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; a result file is as open as any other
        except OSError as error:
            raise self._cannot_write(path, error) from None
        self._staged[path] = Path(tmp)
        return Path(tmp)

    def write_bytes(self, path: PathLike, data: bytes) -> Path:
        """Stage ``data`` as the content of ``path``; returns ``path`` (where it will be)."""
        tmp = self.stage(path)
        try:
            with open(tmp, "wb") as handle:
                handle.write(data)
                handle.flush()
                os.fsync(handle.fileno())
        except OSError as error:
            raise self._cannot_write(Path(path), error) from None
        return Path(path)

    def write_text(self, path: PathLike, text: str) -> Path:
        """Stage ``text`` (UTF-8) as the content of ``path``; returns ``path``."""
        return self.write_bytes(path, text.encode("utf-8"))

    # --------------------------------------------------------------- commit / discard
    def commit(self) -> list[Path]:
        """Rename every staged file into place (all planned files must have been staged)."""
        missing = [p for p in self.planned if p not in self._staged]
        if missing:
            self.discard()
            raise RuntimeError(f"output {missing[0]} was planned but never written")
        done: list[Path] = []
        with _signals_held():  # a Ctrl-C or SIGTERM between two renames is taken after the last
            try:
                for path, tmp in self._staged.items():
                    if not tmp.exists():
                        raise OutputError(f"{path}: field '{self.planned[path]}': its staged copy {tmp} disappeared")
                    os.replace(tmp, path)
                    done.append(path)
            except OSError as error:
                self.discard()
                raise self._cannot_write(path, error) from None
            self._staged.clear()
            self._created.clear()
        return done

    def discard(self) -> None:
        """Remove every staged file and the folders this set created (when left empty)."""
        for tmp in self._staged.values():
            try:
                tmp.unlink(missing_ok=True)
            except OSError:
                pass
        self._staged.clear()
        for folder in reversed(self._created):  # innermost first; a folder someone else filled stays
            try:
                folder.rmdir()
            except OSError:
                pass
        self._created.clear()

    def __enter__(self) -> OutputSet:
        return self

    def __exit__(self, kind, error, trace) -> None:
        if kind is None:
            try:
                self.commit()
            except BaseException:  # a Ctrl-C or SIGTERM taken as the commit began: no staged file left behind
                self.discard()
                raise
        else:
            self.discard()

    # ------------------------------------------------------------------ helpers
    def _planned(self, path: PathLike) -> Path:
        path = Path(path)
        if path not in self.planned:
            raise ValueError(f"{path} is not one of the planned outputs {list(map(str, self.planned))}")
        return path

    def _cannot_write(self, path: Path, error: OSError) -> OutputError:
        return OutputError(f"{path}: field '{self.planned[path]}': cannot write: {error.strerror or error}")

    def _make_folder(self, folder: Path, option: str) -> None:
        missing = []
        for parent in [folder, *folder.parents]:
            if parent.exists():
                break
            missing.append(parent)
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            why = error.strerror or error
            raise OutputError(f"{folder}: field '{option}': cannot create the folder: {why}") from None
        self._created.extend(reversed(missing))


#: The signals that end a command (Ctrl-C, ``kill``, a closed terminal), held back while the outputs are renamed.
_HELD_SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))


@contextmanager
def _signals_held() -> Iterator[None]:
    """Hold back :data:`_HELD_SIGNALS` while the block runs and take them after it, as they would have been: the
    renames of a set are not cut in two, some outputs in place and the others left as staged files. Their handlers
    are replaced by one that notes the signal (a mask would not do: a signal sent to the process reaches another
    thread, whose handler then runs in the main one between two renames); nothing held outside the main thread."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = {}
    for number in _HELD_SIGNALS:
        if signal.getsignal(number) is None:  # a handler not installed from Python: it could not be put back
            continue
        previous[number] = signal.signal(number, lambda taken, frame: caught.append(taken))
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)
        for number in dict.fromkeys(caught):
            signal.raise_signal(number)


#: File-name endings that say what a file holds (spherecal reads ``.urdf`` as URDF and a robot file as YAML).
FORMAT_SUFFIXES = {".urdf": "URDF", ".yaml": "YAML", ".yml": "YAML", ".xml": "XML", ".mjcf": "MJCF",
                   ".json": "JSON", ".csv": "CSV"}


def check_suffix(path: PathLike, option: str, written: str, accepted: tuple[str, ...], hint: str = "",
                 read_by_ending: str = "") -> None:
    """Refuse an output whose name says it holds another format than the one written (``calibrate --out
    cal.urdf`` wrote YAML that every later command then read as URDF: 'invalid XML'). Names without a known
    ending (:data:`FORMAT_SUFFIXES`) are the user's choice for a file its readers take by its content; a format
    they open only by its ending (``read_by_ending`` says who) must carry one of ``accepted``.

    Args:
        path: the output file.
        option: its option (``--out``), for the message.
        written: what is written (``"a YAML robot file"``).
        accepted: the endings that fit, first the one suggested (``(".yaml", ".yml")``).
        hint: said after the suggestion (``"; for a URDF: spherecal export --format urdf"``).
        read_by_ending: why the ending is needed (``"the Rerun viewer opens a recording only by that ending"``);
            "": the format is read by its content.

    Raises:
        OutputError: one line naming the option, the file and the ending to use.
    """
    suffix = Path(path).suffix.lower()
    if suffix in FORMAT_SUFFIXES and suffix not in accepted:
        raise OutputError(f"{path}: field '{option}': {written} named {suffix} would be read as "
                          f"{FORMAT_SUFFIXES[suffix]}; name it {accepted[0]}{hint}")
    if read_by_ending and suffix not in accepted:  # 'validate --rrd spread.txt': the viewer would not open it
        raise OutputError(f"{path}: field '{option}': {written} must be named {' or '.join(accepted)} "
                          f"({read_by_ending}){hint}")
