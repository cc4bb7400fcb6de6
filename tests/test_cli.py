"""The command line: subcommands listed, start-up light, README and CI in step."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).parents[1]


def test_help_lists_every_subcommand() -> None:
    out = subprocess.run(
        [sys.executable, "-m", "spherecal.cli", "--help"], capture_output=True, text=True, cwd=ROOT
    )
    assert out.returncode == 0
    for name in ("simulate", "calibrate", "validate", "demo", "campaign", "plan", "export"):
        assert re.search(rf"^\s+{name}\s", out.stdout, re.M), name


def test_help_imports_no_heavy_dependency() -> None:
    code = (
        "import sys, spherecal.cli as c; c.build_parser();"
        "print(sorted(m for m in ('mujoco','rerun','pyswarms','scipy','numpy') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.stdout.strip() == "[]", out.stdout + out.stderr


def test_subcommand_help_imports_no_heavy_dependency() -> None:
    code = (
        "import sys, contextlib, io, spherecal.cli as c\n"
        "for name in c.COMMANDS:\n"
        "    with contextlib.suppress(SystemExit), contextlib.redirect_stdout(io.StringIO()):\n"
        "        c.main([name, '--help'])\n"
        "print(sorted(m for m in ('mujoco','rerun','pyswarms','scipy','numpy') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert out.stdout.strip() == "[]", out.stdout + out.stderr


def test_ci_runs_exactly_the_readme_test_command() -> None:
    readme = (ROOT / "README.md").read_text()
    ci = (ROOT / ".ci" / "run").read_text()
    command = next(line for line in ci.splitlines() if "pytest" in line and not line.startswith("#"))
    assert command in readme


def test_an_os_error_is_one_line_and_exit_1(capsys, monkeypatch) -> None:
    import spherecal.cli as cli

    def failing(args):
        raise PermissionError(13, "Permission denied", "/root/locked/out.yaml")

    parser = cli.build_parser()
    monkeypatch.setattr(cli, "build_parser", lambda: parser)
    parser.set_defaults(_run=failing)
    for action in parser._subparsers._group_actions:
        for sub in action.choices.values():
            sub.set_defaults(_run=failing)
    assert cli.main(["export", "panda", "--format", "yaml", "--out", "/root/locked/out.yaml"]) == 1
    err = capsys.readouterr().err
    assert err == "spherecal export: error: /root/locked/out.yaml: Permission denied\n"


def test_readme_steps_run_in_the_venv_and_write_only_ignored_files() -> None:
    # the steps called a bare `spherecal`, which is not on PATH after the README's two set-up commands
    readme = (ROOT / "README.md").read_text()
    block = readme.split("The whole method, step by step", 1)[1].split("```bash\n", 1)[1].split("```", 1)[0]
    lines = [line for line in block.splitlines() if line.strip()]
    assert len(lines) == 4 and all(line.startswith(".venv/bin/spherecal ") for line in lines), lines
    written = re.findall(r"--(?:out|rrd) (\S+)", block)
    written = [f"{w}/samples.csv" if "." not in w else w for w in written] + ["spherecal-demo/demo.rrd", "shot.png"]
    if not (ROOT / ".git").exists():
        return
    for path in written:
        check = subprocess.run(["git", "check-ignore", "-q", path], cwd=ROOT)
        assert check.returncode == 0, f"{path} is not ignored by git"


def test_readme_is_short_and_its_docs_links_resolve() -> None:
    """The README stays a front page (at most 200 lines); everything else is in docs/, and every
    page it links exists and is in the site's table of contents."""
    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) <= 200
    links = re.findall(r"\]\((docs/[^)#]+)", readme)
    assert {"docs/guide.md", "docs/real_robot.md", "docs/formats.md", "docs/method.md", "docs/figures.md"} <= set(links)
    index = (ROOT / "docs" / "index.md").read_text()
    for link in links:
        assert (ROOT / link).is_file(), link
        assert f"\n{Path(link).stem}\n" in index, f"{link} is not in docs/index.md's toctree"


def test_readme_python_block_is_the_calibrate_command(tmp_path, monkeypatch, capsys) -> None:
    """The README's Python calibration is what `spherecal calibrate` writes with its defaults (a review: it called
    the bare fit, least squares and geometry only, 0.290 mm held out where the command's model gave 0.224)."""
    import numpy as np

    from spherecal.cli import main
    from spherecal.correction import load_robot, perturb, write_fixtures, write_samples
    from spherecal.identification.synthetic import make_dataset

    readme = (ROOT / "README.md").read_text()
    block = readme.split("## Python", 1)[1].split("```python\n", 1)[1].split("```", 1)[0]
    truth = perturb(load_robot("panda"), np.random.default_rng(3))
    dataset, spec = make_dataset(truth, per_fixture=60, rng=np.random.default_rng(4), noise=1e-4)
    monkeypatch.chdir(tmp_path)
    write_samples(Path("sim/samples.csv"), dataset)
    write_fixtures(Path("sim/fixtures.yaml"), spec)
    space: dict = {}
    exec(block, space)  # noqa: S102 - our own front page
    assert main(["calibrate", "--robot", "panda", "--samples", "sim/samples.csv", "--fixtures", "sim/fixtures.yaml",
                 "--out", "cal.yaml"]) == 0
    written = load_robot("cal.yaml")
    np.testing.assert_allclose(space["done"].model.params, written.params, atol=1e-12)
    assert space["shift"].shape == (1000, 3) and "model: " in capsys.readouterr().out


def test_every_warning_before_a_refusal_reaches_the_user(tmp_path, capsys, monkeypatch) -> None:
    """A user trial: a refusal after two warnings printed '(after 2 warnings: <first>; ...)', and the Gen3 lite's
    joint-limit warning, the second, was never seen. Each warning is its own line before the refusal, whose line
    says how many came before it and does not grow with them."""
    import warnings

    import spherecal.commands.tool as tool
    from spherecal.cli import main
    from spherecal.correction.errors import SpherecalError

    said = [f"warning number {k}: {'x' * 300}" for k in range(5)]

    def run(args) -> int:
        for text in said:
            warnings.warn(text, stacklevel=1)
        raise SpherecalError("cal.yaml: field 'tool': refused")

    monkeypatch.setattr(tool, "run", run)
    assert main(["tool", str(tmp_path / "cal.yaml"), "--offset", "0", "0", "0.1", "--out",
                 str(tmp_path / "t.yaml")]) == 1
    lines = capsys.readouterr().err.splitlines()
    assert lines[:-1] == [f"spherecal tool: warning: {text}" for text in said]
    assert lines[-1] == "spherecal tool: error: cal.yaml: field 'tool': refused (after 5 warnings, above)"
