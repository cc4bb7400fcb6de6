"""One provenance block for every output: its shape, its digests, and that no writer builds its own."""

from __future__ import annotations

import ast
import hashlib
import os
from importlib.metadata import version
from pathlib import Path

from spherecal.correction.files.provenance import comment_block, folder_digest, input_record, provenance

ROOT = Path(__file__).parents[2]


def test_the_block_records_command_versions_seed_and_input_digests(tmp_path) -> None:
    samples = tmp_path / "samples.csv"
    samples.write_bytes(b"t,fixture,q1\n0,P1,0.1\n")
    block = provenance(7, {"samples": samples, "robot": Path("panda"), "folder": tmp_path, "loss": "huber"},
                       command=["spherecal", "calibrate", "--seed", "7"])
    assert list(block) == ["command", "created", "versions", "seed", "inputs"]
    assert block["command"] == "spherecal calibrate --seed 7" and block["seed"] == 7
    assert block["versions"]["numpy"] == version("numpy") and "python" in block["versions"]
    digest = hashlib.sha256(samples.read_bytes()).hexdigest()
    assert block["inputs"]["samples"] == {"path": str(samples), "sha256": digest}
    assert block["inputs"]["robot"] == {"path": "panda", "sha256": "embedded"}
    assert block["inputs"]["folder"]["sha256"] == folder_digest(tmp_path) and block["inputs"]["loss"] == "huber"
    text = comment_block(block)
    assert f"samples={samples} (sha256 {block['inputs']['samples']['sha256']})" in text
    assert text.splitlines()[0] == "command: spherecal calibrate --seed 7" and "seed: 7" in text


def test_a_folder_input_has_the_sha256_of_its_files_paths_and_bytes(tmp_path) -> None:
    # was: "sha256": "folder", whatever the folder held
    source = tmp_path / "robot"
    (source / "front").mkdir(parents=True)
    (source / "front" / "hole_0.csv").write_bytes(b"0.1,0.2\n")
    (source / "front" / "hole_1.csv").write_bytes(b"0.3,0.4\n")
    (source / "notes.txt").write_bytes(b"day 1\n")
    os.symlink("..", source / "front" / "up")  # a link back up: followed once, no loop
    os.mkfifo(source / "pipe")  # reading it would block: skipped
    listed = "".join(f"{hashlib.sha256(p.read_bytes()).hexdigest()}  {p.relative_to(source).as_posix()}\n"
                     for p in sorted(source.rglob("*")) if p.is_file())  # sha256sum's lines, sorted by path
    digest = input_record(source)["sha256"]
    assert digest == hashlib.sha256(listed.encode()).hexdigest()
    (source / "front" / "hole_1.csv").write_bytes(b"0.3,0.5\n")  # one byte changed
    assert input_record(source)["sha256"] != digest
    (source / "front" / "hole_1.csv").write_bytes(b"0.3,0.4\n")
    assert input_record(source)["sha256"] == digest
    (source / "front" / "hole_1.csv").rename(source / "front" / "hole_2.csv")  # same bytes, another name
    assert input_record(source)["sha256"] != digest


def _writers() -> list[Path]:
    folders = ("correction", "identification", "controller", "validation", "spherecal", "bench")
    return [p for folder in folders for p in sorted((ROOT / folder).rglob("*.py"))]


def test_no_writer_builds_its_own_provenance() -> None:
    """Versions and digests come from :func:`provenance` only: nobody else calls ``versions()``,
    ``input_record()`` or ``file_digest()``, or writes a ``"versions"``/``"sha256"`` key by hand."""
    own = ROOT / "correction" / "files" / "provenance.py"
    bad = []
    for path in _writers():
        if path == own:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call):
                name = getattr(node.func, "id", getattr(node.func, "attr", ""))
                if name in ("versions", "input_record", "file_digest"):
                    bad.append(f"{path.relative_to(ROOT)}:{node.lineno} calls {name}()")
            if isinstance(node, ast.Dict):
                keys = {k.value for k in node.keys if isinstance(k, ast.Constant)}
                if keys & {"versions", "sha256"}:
                    bad.append(f"{path.relative_to(ROOT)}:{node.lineno} writes {sorted(keys & {'versions', 'sha256'})}")
    assert not bad, "\n".join(bad)
