"""The experiment-design analysis: its cells cover the issue's axes; one tiny cell runs and renders."""

from __future__ import annotations

import importlib.util
import re

import numpy as np
import pytest

from spherecal.validation.planning.analysis import (
    P3_LIKE,
    Analysis,
    AnalysisConfig,
    Cell,
    cells,
    main,
    markdown,
    run_cells,
)


def test_cells_cover_every_axis():
    config = AnalysisConfig()
    todo = cells(config, {"A": (0.5, 0.0, 0.4), "B": (0.4, 0.3, 0.2), "C": (0.3, -0.3, 0.6)})
    counts = {(len(c.fixtures), c.distances) for c in todo if c.group == "fixtures"}
    assert counts == {(1, False), (2, True), (2, False), (3, True), (3, False), (4, True), (4, False)}
    assert {c.samples for c in todo if c.group == "samples"} == {50, 200, 500, 2000}
    assert {c.noise for c in todo if c.group == "noise"} == {0.0, 1e-4, 3e-4, 1e-3}
    assert any(c.joint_range == P3_LIKE for c in todo if c.group == "joint range")
    assert [c.name for c in todo if c.group == "plan"][-1].startswith("plan's best")
    key = [c for c in todo if c.group == "fixtures" and c.distances and len(c.fixtures) in (2, 3)]
    assert all(c.sets == config.key_sets == 10 for c in key)


def test_one_small_cell_runs_and_renders():
    from spherecal.validation.planning.plan import Plan

    cell = Cell("noise", "tiny", (("P1", (0.5, -0.25, 0.5)), ("P2", (0.5, 0.0, 0.4))), samples=60, sets=2)
    config = AnalysisConfig(configurations=200, workers=1)
    (result,) = run_cells([cell], config)
    again = run_cells([cell], config)[0]
    np.testing.assert_array_equal(result.measured, again.measured)  # seeded
    assert result.measured.shape == (2,) and np.all(result.measured > 0) and result.predicted_mean > 0
    empty = Plan([], None, "none", "kinematic", 3e-4, 500)
    text = markdown(Analysis([result], empty, config, {"cells": 1.0}), "provenance")
    assert "## Fixture noise" in text and "| tiny |" in text and "<!--\nprovenance\n-->" in text


def test_the_page_and_the_usage_name_a_module_that_python_m_can_run(capsys):
    # docs/experiment_design.md, regenerated, said "or `python -m validation.analysis`": no such module installed
    from spherecal.validation.planning.plan import Plan

    empty = Plan([], None, "none", "kinematic", 3e-4, 500)
    page = markdown(Analysis([], empty, AnalysisConfig(), {}), "provenance")
    with pytest.raises(SystemExit):
        main(["--help"])
    usage = capsys.readouterr().out
    named = re.findall(r"python -m ([\w.]+)", page) + re.findall(r"python -m ([\w.]+)", usage)
    assert len(named) == 2 and all(importlib.util.find_spec(name) is not None for name in named), named


def test_the_page_says_the_cpu_time_and_the_load_beside_the_wall_time():
    # the page said "Wall time 152 s" alone, and a later review took a busy machine's figure (26 s elsewhere) for a
    # slowdown of the code (h4, stop 14): the CPU time and the load say which it was
    from spherecal.validation.planning.plan import Plan

    empty = Plan([], None, "none", "kinematic", 3e-4, 500)
    measured = markdown(Analysis([], empty, AnalysisConfig(), {"plan": 5.0, "cells": 36.0}, 77.0, 1.04), "p")
    assert "Wall time 41 s on 2 workers (plan 5 s, cells 36 s); CPU 77 s in all, load average 1.0 at the end" \
        in measured
    unmeasured = markdown(Analysis([], empty, AnalysisConfig(), {}), "p")
    assert "Wall time 0 s on 2 workers (plan 0 s, cells 0 s)." in unmeasured and "CPU" not in unmeasured


def _empty_analysis(config: AnalysisConfig) -> Analysis:
    from spherecal.validation.planning.plan import Plan

    return Analysis([], Plan([], None, "none", "kinematic", 3e-4, 500), config, {"plan": 0.0, "cells": 0.0})


def test_plan_analysis_is_one_of_the_staged_outputs(tmp_path, capsys, monkeypatch):
    """A review: every command's outputs appear together or not at all. --analysis is staged like --out: written and
    named when it replaced a file; interrupted during the analysis, or failing after the document was written,
    nothing is left (no document, no staged copy, no folder it created) and an earlier document is kept."""
    from spherecal.cli import main
    from spherecal.correction.files.atomic import OutputError
    from spherecal.validation.planning import analysis

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(analysis, "run_analysis", _empty_analysis)  # the real one runs for minutes
    monkeypatch.setattr("sys.argv", ["spherecal", "plan", "--analysis", "design.md"])
    assert main(["plan", "--analysis", "design.md"]) == 0
    first = (tmp_path / "design.md").read_text()
    assert "plan --analysis design.md" in first and "written: design.md" in capsys.readouterr().out
    assert main(["plan", "--analysis", "design.md"]) == 0  # its own earlier document: replaced, and said
    assert "spherecal plan: replaced design.md (it existed)" in capsys.readouterr().out.splitlines()
    (tmp_path / "design.md").write_text(first)

    def interrupted(config):
        raise KeyboardInterrupt

    monkeypatch.setattr(analysis, "run_analysis", interrupted)
    for name in ("design.md", "new/design.md"):
        assert main(["plan", "--analysis", name]) == 130
    assert capsys.readouterr().err.count("spherecal plan: interrupted") == 2

    def written_then_failed(path, text):  # as atomic_write_text: its folder made, the whole document written
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("the new document\n")
        raise OutputError(f"{path}: the disk filled after the document was written")

    monkeypatch.setattr(analysis, "run_analysis", _empty_analysis)
    monkeypatch.setattr(analysis, "atomic_write_text", written_then_failed)
    for name in ("design.md", "new/design.md"):
        assert main(["plan", "--analysis", name]) == 1
    assert "the disk filled" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["design.md"]  # no staged copy, no folder 'new'
    assert (tmp_path / "design.md").read_text() == first


def test_plan_analysis_never_replaces_an_input_or_a_foreign_file(tmp_path, capsys, monkeypatch):
    from spherecal.cli import main
    from spherecal.validation.planning import analysis

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(analysis, "run_analysis", _empty_analysis)
    (tmp_path / "notes.md").write_text("my own notes\n")
    assert main(["plan", "--analysis", "notes.md"]) == 1
    assert "field '--analysis': exists and was not written by an earlier `spherecal plan`" in capsys.readouterr().err
    assert (tmp_path / "notes.md").read_text() == "my own notes\n"
