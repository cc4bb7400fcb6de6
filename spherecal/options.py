"""Command-line options shared by the subcommands: one spelling, one unit and one check per quantity.

Units on the command line (each ``--help`` names them):

==========================================  =======  ==========================================
quantity                                    unit     options
==========================================  =======  ==========================================
noise, error spreads, tolerances of length  mm       ``--noise``, ``--mocap-noise``,
                                                     ``--length-std``, ``--tool-std``
positions and distances of fixtures         m        ``--grid``, ``--distance`` (as in the files)
angles                                      deg      ``--angle-std-deg``, ``--dedup-deg``
durations                                   s        ``--seconds``
==========================================  =======  ==========================================

``--samples`` always names a ``samples.csv`` file; a count of samples per fixture is
``--per-fixture``. An old spelling still works the same with a deprecation warning; a value that
looks like the old unit (``--noise 0.0003``, metres before 0.2) is refused with one line saying what
changed, never reinterpreted.

Only argparse is imported here: this module is loaded while the parsers are built (``--help``).
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from pathlib import Path

#: Below this a length in millimetres is taken for the old unit (metres): 10 micrometres (0 is allowed).
MM_FLOOR = 1e-2
#: Above this a fixture or marker noise [mm] is not a measurement but a slip.
MAX_NOISE_MM = 20.0
#: Longest simulated motion per fixture [s] (one hour; a recording of 1.8 M rows is 30 minutes).
MAX_SECONDS = 3600.0
#: Most random validation configurations (memory: every one is a forward kinematics of each model).
MAX_CONFIGURATIONS = 200_000
#: Most samples per fixture asked of a simulation (memory).
MAX_PER_FIXTURE = 100_000


class OptionError(Exception):
    """An option the command cannot use; printed as one line, exit status 1."""


def fail(message: str) -> OptionError:
    """The error to raise for an option that parsed but cannot be used (``raise fail(...)``)."""
    return OptionError(message)


class StoreOnce(argparse._StoreAction):
    """argparse's ``store``, refusing an option given twice: argparse kept the last silently, so ``calibrate
    --samples a.csv --samples b.csv`` calibrated on ``b.csv`` alone, the user believing both were used."""

    def __call__(self, parser, namespace, values, option_string=None):  # noqa: D102 - argparse's hook
        given = namespace.__dict__.setdefault(_GIVEN, {})
        if option_string is not None and self.dest in given:
            shown = " ".join(map(str, values)) if isinstance(values, list) else values
            parser.error(f"field {given[self.dest][0]!r}: given twice ({given[self.dest][1]!r}, then {shown!r}); it "
                         "takes one value, and the second would silently replace the first")
        mark_given(namespace, self.dest, option_string, values)
        setattr(namespace, self.dest, values)


#: Where :class:`StoreOnce` keeps the options given so far during one parse (removed after it).
_GIVEN = "_given_once"
#: Where the parsed options keep what was typed: destination -> option (:func:`given`).
_TYPED = "_typed"


def mark_given(namespace: argparse.Namespace, dest: str, option_string: str | None, values) -> None:
    """Record that ``option_string`` gave ``dest`` (an action's hook; the first spelling given is kept)."""
    shown = " ".join(map(str, values)) if isinstance(values, list) else values
    namespace.__dict__.setdefault(_GIVEN, {}).setdefault(dest, (option_string, shown))


def given(args: argparse.Namespace) -> dict[str, str]:
    """The options typed on the command line: destination -> the option's name (its full spelling, or the old one
    that gave it); an option argparse filled in with its default is not among them."""
    return dict(getattr(args, _TYPED, {}))


def named(args: argparse.Namespace, dest: str) -> str:
    """The option a refusal of ``dest`` names: as typed (an old spelling too), else its own spelling."""
    return given(args).get(dest, "--" + dest.replace("_", "-"))


def refuse_given(args: argparse.Namespace, dests, why: str) -> None:
    """Refuse the first of ``dests`` (destinations) that was typed: the run would not use it (``why``: 'only with
    --truth', one line as ``field '--seed': only with --truth``).

    Raises:
        OptionError: such an option was given.
    """
    typed = given(args)
    for dest in dests:
        if dest in typed:
            raise fail(f"field '{typed[dest]}': {why}")


#: argparse's own refusal of an option's value ('argument --noise: expected a finite number'; several spellings
#: joined by '/'), renamed as every other refusal names an option: field '--noise'.
_ARGPARSE_OPTION = re.compile(r"^argument (-[^\s:/]*(?:/-[^\s:/]*)*): ")


#: argparse's refusals of a missing option: 'the following arguments are required: --robot, --out' and 'one of the
#: arguments --offset --urdf is required' (a required group).
_ARGPARSE_MISSING = re.compile(r"^the following arguments are required: (.+)$")
_ARGPARSE_ONE_OF = re.compile(r"^one of the arguments (.+) is required$")


def _as_field(message: str, choices: dict[str, tuple] | None = None) -> str:
    """argparse's ``argument --name: ...`` as ``field '--name': ...`` (the long spelling of several), and its
    missing arguments as ``field '--robot': required (also missing: --out)``, a positional one by its name as
    ``field 'CAL.yaml': required (also missing: --format, --out)``; a missing option of a few values (``choices``:
    option string -> its values) names them: ``field '--format': required (one of urdf, mjcf, yaml)`` (``export``
    without --format said only 'required')."""
    def field(match: re.Match) -> str:
        spellings = match.group(1).split("/")
        return f"field '{next((s for s in spellings if s.startswith('--')), spellings[0])}': "

    missing = _ARGPARSE_MISSING.match(message)
    if missing:
        first, *rest = missing.group(1).split(", ")
        values = (choices or {}).get(first)
        return (f"field '{first}': required" + (f" (also missing: {', '.join(rest)})" if rest else "")
                + (f" (one of {', '.join(map(str, values))})" if values else ""))
    one_of = _ARGPARSE_ONE_OF.match(message)
    if one_of:
        options = one_of.group(1).split()
        return f"field '{options[0]}': give {' or '.join(options)} (one of them is required)"
    return _ARGPARSE_OPTION.sub(field, message, count=1)


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line (``spherecal CMD: error: ...``) and exit status 1,
    like every other refusal of spherecal. A negative number in exponent notation (``--offset -1e-2 0 0.2``) is
    a value, as ``-0.01`` is (argparse took it for an option: 'expected 3 arguments'), and so is a comma-separated
    list starting with a negative number (``--effort -5,87,...`` was 'expected one argument', not the check of its
    values). An option that takes one value given twice is refused (:class:`StoreOnce`); a repeatable one says so
    in its help. argparse's refusal of a value names its option as every other refusal does (``field '--noise':
    expected a finite number, got 'nan'``)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(
            r"^-((\d+\.?\d*|\.\d+)([eE][-+]?\d+)?|inf|infinity|nan)(,.*)?$", re.IGNORECASE)
        self.register("action", None, StoreOnce)
        self.register("action", "store", StoreOnce)

    def parse_known_args(self, args=None, namespace=None):  # noqa: D102 - argparse's entry
        namespace, extras = super().parse_known_args(args, namespace)
        typed = {dest: option for dest, (option, _) in namespace.__dict__.pop(_GIVEN, {}).items() if option}
        setattr(namespace, _TYPED, {**given(namespace), **typed})  # a subcommand's parse ran inside this one
        return namespace, extras

    def error(self, message: str):  # noqa: D102 - argparse's hook
        choices = {name: tuple(a.choices) for a in self._actions if a.choices for name in a.option_strings}
        self.exit(1, f"{self.prog}: error: {_as_field(message, choices)} (see {self.prog} --help)\n")


