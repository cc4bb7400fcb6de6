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


#: Folder of every spherecal package (the installed name maps onto the design card's folders).
_FOLDERS = {"spherecal.correction": "correction", "spherecal.identification": "identification",
            "spherecal.controller": "controller", "spherecal.validation": "validation", "spherecal": "spherecal"}
#: What a function-level import of our own modules may be there for: a heavy dependency it pulls in.
HEAVY = ("mujoco", "rerun", "pyswarms", "rosbags", "dask", "scipy", "osqp", "qpsolvers", "tqdm")


def _modules() -> dict[str, Path]:
    """Every module of spherecal by its dotted name (packages by their ``__init__``)."""
    found = {}
    for package, folder in _FOLDERS.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            parts = list(path.relative_to(ROOT / folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            found[".".join([package, *parts])] = path
    return found


def module_graph() -> dict[str, set[str]]:
    """Module -> the spherecal modules it imports, at the top or inside a function (a name imported
    from a package counts as that package's module when there is one)."""
    modules = _modules()
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        is_package = path.name == "__init__.py"
        here = name.split(".") if is_package else name.split(".")[:-1]
        deps: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text())):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                prefix = node.module or ""
                if node.level:
                    prefix = ".".join(here[: len(here) - node.level + 1] + ([node.module] if node.module else []))
                targets = [f"{prefix}.{alias.name}" for alias in node.names]
            for target in targets:
                while target and target not in modules:
                    target = target.rpartition(".")[0]
                if target and target != name and not name.startswith(target + "."):
                    deps.add(target)
        graph[name] = deps
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found = []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def test_cycle_finder_finds_a_cycle() -> None:
    """The finder itself: a three-module loop and a self-contained chain."""
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_no_module_imports_another_that_imports_it_back() -> None:
    """No cycle between modules, counting imports inside functions as well."""
    graph = module_graph()
    assert len(graph) > 50 and "spherecal.correction.chain" in graph["spherecal.correction.kinematics"]
    assert cycles(graph) == []


def test_function_level_imports_of_our_modules_name_a_heavy_dependency() -> None:
    """An import of our own code inside a function is there only to defer a named heavy dependency."""
    bad = []
    for package, path in _library_files():
        lines = path.read_text().splitlines()
        for line, module, local, _ in _imports(path, package):
            if local and not module.startswith("external:"):
                comment = " ".join(lines[max(line - 2, 0) : line + 1]).lower()
                if not any(heavy in comment for heavy in HEAVY):
                    bad.append(f"{path.relative_to(ROOT)}:{line} spherecal.{module}")
    assert not bad, "\n".join(bad)
