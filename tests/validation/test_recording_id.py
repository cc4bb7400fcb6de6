"""Rerun recording ids: derived from the run (seed, inputs, versions), so that two runs alike write recordings of
one id, and another seed or input another id; a recording of no run gets one of its own."""

from __future__ import annotations

import uuid

import numpy as np

from spherecal.cli import main
from spherecal.validation.viewer.recording import Recording, recording_id

PLAN = ["plan", "--grid", "0.4,0.5,2;-0.2,0.2,2;0.4,0.5,2", "--per-fixture", "50", "--workers", "1"]


def _ids(path) -> list[tuple[str, str]]:
    from rerun.chunk import RrdReader

    return [(entry.application_id, entry.recording_id) for entry in RrdReader(str(path)).recordings()]


def test_two_runs_alike_write_one_recording_id(tmp_path, monkeypatch, capsys) -> None:
    """A review: Rerun's default id, random per process, made two otherwise identical runs' recordings differ."""
    ids = {}
    for folder, seed in (("one", "0"), ("two", "0"), ("three", "1")):
        (tmp_path / folder).mkdir()
        monkeypatch.chdir(tmp_path / folder)
        argv = [*PLAN, "--seed", seed, "--rrd", "plan.rrd"]
        monkeypatch.setattr("sys.argv", ["spherecal", *argv])  # the command line the provenance records
        assert main(argv) == 0
        (ids[folder],) = _ids(tmp_path / folder / "plan.rrd")
    capsys.readouterr()
    app, one = ids["one"]
    assert app == "spherecal_plan" and uuid.UUID(one).version == 5  # name-based, not Rerun's random default
    assert ids["two"] == ids["one"] != ids["three"]  # the same run again: one id; another seed: another


def test_a_recording_id_follows_the_run_given_and_is_its_own_without_one(tmp_path) -> None:
    run = {"command": "spherecal validate", "created": "2026-01-01", "seed": 3, "inputs": {"samples": "s.csv"},
           "versions": {"spherecal": "0.1"}}
    ids = []
    for k, block in enumerate((run, {**run, "created": "2026-01-02", "command": "python -m spherecal"}, None, None)):
        recording = Recording(tmp_path / f"r{k}.rrd", application_id="spherecal_validate", run=block)
        recording.fixtures(["P1"], np.zeros((1, 3)))
        recording.close()
        ids.append(_ids(tmp_path / f"r{k}.rrd")[0][1])
    assert ids[0] == ids[1] == recording_id("spherecal_validate", run)  # the time and program path play no part
    assert len({ids[0], ids[2], ids[3]}) == 3  # without a run: one each (Rerun's default was one per process)
