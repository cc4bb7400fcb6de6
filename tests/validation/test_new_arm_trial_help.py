"""simulate --help for an arm that is not a Panda (new-arm trial)."""

from __future__ import annotations

import re

from spherecal.cli import main


def test_simulate_help_says_where_the_default_fixtures_are_and_for_which_arm_its_example_is(capsys):
    """--fixtures did not say what the default was (the Panda's points, found only in the guide), and --stiffness's
    example had 7 values, refused on a six-joint arm ('expected 1 or 6 finite values')."""
    main(["simulate", "--help"])
    text = re.sub(r"\s+", " ", capsys.readouterr().out)
    assert "default: the Panda's P1, P2, P3" in text and "scaled to the reach of an arm" in text
    assert "0,3e4,3e4,3e4,0,0,0 on a 7-joint arm" in text
