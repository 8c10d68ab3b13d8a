"""Reading a scenario file's YAML strictly: a key given twice is refused (naming both lines), nesting and alias
expansion are bounded, and two tags say what ``base:`` should do with an inherited value.

- ``key: !replace VALUE`` replaces the inherited mapping whole instead of merging into it (lists and plain values
  are replaced anyway); on ``crowd.agent_types`` it also drops the default types not named.
- ``key: !remove`` drops the inherited key: the format's default applies again (``null`` keeps its own meaning,
  such as a sensor left without a detector).

PyYAML builds a nested document by recursion and an alias by reference, so a deep file ends in a RecursionError and
a few lines of aliases can stand for billions of nodes, which validation would then walk: both are refused here with
one ScenarioError before anything else looks at the data.
"""

from __future__ import annotations

from pathlib import Path

import yaml

from .schema import REMOVE, ScenarioError

MAX_DEPTH = 64  # nested mappings and lists (the bundled scenarios reach 7)
MAX_NODES = 1_000_000  # nodes once every alias is expanded (the largest bundled scenario has about 2,000)


class Replace(dict):
    """A mapping tagged ``!replace``: laid over its base whole, not merged into it."""


class _StrictLoader(yaml.SafeLoader):
    """SafeLoader that refuses duplicate keys and bounds nesting depth."""

    def compose_node(self, parent, index):
        self._depth = getattr(self, "_depth", 0) + 1
        try:
            if self._depth > MAX_DEPTH:
                mark = self.peek_event().start_mark
                raise _Refused(f"nested more than {MAX_DEPTH} levels deep at line {mark.line + 1}; expected a "
                               f"scenario's few levels of mappings and lists")
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def construct_mapping(self, node, deep=False):
        lines: dict = {}
        for key_node, _ in node.value:
            if key_node.tag == "tag:yaml.org,2002:merge":  # `<<: *base`: merged keys may be overridden
                continue
            key = self.construct_object(key_node, deep=True)
            try:
                first = lines.setdefault(key, key_node.start_mark.line + 1)
            except TypeError:  # an unhashable key: PyYAML's own error names it
                break
            if first != key_node.start_mark.line + 1:
                raise _Refused(f"key {key!r} is given twice, at lines {first} and {key_node.start_mark.line + 1}; "
                               f"expected each key once")
        return super().construct_mapping(node, deep=deep)


class _Refused(Exception):
    """A structural fault of the YAML text, turned into a ScenarioError by ``read_yaml``."""


def _replace(loader: _StrictLoader, node):
    if isinstance(node, yaml.MappingNode):
        return Replace(loader.construct_mapping(node, deep=True))
    if isinstance(node, yaml.SequenceNode):
        return loader.construct_sequence(node, deep=True)  # a list replaces its base anyway
    raise _Refused(f"!replace at line {node.start_mark.line + 1} tags a plain value; expected a mapping or a list "
                   "(a plain value replaces its base anyway)")


def _remove(loader: _StrictLoader, node):
    if not (isinstance(node, yaml.ScalarNode) and node.value == ""):
        raise _Refused(f"!remove at line {node.start_mark.line + 1} has a value; expected `key: !remove` alone")
    return REMOVE


_StrictLoader.add_constructor("!replace", _replace)
_StrictLoader.add_constructor("!remove", _remove)


def _expanded_size(root) -> int:
    """Nodes of the composed document with every alias expanded (an alias is the node it names, shared)."""
    sizes: dict[int, int] = {}
    order, stack = [], [root]
    while stack:  # children before parents, each node once
        node = stack.pop()
        if id(node) in sizes:
            continue
        sizes[id(node)] = 0
        order.append(node)
        if isinstance(node, yaml.SequenceNode):
            stack.extend(node.value)
        elif isinstance(node, yaml.MappingNode):
            stack.extend(n for pair in node.value for n in pair)
    for node in reversed(order):
        children = (node.value if isinstance(node, yaml.SequenceNode) else
                    [n for pair in node.value for n in pair] if isinstance(node, yaml.MappingNode) else [])
        sizes[id(node)] = min(1 + sum(sizes[id(c)] for c in children), MAX_NODES + 1)
    return sizes[id(root)]


def read_yaml(path: Path):
    """The data of the YAML file ``path``; one ScenarioError naming the file for text that is not UTF-8, not YAML,
    has a key twice, or is nested or aliased beyond the bounds."""
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as e:
        raise ScenarioError(source, "<file>", f"cannot be read as UTF-8 text: {e}") from None
    loader = None
    try:
        loader = _StrictLoader(text)  # its reader refuses characters YAML does not allow (a NUL, say) at once
        node = loader.get_single_node()
        if node is None:
            return None
        if _expanded_size(node) > MAX_NODES:
            raise _Refused(f"expands to more than {MAX_NODES:,} values through its aliases; expected a scenario "
                           "(the largest bundled one has a few thousand)")
        return loader.construct_document(node)
    except _Refused as e:
        raise ScenarioError(source, "<file>", str(e)) from None
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(e, "problem", None) or str(e).splitlines()[0]
        raise ScenarioError(source, "<file>", f"not valid YAML{where}: {problem}") from None
    finally:
        if loader is not None:
            loader.dispose()
