"""Progress bars: on stderr, silent off a terminal or when asked, counting what was done."""

from __future__ import annotations

import sys

from spherecal.validation.progress import progress_bar


def _run(quiet: bool = False) -> None:
    with progress_bar(1.0, "self-motion", "s simulated", quiet=quiet, decimals=1) as advance:
        advance(0.25)
        advance(0.75)


def test_progress_bar_is_silent_off_a_terminal_and_when_quiet(capsys, monkeypatch) -> None:
    _run()
    assert capsys.readouterr() == ("", "")  # captured stderr is not a terminal (pipes, CI logs)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    _run(quiet=True)
    assert capsys.readouterr() == ("", "")


def test_progress_bar_on_a_terminal_counts_to_the_total_on_stderr(capsys, monkeypatch) -> None:
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    _run()
    out, err = capsys.readouterr()
    assert out == "" and "self-motion: 100%" in err and "1.0/1.0 s simulated" in err
