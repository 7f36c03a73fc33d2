"""YAML read in bounded time and memory (libyaml when present).

A scenario file is composed once into a node graph, which shares every aliased node, so
composing costs time linear in the file's size. Before anything is built from the nodes
the graph is measured with aliases expanded: a file whose expansion has more than
:data:`MAX_NODES` nodes ("billion laughs"), nests deeper than :data:`MAX_DEPTH`, or whose
aliases refer to themselves is refused with its line, never constructed.
"""

from __future__ import annotations

import yaml

from crowdwalk.errors import InputError

__all__ = ["MAX_BYTES", "MAX_DEPTH", "MAX_NODES", "compose_bounded", "construct"]

MAX_BYTES = 20_000_000  # scenario file size [bytes]
MAX_DEPTH = 64  # nesting of sequences and mappings, aliases expanded
MAX_NODES = 2_000_000  # scalars, sequences and mappings, aliases expanded

_Loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def _where(source: str, node_or_mark) -> str:
    mark = getattr(node_or_mark, "start_mark", node_or_mark)
    return f"{source}:{mark.line + 1}" if mark is not None else source


def _check_nesting(text: str, source: str) -> bool:
    """Refuse nesting deeper than MAX_DEPTH from the event stream (no recursion); whether
    the text has aliases."""
    depth, aliases = 0, False
    for event in yaml.parse(text, Loader=_Loader):
        if isinstance(event, yaml.AliasEvent):
            aliases = True
        elif isinstance(event, yaml.CollectionStartEvent):
            depth += 1
            if depth > MAX_DEPTH:
                raise InputError(f"{_where(source, event)}: YAML nesting must be at most "
                                 f"{MAX_DEPTH} levels deep; got more.")
        elif isinstance(event, yaml.CollectionEndEvent):
            depth -= 1
    return aliases


def _children(node) -> list:
    if isinstance(node, yaml.SequenceNode):
        return node.value
    if isinstance(node, yaml.MappingNode):
        return [n for pair in node.value for n in pair]
    return []


def _check_expansion(root, source: str) -> None:
    """Size and depth of the node graph with aliases expanded (memoised, iterative)."""
    size: dict[int, int] = {}
    depth: dict[int, int] = {}
    stack = [(root, False)]
    open_ids: set[int] = set()
    while stack:
        node, done = stack.pop()
        key = id(node)
        if done:
            kids = _children(node)
            size[key] = 1 + sum(size[id(k)] for k in kids)
            depth[key] = 1 + max((depth[id(k)] for k in kids), default=0)
            open_ids.discard(key)
            if size[key] > MAX_NODES:
                raise InputError(f"{_where(source, node)}: YAML aliases must expand to at most "
                                 f"{MAX_NODES:,} nodes; got more (an alias bomb?).")
            if depth[key] > MAX_DEPTH + 1:
                raise InputError(f"{_where(source, node)}: YAML nesting (aliases expanded) must "
                                 f"be at most {MAX_DEPTH} levels deep; got {depth[key] - 1}.")
            continue
        if key in size:
            continue
        if key in open_ids:
            raise InputError(f"{_where(source, node)}: YAML aliases must not refer to the "
                             "node that contains them; got a recursive alias.")
        open_ids.add(key)
        stack.append((node, True))
        stack.extend((k, False) for k in _children(node) if id(k) not in size)


def compose_bounded(text: str, source: str = "<yaml>"):
    """The YAML node graph of ``text`` (None for an empty document), checked against
    :data:`MAX_BYTES`, :data:`MAX_DEPTH` and :data:`MAX_NODES`.

    Raises :class:`~crowdwalk.errors.InputError` for a file outside those bounds and
    ``yaml.YAMLError`` for text that is not YAML.
    """
    if len(text) > MAX_BYTES:
        raise InputError(f"{source}: a scenario file must be at most {MAX_BYTES:,} bytes; "
                         f"got {len(text):,}.")
    aliases = _check_nesting(text, source)
    root = yaml.compose(text, Loader=_Loader)
    if root is not None and aliases:  # without aliases the graph is the file's tree
        _check_expansion(root, source)
    return root


def construct(root):
    """Python data (dicts, lists, scalars) of a node graph from :func:`compose_bounded`."""
    if root is None:
        return None
    return yaml.SafeLoader("").construct_document(root)
