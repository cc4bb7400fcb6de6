"""The public API of ``spherecal.correction`` as its docs site shows it.

Three checks a reader relies on: every exported name is on the API page (by a path that resolves to the
exported object), every array argument of a function defined directly under ``correction/`` has an ``Args:``
entry that gives its shape and unit, and the shapes the kinematic functions' ``Returns:`` promise (batched and for
one configuration) are the shapes they return.
"""

from __future__ import annotations

import importlib
import inspect
import re
from pathlib import Path

import numpy as np
import pytest

import spherecal
import spherecal.correction as correction
from spherecal.correction.elastic import with_stiffness
from spherecal.correction.scale import with_scale

API_PAGE = Path(__file__).resolve().parents[2] / "docs" / "api.md"
MODULES = ("chain", "conversion", "elastic", "errors", "gravity", "inertia", "inertials", "kinematics", "layout",
           "model", "perturbation", "rigid", "scale", "tool")
SECTION = re.compile(r"^(Args|Arguments|Returns|Raises|Warns|Yields|Example|Examples|Attributes|Note):\s*$")


def _section(doc: str, name: str) -> str:
    """The text of one Google-style section of a docstring ('' when absent)."""
    out, inside = [], False
    for line in doc.splitlines():
        match = SECTION.match(line.strip()) if not line.startswith(" ") else None
        if match:
            inside = match.group(1) == name
            continue
        if inside:
            out.append(line)
    return "\n".join(out)


def _args(doc: str) -> dict[str, str]:
    """Argument name -> its entry (continuation lines included); ``a, b: ...`` documents both."""
    entries: dict[str, str] = {}
    current: list[str] = []
    for line in _section(doc, "Args").splitlines():
        match = re.match(r"^    ([\w, ]+):(.*)$", line)
        if match:
            current = [name.strip() for name in match.group(1).split(",")]
            for name in current:
                entries[name] = match.group(2)
        elif line.startswith("     "):
            for name in current:
                entries[name] += " " + line.strip()
    return entries


def _resolve(path: str):
    """The object a dotted path names, walked by attribute from ``spherecal`` as autosummary imports it."""
    parts = path.split(".")
    obj = spherecal
    for i, part in enumerate(parts[1:], start=1):
        if not hasattr(obj, part):
            obj = importlib.import_module(".".join(parts[: i + 1]))
        else:
            obj = getattr(obj, part)
    return obj


def test_every_export_is_on_the_api_page_by_a_path_that_resolves_to_it():
    listed = re.findall(r"^   (spherecal\.correction\.[\w.]+)$", API_PAGE.read_text(), flags=re.M)
    resolved = {}
    for path in listed:
        resolved.setdefault(path.rsplit(".", 1)[1], []).append(_resolve(path))
    missing = [name for name in correction.__all__
               if not any(obj is getattr(correction, name) for obj in resolved.get(name, []))]
    assert not missing, f"exported but not on docs/api.md (or listed by a path that is another object): {missing}"
    extra = sorted(set(resolved) - set(correction.__all__))
    assert not extra, f"on docs/api.md's export list but not exported: {extra}"


def test_every_export_has_a_docstring_and_no_private_name():
    for name in correction.__all__:
        assert not name.startswith("_"), name
        assert inspect.getdoc(getattr(correction, name)), f"{name} has no docstring"


def _array_parameters(function) -> list[str]:
    """Parameters annotated as arrays (``np.ndarray``, possibly ``| None``)."""
    return [name for name, parameter in inspect.signature(function).parameters.items()
            if "ndarray" in str(parameter.annotation)]


def _public_functions():
    for module_name in MODULES:
        module = importlib.import_module(f"spherecal.correction.{module_name}")
        for name, obj in vars(module).items():
            if name.startswith("_") or getattr(obj, "__module__", None) != module.__name__:
                continue
            if inspect.isfunction(obj):
                yield f"{module_name}.{name}", obj
            elif inspect.isclass(obj):
                for method_name, method in vars(obj).items():
                    if not method_name.startswith("_") and inspect.isfunction(method):
                        yield f"{module_name}.{name}.{method_name}", method


SHAPE = re.compile(r"\((?:[\w+\-]+, )*[\w+\-]+,?\)")  # (N, n), (3,), (n+1, 3, N)
UNIT = re.compile(r"\[[^\]]+\]|dimensionless|\bbool\b")


@pytest.mark.parametrize("qualname, function", list(_public_functions()), ids=lambda v: v if isinstance(v, str) else "")
def test_array_arguments_have_a_shape_and_a_unit(qualname, function):
    """An ``np.ndarray`` argument's ``Args:`` entry names its shape and its unit (an array of indices or flags
    says ``bool``; a dimensionless one says so)."""
    arrays = _array_parameters(function)
    if not arrays:
        return
    entries = _args(inspect.getdoc(function) or "")
    for name in arrays:
        assert name in entries, f"{qualname}: array argument {name!r} has no Args entry"
        assert SHAPE.search(entries[name]), f"{qualname}: {name!r} gives no shape: {entries[name]!r}"
        assert UNIT.search(entries[name]), f"{qualname}: {name!r} gives no unit: {entries[name]!r}"


def _promised_shapes(function) -> tuple[str, str | None]:
    """The batched shape and the one-configuration shape a ``Returns:`` section states."""
    returns = " ".join(_section(inspect.getdoc(function), "Returns").split())
    batched = SHAPE.search(returns)
    single = re.search(r"or (\([^)]*\)) for one configuration", returns)
    assert batched, f"{function.__name__}: Returns states no shape: {returns!r}"
    return batched.group(0), single.group(1) if single else None


def _shape(text: str, n: int, count: int, params: int) -> tuple[int, ...]:
    names = {"N": count, "n": n, "n+1": n + 1, "P": params}
    return tuple(names[t] if t in names else int(t) for t in (s.strip() for s in text.strip("()").split(",")) if t)


@pytest.mark.parametrize("name", ["tool_point", "tool_pose", "joint_jacobian", "pose_jacobian", "param_jacobian",
                                  "link_angle_jacobian", "link_frames", "gravity_torques"])
def test_returned_shapes_are_the_documented_ones(name):
    """On an elastic, scaled Panda (every joint-side term active), for N = 2 and for one configuration."""
    function = getattr(correction, name)
    model = with_scale(with_stiffness(correction.load_robot("panda"), np.full(7, 3e4)), np.full(7, 1e-3))
    q = model.random_configurations(2, np.random.default_rng(0))
    batched, single = _promised_shapes(function)
    assert single is not None, f"{name}: Returns does not say what one configuration gives"
    n, params = model.n_joints, model.n_params
    assert np.shape(function(model, q)) == _shape(batched, n, 2, params), name
    assert np.shape(function(model, q[0])) == _shape(single, n, 1, params), name


def test_kinematics_refuse_degrees_and_bad_shapes_as_documented():
    """The Raises the kinematic functions state: JointAngleError for degrees, ValueError for another shape."""
    model = correction.load_robot("panda")
    for name in ("tool_point", "tool_pose", "joint_jacobian", "pose_jacobian", "param_jacobian"):
        function = getattr(correction, name)
        raises = _section(inspect.getdoc(function), "Raises")
        assert "JointAngleError" in raises and "ValueError" in raises, name
        with pytest.raises(correction.JointAngleError):
            function(model, np.full(7, 90.0))
        with pytest.raises(ValueError):
            function(model, np.zeros(6))