# --------------------------------------------------------------------------------------- types
def _finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def finite(text: str) -> float:
    """Any finite number (coordinates)."""
    return _finite(text)


def non_negative(text: str) -> float:
    """A finite number >= 0 (tolerances, spreads)."""
    value = _finite(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return value


def positive(text: str) -> float:
    """A finite number > 0 (durations, limits)."""
    value = _finite(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def seed(text: str) -> int:
    """``--seed``: an integer >= 0 (numpy's generators refuse negative seeds)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}")
    return value


def count(minimum: int = 1, maximum: int | None = None):
    """An argparse type: an integer >= ``minimum`` (and <= ``maximum`` when given)."""
    wanted = f"an integer >= {minimum}" if maximum is None else f"an integer in {minimum}..{maximum}"

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {wanted}, got {text!r}") from None
        if value < minimum or (maximum is not None and value > maximum):
            raise argparse.ArgumentTypeError(f"expected {wanted}, got {text!r}")
        return value

    return parse


def at_most(limit: float, unit: str, allow_zero: bool = False):
    """An argparse type: a finite number > 0 (>= 0 with ``allow_zero``) and <= ``limit`` [``unit``]."""

    def parse(text: str) -> float:
        value = non_negative(text) if allow_zero else positive(text)
        if value > limit:
            hint = " (millimetres? it is in metres)" if unit == "m" else ""  # a user trial typed 50 for 50 mm
            raise argparse.ArgumentTypeError(f"expected at most {limit:g} {unit}, got {text!r}{hint}")
        if 0 < value < limit * 1e-12:  # subnormal-sized: converting it (deg to rad, 1/x) over- or underflows
            raise argparse.ArgumentTypeError(
                f"expected 0{' or' if allow_zero else ' <'} at least {limit * 1e-12:g} {unit}, got {text!r}"
            )
        return value

    return parse


def configurations(text: str) -> int:
    """``--configurations``: 3 .. :data:`MAX_CONFIGURATIONS` random configurations."""
    return count(3, MAX_CONFIGURATIONS)(text)


def duration(text: str) -> float:
    """``--seconds``: a duration > 0 and at most :data:`MAX_SECONDS` [s]."""
    value = positive(text)
    if value > MAX_SECONDS:
        raise argparse.ArgumentTypeError(f"expected at most {MAX_SECONDS:g} s of simulated motion, got {text!r}")
    return value


def millimetres(text: str, allow_zero: bool = True, upper: float | None = None) -> float:
    """A length in millimetres; a value under :data:`MM_FLOOR` (but not 0) reads as the old metres."""
    value = _finite(text)
    if value < 0 or (value == 0 and not allow_zero):
        raise argparse.ArgumentTypeError(f"expected a number {'>=' if allow_zero else '>'} 0 [mm], got {text!r}")
    if 0 < value < MM_FLOOR:
        raise argparse.ArgumentTypeError(
            f"{text} mm is below {MM_FLOOR:g} mm: this option is in millimetres (it took metres before "
            f"spherecal 0.2); for {value * 1e3:g} mm write {value * 1e3:g}"
        )
    if upper is not None and value > upper:
        raise argparse.ArgumentTypeError(f"{text} mm is not a plausible value (at most {upper:g} mm); it is in mm")
    return value


def noise_mm(text: str) -> float:
    """A noise std [mm]: 0 or 0.01 .. 20 mm (a fixture's play or a marker's noise)."""
    return millimetres(text, upper=MAX_NOISE_MM)


def positive_noise_mm(text: str) -> float:
    """A noise std [mm] that must be > 0 (the expected noise of a calibration)."""
    value = noise_mm(text)
    if value == 0:
        raise argparse.ArgumentTypeError(f"expected a noise > 0 [mm], got {text!r}")
    return value


def spread_mm(text: str) -> float:
    """An error spread [mm] (0 allowed), at most 100 mm."""
    return millimetres(text, upper=100.0)


#: Least length of the stillness segmentation [mm] (a radius, a drift, a separation): a joint reading's own jitter
#: moves a tool point about this much, so a smaller one tells nothing apart; below it, metres were typed (a review:
#: '--min-separation 0.03' for 30 mm was read as 0.03 mm, turning the check off).
SEGMENT_FLOOR_MM = 0.1


def segment_mm(text: str) -> float:
    """A length of the stillness segmentation [mm]: from :data:`SEGMENT_FLOOR_MM` to 100 mm (never 0)."""
    value = millimetres(text, allow_zero=False, upper=100.0)
    if value < SEGMENT_FLOOR_MM:
        raise argparse.ArgumentTypeError(
            f"{text} mm is below {SEGMENT_FLOOR_MM:g} mm, less than a joint reading's jitter moves the tool point: "
            f"this option is in millimetres; for {value * 1e3:g} mm write {value * 1e3:g}"
        )
    return value


# ----------------------------------------------------------------------------- deprecations
def warn(message: str) -> None:
    """A one-line warning on stderr."""
    print(f"spherecal: warning: {message}", file=sys.stderr)


class Deprecated(argparse.Action):
    """An old spelling that still works the same: stores into ``dest`` and warns once.

    ``convert`` maps the old value to the new option's unit (e.g. rad -> deg).
    """

    def __init__(self, option_strings, dest, new: str = "", convert=None, **kwargs):
        self.new, self.convert = new, convert
        super().__init__(option_strings, dest, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        warn(f"{option_string} is deprecated, use {self.new} ({option_string} will be removed)")
        mark_given(namespace, self.dest, option_string, values)
        setattr(namespace, self.dest, self.convert(values) if self.convert else values)


def add_deprecated(parser: argparse.ArgumentParser, old: str, new: str, type, convert=None) -> None:
    """Register ``old`` as a deprecated spelling of ``new`` (same destination, hidden from --help)."""
    dest = new.lstrip("-").replace("-", "_")
    parser.add_argument(old, dest=dest, type=type, action=Deprecated, new=new, convert=convert,
                        help=argparse.SUPPRESS)


# ------------------------------------------------------------------------------ common options
def add_robot(parser: argparse.ArgumentParser, default: str | None = "panda") -> None:
    """``--robot``: a robot file, a URDF (with ``--tip-link``, ``--base-link``), or ``panda``."""
    what = "nominal robot: a robot file (YAML), a URDF (.urdf) or an embedded arm: panda, fr3, iiwa14, gen3lite"
    if default is None:
        parser.add_argument("--robot", required=True, help=what)
    else:
        parser.add_argument("--robot", default=default, help=f"{what} (default {default})")
    add_urdf_links(parser)


def add_urdf_links(parser: argparse.ArgumentParser) -> None:
    """``--tip-link`` and ``--base-link``: which chain of a ``--robot`` URDF is the arm."""
    parser.add_argument("--tip-link", default=None, metavar="NAME",
                        help="URDF robot: the link whose origin is the tool point, the ball centre "
                        "(default: the one end of the serial chain; refused when it ends in several)")
    parser.add_argument("--base-link", default=None, metavar="NAME",
                        help="URDF robot: the link whose frame is the world (default: the root link)")
    parser.add_argument("--inertials", default=None, metavar="FILE",
                        help="link masses for gravity torques: a YAML file with an 'inertials' list, one "
                        "{mass: kg, com: [x, y, z] metres in DH frame i} per joint, and an optional 'payload' "
                        "(correction.files.inertials_file); default: the robot's own, else those of the "
                        "embedded arm (Panda, FR3, iiwa14, Gen3 lite) whose joint axes it shares")


def urdf_links(args: argparse.Namespace) -> dict:
    """Keyword arguments ``tip_link``, ``base_link``, ``inertials`` and ``report`` (print the one line saying
    where the inertials came from) of ``correction.load_robot`` from the options."""
    return {"tip_link": getattr(args, "tip_link", None), "base_link": getattr(args, "base_link", None),
            "inertials": getattr(args, "inertials", None), "report": _report(args)}


#: Options (argparse destinations) that name a robot description: a file, or an embedded robot by its name.
ROBOT_OPTIONS = ("robot", "nominal", "calibrated", "truth")


def check_robot_names(args: argparse.Namespace, robot: str | None = None) -> None:
    """Refuse a robot option (:data:`ROBOT_OPTIONS`) given a bare name that is neither a file nor an embedded robot,
    naming the option, before any work: ``iiwa: field '--robot': no such file, nor an embedded robot (did you mean
    'iiwa14'? ...)`` (the library's refusal named the name, not the option). ``robot``: how the command's parser
    names its ``robot`` when it is not ``--robot`` (export's and tool's positional ``CAL.yaml``).

    Raises:
        OptionError: one line naming the value and the option.
    """
    from spherecal.correction.files.robots import unknown_name  # numpy: not at --help (start-up)

    for dest in ROBOT_OPTIONS:
        value = getattr(args, dest, None)
        why = unknown_name(value) if isinstance(value, str) else None
        if why is not None:
            label = robot if dest == "robot" and robot is not None else named(args, dest)
            raise fail(f"{value}: field '{label}': {why}")


def _report(args: argparse.Namespace):
    """A printer of one library note, prefixed with the command's name."""
    command = getattr(args, "command", None)
    prefix = f"spherecal {command}: " if command else "spherecal: "
    return lambda line: print(prefix + line)


def add_seed(parser: argparse.ArgumentParser, what: str = "everything random") -> None:
    """``--seed``: an integer >= 0 (default 0)."""
    parser.add_argument("--seed", type=seed, default=0, help=f"seed of {what} (default 0)")


def add_per_fixture(parser: argparse.ArgumentParser, default: int, what: str = "samples kept per fixture") -> None:
    """``--per-fixture N`` (old spelling ``--samples N``, deprecated: ``--samples`` names a file elsewhere)."""
    parser.add_argument(
        "--per-fixture", type=count(1, MAX_PER_FIXTURE), default=default, metavar="N",
        help=f"{what} (default {default})",
    )
    add_deprecated(parser, "--samples", "--per-fixture", count(1, MAX_PER_FIXTURE))


#: Rate of the simulated joint readings [Hz]: a self-motion of s seconds holds s * 1000 samples.
READINGS_HZ = 1000


def check_per_fixture(args: argparse.Namespace, least: int, simulated: bool = True) -> None:
    """Refuse ``--per-fixture`` below ``least`` or, for samples drawn from a ``simulated`` self-motion of
    ``--seconds`` at :data:`READINGS_HZ`, more than that motion holds (and a motion shorter than one reading).

    Raises:
        OptionError: one line naming the option, as ``field '--per-fixture': ...``.
    """
    option = named(args, "per_fixture")
    if args.per_fixture < least:
        raise fail(f"field '{option}': expected at least {least} samples per fixture, got {args.per_fixture}")
    if not simulated:
        return
    held = round(args.seconds * READINGS_HZ)
    if held < 1:
        raise fail(f"field '{named(args, 'seconds')}': expected at least {1 / READINGS_HZ:g} s (one reading at "
                   f"{READINGS_HZ} Hz), got {args.seconds:g}")
    if args.per_fixture > held:
        raise fail(f"field '{option}': {args.per_fixture} samples per fixture are more than {args.seconds:g} s of "
                   f"{READINGS_HZ} Hz readings hold ({held})")


def add_seconds(parser: argparse.ArgumentParser, default: float, what: str) -> None:
    """``--seconds``: a duration [s] > 0, at most :data:`MAX_SECONDS`."""
    parser.add_argument("--seconds", type=duration, default=default, help=f"{what} [s] (default {default:g})")


def add_workers(parser: argparse.ArgumentParser, what: str = "tasks", also: str = "") -> None:
    """``--workers N`` (the built-in process pool, default 2; ``also``: what else uses it) and
    ``--scheduler ADDRESS`` (a Dask cluster instead, for the ``what``)."""
    parser.add_argument("--workers", type=count(1, 64), default=2,
                        help=f"worker processes for the {what}{also} (default 2; 1: in this process)")
    parser.add_argument(
        "--scheduler", default=None, metavar="ADDRESS",
        help=f"run the {what} on a dask.distributed cluster: 'local' starts one of --workers processes on "
        "127.0.0.1 for this run, else a running scheduler's address (tcp://host:8786) whose workers have "
        "spherecal installed; needs dask.distributed, spherecal's 'dask' extra (default: the built-in process pool)",
    )


def start_viewer(args: argparse.Namespace, instead: str) -> None:
    """With ``--spawn``, start the Rerun viewer before any work (:func:`spherecal.validation.viewer.recording.
    spawn_viewer`: a review found ``demo --spawn`` refused only after 9 s of work). ``instead``: the remedy the
    refusal offers, as ``write it with --rrd FILE and open it elsewhere``.

    Raises:
        OutputError: no viewer could be started (one line naming ``--spawn``).
    """
    if getattr(args, "spawn", False):
        from spherecal.validation.viewer.recording import spawn_viewer  # rerun: heavy, only with --spawn

        spawn_viewer(instead)


# ------------------------------------------------------------------------------------ outputs
#: Options (argparse destinations) that name files a command reads: no output may be one of them.
INPUT_OPTIONS: tuple[str, ...] = (
    "robot", "samples", "fixtures", "mocap", "truth", "nominal", "calibrated", "candidates", "predict", "into",
    "source", "inertials", "urdf",
)


def recorded_options(args: argparse.Namespace) -> dict:
    """The options of a run as its provenance block records them (``correction.files.provenance``): every
    option as given, argparse's internals left out, and each input that names an existing file as a
    :class:`~pathlib.Path`, so that the block records its SHA-256. An output (:data:`OUTPUT_OPTIONS`) is recorded
    as its name: the file it replaces is not an input (a second ``validate --out v.json`` recorded the first
    report's SHA-256 among its inputs)."""
    from pathlib import Path

    return {k: Path(v) if isinstance(v, str) and k not in OUTPUT_OPTIONS and Path(v).is_file() else v
            for k, v in vars(args).items() if not k.startswith("_") and k != "command"}


#: Output options whose file holds one format: what it is, the endings that fit (a name ending for another format
#: is refused), a hint, and why any other ending is refused when its readers open it only by its ending (""
#: for a format read by its content: another name is the user's choice), as
#: :func:`spherecal.correction.files.outputs.check_suffix` takes them.
NAMED_OUTPUTS = {"--rrd": ("a Rerun recording", (".rrd",), "",
                           "the Rerun viewer opens a recording only by that ending"),
                 "--analysis": ("a Markdown document", (".md",), "", "")}
#: A robot file is read by its content (correction.load_robot: a .urdf or an XML <robot> as URDF, any other as YAML).
_ROBOT_OUT = ((".yaml", ".yml"), "; for a URDF or MJCF of it: spherecal export", "")
#: Per command, what its ``--out`` file holds (as :data:`NAMED_OUTPUTS`); export's depends on its --format
#: (controller.export_file), the other commands' --out is a folder.
OUT_FORMATS = {"validate": ("a JSON report", (".json",), "", ""), "plan": ("a JSON report", (".json",), "", ""),
               "calibrate": ("a calibrated robot file (YAML)", *_ROBOT_OUT),
               "tool": ("a robot file (YAML)", *_ROBOT_OUT)}


def planned_outputs(args: argparse.Namespace, outputs: dict):
    """The :class:`spherecal.correction.files.outputs.OutputSet` of a command, checked before any work.

    Args:
        args: the parsed options; every option of :data:`INPUT_OPTIONS` it has is an input.
        outputs: option -> the file (or list of files) it will write; None for an option not given.

    Raises:
        spherecal.correction.files.outputs.OutputError: an output that is an input, is planned twice, is a
            folder, lies where nothing can be written, or is named for another format (one line naming the option
            and the file; :data:`NAMED_OUTPUTS`, :data:`OUT_FORMATS`).
    """
    from spherecal.correction.files.outputs import OutputSet, check_suffix  # numpy: not at --help (start-up)

    inputs = {f"--{name.replace('_', '-')}" if name != "source" else "SOURCE": getattr(args, name, None)
              for name in INPUT_OPTIONS}
    if getattr(args, "command", None) in ("export", "tool"):  # their robot file is the positional argument
        inputs["CAL.yaml"] = inputs.pop("--robot")
    planned = OutputSet({k: v for k, v in outputs.items() if v is not None},
                        {k: v for k, v in inputs.items() if isinstance(v, str)},
                        file_inputs=[k for k in inputs if k != "SOURCE"])  # only SOURCE may name a folder
    formats = dict(NAMED_OUTPUTS)
    if getattr(args, "command", None) in OUT_FORMATS:
        formats["--out"] = OUT_FORMATS[args.command]
    for option, (written, accepted, hint, read_by_ending) in formats.items():  # plan --rrd plan.json: a recording
        if isinstance(outputs.get(option), str):
            check_suffix(outputs[option], option, written, accepted, hint, read_by_ending)
    return planned


#: Commands whose ``--out`` is a folder their files go into; every other output option names a file.
FOLDER_OUT = ("simulate", "import", "demo", "campaign")
#: The options that name outputs (a command has some of them): a command writes their files, never reads them
#: (:func:`recorded_options` hashes none).
OUTPUT_OPTIONS = ("out", "rrd", "analysis", "fixtures_out")


def output_folders(args: argparse.Namespace) -> list[Path]:
    """The folders a command's outputs go into: ``--out`` itself for :data:`FOLDER_OUT`, else each output file's
    folder. A missing one is created (with its missing parents) when the outputs are written
    (``correction.files.outputs.OutputSet``), and :func:`say_created` names it."""
    out = getattr(args, "out", None)
    itself = [Path(out)] if args.command in FOLDER_OUT and isinstance(out, str) and out else []
    return itself + [path.parent for path in output_files(args)]


def output_files(args: argparse.Namespace) -> list[Path]:
    """The files a command names as its outputs (``--out`` of every command but :data:`FOLDER_OUT`, ``--rrd``,
    ``--analysis``, ``--fixtures-out``); one that exists is replaced (never an input: :func:`planned_outputs`), and
    :func:`say_replaced` names it."""
    return [Path(value) for name in OUTPUT_OPTIONS
            if isinstance(value := getattr(args, name, None), str) and value
            and not (name == "out" and args.command in FOLDER_OUT)]


def say_replaced(args: argparse.Namespace, existing: list[Path]) -> None:
    """One line on stdout per output file that existed before a command that succeeded (``existing``: those of
    :func:`output_files`): a second ``calibrate --out cal.yaml`` replaced the first without a word (a user trial)."""
    for path in dict.fromkeys(existing):
        print(f"spherecal {args.command}: replaced {path} (it existed)")


def say_created(args: argparse.Namespace, missing: list[Path]) -> None:
    """One line on stdout per output folder that did not exist before the command and does now (``missing``: those of
    :func:`output_folders` absent before it ran): every command creates a missing folder, and says so, so that a
    mistyped ``--out reslts/cal.yaml`` does not go unseen. A command that failed removed what it created: no line."""
    for folder in dict.fromkeys(missing):
        if folder.is_dir():
            print(f"spherecal {args.command}: created the folder {folder} (it did not exist)")


#: Endings of the files the commands read and write: an output folder named so is a file name given by mistake (a
#: user's ``import ... --out train/samples.csv`` created a folder ``samples.csv`` holding samples.csv and
#: fixtures.yaml, and the next ``calibrate --samples train/samples.csv`` found a folder).
FILE_ENDINGS = (".csv", ".yaml", ".yml", ".json", ".rrd", ".urdf", ".xml", ".mjcf", ".bag", ".mcap", ".db3", ".md")


def check_folder(path: str, option: str = "--out", writes: tuple[str, ...] = ()) -> None:
    """Refuse an output folder that is an existing file or lies under one, before a long run, or that does not
    exist yet and is named like a file (:data:`FILE_ENDINGS`), naming the folder to give instead (``writes``: the
    names of the files the command writes into it; ``--out train/samples.csv`` then means ``--out train``)."""
    from spherecal.correction.files.outputs import check_folder as check

    folder = Path(path)
    # an existing file or link (a loop too): check() names it
    if folder.suffix.lower() in FILE_ENDINGS and not (folder.is_symlink() or folder.exists()):
        meant = folder.parent if folder.name in writes else folder.with_suffix("")
        what = f" ({', '.join(writes)})" if writes else ""
        example = "" if meant.is_dir() and any(meant.iterdir()) else f", e.g. {option} {meant}"
        raise fail(f"{path}: field '{option}': a folder named like a file ({folder.suffix}): {option} is the folder "
                   f"the command writes its files into{what}; give a folder{example}")
    check(path, option)
