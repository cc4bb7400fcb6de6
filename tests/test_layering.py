"""The import layering of the design card, read from the source: correction at the bottom, the
command line on top, no cycles between packages, function-level imports only where start-up needs
them (each with a comment saying why)."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
PACKAGES = ("correction", "identification", "controller", "validation")
#: package -> the spherecal packages it may import (itself always).
ALLOWED: dict[str, set[str]] = {
    "correction": set(),
    "identification": {"correction"},
    "controller": {"correction"},
    "validation": {"correction", "identification", "controller"},
}
CLI = {"cli", "commands", "options", "__main__"}


def _imports(path: Path, package: str) -> list[tuple[int, str, bool, bool]]:
    """(line, spherecal-relative module, at function level, has a comment) of every import."""
    source = path.read_text()
    lines = source.splitlines()
    tree = ast.parse(source)
    in_function: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            in_function |= {id(sub) for sub in ast.walk(node) if isinstance(sub, (ast.Import, ast.ImportFrom))}
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            modules = [("." * node.level) + (node.module or "")]
        elif isinstance(node, ast.Import):
            modules = [alias.name for alias in node.names]
        else:
            continue
        text = "\n".join(lines[max(node.lineno - 2, 0) : node.end_lineno])
        commented = "#" in text
        for module in modules:
            if module.startswith("."):
                module = package  # a relative import stays inside its package
            elif module == "spherecal" or module.startswith("spherecal."):
                module = module.split(".")[1] if "." in module else "spherecal"
            else:
                module = "external:" + module
            found.append((node.lineno, module, id(node) in in_function, commented))
    return found


def _library_files():
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            yield package, path


@pytest.mark.parametrize("package", PACKAGES)
def test_each_package_imports_only_the_layers_below_it(package: str) -> None:
    bad = []
    for owner, path in _library_files():
        if owner != package:
            continue
        for line, module, _, _ in _imports(path, package):
            if module.startswith("external:") or module == package:
                continue
            if module in CLI or module == "spherecal" or module not in ALLOWED[package]:
                bad.append(f"{path.relative_to(ROOT)}:{line} imports spherecal.{module}")
    assert not bad, "\n".join(bad)


def test_no_top_level_import_of_the_old_names() -> None:
    """`import correction` (and the like) would find nothing in an installed spherecal."""
    bad = []
    for folder in (*PACKAGES, "spherecal", "tests", "bench"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text())):
                names = []
                if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    names = [node.module]
                elif isinstance(node, ast.Import):
                    names = [alias.name for alias in node.names]
                bad += [f"{path.relative_to(ROOT)}:{node.lineno} {n}" for n in names if n.split(".")[0] in PACKAGES]
    assert not bad, "\n".join(bad)


def test_function_level_imports_in_library_code_say_why() -> None:
    """Function-level imports only for start-up (heavy dependencies), each with a comment; the
    standard library, numpy and our own light modules are imported at the top."""
    bad = []
    for package, path in _library_files():
        for line, module, local, commented in _imports(path, package):
            if local and not commented:
                bad.append(f"{path.relative_to(ROOT)}:{line} {module}")
    assert not bad, "\n".join(bad)


def test_the_cli_layer_is_imported_by_no_library_module() -> None:
    bad = []
    for package, path in _library_files():
        for line, module, _, _ in _imports(path, package):
            if module in CLI:
                bad.append(f"{path.relative_to(ROOT)}:{line} spherecal.{module}")
    assert not bad, "\n".join(bad)


def test_no_bench_script_shadows_a_package() -> None:
    names = {path.stem for path in (ROOT / "bench").glob("*.py")}
    assert "spherecal" not in names
    assert not (ROOT / "bench" / "__init__.py").exists()
