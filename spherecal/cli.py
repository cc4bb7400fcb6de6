"""The ``spherecal`` command line: one subcommand per job, registered in :data:`COMMANDS`.

The subcommands live in :mod:`spherecal.commands` (the command-line layer on top of the packages;
no library module imports it). Only argparse is imported while the parser is built; a subcommand
imports numpy, MuJoCo, Rerun or pyswarms when it runs, so start-up stays short.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import signal
import sys
import warnings
from importlib.metadata import PackageNotFoundError, version

#: subcommand -> module with ``HELP``, ``add_arguments(parser)`` and ``run(args) -> int``.
COMMANDS: dict[str, str] = {
    "simulate": "spherecal.commands.simulate",
    "import": "spherecal.commands.import_data",
    "calibrate": "spherecal.commands.calibrate",
    "validate": "spherecal.commands.validate",
    "demo": "spherecal.commands.demo",
    "campaign": "spherecal.commands.campaign",
    "plan": "spherecal.commands.plan",
    "export": "spherecal.commands.export",
    "tool": "spherecal.commands.tool",
}

#: The commands that turn a URDF into the model they write, and say how they parametrise it: a joint whose axis is
#: nearly parallel to the previous one's gets a Hayati beta instead of the d of the joint before
#: (``correction.NearlyParallelAxesWarning``). Calibrate says it, and records it in the calibrated file
#: (``urdf.parallel_joints``; ``calibration.fixed``: that d 'Hayati: held at zero ...'); export says it when it
#: converts a URDF itself (``export ARM.urdf --format yaml``; a calibrated file's parametrisation was chosen
#: already). Every other command reads the URDF for the chain alone and stays silent (a review: import, calibrate,
#: validate and export of the Gen3 lite each repeated it).
PARAMETRISING = ("calibrate", "export")


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with every subcommand registered."""
    from spherecal.options import Parser

    parser = Parser(
        prog="spherecal",
        description="Kinematic calibration of a redundant arm from spherical-joint self-motion.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True, parser_class=Parser)
    for name, module_name in COMMANDS.items():
        module = importlib.import_module(module_name)
        command = sub.add_parser(name, help=module.HELP, description=module.HELP)
        module.add_arguments(command)
        command.set_defaults(_run=module.run)
    return parser


def _version() -> str:

    try:
        return version("spherecal")
    except PackageNotFoundError:
        return "unknown"


def _one_line(message: str) -> str:
    """A refusal is one line, even when it quotes a file name holding a newline."""
    return message.replace("\r", "\\r").replace("\n", "\\n")


class Terminated(BaseException):
    """SIGTERM or SIGHUP: raised in the main thread, as Ctrl-C raises KeyboardInterrupt, so that the outputs being
    staged are removed (``correction.files.outputs.OutputSet``) before the command ends with status 128 + signal."""

    def __init__(self, number: int):
        super().__init__(number)
        self.number = number


#: The signals taken as :class:`Terminated` (a ``kill``, a closed terminal); Ctrl-C is Python's KeyboardInterrupt.
_TERMINATING = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))


@contextlib.contextmanager
def _terminate_cleanly():
    """While a command runs, :data:`_TERMINATING` raise :class:`Terminated` in this process (by default they killed
    it at once: a ``kill`` while the outputs were staged left every staged file and the created folder behind). A
    signal a caller handles itself (a handler other than the default) is left to it; the handlers are put back
    after. A worker process forked meanwhile dies of the signal as before."""
    here = os.getpid()

    def terminate(number, frame):
        if os.getpid() != here:  # a forked worker inherited the handler: end it as the signal would
            signal.signal(number, signal.SIG_DFL)
            os.kill(os.getpid(), number)
            return
        raise Terminated(number)

    previous = {}
    try:
        for number in _TERMINATING:
            if signal.getsignal(number) is signal.SIG_DFL:
                previous[number] = signal.signal(number, terminate)
    except ValueError:  # not the main thread: signals cannot be handled here
        pass
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


@contextlib.contextmanager
def _printable_streams():
    """While a command runs, stdout and stderr print a file name's byte that is not UTF-8 as its escape (``\\udcff``):
    with a strict stream (a UTF-8 locale other than C.UTF-8, a pipe under PYTHONIOENCODING) the 'wrote FILE' line
    raised UnicodeEncodeError, a traceback after the outputs were written. Put back after."""
    changed = []
    for stream in (sys.stdout, sys.stderr):
        if getattr(stream, "errors", None) == "strict" and hasattr(stream, "reconfigure"):
            try:
                stream.reconfigure(errors="backslashreplace")
            except (ValueError, OSError):  # a stream that cannot change (detached, closed)
                continue
            changed.append(stream)
    try:
        yield
    finally:
        for stream in changed:
            try:
                stream.reconfigure(errors="strict")
            except (ValueError, OSError):
                pass


