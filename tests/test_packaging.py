"""The installed distribution puts one top-level name on ``sys.path``: ``spherecal``."""

from __future__ import annotations

import ast
import shutil
import subprocess
import sys
import sysconfig
import zipfile
from importlib import metadata
from pathlib import Path, PurePosixPath

import pytest

ROOT = Path(__file__).parents[1]


def _installed() -> metadata.Distribution:
    """The distribution in site-packages (not the ``.egg-info`` of a checkout on the path)."""
    paths = [sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]]
    found = list(metadata.distributions(name="spherecal", path=paths))
    if not found:  # pragma: no cover - the suite is meant to run on an installed spherecal
        pytest.skip("spherecal is not installed in this environment")
    return found[0]


def _top_level(files: list[str]) -> set[str]:
    names = set()
    for name in files:
        top = PurePosixPath(name).parts[0]
        if top.endswith((".dist-info", ".egg-info", ".pth")) or top in ("..", "__pycache__"):
            continue
        names.add(top.removesuffix(".py"))
    return names


def test_the_installed_distribution_has_no_top_level_name_but_spherecal() -> None:
    dist = _installed()
    names = _top_level([str(f) for f in dist.files or ()])
    for hook in [n for n in names if n.startswith("__editable__")]:
        # An editable install ships an import hook instead of the files: read what it maps.
        names.discard(hook)
        tree = ast.parse((Path(dist.locate_file(hook + ".py"))).read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.AnnAssign) and getattr(node.target, "id", "") == "MAPPING":
                names |= {key.split(".")[0] for key in ast.literal_eval(node.value)}
    assert names == {"spherecal"}, names


def test_a_built_wheel_has_no_top_level_name_but_spherecal(tmp_path) -> None:
    pytest.importorskip("setuptools")
    source = tmp_path / "source"  # a copy: the build leaves build/ and *.egg-info beside pyproject.toml
    for name in ("pyproject.toml", "README.md"):
        source.mkdir(exist_ok=True)
        shutil.copy(ROOT / name, source / name)
    for name in ("spherecal", "correction", "identification", "controller", "validation"):
        shutil.copytree(ROOT / name, source / name, ignore=shutil.ignore_patterns("__pycache__"))
    code = "import sys; from setuptools import build_meta; print(build_meta.build_wheel(sys.argv[1]))"
    out = subprocess.run([sys.executable, "-c", code, str(tmp_path)], cwd=source, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-2000:]
    wheel = tmp_path / out.stdout.strip().splitlines()[-1]
    names = zipfile.ZipFile(wheel).namelist()
    assert _top_level(names) == {"spherecal"}
    for package in ("correction", "identification", "controller", "validation", "commands"):
        assert f"spherecal/{package}/__init__.py" in names
    assert "spherecal/correction/data/panda.yaml" in names


_PROBE = """
import importlib, sys
for name in ("correction", "identification", "controller", "validation", "cli", "commands"):
    module = importlib.import_module("spherecal." + name)
    assert module.__file__.startswith(sys.argv[1]), (name, module.__file__)
for name in ("tests", "bench", "spherecal", "docs"):
    try:
        importlib.import_module("spherecal." + name)
    except ImportError:
        continue
    raise SystemExit("spherecal." + name + " imports")
print("ok")
"""


@pytest.mark.parametrize("hook", ["installed", "bare"])
def test_a_source_checkout_exposes_only_the_package_folders(hook: str) -> None:
    """Run at the repository root (as the README's test command is), ``spherecal`` maps the four
    design-card folders and the CLI, never the root's other folders (tests, bench, the CLI folder
    itself). ``bare``: no install hook at all (site-packages on the path for numpy and friends, but
    its ``.pth`` import hooks not run), so the package's own finder does the mapping."""
    if hook == "installed":
        command = [sys.executable, "-c", _PROBE, str(ROOT)]
    else:
        paths = [str(ROOT), sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]]
        code = f"import sys; sys.path[:0] = {paths!r}; exec(compile({_PROBE!r}, 'probe', 'exec'))"
        command = [sys.executable, "-S", "-c", code, str(ROOT)]
    out = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stdout + out.stderr[-2000:]
