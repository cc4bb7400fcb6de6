"""Command-line option types shared by the subcommands (argparse only: imported while parsers are built)."""

from __future__ import annotations

import argparse


def seed(text: str) -> int:
    """``--seed``: an integer >= 0 (numpy's generators refuse negative seeds)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}")
    return value


def _finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if value != value or value in (float("inf"), float("-inf")):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def non_negative(text: str) -> float:
    """A finite number >= 0 (noise levels, tolerances)."""
    value = _finite(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return value


def positive(text: str) -> float:
    """A finite number > 0 (durations, expected noise, limits)."""
    value = _finite(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def add_urdf_links(parser: argparse.ArgumentParser) -> None:
    """``--tip-link`` and ``--base-link``: which chain of a ``--robot`` URDF is the arm."""
    parser.add_argument("--tip-link", default=None, metavar="NAME",
                        help="URDF robot: the link whose origin is the tool point, the ball centre "
                        "(default: the end of the longest chain)")
    parser.add_argument("--base-link", default=None, metavar="NAME",
                        help="URDF robot: the link whose frame is the world (default: the root link)")


def urdf_links(args: argparse.Namespace) -> dict:
    """Keyword arguments ``tip_link``, ``base_link`` of ``correction.load_robot`` from the options."""
    return {"tip_link": getattr(args, "tip_link", None), "base_link": getattr(args, "base_link", None)}