def main(argv: list[str] | None = None) -> int:
    """Run one subcommand; return its exit status. Every refusal (a bad option, bad input, a file that
    cannot be read or written) prints one line and returns 1, after the warnings the command gave before it (each
    on its own line; on success they follow the command's own lines). A long refusal of a calibration (an error
    with ``lines``: :attr:`spherecal.identification.selfcheck_result.InconsistentDataError.lines`) gives its reason in
    that line and its detail on indented lines below it."""
    try:
        args = build_parser().parse_args(argv)  # --help and bad options end here, before numpy loads
    except SystemExit as done:
        return done.code if isinstance(done.code, int) else 1
    # threadpoolctl: not at --help (start-up). The caps go into the environment before numpy (or
    # scipy, each with its own BLAS) loads, and thread_cap limits what a caller had loaded already.
    from spherecal.validation.threads import cap_environment, thread_cap

    cap_environment()
    from spherecal.correction.errors import SpherecalError  # numpy: not at --help (start-up)
    from spherecal.correction.files.urdf_to_dh import NearlyParallelAxesWarning
    from spherecal.options import OptionError, output_files, output_folders, say_created, say_replaced

    missing = [folder for folder in output_folders(args) if not folder.exists()]
    existing = [path for path in output_files(args) if path.is_file()]

    held: list[str] = []  # warnings wait for the outcome: printed after the success lines, or before the refusal

    def one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
        held.append(_one_line(str(message)))

    def flush() -> None:
        for text in held:
            print(f"spherecal {args.command}: warning: {text}", file=sys.stderr)

    with _printable_streams():  # a file name that is not UTF-8 in the lines below: escaped, not a traceback
        try:
            with _terminate_cleanly(), warnings.catch_warnings(), thread_cap():
                warnings.showwarning = one_line_warning  # a warning for the user, not a source location
                if args.command not in PARAMETRISING:  # said once, where the parametrisation is chosen
                    warnings.filterwarnings("ignore", category=NearlyParallelAxesWarning)
                status = int(args._run(args) or 0)
            say_created(args, missing)
            say_replaced(args, existing)
            flush()
            return status
        except (SpherecalError, OptionError) as error:
            # every warning on its own line, then the refusal's one line: a refusal that quoted the first warning and
            # hid the rest behind '; ...' lost the Gen3 lite's joint-limit warning (a user trial)
            flush()
            also = f" (after {len(held)} warning{'s' * (len(held) > 1)}, above)" if held else ""
            # a long refusal of the calibration: its reason in the error line, its clauses (figures, causes, remedies,
            # the commands to try) one an indented line below it (a user trial: 1,850 characters in one line)
            first, *details = getattr(error, "lines", None) or (str(error),)
            print(f"spherecal {args.command}: error: {_one_line(first)}{also}", file=sys.stderr)
            for detail in details:
                print(f"  {_one_line(detail)}", file=sys.stderr)
            return 1
        except OSError as error:  # a file that cannot be read or written: one line, not a traceback
            where = f"{error.filename}: " if error.filename else ""
            print(f"spherecal {args.command}: error: {_one_line(f'{where}{error.strerror or error}')}", file=sys.stderr)
            return 1
        except UnicodeEncodeError as error:  # a file name's byte that is not UTF-8 written into a text file: one line
            from spherecal.correction.files.provenance import printable

            held_text = error.object if isinstance(error.object, str) else ""
            text = printable(held_text[max(error.start - 40, 0):error.end + 40])
            why = f"cannot write '{text}' into a UTF-8 file: a byte in it is not UTF-8 (a file name?); rename it"
            print(f"spherecal {args.command}: error: {_one_line(why)}", file=sys.stderr)
            return 1
        except KeyboardInterrupt:
            print(f"spherecal {args.command}: interrupted", file=sys.stderr)
            return 130
        except Terminated as ended:
            print(f"spherecal {args.command}: terminated ({signal.Signals(ended.number).name})", file=sys.stderr)
            return 128 + ended.number


if __name__ == "__main__":
    sys.exit(main())
