"""Audit: every output records the command that made it, the versions, the seed and its inputs with their SHA-256."""

from __future__ import annotations

import hashlib
import sys

from spherecal.cli import main


def _sha256(path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_tool_records_its_own_command_versions_and_inputs(tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["export", "panda", "--format", "yaml", "--out", "cal.yaml"]) == 0
    argv = ["tool", "cal.yaml", "--offset", "0", "0", "0.2", "--out", "new tool.yaml"]
    monkeypatch.setattr(sys, "argv", ["spherecal", *argv])
    assert main(argv) == 0
    head = [line for line in (tmp_path / "new tool.yaml").read_text().splitlines() if line.startswith("#")]
    text = "\n".join(head)
    # before: only '# spherecal tool: cal.yaml with the tool at [np.float64(0.0), ...]': no version, no SHA-256
    assert "np.float64" not in text, text
    assert "# command: spherecal tool cal.yaml --offset 0 0 0.2 --out 'new tool.yaml'" in head, text
    assert any(line.startswith("# versions: python ") and "spherecal " in line for line in head), text
    assert f"robot=cal.yaml (sha256 {_sha256(tmp_path / 'cal.yaml')})" in text, text
    assert "# seed: None" in head, text


def test_a_replaced_output_is_not_recorded_as_an_input(tmp_path, monkeypatch) -> None:
    import json

    monkeypatch.chdir(tmp_path)
    assert main(["export", "panda", "--format", "yaml", "--out", "cal.yaml"]) == 0
    argv = ["validate", "--nominal", "panda", "--calibrated", "cal.yaml", "--truth", "cal.yaml", "--configurations",
            "50", "--out", "v.json"]
    assert main(argv) == 0
    first = json.loads((tmp_path / "v.json").read_text())["provenance"]["inputs"]
    assert main(argv) == 0  # replaces v.json
    second = json.loads((tmp_path / "v.json").read_text())["provenance"]["inputs"]
    # before: the second run recorded {'path': 'v.json', 'sha256': <the first report's>} as an input
    assert first["out"] == second["out"] == "v.json", second["out"]
    assert second["calibrated"]["sha256"] == _sha256(tmp_path / "cal.yaml")
    assert main(["tool", "cal.yaml", "--offset", "0", "0", "0.2", "--out", "t.yaml"]) == 0
    assert main(["tool", "cal.yaml", "--offset", "0", "0", "0.2", "--out", "t.yaml"]) == 0
    assert "out=t.yaml (sha256" not in (tmp_path / "t.yaml").read_text()


def test_the_recorded_command_runs_again_in_a_shell(tmp_path, monkeypatch) -> None:
    import shlex

    monkeypatch.chdir(tmp_path)
    argv = ["export", "panda", "--format", "yaml", "--out", "my run;1.yaml"]
    monkeypatch.setattr(sys, "argv", ["spherecal", *argv])
    assert main(argv) == 0
    line = next(x for x in (tmp_path / "my run;1.yaml").read_text().splitlines() if x.startswith("# command: "))
    # before: '--out my run;1.yaml' unquoted: a shell splits the name and ends the command at ';'
    assert shlex.split(line.removeprefix("# command: ")) == ["spherecal", *argv], line


def test_a_file_name_that_is_not_utf8_is_written_readably(tmp_path, monkeypatch, capsys) -> None:
    import os

    if os.name != "posix" or sys.getfilesystemencoding() != "utf-8":
        import pytest

        pytest.skip("a byte that is not UTF-8 in a file name: POSIX, UTF-8 file system encoding")
    monkeypatch.chdir(tmp_path)
    assert main(["export", "panda", "--format", "yaml", "--out", "cal.yaml"]) == 0
    name = os.fsdecode(b"new\xfftool.yaml")  # 'new\udcfftool.yaml'
    argv = ["tool", "cal.yaml", "--offset", "0", "0", "0.2", "--out", name]
    monkeypatch.setattr(sys, "argv", ["spherecal", *argv])
    # before: UnicodeEncodeError (a traceback) writing the command line into the file's comments
    assert main(argv) == 0, capsys.readouterr().err
    text = (tmp_path / name).read_text(encoding="utf-8")
    assert "--out $'new\\xfftool.yaml'" in text, text[:400]
    for fmt in ("urdf", "mjcf"):
        out = os.fsdecode(b"exp\xff." + fmt.encode())
        assert main(["export", "cal.yaml", "--format", fmt, "--out", out]) == 0, capsys.readouterr().err
        (tmp_path / out).read_text(encoding="utf-8")


def test_a_name_no_writer_can_hold_is_one_line_and_nothing_written(tmp_path, monkeypatch, capsys) -> None:
    import os

    import pytest

    from tests.refusal import refused

    if os.name != "posix" or sys.getfilesystemencoding() != "utf-8":
        pytest.skip("a byte that is not UTF-8 in a file name: POSIX, UTF-8 file system encoding")
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "--seconds", "5", "--per-fixture", "100", "--known-distances", "--out", "sim"]) == 0
    samples = os.fsdecode(b"s\xff.csv")
    (tmp_path / "sim" / "samples.csv").rename(tmp_path / samples)
    # calibrate's header line ('calibrated by spherecal calibrate (lm) from s\udcff.csv') is written by the library
    # (identification.workflow): before, UnicodeEncodeError escaped as a traceback
    refused(["calibrate", "--robot", "panda", "--samples", samples, "--fixtures", "sim/fixtures.yaml", "--model", "dh",
             "--out", "cal.yaml"], tmp_path, capsys, "not UTF-8", "s\\xff.csv")


def test_a_recording_named_with_a_byte_that_is_not_utf8_is_written(tmp_path, monkeypatch, capsys) -> None:
    import os

    import pytest

    if os.name != "posix" or sys.getfilesystemencoding() != "utf-8":
        pytest.skip("a byte that is not UTF-8 in a file name: POSIX, UTF-8 file system encoding")
    monkeypatch.chdir(tmp_path)
    assert main(["export", "panda", "--format", "yaml", "--out", "cal.yaml"]) == 0
    rrd, report = os.fsdecode(b"v\xff.rrd"), os.fsdecode(b"v\xff.json")
    # before: 'spherecal validate: error: /tmp/.../.v\udcff.rrd.h14ardx6.staged: cannot write the recording: 'utf-8'
    # codec can't encode character ...' (Rerun opens the staged file by a UTF-8 path)
    assert main(["validate", "--nominal", "panda", "--calibrated", "cal.yaml", "--truth", "cal.yaml",
                 "--configurations", "50", "--out", report, "--rrd", rrd]) == 0, capsys.readouterr().err
    assert sorted(os.listdir(tmp_path)) == sorted(["cal.yaml", report, rrd])
