"""The one YAML loader for files a user hands us (robot files, fixtures, plan candidates).

PyYAML's ``safe_load`` builds no objects, but it still takes whatever it is given: a few hundred
bytes of nested anchors and aliases ("billion laughs") that expand to billions of nodes when
anything walks the result, a document nested ten thousand levels deep (a ``RecursionError``), a
file of gigabytes, and a key given twice (the last one silently wins). :func:`load_yaml` refuses
each of these in well under a second with one line naming the file, row and field:

- the text is at most :data:`MAX_BYTES` long;
- mappings and sequences nest at most :data:`MAX_DEPTH` deep;
- the document, with every alias expanded, has at most :data:`MAX_NODES` nodes;
- no mapping has the same key twice.

Numbers in exponent notation without a point (``1e-3``, ``5E+2``), which YAML 1.2 and the tools that write it
(ruamel.yaml, yaml-cpp, ROS parameter files) read as floats, are floats here too: PyYAML's YAML 1.1 rules
made them strings, and a mass ``1e6`` or a distance ``1e-1`` was refused as "not a number".
"""

from __future__ import annotations

import re
from typing import Any

import yaml

from ..errors import SpherecalError

#: Largest YAML file read [bytes] (a robot or fixtures file is a few kB).
MAX_BYTES = 1_000_000
#: Largest YAML file read from disk [bytes]: MAX_BYTES characters of UTF-8 (at most 4 bytes each).
MAX_FILE_BYTES = 4 * MAX_BYTES
#: Deepest nesting of mappings and sequences.
MAX_DEPTH = 50
#: Most nodes of the document with aliases expanded.
MAX_NODES = 200_000


class YamlError(SpherecalError):
    """A YAML document that is invalid or beyond the limits (one line naming file, row and field)."""


class _Loader(yaml.SafeLoader):
    """SafeLoader that counts nesting while it composes (before any recursion can overflow), with YAML 1.2's
    floats in exponent notation without a point (``1e-3``)."""

    yaml_implicit_resolvers = {key: list(value) for key, value in yaml.SafeLoader.yaml_implicit_resolvers.items()}

    def __init__(self, stream: str, source: str):
        super().__init__(stream)
        self._depth = 0
        self._source = source

    def compose_node(self, parent, index):  # noqa: D102 - PyYAML's hook
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                mark = self.peek_event().start_mark
                raise YamlError(f"{self._source}: row {mark.line + 1}: nested more than {MAX_DEPTH} levels")
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


#: A float YAML 1.2 reads and YAML 1.1 does not: digits, an optional point, an exponent (``1e6``, ``-2.5E-3``).
_EXPONENT_FLOAT = re.compile(r"^[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)[eE][-+]?[0-9]+$")
for _first in "-+0123456789.":
    _Loader.yaml_implicit_resolvers.setdefault(_first, []).insert(0, ("tag:yaml.org,2002:float", _EXPONENT_FLOAT))


def _expanded_size(root: yaml.Node, source: str) -> None:
    """Refuse a node graph that expands (aliases followed) to more than :data:`MAX_NODES` nodes."""
    sizes: dict[int, int] = {}

    def size(node: yaml.Node) -> int:  # depth is bounded by MAX_DEPTH: the recursion is safe
        known = sizes.get(id(node))
        if known is not None:
            return known
        total = 1
        if isinstance(node, yaml.MappingNode):
            for key, value in node.value:
                total += size(key) + size(value)
                if total > MAX_NODES:
                    break
        elif isinstance(node, yaml.SequenceNode):
            for value in node.value:
                total += size(value)
                if total > MAX_NODES:
                    break
        if total > MAX_NODES:
            raise YamlError(
                f"{source}: row {node.start_mark.line + 1}: expands to more than {MAX_NODES} values "
                "(anchors and aliases)"
            )
        sizes[id(node)] = total
        return total

    size(root)


def _duplicate_keys(root: yaml.Node, source: str) -> None:
    seen_nodes: set[int] = set()
    stack = [root]
    while stack:
        node = stack.pop()
        if id(node) in seen_nodes:  # an alias: checked where its anchor is
            continue
        seen_nodes.add(id(node))
        if isinstance(node, yaml.MappingNode):
            keys: set[Any] = set()
            for key, value in node.value:
                name = key.value if isinstance(key, yaml.ScalarNode) else id(key)
                if name in keys:
                    raise YamlError(f"{source}: row {key.start_mark.line + 1}, field {name!r}: duplicate key")
                keys.add(name)
                stack.append(value)
        elif isinstance(node, yaml.SequenceNode):
            stack.extend(node.value)


def load_yaml(text: str, source: str, error: type[SpherecalError] = YamlError) -> tuple[Any, yaml.Node | None]:
    """Parse one YAML document from untrusted text, within the limits above.

    Args:
        text: the document.
        source: the file name, for messages.
        error: the exception class to raise (a :class:`SpherecalError`, e.g. ``RobotFileError``).

    Returns:
        ``(data, root)``: the plain Python data (None for an empty document) and its node tree (for
        row numbers).

    Raises:
        error: invalid YAML, too large, too deep, too many nodes after alias expansion, a duplicate key.
    """
    try:
        if len(text) > MAX_BYTES:
            raise YamlError(f"{source}: row 1: {len(text)} characters, a YAML file here is at most "
                            f"{MAX_BYTES}")
        loader = _Loader(text, source)
        try:
            root = loader.get_single_node()
            if root is None:
                return None, None
            _expanded_size(root, source)
            _duplicate_keys(root, source)
            return loader.construct_document(root), root
        finally:
            loader.dispose()
    except YamlError as refused:
        raise error(str(refused)) from None
    except yaml.YAMLError as invalid:
        mark = getattr(invalid, "problem_mark", None)
        row = f"row {mark.line + 1}" if mark is not None else "row ?"
        problem = str(getattr(invalid, "problem", None) or invalid).splitlines()[0]
        raise error(f"{source}: {row}: invalid YAML: {problem}") from None
    except RecursionError:  # a deep flow scalar the composer's guard did not see
        raise error(f"{source}: row ?: nested too deeply") from None


def node_line(node: Any, *path: Any, key_line: bool = False) -> int:
    """1-based line of the YAML node at ``path`` (keys and indices) below ``node``, or of the deepest node found.
    With ``key_line``, a path ending at a mapping key gives the key's line (a block's ``name:`` line, not the
    line below it where the block's value starts)."""

    for step, key in enumerate(path):
        if isinstance(node, yaml.MappingNode):
            match = [(k, v) for k, v in node.value if getattr(k, "value", None) == key]
            if not match:
                break
            if key_line and step == len(path) - 1:
                return match[-1][0].start_mark.line + 1
            node = match[-1][1]
        elif isinstance(node, yaml.SequenceNode) and isinstance(key, int) and key < len(node.value):
            node = node.value[key]
        else:
            break
    return node.start_mark.line + 1


def dump_yaml(data: Any, **options: Any) -> str:
    """``yaml.safe_dump(data, **options)`` through libyaml's emitter when PyYAML has it (``CSafeDumper``:
    the same text, 3-4x faster on a calibrated robot file), else PyYAML's own."""
    return yaml.dump(data, Dumper=getattr(yaml, "CSafeDumper", yaml.SafeDumper), **options)
