"""A new user's trial of the command line on MUKCa's real Gen3 lite recordings (tests/data/mukca, MIT): what the
refusals and summaries say, line by line (the decisions are tested elsewhere)."""

from __future__ import annotations

from pathlib import Path

import pytest

from spherecal.cli import main

DATA = Path(__file__).parents[1] / "data" / "mukca"
KINOVA = DATA / "gen3lite_ball.yaml"


def _imported(tmp_path: Path, placement: str) -> Path:
    out = tmp_path / placement.replace("/", "_")
    assert main(["import", str(DATA / placement), "--format", "mukca", "--robot", str(KINOVA), "--out", str(out)]) == 0
    return out


def _calibrate(folder: Path, capsys, *extra: str) -> tuple[int, list[str]]:
    capsys.readouterr()
    code = main(["calibrate", "--robot", str(KINOVA), "--samples", str(folder / "samples.csv"), "--fixtures",
                 str(folder / "fixtures.yaml"), "--out", str(folder / "cal.yaml"), *extra])
    captured = capsys.readouterr()
    return code, (captured.err if code else captured.out).splitlines()


def _refusal(lines: list[str]) -> tuple[str, list[str]]:
    """The refusal's first line and its indented detail lines."""
    k = next(i for i, line in enumerate(lines) if "error: refused:" in line)
    return lines[k], [line for line in lines[k + 1:] if line.startswith("  ")]


def test_a_refusal_for_not_beating_nominal_says_by_how_much_in_its_first_line(tmp_path, capsys) -> None:
    # dinova_2 right-high, one socket: 1.74 mm predicted against 2.85 mm of the nominal reads as a pass; the 2x margin
    # was printed at the end of the training sockets' line, '(at most 0.5x needed)'
    code, lines = _calibrate(_imported(tmp_path, "dinova_2/right-high"), capsys)
    assert code == 1
    first, detail = _refusal(lines)
    assert "cannot be expected to beat the nominal model by 2x near the recording, its predicted error 0.6" in first
    assert "x the nominal's, where at most 0.5x is needed" in first
    sockets = next(line for line in detail if "on the training sockets" in line)
    assert "needed" not in sockets


@pytest.mark.parametrize(("placement", "excluded"), [("dinova_2/gen3lite", None), ("dinova_1/front", "front_h0")])
def test_a_one_socket_refusal_at_the_noise_shown_says_which_bar_it_missed(tmp_path, capsys, placement, excluded
                                                                          ) -> None:
    # one socket judged at the noise its residuals show must beat nominal near the recording and not be worse over the
    # whole workspace; the refusal quoted the 2x verdict of a declared noise over figures that pass ('1.8 mm against
    # 2.64 mm'), or (dinova_1 front without front_h0, whose prediction passed) no verdict at all
    code, lines = _calibrate(_imported(tmp_path, placement), capsys,
                             *(("--exclude-fixture", excluded) if excluded else ()))
    assert code == 1
    _, detail = _refusal(lines)
    shown = next(line for line in detail if line.startswith("  at the noise the residuals show, "))
    assert shown.startswith(
        "  at the noise the residuals show, the calibration is expected to beat the nominal model near the recording, "
        "but from one socket it must not be worse over the whole workspace, and it is expected to be: predicted mean "
        "error ")
    assert "by 2x" not in shown and "samples.csv" not in shown
    # the one socket's remedy, not the 2x margin's 'record more self-motion'
    assert any(line.startswith("  record a second socket or another placement") for line in detail), detail
    assert not any("record more self-motion" in line for line in detail), detail
    assert any(line.startswith("  over the whole workspace (500 random configurations") for line in detail)


def test_validate_keeps_its_columns_under_their_heads_for_long_fixture_names(tmp_path, capsys) -> None:
    # MUKCa's dinova_2 names a socket 'gen3lite_raised_frontright_h0' (29 characters): its figures stood 7 columns
    # right of the heads
    folder = _imported(tmp_path, "dinova_2")
    capsys.readouterr()
    assert main(["validate", "--nominal", str(KINOVA), "--calibrated", str(KINOVA), "--samples",
                 str(folder / "samples.csv"), "--fixtures", str(folder / "fixtures.yaml")]) == 0
    lines = capsys.readouterr().out.splitlines()
    head = next(line for line in lines if line.startswith("fixture "))
    for line in lines[lines.index(head) + 1:]:
        if not line.strip():
            break
        # each figure ends where its head ends
        assert line.index(" ", len(line.split()[0])) <= head.index("samples") + len("samples")
        assert len(line) == len(head), (head, line)
