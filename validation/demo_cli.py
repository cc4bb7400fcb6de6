"""`spherecal demo`: End-to-end demo on the embedded Panda: simulate, calibrate, validate, record."""

from __future__ import annotations

import argparse

HELP = "End-to-end demo on the embedded Panda: simulate, calibrate, validate, record."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the options of `spherecal demo`."""


def run(args: argparse.Namespace) -> int:
    """Not built yet: exits 2."""
    from validation.cli import not_yet_available

    return not_yet_available("demo")
